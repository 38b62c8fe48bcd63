"""QEMU tier: what happens around a runtime fault (issue 9).

tests/qemu/projects/faults has two resources: r0.ta runs Faulty, which
divides by the global `divisor` (a division by zero when it is written 0),
r1.tb runs Healthy, which counts `beats`.

* a configuration with a faulted task is stopped and unloaded like any
  other: `stop --resource r1`, `start --resource r1`, `stop --keep-loaded`
  and `stop` act on what they name, report the fault as a fact (stdout)
  and exit 0; only `start` of the faulted task's own resource fails (its
  task faults again); refused input (an unknown resource) changes nothing;
* what a killed `load` leaves behind (a configuration module, a resource
  never started, slots never published) is removed by a plain `stop`;
* `swap --restart` recovers a faulted task in one command, state kept;
* the watchdog (tests/qemu/projects/watchdog): a cycle longer than its
  task's watchdog time faults at the loop it was in, N overrunning cycles
  in a row fault, the other tasks go on (the simulation's side, on
  simulated time: tests/unit/test_watchdog.py).

The manager is this checkout's (a plc_manager link on the guest's
sys.path); the fixtures check the kernel log after every test.
"""

from __future__ import annotations

import compileall
import json
import shutil
import time
from pathlib import Path

import pytest

from kmod_helpers import gen_and_build, loaded_modules

pytestmark = pytest.mark.qemu
HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
PROJECT = HERE / "projects" / "faults"
FAULT = "division by zero in Faulty line 15"


@pytest.fixture(scope="module")
def faults(guest_workdir):
    work = Path(guest_workdir) / "faults"
    work.mkdir(exist_ok=True)
    tree = work / "a"
    manifest = gen_and_build(PROJECT, tree)
    pmdir = work / "pm"
    pmdir.mkdir(exist_ok=True)
    link = pmdir / "plc_manager"
    if not link.is_symlink():
        link.symlink_to(ROOT / "manager")
    compileall.compile_dir(str(ROOT / "manager"), quiet=1)
    return work, tree, manifest, pmdir


def pm(guest, pmdir, *args, timeout=180):
    code = (f"import sys\nsys.path.insert(0, {str(pmdir)!r})\n"
            "from plc_manager.cli import main\nsys.exit(main(sys.argv[1:]))")
    r = guest.pyrun(code, argv=[str(a) for a in args], timeout=timeout)
    return r.exit_code, r.output


def ok(guest, pmdir, *args) -> str:
    rc, out = pm(guest, pmdir, *args)
    assert rc == 0, f"plc-manager {' '.join(map(str, args))}: exit {rc}\n{out}"
    return out


def tasks(guest, pmdir) -> dict:
    st = json.loads(ok(guest, pmdir, "status", "--json"))
    return {t["path"]: t for r in st["resources"] for t in r["tasks"]}


def wait_state(guest, pmdir, path, state, timeout=60.0) -> dict:
    deadline = time.monotonic() + timeout
    while True:
        ts = tasks(guest, pmdir)
        if ts[path]["state"] == state:
            return ts
        assert time.monotonic() < deadline, f"{path} is {ts[path]['state']}, not {state}"
        time.sleep(0.2)


def copy_tree(src: Path, dst: Path) -> Path:
    if dst.exists():
        shutil.rmtree(dst)
    shutil.copytree(src, dst, symlinks=True)
    return dst


def stop_clean(guest, pmdir):
    if loaded_modules(guest):
        rc, out = pm(guest, pmdir, "stop")
        assert rc == 0 and loaded_modules(guest) == [], out


