# SPDX-License-Identifier: MIT
"""QEMU tier, issue 26: the user-space I/O provider (iec_io_user.c) with the
reference daemon (`plc-manager io-daemon`, manager/iodaemon.py) closing a
loop in the PREEMPT_RT guest.  Project tests/qemu/projects/io_user: the
program's count (%QD0, output slot 0) is the echo of its input (%ID0) plus
one and sig_out (%QW8, an INT) the echo of sig_in (%IW8) minus one; the
daemon copies each published cycle's outputs back to the inputs.  When the
daemon answers a cycle before the next one starts, count advances by one
(the program counts those cycles in instep): count == instep and sig_out ==
-count exactly, whatever the daemon missed.  The same task is bound to
comedi too (issue 26's "bound to comedi AND to the user-space provider"):
the comedi fixture loads comedi_test, whose AI 2, read one sample at a time,
gives back what AO 2 holds; the program writes its cycle count n to AO 2
(%QW12) and reads AI 2 (%IW12), and sends that comedi input to the daemon
in output slot 2 (%QD12).  Seen outside the program: every cycle's record
in the daemon's trace carries the comedi input of that cycle, which is the
count the cycle before wrote (cycle - 1); user space reads AO 2 and AI 2
through /dev/comedi0 while the task runs and after the stop (AO 2 SAFE
HOLD: the last cycle's n).  Also: the device at load in its
safe state; safe state on stop (SAFE -7, SAFE HOLD) seen by the daemon;
the resource cannot be removed while the daemon holds the device (rmmod
and plc-manager stop fail, naming the holder); the daemon killed while the
task runs: the task faults on stale inputs (STALE 400 ms) and the module
can go.  The guest's kernel log is checked for WARNING, BUG and Oops by the
guest fixture."""

from __future__ import annotations

import compileall
import json
import time
from pathlib import Path

import pytest

from kmod_helpers import gen_and_build, loaded_modules, pm
from test_io_comedi import channels

pytestmark = pytest.mark.qemu
HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
PROJECT = HERE / "projects" / "io_user"
NODE = "/dev/iec_io_rig_bench_fb"
MON = "/dev/iec_io_rig_bench_mon"      # input-only: published as each cycle begins

# a read-only look at the device, as a second process may take one
PEEK = r"""
import json, sys
from plc_manager.iodaemon import UserDevice
with UserDevice(sys.argv[1], writable=False) as d:
    o = d.read_outputs()
    print(json.dumps({"cycle": o.cycle, "flags": o.flags, "status": d.status(),
                      "values": o.values, "inputs": d.current_inputs()}))
"""


# the daemon in the background, forked from the guest's warm Python (a
# fresh interpreter takes some 20 s to start under TCG)
DAEMON = r"""
import os, sys
log, argv = sys.argv[1], sys.argv[2:]
pid = os.fork()
if pid == 0:
    os.setsid()
    fd = os.open(log, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
    os.dup2(fd, 1)
    os.dup2(fd, 2)
    sys.stdout = open(1, "w", buffering=1, closefd=False)
    sys.stderr = open(2, "w", buffering=1, closefd=False)
    from plc_manager.cli import main
    os._exit(main(["io-daemon", *argv]))
print(pid)
"""


def values(guest, *names) -> dict:
    out = pm(guest, "read", "--json", *names)[1]
    return {v["path"]: v["value"] for v in json.loads(out)}


def peek(guest) -> dict:
    r = guest.pyrun(code=PEEK, argv=[NODE], timeout=60)
    assert r.exit_code == 0, r.output
    return json.loads(r.output)


def wait_for(what, check, timeout=30.0, every=0.2):
    deadline = time.monotonic() + timeout
    while True:
        got = check()
        if got:
            return got
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(every)


@pytest.fixture
def daemons(guest):
    """The pids of the test's daemons in the guest: those still listed at
    the end (the test failed before it killed them) are killed, before the
    comedi fixture stops the configuration they would hold."""
    pids: list = []
    yield pids
    for pid in pids:
        guest.run(f"kill -9 {pid}; for i in $(seq 50); do kill -0 {pid} 2>/dev/null "
                  "|| break; sleep 0.1; done")


