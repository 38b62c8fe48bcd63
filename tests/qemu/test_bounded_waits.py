"""QEMU tier: nothing the manager does waits for ever (issue 8, item 5).

tests/qemu/projects/stuck has a task (rheavy.heavy) whose cycle is made to
run for seconds by a long but finite loop (LOAD string searches, below the
loop budget), far longer than the kernel's bound on waiting for a task
(the configuration module's wait_ms, set to 20 ms here, plus four 10 ms
periods).  While that cycle runs (each check is verified to have run inside
one cycle, and repeated in a new one if a slow TCG guest let it end):

* `stop rheavy` and `clear all` through sysfs fail with ETIMEDOUT within
  the bound, and the kernel log names the task and how long it has been
  inside its cycle; `clear <slot of Beat>` succeeds at once (the grace
  period of a slot waits only for the tasks that run it);
* the task's resource module and its program type's module cannot be
  removed (code the task may still run): rmmod is refused, nothing freed;
* `clear all` fails the same way, the program types stay loaded.

* `plc-manager stop` removes everything else (the healthy resource and
  the program type the stuck task does not run), names the task and what
  stays loaded, and exits 1.

Once the cycle has ended, `plc-manager stop` removes everything.  The
kernel log stays free of WARNING/BUG/Oops/stalls (the guest fixture
checks).  plc-manager's side of a timeout (one line naming the task, exit
1) is tested without a guest in tests/unit/test_manager_timeouts.py: under
TCG a plc-manager command takes longer than any cycle that stays below
RCU's 21 s stall limit.  The manager used here is this checkout's (a
plc_manager link on the guest's sys.path), not the installed one.
"""

from __future__ import annotations

import compileall
import errno
import json
import time
from pathlib import Path

import pytest

from kmod_helpers import gen_and_build, loaded_modules, sysfs

pytestmark = pytest.mark.qemu
HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]

WAIT_MS = 20                 # the test's bound: 20 ms + 4 x 10 ms periods
# the long cycle, about: long enough for the checks in a slow TCG guest,
# well below the 21 s after which RCU reports a CPU starved by a FIFO task
LONG_CYCLE_S = 16.0
LOOP_BUDGET = 1_000_000      # iterations per cycle before "endless loop"
CALIB = 20000                # iterations of the calibration cycles


@pytest.fixture(scope="module")
def stuck(guest_workdir):
    work = Path(guest_workdir)
    tree = work / "stuck"
    manifest = gen_and_build(HERE / "projects" / "stuck", tree)
    pmdir = work / "stuck_pm"
    pmdir.mkdir(exist_ok=True)
    link = pmdir / "plc_manager"
    if not link.is_symlink():
        link.symlink_to(ROOT / "manager")
    compileall.compile_dir(str(ROOT / "manager"), quiet=1)
    return tree, manifest, pmdir


def pm(guest, pmdir, *args, timeout=120):
    code = (f"import sys\nsys.path.insert(0, {str(pmdir)!r})\n"
            "from plc_manager.cli import main\nsys.exit(main(sys.argv[1:]))")
    r = guest.pyrun(code, argv=[str(a) for a in args], timeout=timeout)
    return r.exit_code, r.output


def heavy(guest, pmdir) -> dict:
    rc, out = pm(guest, pmdir, "status", "--json")
    assert rc == 0, out
    st = json.loads(out)
    return next(t for r in st["resources"] for t in r["tasks"] if t["path"] == "rheavy.heavy")


def cycle_state(guest, manifest):
    """rheavy.heavy's completed cycles and how long it has been inside the
    current one (sysfs status; -1: not in a cycle)."""
    out = guest.run(f"cat {sysfs(manifest)}/status").output
    line = next((ln for ln in out.splitlines() if ln.startswith("task rheavy.heavy ")), None)
    assert line is not None, f"no task rheavy.heavy in the status:\n{out}"
    words = line.split()
    return int(words[words.index("cycles") + 1]), int(words[words.index("in_cycle_ms") + 1])