def test_a_faulted_task_does_not_prevent_stop_or_unload(guest, faults):
    work, tree, manifest, pmdir = faults
    assert loaded_modules(guest) == []
    ok(guest, pmdir, "load", tree)
    try:
        ok(guest, pmdir, "write", "divisor", "0")
        ts = wait_state(guest, pmdir, "r0.ta", "fault")
        assert ts["r1.tb"]["state"] == "running"
        assert f'{ts["r0.ta"]["fault"]} in {ts["r0.ta"]["fault_pou"]} line ' \
               f'{ts["r0.ta"]["fault_line"]}' == FAULT, ts["r0.ta"]

        # refused input changes nothing: unknown resources, bad files
        # (every kind is in tests/unit/test_manager_badfiles.py)
        def snapshot():
            st = json.loads(ok(guest, pmdir, "status", "--json"))
            return (sorted(loaded_modules(guest)),
                    [(s["type_name"], s["module"], s["publications"]) for s in st["slots"]],
                    {t["path"]: (t["state"], t["faults"]) for r in st["resources"]
                     for t in r["tasks"]})
        before = snapshot()
        prog = next(p for p in manifest["program_types"] if p["name"] == "Faulty")["module"]
        truncated = copy_tree(tree, work / "truncated")
        ko = truncated / prog / f"{prog}.ko"
        ko.write_bytes(ko.read_bytes()[:4096])
        edited = copy_tree(tree, work / "edited")
        m = json.loads((edited / "manifest.json").read_text())
        m["variables"][0]["type"] = "LINT"
        (edited / "manifest.json").write_text(json.dumps(m))
        for args, want in ((("stop", "--resource", "nosuch"), "no resource 'nosuch'"),
                           (("start", "--resource", "nosuch"), "no resource 'nosuch'"),
                           (("stop", "--keep-loaded", "--resource", "nosuch"),
                            "no resource 'nosuch'"),
                           (("load", truncated), "not a valid kernel module (truncated"),
                           (("swap", ko), "not a valid kernel module (truncated"),
                           (("load", edited), "the manifest was changed after"),
                           (("swap", edited), "the manifest was changed after")):
            rc, out = pm(guest, pmdir, *args)
            assert rc == 1 and out.strip().startswith("plc-manager: "), out
            assert len(out.strip().splitlines()) == 1 and want in out, out
        assert snapshot() == before

        # --resource acts on that resource and says nothing about the other
        out = ok(guest, pmdir, "stop", "--resource", "r1")
        assert "r0" not in out and "fault" not in out, out
        ts = tasks(guest, pmdir)
        assert ts["r1.tb"]["state"] == "stopped" and ts["r0.ta"]["state"] == "fault", ts
        out = ok(guest, pmdir, "start", "--resource", "R1")
        assert "r0" not in out and "fault" not in out, out
        ts = tasks(guest, pmdir)
        assert ts["r1.tb"]["state"] == "running" and ts["r0.ta"]["state"] == "fault", ts
        # the faulted resource: a fault about r0 only, the stop does not refuse
        out = ok(guest, pmdir, "stop", "--resource", "r0")
        assert f"task r0.ta is stopped on a fault: {FAULT}" in out, out
        assert tasks(guest, pmdir)["r1.tb"]["state"] == "running"
        # restarting it with the cause still there: it faults again, said so
        rc, out = pm(guest, pmdir, "start", "--resource", "r0")
        assert rc == 1 and out.strip() == f"plc-manager: task r0.ta stopped on a fault: " \
                                         f"{FAULT}", out
        ts = tasks(guest, pmdir)
        assert ts["r0.ta"]["state"] == "fault" and ts["r0.ta"]["faults"] == 2, ts["r0.ta"]
        assert ts["r1.tb"]["state"] == "running"

        out = ok(guest, pmdir, "stop", "--keep-loaded")
        assert f"task r0.ta is stopped on a fault: {FAULT}" in out, out
        assert sorted(loaded_modules(guest)) == sorted(manifest["load_order"])
        ts = tasks(guest, pmdir)
        assert ts["r1.tb"]["state"] == "stopped" and ts["r0.ta"]["state"] == "fault", ts

        ok(guest, pmdir, "start", "--resource", "r1")
        out = ok(guest, pmdir, "stop")
        assert f"task r0.ta is stopped on a fault: {FAULT}" in out, out
        assert "nothing of faults is loaded" in out.lower(), out
        assert loaded_modules(guest) == []
    finally:
        stop_clean(guest, pmdir)


