"""The per-task watchdog (issue 9, item 2) in `iec2kmod sim`: the
{watchdog TIME[, N]} pragma in front of a TASK, its checks, and the same
faults, at the same simulated times and places, in the C simulator and the
reference interpreter.

Simulated time (iec2kmod/execmodel.py): each loop iteration costs
SIM_ITERATION_NS of simulated execution time.  A 5 ms watchdog therefore
allows 50,000 iterations, and the 50,001st faults, located at its loop; a
1 ms task whose cycles run 20,000 iterations (2 ms) overruns every cycle,
and with {watchdog off, 3} its third cycle faults (its results not
published).  The kernel's watchdog is wall time (tests/qemu/test_faults.py).
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from iec2kmod import interp, sim
from iec2kmod.parse import frontend
from iec2kmod.checks.tasks import WATCHDOG_DEFAULT_NS
from iec2kmod.execmodel import SIM_ITERATION_NS

ROOT = Path(__file__).resolve().parents[2]

SOURCE = """\
PROGRAM Spin
VAR_EXTERNAL n : DINT; spins : DINT; END_VAR
VAR i : DINT; END_VAR
    spins := spins + 1;
    FOR i := 1 TO n DO
        spins := spins + 1;
    END_FOR;
END_PROGRAM

PROGRAM Slow
VAR_EXTERNAL m : DINT; slow_runs : DINT; END_VAR
VAR i : DINT; END_VAR
    slow_runs := slow_runs + 1;
    WHILE i < m DO
        i := i + 1;
    END_WHILE;
    i := 0;
END_PROGRAM

PROGRAM Beat
VAR_EXTERNAL beats : DINT; END_VAR
    beats := beats + 1;
END_PROGRAM

