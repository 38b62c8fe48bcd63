# SPDX-License-Identifier: MIT
"""Write cpio "newc" initramfs archives in pure Python, and resolve kernel
module dependencies from the modules' own ``.modinfo`` (no depmod needed)."""

from __future__ import annotations

import io
import os
import stat
from typing import Dict, Iterable, List, Optional

from ...kbuild import modinfo

__all__ = ["CpioWriter", "ModuleIndex"]


class CpioWriter:
    """Build a cpio archive in the SVR4 "newc" format (magic 070701), which is
    what the kernel's initramfs unpacker reads.  Parents must be added before
    their children."""

    def __init__(self) -> None:
        self._buf = io.BytesIO()
        self._ino = 1
        self._names: set = set()
        self._closed = False

    def _entry(self, name: str, mode: int, data: bytes = b"", *, nlink: int = 1,
               rdev: tuple = (0, 0), mtime: int = 0) -> None:
        if self._closed:
            raise ValueError("archive already finished")
        name = name.lstrip("/") or "."
        if name in self._names:
            raise ValueError(f"duplicate cpio entry {name!r}")
        self._names.add(name)
        bname = name.encode() + b"\0"
        fields = [self._ino, mode, 0, 0, nlink, mtime, len(data), 0, 0,
                  rdev[0], rdev[1], len(bname), 0]
        self._ino += 1
        hdr = b"070701" + b"".join(b"%08X" % f for f in fields)
        out = self._buf
        out.write(hdr)
        out.write(bname)
        out.write(b"\0" * (-(len(hdr) + len(bname)) % 4))
        out.write(data)
        out.write(b"\0" * (-len(data) % 4))

    def add_dir(self, name: str, perm: int = 0o755) -> None:
        self._entry(name, stat.S_IFDIR | perm, nlink=2)

    def add_dirs(self, path: str) -> None:
        """Add *path* and all its missing parents."""
        parts = path.strip("/").split("/")
        for i in range(1, len(parts) + 1):
            p = "/".join(parts[:i])
            if p and p not in self._names:
                self.add_dir(p)

    def add_file(self, name: str, data: bytes, perm: int = 0o644) -> None:
        self._entry(name, stat.S_IFREG | perm, data)

    def add_host_file(self, name: str, host_path: str, perm: Optional[int] = None) -> None:
        with open(host_path, "rb") as f:
            data = f.read()
        if perm is None:
            perm = os.stat(host_path).st_mode & 0o7777
        self.add_file(name, data, perm)

    def add_symlink(self, name: str, target: str) -> None:
        self._entry(name, stat.S_IFLNK | 0o777, target.encode())

    def add_chardev(self, name: str, major: int, minor: int, perm: int = 0o600) -> None:
        self._entry(name, stat.S_IFCHR | perm, rdev=(major, minor))

    def finish(self) -> bytes:
        if not self._closed:
            self._entry("TRAILER!!!", 0, nlink=1)
            self._closed = True
            # pad the archive to a 512-byte multiple, like GNU cpio
            self._buf.write(b"\0" * (-self._buf.tell() % 512))
        return self._buf.getvalue()


class ModuleIndex:
    """Index of the ``.ko`` files under ``lib/modules/<kver>/kernel`` of an
    extracted kernel package, with dependency resolution."""

    def __init__(self, moddir: str) -> None:
        self.moddir = moddir
        self._paths: Dict[str, str] = {}
        for root, _dirs, files in os.walk(moddir):
            for fn in files:
                if fn.endswith(".ko"):
                    self._paths[self.canon(fn[:-3])] = os.path.join(root, fn)
        if not self._paths:
            raise FileNotFoundError(f"no .ko files under {moddir}")

    @staticmethod
    def canon(name: str) -> str:
        return name.replace("-", "_")

    def path(self, name: str) -> str:
        try:
            return self._paths[self.canon(name)]
        except KeyError:
            raise KeyError(f"kernel module {name!r} not found under {self.moddir}") from None

    def depends(self, name: str) -> List[str]:
        deps = modinfo(self.path(name)).get("depends", [""])[0]
        return [self.canon(d) for d in deps.split(",") if d]

    def load_order(self, wanted: Iterable[str]) -> List[str]:
        """The wanted modules and all their dependencies, dependencies first."""
        order: List[str] = []
        state: Dict[str, int] = {}

        def visit(n: str, chain: tuple) -> None:
            n = self.canon(n)
            if state.get(n) == 2:
                return
            if state.get(n) == 1:
                raise ValueError("module dependency cycle: " + " -> ".join(chain + (n,)))
            state[n] = 1
            for d in self.depends(n):
                visit(d, chain + (n,))
            state[n] = 2
            order.append(n)

        for w in wanted:
            visit(w, ())
        return order
