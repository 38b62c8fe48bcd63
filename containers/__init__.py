"""The container recipe for reproducible module builds (installed as the
package ``iec2kmod.containers`` so that a non-editable install finds it:
iec2kmod/resources.py)."""
from pathlib import Path

ROOT = Path(__file__).resolve().parent
