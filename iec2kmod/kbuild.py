# SPDX-License-Identifier: MIT
"""Run kbuild for out-of-tree modules against the PREEMPT_RT headers.

    kdir = find_kdir()                       # /usr/src/linux-headers-6.1.0-56-rt-amd64
    res = build_modules("/path/to/module/dir")   # make -C KDIR M=DIR W=1 modules
    if not res.ok: print(res.output)
    clean_modules("/path/to/module/dir")

Also a small reader of a module's ``.modinfo`` section (``modinfo(path)``), so
that callers need no ``modinfo`` binary.
"""

from __future__ import annotations

import dataclasses
import functools
import glob
import os
import re
import struct
import subprocess
import time
from typing import Dict, List, Optional, Sequence, Tuple

from . import buildcache

HEADERS_PACKAGE = "linux-headers-rt-amd64"


class KbuildError(RuntimeError):
    """A kbuild prerequisite is missing (headers, make, compiler)."""


def _release_of(kdir: str) -> Optional[str]:
    """Kernel release the kbuild dir is for (UTS_RELEASE, as ``uname -r`` shows it).

    Debian's ``include/config/kernel.release`` holds the upstream version
    (``6.1.192-rt64``), not the release modules are built for, so read
    ``include/generated/utsrelease.h`` first."""
    try:
        with open(os.path.join(kdir, "include/generated/utsrelease.h")) as f:
            m = re.search(r'UTS_RELEASE\s+"([^"]+)"', f.read())
            if m:
                return m.group(1)
    except OSError:
        pass
    base = os.path.basename(os.path.normpath(os.path.realpath(kdir)))
    if base.startswith("linux-headers-"):
        return base[len("linux-headers-"):]
    return None


def _is_kbuild_dir(kdir: str) -> bool:
    return os.path.isfile(os.path.join(kdir, "Makefile")) and os.path.isfile(
        os.path.join(kdir, "Module.symvers"))


def find_kdir(release: Optional[str] = None) -> str:
    """Return the kbuild directory of the PREEMPT_RT headers.

    Order: ``$IEC2KMOD_KDIR``; ``/lib/modules/<release>/build`` when *release* is
    given; the newest ``/usr/src/linux-headers-*-rt-amd64`` with a Makefile and
    Module.symvers.  Raises :class:`KbuildError` naming the package to install.
    """
    env = os.environ.get("IEC2KMOD_KDIR")
    if env:
        if not _is_kbuild_dir(env):
            raise KbuildError(
                f"IEC2KMOD_KDIR={env} is not a kbuild directory (no Makefile/Module.symvers)")
        return env
    cands: List[str] = []
    if release:
        cands.append(f"/lib/modules/{release}/build")
        cands.append(f"/usr/src/linux-headers-{release}")
    else:
        found = glob.glob("/usr/src/linux-headers-*-rt-amd64")
        found.sort(key=_version_key, reverse=True)
        cands.extend(found)
        cands.extend(sorted(glob.glob("/lib/modules/*-rt-amd64/build"), reverse=True))
    for c in cands:
        if _is_kbuild_dir(c):
            return os.path.realpath(c)
    what = f"for kernel {release}" if release else "(/usr/src/linux-headers-*-rt-amd64)"
    raise KbuildError(
        f"PREEMPT_RT kernel headers not found {what}: install them with "
        f"'apt-get install {HEADERS_PACKAGE}' (or run scripts/setup.sh)")


def _version_key(path: str):
    return [int(x) if x.isdigit() else x for x in re.split(r"(\d+)", path)]


def kernel_release(kdir: Optional[str] = None) -> str:
    """Kernel release (``uname -r`` of the target), e.g. ``6.1.0-56-rt-amd64``."""
    kdir = kdir or find_kdir()
    rel = _release_of(kdir)
    if not rel:
        raise KbuildError(f"cannot tell the kernel release of {kdir}")
    return rel


@dataclasses.dataclass
class BuildResult:
    command: List[str]
    returncode: int
    output: str          # stdout and stderr, interleaved
    duration: float
    cached: bool = False     # restored from the build cache (iec2kmod/buildcache.py)

    @property
    def ok(self) -> bool:
        return self.returncode == 0

    def warnings(self) -> List[str]:
        """Compiler/modpost/sparse warning lines (``warning:`` / ``WARNING:``),
        and sparse's ``error:`` lines (sparse reports them without failing
        the build)."""
        return [l for l in self.output.splitlines()
                if re.search(r"\bwarning:|^WARNING:|: error:", l, re.IGNORECASE)]

    def check(self) -> "BuildResult":
        if not self.ok:
            raise KbuildError(
                f"kbuild failed (exit {self.returncode}): {' '.join(self.command)}\n{self.output}")
        return self


