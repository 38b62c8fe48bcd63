"""QEMU tier: every execution case runs in the PREEMPT_RT kernel and ends
in the state `iec2kmod sim` computes (issue 8, item 4).

The cases are grouped exactly as tests/kbuild/test_execution_kbuild.py
builds them (one configuration per area, one task per case; a case with
its own CONFIGURATION alone), and its cached module trees are loaded
rather than built again.  For each group, in a one-CPU guest: insert the
modules, `run all MS` (sysfs control: every task starts from one common
first release, and every periodic task stops by itself before its first
release MS ms later, so each runs a known number of cycles whatever the
guest's speed), wait, stop the event tasks, read every task's cycle count
and fault and every variable of the configuration, unload.  The
simulator runs the same sources up to the same instant: every task must
have run as many cycles, faulted on the same line, and every variable
must hold the same value.  The programs' clock is the cycle's release
time in both, so timers agree to the nanosecond.

No inputs on either side (an INPUT directive needs a write at an exact
cycle).  One CPU, so that tasks released at the same instant run in
priority order as in the simulator.  The kernel log must stay clean."""

from __future__ import annotations

import json
import math
import os
import shutil
import struct
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from kmod_helpers import ROOT, control, loaded_modules, sysfs

sys.path.insert(0, str(ROOT / "tests" / "kbuild"))
sys.path.insert(0, str(ROOT / "tests" / "execution"))

import runner  # noqa: E402
import test_execution_kbuild as kb  # noqa: E402
from iec2kmod import sim  # noqa: E402
from iec2kmod.compilation import Compilation  # noqa: E402

pytestmark = pytest.mark.qemu

GROUPS = kb._groups()
# a debugging aid: IEC2KMOD_KERNEL_GROUPS=stdfb,faults runs only those groups
ONLY = [g for g in os.environ.get("IEC2KMOD_KERNEL_GROUPS", "").split(",") if g]
WAIT_S = 60          # per group, for its periodic tasks to stop after the run


def manager(guest, *argv, timeout=300):
    r = guest.pyrun(script="plc-manager", argv=[str(a) for a in argv], timeout=timeout)
    return r.exit_code, r.output


def status_json(guest):
    rc, out = manager(guest, "status", "--json")
    assert rc == 0, out
    return json.loads(out)


def _tasks(st):
    """{task name and resource.task, lower case: the task's status} from the
    manager's status JSON."""
    out = {}
    for r in st["resources"]:
        for t in r["tasks"]:
            out[t["name"].lower()] = t
            out[t["path"].lower()] = t
    return out


def running_periodic(guest, manifest) -> list[str]:
    """The periodic tasks in the running state, from the sysfs status file
    ("task RES.NAME state S interval_ns N ..." per task)."""
    r = guest.run(f"cat {sysfs(manifest)}/status")
    assert r.exit_code == 0, r.output
    out = []
    for line in r.output.splitlines():
        w = line.split()
        if len(w) >= 6 and w[0] == "task" and w[2] == "state" and w[4] == "interval_ns":
            if w[3] == "running" and int(w[5]):
                out.append(w[1])
    assert out or " state " in r.output, f"no task in the status file:\n{r.output}"
    return sorted(out)


def run_ms(cases, project) -> int:
    """Length of the run in whole ms: the periodic releases before it give
    every case at least the cycles it checks."""
    cfg = project.configurations[0]
    periods = [t.interval_ns for r in cfg.resources for t in r.tasks.values() if t.interval_ns]
    if len(cases) == 1 and cases[0].standalone:
        span = (cases[0].last_cycle - 1) * min(periods)
    else:
        span = max((c.last_cycle - 1) * c.interval_ns for c in cases)
    return span // 1_000_000 + 1


def run_in_kernel(guest, tree: Path, ms: int, paths):
    """Inserts the modules, `run all MS` (every periodic task stops by
    itself before its first release MS ms after the common start), waits
    for that, stops the event tasks, reads every task and variable."""
    # insmod and start by hand: `plc-manager load` refuses a configuration
    # whose task faults at once, and the faults area does that on purpose
    manifest = json.loads((tree / "manifest.json").read_text())
    order = manifest["load_order"]
    r = guest.run(" && ".join(f"insmod {tree / m / (m + '.ko')}" for m in order))
    assert r.exit_code == 0, f"insmod {tree.name}: {r.output}"
    try:
        control(guest, manifest, f"run all {ms}")
        time.sleep(ms / 1000)
        deadline = time.monotonic() + WAIT_S
        while True:
            # polled in sysfs (a shell `cat`, not a plc-manager process per
            # poll); the manager reads the final status below
            running = running_periodic(guest, manifest)
            if not running:
                break
            if time.monotonic() > deadline:
                pytest.fail(f"{tree.name}: still running {WAIT_S} s after the end of a "
                            f"{ms} ms run: {running}")
            time.sleep(0.05)
        control(guest, manifest, "stop all")
        tasks = _tasks(status_json(guest))
        values = {}
        for i in range(0, len(paths), 400):
            rc, out = manager(guest, "read", "--json", *paths[i:i + 400])
            assert rc == 0, out
            values.update({v["path"].upper(): (v["kind"], v["value"]) for v in json.loads(out)})
        return tasks, values
    finally:
        # the manager's order: stop, resources out, clear the slots, the rest out
        res = {m["name"] for m in manifest["modules"] if m["kind"] == "resource"}
        r = guest.run(" && ".join(
            [f"echo stop all > {sysfs(manifest)}/control"]
            + [f"rmmod {m}" for m in reversed(order) if m in res]
            + [f"echo clear all > {sysfs(manifest)}/control"]
            + [f"rmmod {m}" for m in reversed(order) if m not in res]))
        assert r.exit_code == 0, f"unload {tree.name}: {r.output}"
        assert loaded_modules(guest) == []