@pytest.mark.parametrize("partial", ["config+r1", "no_programs"])
def test_stop_removes_what_a_killed_load_left(guest, faults, partial):
    """The modules a `load` killed half way may leave: the configuration
    with a resource never started and empty slots, or every resource and
    no program type (slots never published), started.  A plain `stop`
    removes all of it and exits 0 (benchmarks/soak.py kills the manager at
    random points)."""
    work, tree, manifest, pmdir = faults
    order = manifest["load_order"]
    kinds = {m["name"]: m["kind"] for m in manifest["modules"]}
    res = [n for n in order if kinds[n] == "resource"]
    want = {"config+r1": [order[0], res[-1]],
            "no_programs": [order[0]] + res}[partial]
    assert loaded_modules(guest) == []
    try:
        for name in want:
            r = guest.run(f"insmod {tree / name / (name + '.ko')}")
            assert r.exit_code == 0, r.output
        if partial == "no_programs":         # started with every slot empty
            ok(guest, pmdir, "start")
            assert all(t["state"] == "running" for t in tasks(guest, pmdir).values())
        out = ok(guest, pmdir, "stop")
        assert "nothing of faults is loaded" in out.lower(), out
        assert loaded_modules(guest) == []
    finally:
        for name in reversed(want):
            guest.run(f"rmmod {name} 2>/dev/null")