def _make(kdir: str, moddir: str, targets: Sequence[str], extra: Sequence[str],
          timeout: float, jobs: Optional[int]) -> BuildResult:
    if not os.path.isdir(moddir):
        raise KbuildError(f"module directory {moddir} does not exist")
    bad = next((c for c in os.path.abspath(moddir) if c.isspace() or c in ":#$"), None)
    if bad is not None:
        # make splits M= at white space and takes ':' '#' '$' as its own
        raise KbuildError(f"kbuild cannot build in {os.path.abspath(moddir)!r}: its path holds "
                          f"{bad!r}, which make does not accept in M=; build in a directory "
                          "whose path has no white space, ':', '#' or '$'")
    make = _which("make")
    if not make:
        raise KbuildError("'make' not found: apt-get install make (or run scripts/setup.sh)")
    cmd = [make, "-C", kdir, f"M={os.path.abspath(moddir)}"]
    if jobs is None:
        jobs = os.cpu_count() or 1
    cmd.append(f"-j{jobs}")
    cmd.extend(extra)
    cmd.extend(targets)
    t0 = time.monotonic()
    ckey = before = None
    if list(targets) == ["modules"] and buildcache.cache_dir():
        ckey = buildcache.key(moddir, _toolchain_id(kdir, "C=1" in extra), [*extra, *targets])
        hit = buildcache.restore(ckey, moddir)
        if hit is not None:
            return BuildResult(cmd, hit[0], hit[1], time.monotonic() - t0, cached=True)
        before = buildcache.snapshot(moddir)
    try:
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                           stdin=subprocess.DEVNULL, timeout=timeout)
    except subprocess.TimeoutExpired as e:
        out = (e.stdout or b"").decode("utf-8", "replace")
        raise KbuildError(f"kbuild timed out after {timeout:.0f} s: {' '.join(cmd)}\n{out}")
    res = BuildResult(cmd, p.returncode, p.stdout.decode("utf-8", "replace"),
                      time.monotonic() - t0)
    if ckey and res.ok:
        buildcache.store(ckey, moddir, before, res.output)
    return res


@functools.lru_cache(maxsize=None)
def _toolchain_id(kdir: str, sparse: bool) -> Tuple[str, ...]:
    """What a module build reads besides its tree (the build cache's key):
    the headers (release, configuration, exported symbols), the compiler,
    make, and sparse when it runs."""
    kdir = os.path.realpath(kdir)
    parts = [kdir, _release_of(kdir) or "-"]
    for f in (".config", "Module.symvers", "include/generated/autoconf.h", ".kernelvariables"):
        parts.append(f + "=" + buildcache.file_digest(os.path.join(kdir, f)))
    for tool in ["gcc-12", "gcc", "make", "ld"] + (["sparse"] if sparse else []):
        exe = _which(tool)
        if exe:
            parts.append(f"{tool}={buildcache.file_digest(os.path.realpath(exe))}")
    return tuple(parts)


def _which(prog: str) -> Optional[str]:
    for d in os.environ.get("PATH", "/usr/bin:/bin").split(os.pathsep):
        p = os.path.join(d, prog)
        if os.access(p, os.X_OK):
            return p
    return None


SPARSE_PACKAGE = "sparse"


def require_sparse() -> str:
    """The sparse binary (kbuild's ``C=1`` checker), or :class:`KbuildError`
    naming the package to install."""
    sparse = _which("sparse")
    if not sparse:
        raise KbuildError(f"'sparse' not found: apt-get install {SPARSE_PACKAGE} "
                          f"(or run scripts/setup.sh)")
    return sparse


def build_modules(moddir: str, *, kdir: Optional[str] = None, warnings: bool = True,
                  sparse: bool = False, extra_args: Sequence[str] = (),
                  timeout: float = 600, jobs: Optional[int] = None) -> BuildResult:
    """``make -C KDIR M=MODDIR W=1 modules`` (with ``C=1``: sparse checks every
    source it compiles); returns the result (does not raise on a failed build;
    call ``.check()`` for that)."""
    kdir = kdir or find_kdir()
    if sparse:
        require_sparse()
    extra = (["W=1"] if warnings else []) + (["C=1"] if sparse else []) + list(extra_args)
    return _make(kdir, moddir, ["modules"], extra, timeout, jobs)


def clean_modules(moddir: str, *, kdir: Optional[str] = None, timeout: float = 120) -> BuildResult:
    """``make -C KDIR M=MODDIR clean``."""
    kdir = kdir or find_kdir()
    return _make(kdir, moddir, ["clean"], [], timeout, 1)


# --------------------------------------------------------------- modinfo ----

def _elf_section(data: bytes, wanted: str) -> Optional[bytes]:
    if data[:4] != b"\x7fELF" or data[4] != 2:     # ELFCLASS64 only
        raise ValueError("not a 64-bit ELF file")
    end = "<" if data[5] == 1 else ">"
    (e_shoff,) = struct.unpack_from(end + "Q", data, 0x28)
    e_shentsize, e_shnum, e_shstrndx = struct.unpack_from(end + "HHH", data, 0x3A)
    def sh(i):
        # name, type, flags, addr, offset, size
        return struct.unpack_from(end + "IIQQQQ", data, e_shoff + i * e_shentsize)
    strtab = sh(e_shstrndx)
    names = data[strtab[4]:strtab[4] + strtab[5]]
    for i in range(e_shnum):
        s = sh(i)
        n = names[s[0]:names.index(b"\0", s[0])].decode()
        if n == wanted:
            return data[s[4]:s[4] + s[5]]
    return None


def modinfo(path: str) -> Dict[str, List[str]]:
    """Parse the ``.modinfo`` section of a ``.ko`` file: ``{key: [values...]}``
    (e.g. ``modinfo(p)["vermagic"][0]``, ``modinfo(p).get("depends")``)."""
    with open(path, "rb") as f:
        data = f.read()
    try:
        sec = _elf_section(data, ".modinfo")
    except (ValueError, struct.error, IndexError) as e:
        raise KbuildError(f"{path}: not a kernel module ({e})")
    if sec is None:
        raise KbuildError(f"{path}: no .modinfo section (not a kernel module?)")
    info: Dict[str, List[str]] = {}
    for entry in sec.split(b"\0"):
        if b"=" in entry:
            k, v = entry.split(b"=", 1)
            info.setdefault(k.decode(), []).append(v.decode("utf-8", "replace"))
    return info
