"""QEMU tier: the generated modules in Debian's PREEMPT_RT kernel.

One project (tests/qemu/projects/rt_basic) with two resources, periodic
and event tasks, and three programs that fault on purpose; checks that
tasks run at their periods, that a fault stops only its own task, that
nothing in use can be unloaded, that unloading leaves nothing behind, and
that the kernel log stays clean (the guest fixture fails a test on
WARNING, BUG, Oops, "scheduling while atomic", ...)."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from kmod_helpers import (control, gen_and_build, load, loaded_modules, status, sysfs,
                          unload)

pytestmark = pytest.mark.qemu
HERE = Path(__file__).resolve().parent


@pytest.fixture(scope="module")
def rt_basic(guest_workdir):
    tree = Path(guest_workdir) / "rt_basic"
    manifest = gen_and_build(HERE / "projects" / "rt_basic", tree)
    return tree, manifest


def test_modinfo_carries_description_and_hashes(rt_basic):
    from iec2kmod import kbuild
    tree, manifest = rt_basic
    for m in manifest["modules"]:
        info = kbuild.modinfo(str(tree / m["name"] / f"{m['name']}.ko"))
        assert info["license"] == ["Dual MIT/GPL"]
        assert "iec2kmod" in info["description"][0]
        assert info["iec_source_hash"] == [manifest["source_hash"]]
        assert "preempt_rt" in info["vermagic"][0]
        if m["kind"] == "program":
            assert info["iec_interface_hash"] == [m["interface_hash"]]


def test_tasks_run_faults_stay_in_their_task_and_unload_is_clean(guest, rt_basic):
    tree, manifest = rt_basic
    load(guest, tree, manifest)
    try:
        st = status(guest, manifest)
        assert all(t["state"] == "stopped" for t in st["tasks"].values()), st["text"]
        assert all(s["module"].startswith("iec_rtbasic_p_") for s in st["slots"].values())
        control(guest, manifest, "start all")
        t0 = time.monotonic()
        time.sleep(5)
        st = status(guest, manifest)
        elapsed = time.monotonic() - t0
        tasks = st["tasks"]
        # periodic tasks advance at about their period (TCG: generous bounds)
        fast = int(tasks["r1.fast"]["cycles"]) + int(tasks["r1.fast"]["overruns"])
        slow = int(tasks["r2.slow"]["cycles"]) + int(tasks["r2.slow"]["overruns"])
        assert 0.5 * elapsed / 0.002 < fast < 1.5 * elapsed / 0.002 + 100, st["text"]
        assert 0.5 * elapsed / 0.010 < slow < 1.5 * elapsed / 0.010 + 20, st["text"]
        # the event task runs on every rising edge of tick: every 10 fast cycles
        ev = int(tasks["r1.ev"]["cycles"])
        ran = int(tasks["r1.fast"]["cycles"])
        assert abs(ev - ran // 10) <= 2, st["text"]
        # the three faulty programs stopped their own tasks, with POU and line
        src = (HERE / "projects" / "rt_basic" / "rt_basic.st").read_text().splitlines()
        for task, pou, fault, needle in (
                ("r2.tdiv", "DivFault", "division", "q := 100 / zero;"),
                ("r2.tidx", "IndexFault", "array", "a[n] := n;"),
                ("r2.tloop", "LoopFault", "endless", "WHILE n > 30 DO")):
            t = tasks[task]
            assert t["state"] == "fault" and t["pou"] == pou, st["text"]
            assert t["fault"].startswith(fault), st["text"]
            assert needle in src[int(t["line"]) - 1], (task, t["line"])
        for task in ("r1.fast", "r1.ev", "r2.slow"):
            assert tasks[task]["state"] == "running" and tasks[task]["faults"] == "0"
        # still running a while later
        time.sleep(1)
        later = status(guest, manifest)["tasks"]
        assert int(later["r2.slow"]["cycles"]) > int(tasks["r2.slow"]["cycles"])
        assert int(later["r2.tdiv"]["cycles"]) == int(tasks["r2.tdiv"]["cycles"])
        # nothing in use can be unloaded
        prog = next(m["name"] for m in manifest["modules"] if m["kind"] == "program")
        assert guest.run(f"rmmod {prog}").exit_code != 0
        assert guest.run(f"rmmod {manifest['load_order'][0]}").exit_code != 0
        assert prog in loaded_modules(guest)
    finally:
        unload(guest, manifest)
    assert loaded_modules(guest) == []
    assert guest.run(f"test -e {sysfs(manifest)}").exit_code != 0


def test_restart_and_reload_cycles(guest, rt_basic):
    """Unloading is where kernel-mode RT systems crash: load, run, stop and
    unload several times, also removing one resource while another runs."""
    tree, manifest = rt_basic
    for round_ in range(3):
        load(guest, tree, manifest)
        control(guest, manifest, "start all")
        time.sleep(0.5)
        if round_ == 1:
            control(guest, manifest, "stop r1")
            control(guest, manifest, "start r1")
        if round_ == 2:
            # a resource whose tasks are running cannot be removed (a cycle
            # may be running its code); stopped, it goes while the others run
            res = next(m["name"] for m in manifest["modules"] if m["kind"] == "resource")
            r = guest.run(f"rmmod {res}")
            assert r.exit_code != 0 and res in loaded_modules(guest), r.output
            rname = res.rsplit("_r_", 1)[1]
            control(guest, manifest, f"stop {rname}")
            assert guest.run(f"rmmod {res}").exit_code == 0
            control(guest, manifest, "stop all")
            others = [m["name"] for m in manifest["modules"] if m["kind"] == "resource" and
                      m["name"] != res]
            for name in others:
                assert guest.run(f"rmmod {name}").exit_code == 0
            control(guest, manifest, "clear all")
            for name in reversed(manifest["load_order"]):
                if name in loaded_modules(guest):
                    assert guest.run(f"rmmod {name}").exit_code == 0, name
        else:
            unload(guest, manifest)
        assert loaded_modules(guest) == []
