"""Where the data folders the compiler reads live: ``kmod_templates/`` (the
Jinja2 templates and the hand-written runtime C compiled into every module)
and ``containers/`` (the recipe of the module-build container).

In the repository they are top-level folders beside ``iec2kmod/``; an
installed (non-editable) copy ships them inside the package, as
``iec2kmod/kmod_templates`` and ``iec2kmod/containers`` (pyproject.toml maps
the folders there with ``package-dir``).  An editable install and
``PYTHONPATH=<checkout>`` find the repository's folders."""

from __future__ import annotations

from pathlib import Path

_HERE = Path(__file__).resolve().parent


def _find(name: str, probe: str) -> Path:
    """The folder *name* that holds *probe*: inside the package (installed),
    else beside it (the repository)."""
    for d in (_HERE / name, _HERE.parent / name):
        if (d / probe).is_file():
            return d
    raise FileNotFoundError(f"iec2kmod: the {name}/ folder is missing (looked for {probe} in "
                            f"{_HERE / name} and {_HERE.parent / name}); reinstall iec2kmod")


def templates_root() -> Path:
    """The kmod_templates folder (kernel/, runtime/, sim/, c/)."""
    return _find("kmod_templates", "kernel/iec_kmod.h")


def containers_root() -> Path:
    """The containers folder (build-rootfs.sh, the Dockerfile)."""
    return _find("containers", "build-rootfs.sh")