def in_cycle_ms(guest, manifest) -> int:
    return cycle_state(guest, manifest)[1]


def guest_timed(guest, cmd):
    """Runs shell *cmd* in the guest; (exit code, output, seconds on the
    guest's clock, /proc/uptime)."""
    r = guest.run(f"a=$(cut -d' ' -f1 /proc/uptime); ( {cmd} ) 2>&1; rc=$?; "
                  f"b=$(cut -d' ' -f1 /proc/uptime); echo \"@@ $rc $a $b\"")
    body, _, tail = r.output.rpartition("@@ ")
    rc, a, b = tail.split()
    return int(rc), body, float(b) - float(a)


def wait_until(pred, what, timeout):
    deadline = time.monotonic() + timeout
    while True:
        v = pred()
        if v:
            return v
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.1)


class LongCycles:
    """rheavy.heavy made to run cycles of about LONG_CYCLE_S (calibrated),
    one at a time, and checks run inside one of them (check())."""

    def __init__(self, guest, manifest, pmdir):
        config = manifest["load_order"][0]
        ctl = f"{sysfs(manifest)}/control"
        r = guest.run(f"echo {WAIT_MS} > /sys/module/{config}/parameters/wait_ms")
        assert r.exit_code == 0, r.output

        # Every heavy cycle runs alone: a start, then at once a stop (which
        # times out while the cycle runs, but the task begins no further
        # cycle), so the task never holds its CPU for more than one cycle:
        # back to back for 21 s, RCU would report the CPU as stalled.
        def one_cycle():
            r = guest.run(f"echo start rheavy > {ctl}")
            assert r.exit_code == 0, r.output
            wait_until(lambda: in_cycle_ms(guest, manifest) >= 0, "a cycle", 60)
            guest.run(f"echo stop rheavy > {ctl}")

        # calibrate the loop: one cycle of CALIB iterations
        r = guest.run(f"echo stop rheavy > {ctl}")
        assert r.exit_code == 0, r.output
        assert pm(guest, pmdir, "write", "load", str(CALIB))[0] == 0
        one_cycle()
        wait_until(lambda: in_cycle_ms(guest, manifest) < 0, "the calibration cycle", 120)
        per_iter = heavy(guest, pmdir)["exec_max_ns"] / CALIB
        n = min(int(LONG_CYCLE_S * 1e9 / per_iter), LOOP_BUDGET - 1000)
        expect_ms = n * per_iter / 1e6
        calib = f"{per_iter:.0f} ns per iteration, {n} iterations: {expect_ms / 1e3:.1f} s"
        assert expect_ms >= 5000, f"{calib}: the loop budget allows no 5 s cycle"

        assert pm(guest, pmdir, "write", "load", str(n))[0] == 0
        mark = guest.log_mark()
        times, tries = {}, []

        def check(name, op, early=False):
            """op() while rheavy.heavy is inside one long cycle, verified
            before and after (a TCG guest's speed varies: if the cycle ended
            meanwhile, the check runs again in a new one); *early*: in the
            first quarter of the cycle (plc-manager is slow in a TCG guest)."""
            for _ in range(6):
                if in_cycle_ms(guest, manifest) < 0:
                    one_cycle()
                wait_until(lambda: in_cycle_ms(guest, manifest) > 300, "a long cycle", 60)
                cycles, before = cycle_state(guest, manifest)
                if early and before > expect_ms / 4:
                    wait_until(lambda: in_cycle_ms(guest, manifest) < 0, "the cycle's end",
                               10 * LONG_CYCLE_S + 30)
                    continue
                t0 = time.monotonic()
                result = op()
                times[name] = time.monotonic() - t0
                after = cycle_state(guest, manifest)
                if after[0] == cycles and after[1] > before:
                    return result
                tries.append(f"{name}: cycle {cycles} at {before} ms, took "
                             f"{times[name] * 1000:.0f} ms, then cycle {after[0]} at {after[1]} ms")
            pytest.fail(f"{calib}: the long cycle ended during '{name}' six times: " +
                        "; ".join(tries[-4:]))

        self.check, self.calib, self.mark, self.times = check, calib, mark, times
        self.expect_ms = expect_ms


