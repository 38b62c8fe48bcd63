"""kbuild tier: every execution-test source builds into kernel modules with
W=1 and zero warnings, on the host (with sparse, C=1: zero sparse warnings
too) and in the container.  The sources of an
area are wrapped into one configuration exactly as the execution runner
does (one task and one program instance per case), so one kbuild run
covers an area; a case with its own CONFIGURATION builds alone.

Host builds are kept under ``$IEC2KMOD_CACHE/kbuild_exec/<group>-<key>``,
the key hashing the group's sources and everything that generates or
compiles them (iec2kmod/, kmod_templates/, the kernel headers used): the
QEMU tier (tests/qemu/test_exec_kernel.py) loads these same modules
instead of building them a second time."""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "execution"))

import runner  # noqa: E402


def _groups():
    cases = runner.discover()
    groups = {}
    for c in cases:
        if c.standalone:
            groups[f"{c.area}_{c.path.stem}"] = [c]
        else:
            groups.setdefault(c.area, []).append(c)
    return groups


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "iec2kmod.cli", *args], cwd=ROOT,
                          capture_output=True, text=True, timeout=3600)


def group_sources(name, cases, tmp: Path) -> list[str]:
    """The sources of a group: the cases, and the runner's wrapper
    configuration unless the case has its own."""
    if len(cases) == 1 and cases[0].standalone:
        return [str(cases[0].path)]
    cfg = tmp / f"{name}_config.st"
    cfg.write_text(runner.wrapper_config(name, cases))
    return [str(c.path) for c in cases] + [str(cfg)]


def _generator_key() -> str:
    h = hashlib.sha256()
    for top in ("iec2kmod", "kmod_templates"):
        for f in sorted((ROOT / top).rglob("*")):
            if f.is_file() and "__pycache__" not in f.parts:
                h.update(str(f.relative_to(ROOT)).encode())
                h.update(f.read_bytes())
    h.update(os.uname().release.encode())
    h.update(" ".join(sorted(p.name for p in Path("/usr/src").glob("linux-headers-*"))).encode())
    return h.hexdigest()


_GEN_KEY: list = []


def cache_dir(name, sources) -> Path:
    if not _GEN_KEY:
        _GEN_KEY.append(_generator_key())
    h = hashlib.sha256(_GEN_KEY[0].encode())
    for src in sources:
        h.update(Path(src).name.encode())
        h.update(Path(src).read_bytes())
    return runner.build_root() / "kbuild_exec" / f"{name}-{h.hexdigest()[:16]}"


_FPU_REG = re.compile(r"%(?:[xyz]mm\d+|mm\d|st(?:\(\d\))?)\b")


def fpu_outside_sections(tree: Path) -> list:
    """Instructions on FPU/SIMD registers in code that does not run between
    kernel_fpu_begin() and kernel_fpu_end(): every module but a program
    type that uses REAL (manifest "uses_fpu").  Such an instruction clobbers
    the registers of the user process the task preempted (a heap corrupted
    in plc-manager, found in the QEMU tier)."""
    manifest = json.loads((tree / "manifest.json").read_text())
    found = []
    for m in manifest["modules"]:
        if m.get("uses_fpu"):
            continue
        ko = tree / m.get("dir", m["name"]) / f"{m['name']}.ko"
        p = subprocess.run(["objdump", "-d", "--no-show-raw-insn", str(ko)],
                           capture_output=True, text=True, timeout=120)
        assert p.returncode == 0, p.stderr
        func = "?"
        for line in p.stdout.splitlines():
            if line.endswith(">:"):
                func = line.split("<", 1)[1][:-2]
            elif _FPU_REG.search(line):
                found.append(f"{ko.name}: {func}: {line.strip()}")
    return found


def _build(name, cases, tmp: Path, container: bool):
    sources = group_sources(name, cases, tmp)
    cached = None if container else cache_dir(name, sources)
    if cached is not None and (cached / "built.ok").exists():
        return None
    out = tmp / f"tree_{name}"
    p = _cli("gen", *sources, "-o", str(out))
    if p.returncode != 0:
        return f"{name}: gen failed: {p.stderr[-2000:]}"
    # the host build runs sparse too (C=1): zero warnings from it as well
    p = _cli("build", str(out), *(["--container"] if container else ["--sparse"]))
    if p.returncode != 0:
        return f"{name}: build failed ({p.returncode}): {p.stderr[-3000:]}"
    fpu = fpu_outside_sections(out)
    if fpu:
        return (f"{name}: FPU registers used outside kernel_fpu_begin/end:\n  "
                + "\n  ".join(fpu[:20]))
    if cached is not None:
        (out / "built.ok").write_text("")
        for old in cached.parent.glob(f"{name}-*"):
            shutil.rmtree(old, ignore_errors=True)
        cached.parent.mkdir(parents=True, exist_ok=True)
        shutil.copytree(out, cached.with_suffix(".tmp"), dirs_exist_ok=True)
        os.replace(cached.with_suffix(".tmp"), cached)
    return None


def built_tree(name, cases, tmp: Path) -> Path:
    """The host-built module tree of a group, from the cache (built now if
    missing); raises AssertionError with the build's message on failure."""
    err = _build(name, cases, tmp, container=False)
    assert err is None, err
    return cache_dir(name, group_sources(name, cases, tmp))


def _all(tmp_path, container):
    groups = _groups()
    n = sum(len(v) for v in groups.values())
    assert n >= 150, f"only {n} execution cases"
    with ThreadPoolExecutor(max_workers=2) as pool:
        errors = [e for e in pool.map(lambda kv: _build(kv[0], kv[1], tmp_path, container),
                                      groups.items()) if e]
    assert not errors, "\n\n".join(errors)


@pytest.mark.kbuild
def test_every_execution_source_builds_on_the_host(tmp_path):
    _all(tmp_path, container=False)


@pytest.mark.container
def test_every_execution_source_builds_in_the_container(tmp_path):
    _all(tmp_path, container=True)
