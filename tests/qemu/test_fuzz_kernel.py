"""QEMU tier: generated projects in the PREEMPT_RT kernel (issue 8, item 4).

The differential tier (tests/differential) runs random valid projects in the
C simulator, under ASan+UBSan and in the reference interpreter.  Here the
fewest of the first 50 projects of a fixed seed that together reach every
construct the 50 reach (progen's feature names; 12 of them, chosen greedily,
deterministic) are built as kernel modules (two configurations of at most 25
projects, built side by side: one make of 15 took over kbuild's 600 s on
the loaded machine; bodies at 0.6 of the full size as in the CI campaign), built
with W=1 and sparse (zero warnings, and no FPU register outside a
kernel_fpu_begin/end section: tests/kbuild/test_execution_kbuild.py), run in
a one-CPU guest for a known number of cycles
(`run all MS`, as in test_exec_kernel.py) and compared with the simulator:
every task's cycle count and fault (line) and every variable of the
configuration.  No input trace (an input needs a write at an exact cycle);
the kernel log must stay clean.

More random projects, each one whatever it reaches:
IEC2KMOD_FUZZ_KERNEL_COUNT=N runs the first N projects of the seed, all of
them (N=50 is what this test ran before it chose).  Reproduce one batch:
python3 benchmarks/fuzz_diff.py --unit SEED (the seeds are printed on
failure)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from kmod_helpers import ROOT

sys.path.insert(0, str(ROOT / "tests" / "differential"))
sys.path.insert(0, str(ROOT / "tests" / "execution"))
sys.path.insert(0, str(ROOT / "tests" / "kbuild"))

import difftest  # noqa: E402
import progen  # noqa: E402
import runner  # noqa: E402
import test_exec_kernel as ek  # noqa: E402
import test_execution_kbuild as kb  # noqa: E402
from iec2kmod.compilation import Compilation  # noqa: E402

pytestmark = pytest.mark.qemu

SEED = 20261124
POOL, MAX_BATCH, CYCLES, SIZE = 50, 25, 40, 0.6
MUST = ("fb_external_depth3", "external_array", "external_string", "array_of_fb",
        "il_body", "several_resources", "event_task", "std_fb_TON", "located_Q")


def chosen_seeds() -> tuple:
    """(the seeds this test runs, every feature the pool of POOL seeds reaches):
    a greedy cover of the pool's features, or the first N seeds, all of them,
    with IEC2KMOD_FUZZ_KERNEL_COUNT=N."""
    count = os.environ.get("IEC2KMOD_FUZZ_KERNEL_COUNT")
    pool = [difftest.unit_seed(SEED, i) for i in range(int(count) if count else POOL)]
    feats = {s: progen.generate_unit(s, 0, CYCLES, SIZE).features for s in pool}
    every = set().union(*feats.values())
    if count:
        return pool, every
    left, chosen = set(every), []
    while left:
        best = max(pool, key=lambda s: len(feats[s] & left))   # first of the best: stable
        chosen.append(best)
        left -= feats[best]
    return [s for s in pool if s in chosen], every


def _build(batch_no, seeds, tmp_path):
    """Sources and built module tree of one batch of generated projects."""
    units = [progen.generate_unit(s, k, CYCLES, SIZE) for k, s in enumerate(seeds)]
    src = tmp_path / f"src{batch_no}"
    src.mkdir()
    files = []
    for u in units:
        f = src / f"{u.prefix}prog.st"
        f.write_text(u.decl_text)
        files.append(f)
    cfg = src / "batch_config.st"
    # the guest has one CPU (tasks released together run in priority order,
    # as in the simulator): a resource pinned ON CPU1 would be refused there
    cfg.write_text(progen.config_text(f"fuzz_k{batch_no}", units).replace(" ON CPU1", " ON CPU0"))
    files.append(cfg)
    tree = tmp_path / f"tree{batch_no}"
    # sparse too (C=1): zero warnings from it on generated code as well
    for cmd in (["gen", *map(str, files), "-o", str(tree)], ["build", "--sparse", str(tree)]):
        p = subprocess.run([sys.executable, "-m", "iec2kmod.cli", *cmd], cwd=ROOT,
                           capture_output=True, text=True, timeout=1800)
        assert p.returncode == 0, (f"batch {batch_no} (seeds {seeds}): iec2kmod "
                                   f"{cmd[0]} failed:\n{p.stdout}{p.stderr}")
    fpu = kb.fpu_outside_sections(tree)
    assert not fpu, f"batch {batch_no}: FPU registers outside kernel_fpu_begin/end:\n" + \
        "\n".join(fpu[:20])
    return units, files, tree


def test_generated_projects_in_the_kernel_equal_the_simulation(guest_factory, guest_workdir,
                                                               tmp_path):
    seeds, every = chosen_seeds()
    batch = min(MAX_BATCH, -(-len(seeds) // 2))       # two builds side by side
    batches = [seeds[i:i + batch] for i in range(0, len(seeds), batch)]
    t0 = time.monotonic()
    with ThreadPoolExecutor(max_workers=2) as pool:
        built = list(pool.map(lambda nb: _build(nb[0], nb[1], tmp_path), enumerate(batches)))
    t_build = time.monotonic() - t0
    reached = set().union(*(u.features for units, _, _ in built for u in units))
    for must in MUST:
        assert must in reached, f"the generated projects no longer reach {must}"
    assert reached == every, f"the chosen projects miss {sorted(every - reached)}"
    g = guest_factory(smp=1)
    mark = g.log_mark()
    problems, timings = [], {}
    for n, (units, files, tree) in enumerate(built):
        t1 = time.monotonic()
        dest = Path(guest_workdir) / "fuzz_kernel" / f"b{n}"
        shutil.rmtree(dest, ignore_errors=True)
        dest.mkdir(parents=True)
        shutil.copy(tree / "manifest.json", dest)
        for ko in tree.glob("*/*.ko"):
            (dest / ko.parent.name).mkdir(exist_ok=True)
            shutil.copy(ko, dest / ko.parent.name)
        project = runner.check_project(files)
        ms = (CYCLES - 1) * units[0].interval_ns // 1_000_000 + 1
        tasks, values = ek.run_in_kernel(g, dest, ms,
                                         [e.path for e in Compilation(project).plan.table])
        found = ek.compare_group(f"batch {n}", project, ms, tasks, values)
        if found:
            problems.append(f"batch {n}, seeds {batches[n]}:")
            problems += found
        timings[f"b{n}"] = round(time.monotonic() - t1, 1)
    g.check_kernel_log(since=mark)
    print(f"\n{len(seeds)} generated projects ({len(every)} features): build {t_build:.0f} s; batches {timings}")
    assert not problems, f"{len(problems)} lines:\n" + "\n".join(problems[:80])
