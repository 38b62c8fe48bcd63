"""iec2kmod: IEC 61131-3 projects compiled into Linux PREEMPT_RT kernel modules."""

import importlib
import importlib.abc
import importlib.util
import sys

__version__ = "0.1.0"

# The front end (frontend, parser, stfast, literals) lives in iec2kmod.parse
# (issue 24); its old names stay importable, as the same module objects:
# ``from iec2kmod import frontend`` and ``import iec2kmod.frontend`` give
# iec2kmod.parse.frontend.
_MOVED = {f"{__name__}.{m}": f"{__name__}.parse.{m}"
          for m in ("frontend", "parser", "stfast", "literals")}


class _MovedModule(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    def find_spec(self, name, path=None, target=None):
        if name in _MOVED:
            return importlib.util.spec_from_loader(name, self)
        return None

    def create_module(self, spec):
        return importlib.import_module(_MOVED[spec.name])

    def exec_module(self, module):
        pass


# first: an installed copy's finder (an editable install of another tree)
# must not answer for the old names
if not any(isinstance(f, _MovedModule) for f in sys.meta_path):
    sys.meta_path.insert(0, _MovedModule())


def __getattr__(name):
    if f"{__name__}.{name}" in _MOVED:
        return importlib.import_module(_MOVED[f"{__name__}.{name}"])
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
