# SPDX-License-Identifier: MIT
"""QEMU tier, issue 26: plc-manager and bound I/O, on examples/tank_io (a PI
tank level loop in volts on comedi_test, README "Real I/O").  The session
guest loads comedi, kcomedilib and comedi_test for the test (the comedi
fixture, tests/qemu/conftest.py) (/dev/comedi0: 8 AI, 8 AO
channels, 16 bits; an AI channel read one sample at a time gives back the
AO channel of the same number).

- load checks the I/O map's devices before inserting anything: comedi_test
  removed, it refuses naming /dev/comedi0 and inserts nothing; the
  resource module itself, inserted by hand, still refuses (the kernel's
  second line of defence);
- REAL scaling: the REAL inputs hold lo + raw * (hi - lo) / 65535 of the
  samples user space reads from the device, bit for bit as
  iec2kmod.iomap.phys_of computes them, and the REAL outputs reach the
  device as raw_of of the variables;
- status shows the bindings and the last samples (raw and volts);
- an LREAL on the channel's range 1 (-5..5 V): the same sample, half the
  volts, not rounded to a REAL;
- force by address: a forced input is what the program sees while status
  shows the device's sample; a forced analog output is what reaches the device
  (read back through comedi_test's AI loopback, from user space and by the
  program), while the variable and the device differ after a stop (the
  safe value);
- the cycle's order seen from the device: after a stop AO 0 holds the
  kernel's last written sample of %QD0, and the last AI 0 sample (the
  loopback of AO 0 read in copy-in, before the programs ran) is the one the
  cycle before wrote, one model step behind while the level moves."""

from __future__ import annotations

import compileall
import json
import time
from pathlib import Path

import pytest

from iec2kmod.iomap import phys_of, raw_of
from kmod_helpers import gen_and_build, loaded_modules, pm
from test_io_comedi import channels, values

pytestmark = pytest.mark.qemu
HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
PROJECT = ROOT / "examples" / "tank_io"


def io_status(guest) -> dict:
    js = json.loads(pm(guest, "status", "--json")[1])
    return {b["address"]: b for b in js["io"]}


def wait_io(guest, address, raw, timeout=30.0) -> dict:
    deadline = time.monotonic() + timeout
    while (st := io_status(guest))[address]["last"] != raw:
        assert time.monotonic() < deadline, st
        time.sleep(0.2)
    return st


def lreal_variant(dest: Path) -> Path:
    """tank_io with its level input an LREAL on AI 0's range 1 (-5..5 V)."""
    dest.mkdir(parents=True, exist_ok=True)
    st = (PROJECT / "tank_io.st").read_text()
    st = st.replace("level AT %ID0 : REAL;", "level AT %IL0 : LREAL;")
    st = st.replace("    level : REAL;                     (* V, the level transmitter",
                    "    level : LREAL;                    (* V, the level transmitter")
    st = st.replace("err := setpoint - level;", "err := setpoint - LREAL_TO_REAL(level);")
    iomap = (PROJECT / "tank_io.iomap").read_text().replace("%ID0 : daq.0.0 RANGE 0",
                                                            "%IL0 : daq.0.0 RANGE 1")
    assert "level AT %IL0 : LREAL;" in st and "LREAL_TO_REAL(level)" in st
    assert "%IL0 : daq.0.0 RANGE 1" in iomap
    (dest / "tank_io.st").write_text(st)
    (dest / "tank_io.iomap").write_text(iomap)
    return dest


