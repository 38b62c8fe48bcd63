# SPDX-License-Identifier: MIT
"""Build helpers for the runtime tests (imported by tests/runtime/conftest.py
and the test modules): compile C drivers against
kmod_templates/runtime with the strict and the sanitizer flag sets."""
import hashlib
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
RUNTIME = REPO / "kmod_templates" / "runtime"
CDIR = Path(__file__).resolve().parent / "c"

# tests/ on the path, for the reference models (tests/reference)
if str(REPO / "tests") not in sys.path:
    sys.path.insert(0, str(REPO / "tests"))

STRICT = ["-std=gnu11", "-Wall", "-Wextra", "-Werror", "-O2"]
SANITIZE = STRICT + [
    "-g", "-fno-omit-frame-pointer",
    "-fsanitize=undefined,address,float-cast-overflow",
    "-fno-sanitize-recover=all",
]
MODES = {"strict": STRICT, "sanitize": SANITIZE}

# Non-FP runtime objects and FP runtime objects (the latter get the FP flags
# in the kernel; in user space they are ordinary objects).
RT_INT_SOURCES = ["iec_string.c", "iec_std_fb.c"]
RT_FP_SOURCES = ["iec_math.c", "iec_real.c"]


def need_gcc():
    if shutil.which("gcc") is None:
        pytest.fail("gcc is required for the runtime tests: apt-get install gcc")


class Builder:
    def __init__(self, root: Path):
        self.root = root

    def build(self, sources, mode="strict", extra=(), shared=False, libs=()):
        """Compile sources (paths) into an executable (or .so) and return
        its path.  Builds are cached by their inputs."""
        need_gcc()
        flags = list(MODES[mode]) + list(extra)
        if shared:
            flags += ["-fPIC", "-shared"]
        srcs = [str(s) for s in sources]
        h = hashlib.sha256()
        for s in srcs:
            h.update(s.encode())
            h.update(Path(s).read_bytes())
        for hdr in sorted(RUNTIME.glob("*.h")) + sorted(CDIR.glob("*.h")):
            h.update(hdr.read_bytes())
        h.update(" ".join(flags + list(libs)).encode())
        out = self.root / (h.hexdigest()[:16] + (".so" if shared else ""))
        if not out.exists():
            cmd = ["gcc", *flags, "-I", str(RUNTIME), "-I", str(CDIR),
                   *srcs, "-o", str(out) + ".tmp", *libs]
            r = subprocess.run(cmd, capture_output=True, text=True)
            if r.returncode != 0:
                raise AssertionError(
                    "compile failed:\n" + " ".join(cmd) + "\n" + r.stdout + r.stderr)
            os.replace(str(out) + ".tmp", out)
        return out


def rt(*names):
    return [RUNTIME / n for n in names]


def cfile(name):
    return CDIR / name


def run_driver(exe, stdin=None, timeout=300):
    env = dict(os.environ)
    env.setdefault("ASAN_OPTIONS", "detect_leaks=1")
    env.setdefault("UBSAN_OPTIONS", "print_stacktrace=1")
    r = subprocess.run([str(exe)], input=stdin, capture_output=True,
                       text=True, timeout=timeout, env=env)
    return r