def same(kind, kernel, simulated, size) -> bool:
    if isinstance(simulated, float) or kind == "f":
        if not isinstance(kernel, (int, float)) or not isinstance(simulated, (int, float)):
            return False
        if size == 4:   # REAL: the simulator prints 9 digits, the kernel has the float
            return struct.pack("<f", kernel) == struct.pack("<f", simulated)
        return kernel == simulated or (math.isnan(kernel) and math.isnan(simulated))
    if isinstance(simulated, str) and isinstance(kernel, str) and kind == "e":
        return simulated.upper() == kernel.upper()
    return kernel == simulated


def compare_group(name, project, ms, tasks, values) -> list[str]:
    """The kernel's tasks and variables against the simulation of the same
    sources up to the last release before ``ms``."""
    plan = Compilation(project).plan
    cfg = project.configurations[0]
    implicit = cfg.resources[0].node.name is None
    periods = {}
    for r in cfg.resources:
        for t in r.tasks.values():
            periods[(t.name if implicit else f"{r.name}.{t.name}").lower()] = t.interval_ns
    end = ms * 1_000_000 - 1
    res = sim.run(project, end, watch=[e.path for e in plan.table],
                  build_dir=runner.build_root() / "sim")
    problems = []
    sim_faults = {f[1].lower(): f for f in res.faults}
    for n, period in periods.items():
        t = tasks[n]
        want = next((v for k, v in res.cycles.items() if k.lower() == n), 0)
        if int(t["cycles"]) != want:
            problems.append(f"{name}: task {n} ran {t['cycles']} cycles in the kernel "
                            f"({t['overruns']} overruns), {want} in the simulation")
        f = sim_faults.get(n)
        if t["state"] == "fault" or f is not None:
            if f is None or t["state"] != "fault" or int(t["fault_line"] or 0) != f[5]:
                problems.append(f"{name}: task {n}: kernel {t['state']} {t.get('fault')} "
                                f"line {t.get('fault_line')} after {t['cycles']} cycles; "
                                f"simulation {f}")
    final = {k.upper(): v for k, v in res.values_at(end).items()}
    for e in plan.table:
        key = e.path.upper()
        if key not in values:
            problems.append(f"{name}: {e.path} is not readable in the kernel")
            continue
        want = final.get(key, "<none>")
        kind, got = values[key]
        if e.kind == "e" and isinstance(got, int) and isinstance(want, str):
            # the manager reads an enumeration as its integer, the simulator
            # prints the value's name: compare the integers
            et = e.type.elem if hasattr(e.type, "elem") and not hasattr(e.type, "values") \
                else e.type
            want = et.values.get(want.upper(), (None, want))[1]
        if not same(e.kind, got, want, e.size):
            problems.append(f"{name}: {e.path} = {got!r} in the kernel, {want!r} in the "
                            f"simulation")
    return problems


def test_every_execution_case_in_the_kernel_equals_the_simulation(guest_factory,
                                                                   guest_workdir, tmp_path):
    groups = {k: v for k, v in GROUPS.items() if not ONLY or k in ONLY}
    n = sum(len(v) for v in groups.values())
    assert n >= (1 if ONLY else 150), f"only {n} execution cases"
    t0 = time.monotonic()
    with ThreadPoolExecutor(max_workers=2) as pool:
        trees = dict(zip(groups, pool.map(
            lambda kv: kb.built_tree(kv[0], kv[1], tmp_path), groups.items())))
    t_build = time.monotonic() - t0
    g = guest_factory(smp=1)
    mark = g.log_mark()
    problems, timings = [], {}
    for name, cases in groups.items():
        t1 = time.monotonic()
        dest = Path(guest_workdir) / "exec_kernel" / name
        shutil.rmtree(dest, ignore_errors=True)
        dest.mkdir(parents=True)
        shutil.copy(trees[name] / "manifest.json", dest)
        for ko in trees[name].glob("*/*.ko"):
            (dest / ko.parent.name).mkdir(exist_ok=True)
            shutil.copy(ko, dest / ko.parent.name)
        project = runner.check_project(kb.group_sources(name, cases, tmp_path))
        ms = run_ms(cases, project)
        tasks, values = run_in_kernel(g, dest, ms, [e.path for e in Compilation(project).plan.table])
        problems += compare_group(name, project, ms, tasks, values)
        timings[name] = round(time.monotonic() - t1, 1)
    g.check_kernel_log(since=mark)
    print(f"\nbuild/cache {t_build:.0f} s; groups: {timings}")
    assert not problems, f"{len(problems)} differences:\n" + "\n".join(problems[:80])