CONFIGURATION Wd
    VAR_GLOBAL n : DINT := 10; m : DINT := 5000; spins : DINT; slow_runs : DINT;
               beats : DINT; END_VAR
    RESOURCE r0 ON PLC
        {watchdog T#5ms}
        TASK spin (INTERVAL := T#10ms, PRIORITY := 2);
        {watchdog off, 3}
        TASK slow (INTERVAL := T#1ms, PRIORITY := 3);
        TASK beat (INTERVAL := T#1ms, PRIORITY := 4);
        PROGRAM s WITH spin : Spin;
        PROGRAM w WITH slow : Slow;
        PROGRAM b WITH beat : Beat;
    END_RESOURCE
END_CONFIGURATION
"""


@pytest.fixture(scope="module")
def project(tmp_path_factory):
    d = tmp_path_factory.mktemp("wd")
    (d / "wd.st").write_text(SOURCE)
    (d / "in.csv").write_text("time,variable,value\n"
                              "20ms,n,50000\n"      # 50,000 iterations: 5 ms, within
                              "35ms,n,50001\n"      # the 50,001st: the watchdog
                              "40ms,m,20000\n")     # 2 ms cycles in a 1 ms task
    r = frontend.run([str(d / "wd.st")], use_cache=False)
    assert r.ok, [str(x) for x in r.diags.errors]
    return r.project, d


def both(project, d):
    watch = ["spins", "slow_runs", "beats"]
    c = sim.run(project, 60_000_000, watch=watch, inputs=str(d / "in.csv"),
                build_dir=d / "build")
    v = interp.run(project, 60_000_000, watch=watch, inputs=str(d / "in.csv"))
    return c, v


def test_the_pragma_sets_each_task(project):
    p, _ = project
    tasks = {t.name: t for t in p.configurations[0].resources[0].tasks.values()}
    assert (tasks["spin"].watchdog_ns, tasks["spin"].watchdog_overruns) == (5_000_000, 0)
    assert (tasks["slow"].watchdog_ns, tasks["slow"].watchdog_overruns) == (0, 3)
    assert (tasks["beat"].watchdog_ns, tasks["beat"].watchdog_overruns) == \
        (WATCHDOG_DEFAULT_NS, 0)


def test_sim_and_interpreter_fault_alike(project):
    p, d = project
    c, v = both(p, d)
    assert c.faults == v.faults, (c.faults, v.faults)
    assert c.changes == v.changes
    assert c.cycles == v.cycles
    faults = {f[1]: f for f in c.faults}
    # the watchdog: the 50,001st iteration in the cycle at 40 ms, at the FOR
    t, _, what, pou, file, line = faults["r0.spin"]
    assert (t, pou, line) == (40_000_000, "Spin", 5), faults["r0.spin"]
    assert what.startswith("watchdog"), what
    # 50,000 at 20 ms and 30 ms passed: spins counted 1 + 50,000 twice
    # (plus 1 + 10 at 0 and 10 ms); the faulting cycle published nothing
    names = c.names
    last = {}
    for tt, k, val in c.changes:
        last[names[k]] = (tt, val)
    assert last["spins"] == (30_000_000, 2 * 11 + 2 * 50_001), last
    # three overrunning cycles in a row from 40 ms: the third faults
    t, _, what, pou, file, line = faults["r0.slow"]
    assert t == 42_000_000 and what.startswith("overruns") and (pou, line) == ("?", 0)
    assert last["slow_runs"] == (41_000_000, 42), last      # 0..41 ms, not 42
    # the other task goes on
    assert "r0.beat" not in faults and c.cycles["r0.beat"] == 61


def test_iteration_cost_is_the_same_constant_everywhere():
    text = (ROOT / "kmod_templates" / "sim" / "sim_main.c").read_text()
    m = re.search(r"#define SIM_ITERATION_NS (\d+)LL", text)
    assert m and int(m.group(1)) == SIM_ITERATION_NS


@pytest.mark.parametrize("pragma, message", [
    ("{watchdog}", "malformed watchdog pragma"),
    ("{watchdog 5ms}", "watchdog time '5ms' is not a TIME literal"),
    ("{watchdog T#0ms}", "the watchdog time must be positive"),
    ("{watchdog T#5ms, -1}", "the overrun limit '-1' is not a number of cycles"),
    ("{watchdog T#5ms, 2, 3}", "malformed watchdog pragma"),
])
def test_bad_pragmas_are_source_errors(tmp_path, pragma, message):
    src = SOURCE.replace("{watchdog T#5ms}", pragma)
    (tmp_path / "wd.st").write_text(src)
    p = subprocess.run([sys.executable, "-m", "iec2kmod.cli", "check", str(tmp_path / "wd.st")],
                       cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert p.returncode == 1, p.stdout + p.stderr
    line = src[:src.index(pragma)].count("\n") + 1
    assert f"wd.st:{line}:9: error: {message}" in p.stderr, p.stderr
    assert "Traceback" not in p.stderr


def test_event_task_overrun_limit_and_misplaced_pragma(tmp_path):
    src = SOURCE.replace("{watchdog off, 3}\n        TASK slow (INTERVAL := T#1ms,",
                         "{watchdog off, 3}\n        TASK slow (SINGLE := go,")
    src = src.replace("beats : DINT; END_VAR", "beats : DINT; go : BOOL; END_VAR")
    src = src.replace("END_RESOURCE", "END_RESOURCE\n    {watchdog T#1ms}")
    (tmp_path / "wd.st").write_text(src)
    p = subprocess.run([sys.executable, "-m", "iec2kmod.cli", "check", str(tmp_path / "wd.st")],
                       cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert p.returncode == 1
    assert "error: an overrun limit needs a periodic task (INTERVAL)" in p.stderr, p.stderr
    assert "warning: watchdog pragma applies to nothing: put it right in front of a TASK" \
        in p.stderr, p.stderr


def test_a_comment_between_the_pragma_and_its_task(tmp_path):
    """Blanks between a {watchdog} and its TASK are what the grammar skips,
    comments too, as for {selective} (parse/lexical.PRAGMAS): the pragma is
    not lost with a warning because a comment names the task."""
    src = SOURCE.replace("{watchdog T#5ms}", "{watchdog T#7ms} (* the fast task *)\n        // ok")
    assert "{watchdog T#7ms}" in src
    (tmp_path / "wd.st").write_text(src)
    r = frontend.run([str(tmp_path / "wd.st")], use_cache=False)
    assert r.ok and not r.diags.warnings, [d.message for d in r.diags.warnings]
    tasks = [t for c in r.project.configurations for res in c.resources
             for t in res.tasks.values()]
    assert 7_000_000 in [t.watchdog_ns for t in tasks]