def test_a_daemon_closes_the_loop(guest, comedi, daemons, guest_workdir):
    g = guest
    tree = Path(guest_workdir) / "io_user"
    manifest = gen_and_build(PROJECT, tree)
    assert manifest["io"]["Bench"]["devices"] == [
        {"name": "fb", "provider": "user", "board": None, "minor": 0, "node": NODE,
         "inputs": 2, "outputs": 3, "stale_ms": 400},
        {"name": "mon", "provider": "user", "board": None, "minor": 0, "node": MON,
         "inputs": 1, "outputs": 0, "stale_ms": 0},
        {"name": "daq", "provider": "comedi", "board": "comedi_test", "minor": 0}]
    comedi("comedi_test")
    assert channels(g, "1.2", "0.2") == [32767, 32767]     # comedi_test at its load
    compileall.compile_dir(str(ROOT / "manager"), quiet=1)
    log = Path(guest_workdir) / "iodaemon.log"
    mon_log = Path(guest_workdir) / "iodaemon-mon.log"

    # loaded, not started: the device is there, its outputs in the safe state
    pm(g, "load", "--no-start", tree)
    r = g.pyrun(script="plc-manager", argv=["io-daemon", NODE, "--show"], timeout=60)
    assert r.exit_code == 0, r.output
    assert "2 inputs, 3 outputs, interval 20 ms, stale 400 ms" in r.output, r.output
    assert [ln.split() for ln in r.output.splitlines()[1:]] == [
        ["in", "0", "%ID0", "DINT"], ["in", "1", "%IW8", "INT"],
        ["out", "0", "%QD0", "DINT"], ["out", "1", "%QW8", "INT"],
        ["out", "2", "%QD12", "UDINT"]], r.output
    p = peek(g)
    assert (p["flags"], p["status"], p["values"]) == (
        1, 1, {"%QD0": 0, "%QW8": -7, "%QD12": 0}), p
    assert channels(g, "1.2", "0.2") == [32767, 32767]     # AO 2 SAFE HOLD: untouched

    # the daemon, then the task
    rules = ["--map", "%ID0=%QD0", "--map", "%IW8=%QW8"]
    r = g.pyrun(code=DAEMON, argv=[str(log), NODE, *rules, "--trace"], timeout=60)
    assert r.exit_code == 0, r.output
    daemon = r.output.strip()
    daemons.append(daemon)
    wait_for("the daemon", lambda: log.exists() and "answering each cycle" in log.read_text(),
             timeout=60)
    r = g.pyrun(code=DAEMON, argv=[str(mon_log), MON, "--map", "%IW10=-1234", "--trace"],
                timeout=60)
    assert r.exit_code == 0, r.output
    mon = r.output.strip()
    daemons.append(mon)
    wait_for("the mon daemon", lambda: mon_log.exists() and
             "answering each cycle" in mon_log.read_text(), timeout=60)
    # a second read-write opener is refused: the inputs have one writer
    r = g.pyrun(script="plc-manager", argv=["io-daemon", NODE, "--cycles", "1"], timeout=60)
    assert r.exit_code == 2 and "another daemon has it open read-write" in r.output, r.output
    pm(g, "start")
    # comedi while the task runs: AO 2 and AI 2, read from user space, hold a
    # count the task wrote between two reads of n
    n0 = wait_for("30 cycles", lambda: (lambda n: n if n >= 30 else None)(
        values(g, "Bench.n")["Bench.n"]), timeout=60)
    ao, ai = channels(g, "1.2", "0.2")      # AI 2 read after AO 2: as new or newer
    n1 = values(g, "Bench.n")["Bench.n"]
    assert n0 - 1 <= ao <= ai <= n1, (n0, ao, ai, n1)
    wait_for("100 cycles", lambda: values(g, "Bench.n")["Bench.n"] >= 100, timeout=60)
    pm(g, "stop", "--keep-loaded")
    v = values(g, "Bench.n", "Bench.count", "Bench.instep", "Bench.behind", "Bench.sig_out",
               "Bench.ext")
    print("loop:", v)
    # comedi's loopback in the program: each cycle read back on AI 2 what
    # the cycle before wrote to AO 2 (the first, comedi_test's 32767, which
    # aout starts with); after the stop AO 2 holds the last n (SAFE HOLD)
    c = values(g, "Bench.n", "Bench.ain", "Bench.aout", "Bench.ain_out", "Bench.lb_ok",
               "Bench.lb_bad")
    print("comedi:", c)
    assert (c["Bench.lb_ok"], c["Bench.lb_bad"]) == (c["Bench.n"], 0), c
    assert c["Bench.aout"] == c["Bench.n"] == v["Bench.n"], (c, v)
    assert c["Bench.ain"] == c["Bench.ain_out"] == c["Bench.n"] - 1, c
    assert channels(g, "1.2", "0.2") == [c["Bench.n"], c["Bench.n"]], c
    assert v.pop("Bench.ext") == -1234, v           # through the input-only device
    mon_recs = [json.loads(ln) for ln in mon_log.read_text().splitlines()
                if ln.startswith("{")]
    assert len(mon_recs) >= 50 and all(r["values"] == {} for r in mon_recs), mon_recs[-3:]
    assert all(b["cycle"] > a["cycle"] for a, b in zip(mon_recs, mon_recs[1:])), mon_recs
    # count advanced exactly in the cycles that saw the previous one's echo
    assert v["Bench.count"] == v["Bench.instep"], v
    assert v["Bench.instep"] + v["Bench.behind"] == v["Bench.n"], v
    assert v["Bench.sig_out"] == -v["Bench.count"], v      # signed INT through a slot
    # in step most of the time on a quiet machine (benchmarks/io_user_latency.py:
    # 78-95 %); two Python daemons in a TCG guest on a loaded host do less
    assert v["Bench.instep"] >= v["Bench.n"] // 4, v

    # what the daemon saw: whole records, count never ahead of the cycles
    recs = wait_for("the safe record", lambda: [
        json.loads(ln) for ln in log.read_text().splitlines() if ln.startswith("{")]
        if '"flags": 1' in log.read_text() else None)
    run = [x for x in recs if x["flags"] == 0]
    assert len(run) >= 50, recs[-5:]
    lags = sorted(x["cycle"] - x["in_tag"] for x in run if x["in_tag"])
    print(f"daemon saw {len(run)} of {run[-1]['cycle'] - run[0]['cycle'] + 1} cycles; "
          f"loop lag in cycles min/median/max {lags[0]}/{lags[len(lags) // 2]}/{lags[-1]}")
    for a, b in zip(run, run[1:]):
        assert b["cycle"] > a["cycle"], (a, b)
        assert 0 <= b["values"]["%QD0"] - a["values"]["%QD0"] <= b["cycle"] - a["cycle"], (a, b)
        assert b["values"]["%QW8"] == -b["values"]["%QD0"], b
    # the comedi input of each cycle the daemon saw: the count the cycle
    # before wrote to AO 2 (the task's cycles are the program's n)
    assert all(x["values"]["%QD12"] == x["cycle"] - 1 for x in run if x["cycle"] > 1), \
        [x for x in run if x["values"]["%QD12"] != x["cycle"] - 1][:5]
    assert run[-1]["cycle"] <= v["Bench.n"], (run[-1], v)
    # the stop's safe state: SAFE -7; SAFE HOLD keeps the last count
    last = recs[-1]
    assert last["flags"] == 1 and last["values"] == {
        "%QD0": v["Bench.count"], "%QW8": -7, "%QD12": c["Bench.ain_out"]}, (last, v, c)

    # the daemon holds the device: the resource cannot go
    r = g.run("rmmod iec_rig_r_bench")
    assert r.exit_code != 0 and "iec_rig_r_bench" in loaded_modules(g), r.output
    print("rmmod:", r.output.strip())
    rc, out = pm(g, "stop", check=None)
    print("plc-manager stop:", out.strip())
    assert rc != 0, out
    assert f"pid {daemon}" in out and NODE in out and f"pid {mon}" in out and MON in out, out
    assert "iec_rig_r_bench" in loaded_modules(g)

    # running again; the daemon is killed: the inputs go stale, the task faults
    pm(g, "start")
    n0 = values(g, "Bench.n")["Bench.n"]
    wait_for("running", lambda: values(g, "Bench.n")["Bench.n"] >= n0 + 20, timeout=60)
    g.run(f"kill -9 {daemon} {mon}")
    daemons.clear()
    text = wait_for("the stale fault", lambda: (lambda t: t if "stopped on a fault" in t
                                                else None)(pm(g, "status")[1]), timeout=30)
    assert "bench.fast: stopped on a fault: I/O device error in io fb: inputs stale " \
           "errno 110" in text, text
    p = peek(g)
    assert p["status"] == 3 and p["flags"] == 1 and p["values"]["%QW8"] == -7, p
    pm(g, "stop")
    assert loaded_modules(g) == []
    assert g.run(f"ls {NODE} {MON}").exit_code != 0
    assert "iec2kmod: task bench.fast stopped: I/O device error in io fb: inputs stale" \
        in g.run("dmesg").output


