"""Jinja2 templates and the hand-written runtime C compiled into every generated module
(installed as the package ``iec2kmod.kmod_templates``; iec2kmod/resources.py finds it
there or, in the repository, beside iec2kmod/)."""
from pathlib import Path

ROOT = Path(__file__).resolve().parent