def test_manager_and_real_scaling_on_comedi_test(guest, comedi, guest_workdir):
    tree = Path(guest_workdir) / "tank_io"
    manifest = gen_and_build(PROJECT, tree)
    tree_l = Path(guest_workdir) / "tank_io_lreal"
    gen_and_build(lreal_variant(Path(guest_workdir) / "src_lreal"), tree_l)
    res = next(m["name"] for m in manifest["modules"] if m["kind"] == "resource")
    compileall.compile_dir(str(ROOT / "manager"), quiet=1)
    g = guest
    md = comedi("comedi_test")
    assert channels(g, "0.0", "0.1", "1.0", "1.1") == [32767] * 4

    # the device missing: the manager refuses before inserting anything
    g.check_call("rmmod comedi_test")
    rc, out = pm(g, "load", tree, check=1)
    assert "plc-manager: resource Tank: device daq (/dev/comedi0, comedi_test) is missing: " \
           "load its comedi driver first (modprobe comedi_test); nothing inserted" in out, out
    assert "inserted" not in out.replace("nothing inserted", ""), out
    assert loaded_modules(g) == []
    # the kernel's own check still refuses the resource module
    for name in manifest["load_order"][:-1]:
        g.check_call(f"insmod {tree / name / (name + '.ko')}")
    r = g.run(f"insmod {tree / res / (res + '.ko')}")
    assert r.exit_code != 0, r.output
    assert "iec2kmod: resource Tank: device daq (comedi minor 0): no attached comedi device" \
        in g.run("dmesg").output
    g.check_call(f"echo clear all > /sys/kernel/iec2kmod/{manifest['configuration'].lower()}"
                 "/control")
    for name in reversed(manifest["load_order"][:-1]):
        g.check_call(f"rmmod {name}")
    assert loaded_modules(g) == []
    g.check_call(f"insmod {md}/drivers/comedi_test.ko")

    # loaded, not started: the valve (SAFE 0.0 V) is at its sample, the
    # level (SAFE HOLD) as it was; status shows what was written, no input yet
    pm(g, "load", "--no-start", tree)
    zero = raw_of(-10.0, 10.0, 16, 0.0)
    assert zero == 32768
    assert channels(g, "1.0", "1.1") == [32767, zero]
    st = io_status(g)
    assert [(a, b["variable"], b["where"], b["input"], b["last"]) for a, b in st.items()] == [
        ("%ID0", "Tank.level", "daq.0.0", True, None),
        ("%ID4", "Tank.valve_fb", "daq.0.1", True, None),
        ("%QD0", "Tank.level_tx", "daq.1.0", False, None),
        ("%QD4", "Tank.valve", "daq.1.1", False, zero)], st
    text = pm(g, "status")[1]
    assert "%QD4     Tank.valve     daq.1.1  out  0 V      32768  0.00015259 V" in text, text

    # the loop runs: the model's level climbs from 2 V toward the 6 V setpoint
    pm(g, "start")
    deadline = time.monotonic() + 60
    while values(g, "Tank.level")["Tank.level"] < 3.0:
        assert time.monotonic() < deadline
        time.sleep(0.3)

    # force the valve by its address: the forced volts reach the device
    pm(g, "force", "%QD4", "2.5")
    want = raw_of(-10.0, 10.0, 16, 2.5)
    assert want == 40959
    wait_io(g, "%QD4", want)
    wait_io(g, "%ID4", want)           # and come back through AI 1
    assert channels(g, "1.1", "0.1") == [want, want]
    v = values(g, "%QD4", "Tank.valve_fb")
    assert v["Tank.valve"] == 2.5
    assert v["Tank.valve_fb"] == phys_of(-10.0, 10.0, 16, want) != 2.5, v

    # a forced input: the program sees the forced volts, status the device's
    pm(g, "force", "%ID0", "1.0")
    time.sleep(0.5)
    st = io_status(g)
    assert values(g, "%ID0")["Tank.level"] == 1.0
    assert st["%ID0"]["last"] is not None
    assert abs(phys_of(-10.0, 10.0, 16, st["%ID0"]["last"]) - 1.0) > 1.0, st
    pm(g, "unforce", "%ID0")

    # stopped: every REAL input is phys_of its last sample, every REAL
    # output went out as raw_of its value; AO 0 holds, the valve is safe
    pm(g, "stop", "--keep-loaded")
    st = io_status(g)
    v = values(g, "Tank.level", "Tank.valve_fb", "Tank.level_tx")
    assert v["Tank.level"] == phys_of(-10.0, 10.0, 16, st["%ID0"]["last"]), (v, st)
    assert v["Tank.valve_fb"] == phys_of(-10.0, 10.0, 16, st["%ID4"]["last"]), (v, st)
    assert st["%QD0"]["last"] == raw_of(-10.0, 10.0, 16, v["Tank.level_tx"]), (v, st)
    assert channels(g, "1.0", "1.1") == [st["%QD0"]["last"], zero]
    assert st["%QD4"]["last"] == zero        # the device has the safe value,
    assert values(g, "%QD4")["Tank.valve"] == 2.5    # the variable its forced one
    assert channels(g, "0.0")[0] == st["%QD0"]["last"]   # AI 0 loops AO 0 back
    pm(g, "unforce", "--all")
    pm(g, "stop")
    assert loaded_modules(g) == []

    # an LREAL on range 1 (-5..5 V) of the same channel: the same sample,
    # half the volts, in binary64.  The valve's read-back forced to 0.25 V
    # keeps the model's level moving (from 2 V toward 0.5 V, more than one
    # sample a cycle for some 20 s), so the stop comes while AO 0 changes
    # every cycle: the samples are not all k * 13107 (exact in binary32) and
    # the cycle's input is seen one step behind its output
    pm(g, "load", "--no-start", tree_l)
    pm(g, "force", "%ID4", "0.25")
    pm(g, "start")
    deadline = time.monotonic() + 60
    while io_status(g)["%IL0"]["last"] is None:
        assert time.monotonic() < deadline
        time.sleep(0.3)
    time.sleep(1.0)
    pm(g, "stop", "--keep-loaded")
    st = io_status(g)
    raw = st["%IL0"]["last"]
    v = values(g, "%IL0", "Tank.valve_fb", "Tank.level_tx")
    level = v["Tank.level"]
    assert v["Tank.valve_fb"] == 0.25, v
    assert level == phys_of(-5.0, 5.0, 16, raw, "LREAL"), (level, raw)
    if raw % 13107:     # (only k * 13107 give a value exact in binary32 too)
        assert level != phys_of(-5.0, 5.0, 16, raw, "REAL")     # not rounded to binary32
    assert abs(level - phys_of(-10.0, 10.0, 16, raw) / 2) < 1e-3
    # AO 0 holds the sample the last cycle wrote (SAFE HOLD), the kernel's
    # last value of %QD0, raw_of TankModel's level_tx; that cycle's copy-in
    # read AI 0 before its programs ran, so its input is the AO 0 of the
    # cycle before: one step of the model behind (2 % of the level's
    # distance to 0.5 V: tens of samples here), not the same sample
    out = st["%QD0"]["last"]
    assert channels(g, "0.0", "1.0") == [out, out], (out, raw, v)
    assert out == raw_of(-10.0, 10.0, 16, v["Tank.level_tx"]), (out, v)
    prev = phys_of(-10.0, 10.0, 16, raw)        # the model's level a cycle ago, +-1/2 sample
    assert abs(v["Tank.level_tx"] - (prev + 0.04 * 0.25 - 0.02 * prev)) < 5e-4, (prev, v)
    if abs(0.01 - 0.02 * prev) > 3 * 20 / 65535:    # moving (the first 17 s or so)
        assert out != raw, (out, raw, v)
    pm(g, "unforce", "--all")
    pm(g, "stop")
    assert loaded_modules(g) == []