# insmod of the resource module while a thread keeps opening its user
# devices and a netlink socket hears the kernel's uevents: what user space
# could see of a load that fails
FAILED_INSMOD = r"""
import collections, ctypes, errno, json, os, socket, sys, threading, time
ko, probe, nodes = sys.argv[1], sys.argv[2], sys.argv[3:]
ev = socket.socket(socket.AF_NETLINK, socket.SOCK_DGRAM, 15)    # NETLINK_KOBJECT_UEVENT
ev.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 20)
ev.bind((0, 1))
opens, done = collections.Counter(), threading.Event()
def opener():
    while not done.is_set():
        for n in nodes:
            try:
                os.close(os.open(n, os.O_RDONLY))
                opens["opened"] += 1
            except OSError as e:
                opens[errno.errorcode.get(e.errno, str(e.errno))] += 1
th = threading.Thread(target=opener)
th.start()
time.sleep(0.2)
libc = ctypes.CDLL(None, use_errno=True)
fd = os.open(ko, os.O_RDONLY)
rc = libc.syscall(313, fd, b"", 0)                              # finit_module
err = ctypes.get_errno() if rc else 0
os.close(fd)
time.sleep(0.2)
done.set()
th.join()
with open(probe, "w") as f:     # an event the socket must hear: it listens
    f.write("change")
events = []
ev.settimeout(1.0)
try:
    while True:
        events.append(ev.recv(65536).split(b"\0")[0].decode())
except socket.timeout:
    pass
print(json.dumps({"rc": rc, "errno": errno.errorcode.get(err, str(err)), "opens": opens,
                  "events": events, "left": [n for n in nodes if os.path.exists(n)]}))
"""


