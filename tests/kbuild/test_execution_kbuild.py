"""kbuild tier: every execution-test source builds into kernel modules with
W=1 and zero warnings, on the host (with sparse, C=1: zero sparse warnings
too) and in the container.  The sources of an
area are wrapped into one configuration exactly as the execution runner
does (one task and one program instance per case), so one kbuild run
covers an area; a case with its own CONFIGURATION builds alone."""

from __future__ import annotations

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


def _build(name, cases, tmp: Path, container: bool):
    if len(cases) == 1 and cases[0].standalone:
        sources = [str(cases[0].path)]
    else:
        cfg = tmp / f"{name}_config.st"
        cfg.write_text(runner.wrapper_config(name, cases))
        sources = [str(c.path) for c in cases] + [str(cfg)]
    out = tmp / f"tree_{name}"
    p = _cli("gen", *sources, "-o", str(out))
    if p.returncode != 0:
        return f"{name}: gen failed: {p.stderr[-2000:]}"
    # the host build runs sparse too (C=1): zero warnings from it as well
    p = _cli("build", str(out), *(["--container"] if container else ["--sparse"]))
    if p.returncode != 0:
        return f"{name}: build failed ({p.returncode}): {p.stderr[-3000:]}"
    return None


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