@pytest.fixture(scope="module")
def fixed(faults, kdir):
    """Faulty rebuilt to divide by MAX(divisor, 1) (same interface): only
    its program-type module is built, a project directory to swap in."""
    import subprocess
    import sys
    from iec2kmod import kbuild
    work, tree, manifest, _ = faults
    src = work / "src_fixed"
    src.mkdir(exist_ok=True)
    text = (PROJECT / "faults.st").read_text()
    assert "1000 / divisor;" in text
    (src / "faults.st").write_text(text.replace("1000 / divisor;", "1000 / MAX(divisor, 1);"))
    out = work / "fixed"
    if out.exists():
        shutil.rmtree(out)
    p = subprocess.run([sys.executable, "-m", "iec2kmod.cli", "gen", str(src), "-o", str(out)],
                       cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stdout + p.stderr
    (d,) = [p for p in out.iterdir() if p.name.startswith("iec_faults_p_faulty_")]
    kbuild.build_modules(str(d), kdir=kdir, extra_args=[
        f"KBUILD_EXTRA_SYMBOLS={tree / 'Module.symvers'}"]).check()
    return out


def read(guest, pmdir, *names) -> dict:
    out = ok(guest, pmdir, "read", "--json", *names)
    return {v["path"]: v["value"] for v in json.loads(out)}


def test_swap_restart_recovers_a_faulted_task_in_one_command(guest, faults, fixed):
    work, tree, manifest, pmdir = faults
    assert loaded_modules(guest) == []
    ok(guest, pmdir, "load", tree)
    try:
        ok(guest, pmdir, "write", "divisor", "0")
        ts = wait_state(guest, pmdir, "r0.ta", "fault")
        runs = read(guest, pmdir, "r0.pf.runs")["r0.pf.runs"]
        assert runs > 0 and ts["r0.ta"]["starts"] == 1 and ts["r0.ta"]["faults"] == 1
        t_fault = ts["r0.ta"]["fault_ns"]

        out = ok(guest, pmdir, "swap", "--restart", fixed)
        assert f"restarting task r0.ta (stopped on a fault: {FAULT})" in out, out
        assert "task r0.ta runs again" in out, out
        ts = tasks(guest, pmdir)
        ta = ts["r0.ta"]
        assert ta["state"] == "running" and ts["r1.tb"]["state"] == "running", ts
        # the fault stays known: count, what, when; the restart's time
        assert ta["faults"] == 1 and ta["starts"] == 2, ta
        assert f'{ta["fault"]} in {ta["fault_pou"]} line {ta["fault_line"]}' == FAULT, ta
        assert ta["fault_ns"] == t_fault and ta["started_ns"] > t_fault, ta
        # the new body runs, the instance kept its state
        v = read(guest, pmdir, "r0.pf.runs", "quotient")
        assert v["quotient"] == 1000 and v["r0.pf.runs"] > runs, (v, runs)
        text = ok(guest, pmdir, "status")
        line = next(ln for ln in text.splitlines() if ln.strip().startswith("r0.ta:"))
        assert f"last fault: {FAULT} at " in line and "; restarted at " in line, text
        # the same build again: nothing to swap, nothing restarted
        rc, out = pm(guest, pmdir, "swap", "--restart", fixed)
        assert rc == 0 and "runs already" in out and "nothing to restart" in out, out
        assert "restarting" not in out, out
        # the faulty build back (divisor is still 0): the task faults again;
        # a swap to the fix without --restart leaves it stopped on the fault,
        # and `swap --restart` of the build that runs now restarts it alone
        ok(guest, pmdir, "swap", tree)
        wait_state(guest, pmdir, "r0.ta", "fault")
        ok(guest, pmdir, "swap", fixed)
        assert tasks(guest, pmdir)["r0.ta"]["state"] == "fault"
        out = ok(guest, pmdir, "swap", "--restart", fixed)
        assert "runs already" in out and "restarting task r0.ta" in out, out
        assert "task r0.ta runs again" in out, out
        ts = tasks(guest, pmdir)
        assert ts["r0.ta"]["state"] == "running" and ts["r0.ta"]["faults"] == 2, ts
    finally:
        stop_clean(guest, pmdir)


def test_the_watchdog_stops_a_long_cycle_and_repeated_overruns(guest_factory, faults):
    """In virtual time (icount): the guest's clock advances with the
    instructions it runs, so a loaded host cannot stretch a cycle past its
    watchdog time (under plain TCG on a busy host a 1-line cycle was seen
    to take 84 ms of guest time)."""
    work, _, _, pmdir = faults
    tree = work / "wd"
    gen_and_build(HERE / "projects" / "watchdog", tree)
    guest = guest_factory(icount=True)
    assert loaded_modules(guest) == []
    ok(guest, pmdir, "load", tree)
    try:
        before = tasks(guest, pmdir)
        assert all(t["state"] == "running" for t in before.values()), before
        ok(guest, pmdir, "write", "n", "900000")      # far longer than 20 ms
        ts = wait_state(guest, pmdir, "rw.spin", "fault")
        spin = ts["rw.spin"]
        text = (HERE / "projects" / "watchdog" / "watchdog.st").read_text()
        for_line = text[:text.index("FOR i := 1 TO n DO")].count("\n") + 1
        assert spin["fault"].startswith("watchdog") and \
            (spin["fault_pou"], spin["fault_line"]) == ("Spin", for_line), spin
        # the cycle was stopped near its watchdog time, not by the budget
        assert spin["exec_max_ns"] < 20_000_000 + 200_000_000, spin
        ok(guest, pmdir, "write", "m", "900000")      # every 50 ms cycle overruns
        ts = wait_state(guest, pmdir, "rw.slow", "fault")
        slow = ts["rw.slow"]
        assert slow["fault"].startswith("overruns") and slow["overruns"] >= 3, slow
        assert ts["rb.beat"]["state"] == "running", ts
        beats = ts["rb.beat"]["cycles"]
        time.sleep(0.5)
        assert tasks(guest, pmdir)["rb.beat"]["cycles"] > beats
        out = ok(guest, pmdir, "stop")
        assert "task rw.spin is stopped on a fault: watchdog" in out, out
        assert "task rw.slow is stopped on a fault: overruns" in out, out
        assert loaded_modules(guest) == []
    finally:
        stop_clean(guest, pmdir)