def test_a_failed_load_never_shows_its_user_devices(guest, comedi, guest_workdir):
    """The resource module inserted by hand (as plc-manager would not: its
    device check refuses first) with comedi loaded but no board at
    /dev/comedi0: its own check refuses at init, after the user devices fb
    and mon (before daq in the I/O map) were opened.  Their character
    devices are registered as init's last step, so none ever appears: no
    uevent names /dev/iec_io_rig_bench_*, a thread opening both nodes all
    along gets only ENOENT, nothing is left, and the configuration's other
    modules come out (nothing holds them).  Before, each node was
    registered with its device and removed again (an add and a remove
    uevent each)."""
    g = guest
    tree = Path(guest_workdir) / "io_user_fail"
    manifest = gen_and_build(PROJECT, tree)
    res = manifest["load_order"][-1]
    assert res == "iec_rig_r_bench", manifest["load_order"]
    comedi()                    # comedi and kcomedilib: no board attached
    for name in manifest["load_order"][:-1]:
        g.check_call(f"insmod {tree / name / (name + '.ko')}")
    probe = f"/sys/module/{manifest['load_order'][0]}/uevent"
    r = g.pyrun(code=FAILED_INSMOD, argv=[str(tree / res / (res + ".ko")), probe, NODE, MON],
                timeout=120)
    assert r.exit_code == 0, r.output
    got = json.loads(r.output.strip().splitlines()[-1])
    print("failed insmod:", got)
    assert got["rc"] == -1 and got["errno"] == "ENODEV", got
    assert f"change@/module/{manifest['load_order'][0]}" in got["events"], got
    assert [e for e in got["events"] if "iec_io_" in e] == [], got
    assert set(got["opens"]) == {"ENOENT"} and got["opens"]["ENOENT"] > 2, got
    assert got["left"] == [] and res not in loaded_modules(g), got
    assert ("iec2kmod: resource Bench: device daq (comedi minor 0): no attached comedi "
            "device at that minor") in g.run("dmesg").output
    g.check_call(f"echo clear all > /sys/kernel/iec2kmod/{manifest['configuration'].lower()}"
                 "/control")
    for name in reversed(manifest["load_order"][:-1]):
        g.check_call(f"rmmod {name}")
    assert loaded_modules(g) == []