def test_stop_clear_and_unload_give_up_on_a_long_cycle_naming_the_task(guest, stuck):
    tree, manifest, pmdir = stuck
    ctl = f"{sysfs(manifest)}/control"
    rc, out = pm(guest, pmdir, "load", tree)
    assert rc == 0, out
    try:
        lc = LongCycles(guest, manifest, pmdir)
        check, calib, mark = lc.check, lc.calib, lc.mark

        def timed_out(rc, out):
            return rc != 0 and "timed out" in out.lower()

        # sysfs stop: ETIMEDOUT after the bound
        text = guest.run(f"cat {sysfs(manifest)}/status").output
        slot_of = {ln.split()[2]: ln.split()[1] for ln in text.splitlines()
                   if ln.startswith("slot ")}
        guest_s = {}
        cmd = "stop rheavy"
        rc, out, guest_s[cmd] = check(cmd, lambda: guest_timed(guest, f"echo {cmd} > {ctl}"))
        assert timed_out(rc, out), (cmd, out, guest.dmesg(since=mark))

        # a read of the stuck task's instance variable waits for a cycle
        # boundary (EBUSY after about 1 s) holding no mutex: a STATUS sent
        # meanwhile (raw netlink, tests/qemu/rawnl.py) answers at once
        # (issue 23: it used to wait behind the read's retry sleeps)
        code = ("import json, sys, threading, time\n"
                f"sys.path.insert(0, {str(HERE)!r})\n"
                "from rawnl import Genl, var\n"
                "res = {}\n"
                "def reader():\n"
                "    nl, t0 = Genl(), time.monotonic()\n"
                "    res['get'] = nl.cmd('IEC_CMD_VAR_GET', var('rheavy.h.k'))[0]\n"
                "    res['get_s'] = time.monotonic() - t0\n"
                "nl = Genl()\n"
                "th = threading.Thread(target=reader)\n"
                "th.start()\n"
                "time.sleep(0.2)\n"
                "t0 = time.monotonic()\n"
                "res['status'] = nl.cmd('IEC_CMD_STATUS')[0]\n"
                "res['status_s'] = time.monotonic() - t0\n"
                "th.join()\n"
                "print('RES ' + json.dumps(res))\n")
        # (the read's EBUSY after its whole wait shows the cycle ran all along)
        tries = []
        for _ in range(6):
            if in_cycle_ms(guest, manifest) < 0:
                assert guest.run(f"echo start rheavy > {ctl}").exit_code == 0
                wait_until(lambda: in_cycle_ms(guest, manifest) >= 0, "a cycle", 60)
                guest.run(f"echo stop rheavy > {ctl}")
            wait_until(lambda: in_cycle_ms(guest, manifest) > 300, "a long cycle", 60)
            r = guest.pyrun(code, timeout=60)
            assert r.exit_code == 0 and "RES " in r.output, r.output
            res = json.loads(r.output.split("RES ", 1)[1].splitlines()[0])
            tries.append(res)
            if res["get"] == errno.EBUSY:
                break
        assert res["get"] == errno.EBUSY and res["get_s"] >= 0.8, tries
        assert res["status"] == 0 and res["status_s"] < 0.4, tries
        print(f"\nVAR_GET in a long cycle: EBUSY after {res['get_s']:.2f} s; "
              f"STATUS meanwhile: {res['status_s'] * 1000:.0f} ms")
        assert guest_s[cmd] < 1.0, guest_s
        # a slot the stuck task does not run is not held up by it (the
        # slot it runs: `clear all` below)
        cmd = f"clear {slot_of['BEAT']}"
        rc, out, guest_s[cmd] = check(cmd, lambda: guest_timed(guest, f"echo {cmd} > {ctl}"))
        assert rc == 0, (cmd, out, guest.dmesg(since=mark))
        assert guest_s[cmd] < 0.5, guest_s

        # what the task may still run cannot be removed: refused, not freed
        for m in manifest["modules"]:
            if m["name"].endswith("_rheavy") or m["name"].startswith("iec_stuck_p_heavy"):
                r = check(f"rmmod {m['name']}", lambda: guest.run(f"rmmod {m['name']}"))
                assert r.exit_code != 0, r.output
        assert sorted(loaded_modules(guest)) == sorted(manifest["load_order"])

        # clear all, the last check (no long cycle after it: the slots are
        # empty; the grace period waits for the cycles in progress of the
        # tasks that run a slot: ETIMEDOUT after the bound)
        rc, out, guest_s["clear all"] = check(
            "clear all", lambda: guest_timed(guest, f"echo clear all > {ctl}"), early=True)
        assert timed_out(rc, out), (out, guest.dmesg(since=mark))
        assert guest_s["clear all"] < 1.0, guest_s
        assert sorted(loaded_modules(guest)) == sorted(manifest["load_order"])

        # still in that cycle, plc-manager stop: its stop times out, and it
        # goes on removing what the stuck task cannot be running (the
        # other resource, BEAT's program type: the grace period of BEAT's
        # slot does not wait for rheavy.heavy).  Removing any module waits
        # for an RCU grace period, which the FIFO task spinning on its CPU
        # holds up until its cycle ends: so the stop either ends with those
        # removed and the rest named (exit 1), or, the cycle over, with
        # everything removed (exit 0); never with nothing removed.
        assert in_cycle_ms(guest, manifest) > 0
        rc, out = pm(guest, pmdir, "stop")
        assert "stop: task rheavy.heavy (inside one cycle for" in out, out
        left = sorted(loaded_modules(guest))
        stays = sorted(m["name"] for m in manifest["modules"]
                       if m["name"].endswith("_rheavy") or m["name"].startswith("iec_stuck_p_heavy")
                       or m["kind"] == "configuration")
        assert len(stays) == 3, manifest["modules"]
        if rc == 0:
            assert left == [] and "nothing of stuck is loaded" in out, (left, out)
        else:
            assert rc == 1 and left == stays, (rc, left, out)
            assert "still loaded:" in out and "stop again once that cycle has ended" in out
        stop_outcome = "everything removed once the cycle ended" if rc == 0 else \
            f"left loaded {', '.join(left)}"

        log = guest.dmesg(since=mark)
        for what in ("stop", "clear"):
            assert f"iec2kmod: {what}: task rheavy.heavy does not come back: inside one " \
                   f"cycle for" in log, log
        assert "stays loaded until that cycle ends" in log, log

        # the cycle ends: everything goes
        if rc != 0:
            assert pm(guest, pmdir, "write", "load", "0")[0] == 0
            wait_until(lambda: in_cycle_ms(guest, manifest) < 0, "the end of the long cycle",
                       10 * LONG_CYCLE_S + 30)
        print(f"\nlong cycle: {calib}; bound {WAIT_MS} ms + 4 x 10 ms periods; "
              f"gave up after (guest clock, 10 ms resolution): " +
              ", ".join(f"{k} {v * 1000:.0f} ms" for k, v in guest_s.items()) +
              f"; plc-manager stop in the cycle: exit {rc}, {stop_outcome}")
    finally:
        # never leave the guest stuck: wait for the cycle, then stop
        deadline = time.monotonic() + 120
        rc, out = 0, "nothing was loaded"
        while loaded_modules(guest) and time.monotonic() < deadline:
            rc, out = pm(guest, pmdir, "stop")
            if rc == 0:
                break
            time.sleep(1)
    assert rc == 0, out
    assert loaded_modules(guest) == []
    assert guest.run(f"test -e {sysfs(manifest)}").exit_code != 0


