"""The container recipe for reproducible module builds (installed as the
package ``iec2kmod_containers`` so that a non-editable install finds it)."""
from pathlib import Path

ROOT = Path(__file__).resolve().parent
