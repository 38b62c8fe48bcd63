# SPDX-License-Identifier: MIT
"""A content-addressed cache of kbuild results (opt-in: ``$IEC2KMOD_BUILD_CACHE``).

A kbuild of a module tree reads the tree's sources, the kernel headers, the
compiler (and sparse with ``C=1``) and the make arguments, and nothing else;
the same inputs give the same modules and the same compiler output.  When
``$IEC2KMOD_BUILD_CACHE`` names a directory, a successful build is stored
there under the SHA-256 of those inputs: every file the build created or
changed (``.ko``, ``.o``, ``Module.symvers``, ...) and its output with the
tree's path replaced by a placeholder.  A later build of identical inputs, in
any directory, restores the files and replays the output (warnings
included, so a ``W=1``/sparse gate sees exactly what the real build printed).

    key = buildcache.key(moddir, toolchain=[...], args=[...])
    hit = buildcache.restore(key, moddir)          # (returncode, output) or None
    ... run the build ...
    buildcache.store(key, moddir, before, returncode, output)

Only successful builds are stored (a failure is rebuilt and reported
fresh).  The test suite turns the cache on (tests/conftest.py) so that CI
does not rebuild modules whose inputs did not change; ``iec2kmod build``
uses it only when the variable is set.  ``IEC2KMOD_BUILD_CACHE=off`` (or
unset) builds every time.  The cache keeps the newest ``MAX_ENTRIES``
entries."""

from __future__ import annotations

import contextlib
import hashlib
import io
import os
import shutil
import tarfile
import tempfile
import time
from typing import Dict, Iterable, Optional, Tuple

FORMAT = "iec2kmod-buildcache-1"
MAX_ENTRIES = 400
PLACEHOLDER = "@@IEC2KMOD_MODDIR@@"

# what kbuild writes into a module tree (never an input of a build)
_PRODUCT_SUFFIXES = (".o", ".ko", ".mod", ".mod.c", ".cmd", ".a", ".order", ".symvers",
                     ".dwo", ".ko.debug", ".lto", ".tmp")
_PRODUCT_NAMES = {"Module.symvers", "modules.order", ".cache.mk", ".modules-order.tmp"}
# written by `iec2kmod build` after the make (the kernel release), not read by it
_NOT_INPUTS = {"manifest.json"}


def cache_dir() -> Optional[str]:
    d = os.environ.get("IEC2KMOD_BUILD_CACHE", "")
    if not d or d.lower() in ("off", "0", "no"):
        return None
    return d


def _is_product(rel: str) -> bool:
    name = os.path.basename(rel)
    return (name in _PRODUCT_NAMES or name.startswith(".tmp_") or
            any(name.endswith(s) for s in _PRODUCT_SUFFIXES))


def _walk(moddir: str) -> Iterable[str]:
    for root, dirs, files in os.walk(moddir):
        dirs.sort()
        for f in sorted(files):
            p = os.path.join(root, f)
            if os.path.isfile(p) and not os.path.islink(p):
                yield os.path.relpath(p, moddir)


def snapshot(moddir: str) -> Dict[str, Tuple[int, int]]:
    """(mtime_ns, size) of every file of the tree, to find what a build wrote."""
    out = {}
    for rel in _walk(moddir):
        st = os.stat(os.path.join(moddir, rel))
        out[rel] = (st.st_mtime_ns, st.st_size)
    return out


def key(moddir: str, toolchain: Iterable[str], args: Iterable[str]) -> str:
    """SHA-256 over the tree's inputs (relative paths and contents), the
    toolchain's identity and the make arguments."""
    h = hashlib.sha256(FORMAT.encode() + b"\0")
    for part in toolchain:
        h.update(b"T" + part.encode() + b"\0")
    for a in args:
        h.update(b"A" + _arg_identity(a).encode() + b"\0")
    for rel in _walk(moddir):
        if _is_product(rel) or rel in _NOT_INPUTS:
            continue
        with open(os.path.join(moddir, rel), "rb") as f:
            data = f.read()
        h.update(b"F" + rel.encode() + b"\0" + str(len(data)).encode() + b"\0" + data)
    return h.hexdigest()


def _arg_identity(arg: str) -> str:
    """A make argument as an input of the build: ``VAR=/abs/file`` (such as
    KBUILD_EXTRA_SYMBOLS=/tmp/xyz/Module.symvers) stands for the file's
    content, not its path, so the same build under another temporary
    directory hits."""
    name, eq, value = arg.partition("=")
    if eq and os.path.isabs(value) and os.path.isfile(value):
        return f"{name}=@content:{file_digest(value)}"
    return arg


def file_digest(path: str) -> str:
    """SHA-256 of a file, '-' when it does not exist (part of a toolchain id)."""
    try:
        with open(path, "rb") as f:
            return hashlib.sha256(f.read()).hexdigest()
    except OSError:
        return "-"


def _entry(k: str) -> Optional[str]:
    d = cache_dir()
    return os.path.join(d, k[:2], k + ".tar") if d else None


def restore(k: str, moddir: str) -> Optional[Tuple[int, str]]:
    """Unpack a cached build into *moddir*: (returncode, output) or None."""
    path = _entry(k)
    if not path or not os.path.isfile(path):
        return None
    try:
        with tarfile.open(path) as tar:
            out = tar.extractfile("output").read().decode("utf-8", "replace")
            members = [m for m in tar.getmembers() if m.name.startswith("files/")]
            now = time.time()
            for m in members:
                rel = m.name[len("files/"):]
                if not m.isfile() or rel.startswith("/") or ".." in rel.split("/"):
                    return None
                dst = os.path.join(moddir, rel)
                os.makedirs(os.path.dirname(dst), exist_ok=True)
                with open(dst, "wb") as f:
                    f.write(tar.extractfile(m).read())
                os.utime(dst, (now, now))
        os.utime(path)          # most recently used
    except (OSError, tarfile.TarError, KeyError):
        return None
    return 0, out.replace(PLACEHOLDER, os.path.abspath(moddir))


def store(k: str, moddir: str, before: Dict[str, Tuple[int, int]], output: str) -> None:
    """Keep what a successful build wrote (files new or changed since *before*)."""
    path = _entry(k)
    if not path:
        return
    moddir = os.path.abspath(moddir)
    after = snapshot(moddir)
    written = [rel for rel, st in after.items() if before.get(rel) != st]
    os.makedirs(os.path.dirname(path), exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=os.path.dirname(path), suffix=".part")
    try:
        with os.fdopen(fd, "wb") as raw, tarfile.open(fileobj=raw, mode="w") as tar:
            data = output.replace(moddir, PLACEHOLDER).encode()
            info = tarfile.TarInfo("output")
            info.size = len(data)
            tar.addfile(info, io.BytesIO(data))
            for rel in sorted(written):
                tar.add(os.path.join(moddir, rel), arcname="files/" + rel, recursive=False)
        os.replace(tmp, path)
    except OSError:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        return
    _evict(cache_dir())



def _evict(d: str) -> None:
    entries = []
    for sub in os.listdir(d):
        p = os.path.join(d, sub)
        if os.path.isdir(p):
            for f in os.listdir(p):
                if f.endswith(".tar"):
                    fp = os.path.join(p, f)
                    with contextlib.suppress(OSError):
                        entries.append((os.stat(fp).st_mtime, fp))
    entries.sort(reverse=True)
    for _, fp in entries[MAX_ENTRIES:]:
        with contextlib.suppress(OSError):
            os.unlink(fp)


def clear() -> None:
    d = cache_dir()
    if d and os.path.isdir(d):
        shutil.rmtree(d)