@pytest.fixture(scope="module")
def v2(stuck, kdir):
    """Both program types rebuilt with another algorithm (same
    interfaces): {type name: module to swap in}."""
    import subprocess
    import sys
    from iec2kmod import kbuild
    tree, manifest, _ = stuck
    src = tree.parent / "stuck_v2_src"
    src.mkdir(exist_ok=True)
    text = (HERE / "projects" / "stuck" / "stuck.st").read_text()
    for a in ("beats := beats + 1;", "done := done + 1;"):
        assert a in text
        text = text.replace(a, a.replace("+ 1", "+ 2"))
    (src / "stuck.st").write_text(text)
    out = tree.parent / "stuck_v2"
    p = subprocess.run([sys.executable, "-m", "iec2kmod.cli", "gen", str(src), "-o", str(out)],
                       cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stdout + p.stderr
    kos = {}
    for t in ("beat", "heavy"):
        (d,) = [p for p in out.iterdir() if p.name.startswith(f"iec_stuck_p_{t}_")]
        kbuild.build_modules(str(d), kdir=kdir, extra_args=[
            f"KBUILD_EXTRA_SYMBOLS={tree / 'Module.symvers'}"]).check()
        kos[t.upper()] = d / f"{d.name}.ko"
    return kos


def test_a_swap_does_not_wait_for_ever_for_a_long_cycle(guest, stuck, v2):
    """insmod of a new build publishes it at once and returns within the
    bound although a cycle in progress may still run an old body; the old
    module stays loaded (refused by rmmod) until the cycle has ended.  A
    swap of the other program type, which the long cycle does not run, is
    not held up at all: its old module is released at once."""
    tree, manifest, pmdir = stuck
    old = {t: next(m["name"] for m in manifest["modules"]
                   if m["name"].startswith(f"iec_stuck_p_{t.lower()}_")) for t in v2}
    rc, out = pm(guest, pmdir, "load", tree)
    assert rc == 0, out
    try:
        lc = LongCycles(guest, manifest, pmdir)

        def swap():
            rc, out, secs = guest_timed(guest, f"insmod {v2['HEAVY']}")
            rm = guest.run(f"rmmod {old['HEAVY']}")
            beat = guest_timed(guest, f"insmod {v2['BEAT']}")
            refs = guest.run(f"cat /sys/module/{old['BEAT']}/refcnt").output.strip()
            return rc, out, secs, rm, beat, refs
        rc, out, secs, rm, beat, refs = lc.check("insmod", swap, early=True)
        assert rc == 0, out
        assert secs < 1.0, secs
        assert rm.exit_code != 0 and old["HEAVY"] in loaded_modules(guest), rm.output
        assert beat[0] == 0 and beat[2] < 0.5, beat
        assert refs == "0", refs          # BEAT's old body: no reference left
        text = guest.run(f"cat {sysfs(manifest)}/status").output
        assert f" module {v2['HEAVY'].stem} " in text, text
        assert f" module {v2['BEAT'].stem} " in text, text
        log = guest.dmesg(since=lc.mark)
        assert "publish: task rheavy.heavy does not come back: inside one cycle for" in log, log
        assert f"slot HEAVY: {old['HEAVY']} stays loaded until that cycle ends" in log, log
        assert f"slot BEAT: {old['BEAT']} stays loaded" not in log, log
        print(f"\ninsmod of a new build during a long cycle: {secs * 1000:.0f} ms; of the other "
              f"type: {beat[2] * 1000:.0f} ms (guest clock; bound {WAIT_MS} ms + 4 x 10 ms)")
        wait_until(lambda: in_cycle_ms(guest, manifest) < 0, "the end of the long cycle",
                   10 * LONG_CYCLE_S + 30)
    finally:
        deadline = time.monotonic() + 120
        rc, out = 0, "nothing was loaded"
        while loaded_modules(guest) and time.monotonic() < deadline:
            rc, out = pm(guest, pmdir, "stop")
            if rc == 0:
                break
            time.sleep(1)
    assert rc == 0, out
    assert loaded_modules(guest) == []
