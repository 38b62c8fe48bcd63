"""Jinja2 templates and the hand-written runtime C compiled into every generated module."""
from pathlib import Path

ROOT = Path(__file__).resolve().parent
