"""Kernel modules of a configuration: `iec2kmod gen` and `iec2kmod build`.

    split.py      which modules, what each holds (data, from the Compilation)
    tree.py       writing the kbuild tree: C of each module, Kbuild, Makefile
    manifest.py   manifest.json (what plc-manager needs)
    build.py      `iec2kmod build`: kbuild on the host or in the container
"""

from .manifest import manifest_digest
from .split import MODULE_NAME_MAX, _modname, interface_hash
from .tree import FP_FLAGS, RUNTIME_HEADERS, generate_tree, write_tree

__all__ = ["generate_tree", "write_tree", "manifest_digest", "interface_hash", "FP_FLAGS",
           "RUNTIME_HEADERS", "MODULE_NAME_MAX", "_modname"]
