# SPDX-License-Identifier: MIT
"""QEMU tier, issue 26: located variables bound to a real comedi driver by
an I/O map (iec2kmod/iomap.py, kmod_templates/kernel/iec_io*.c).  The
session guest loads comedi, kcomedilib and comedi_test for the test (the
comedi fixture, tests/qemu/conftest.py, removes them after it);
comedi_test auto-configures /dev/comedi0 (8 AI, 8 AO channels, 16 bits).  comedi_test's AI channels,
read one sample at a time (INSN_READ), give back what was last written to
the AO channel of the same number (its loopback; the waveforms come only
through asynchronous commands), so the program's outputs come back as its
inputs through the driver.  Observed from outside the program: user space
reads the AO/AI channels through /dev/comedi0 (the COMEDI_INSN ioctl).
Also: a device missing at load (comedi_test not loaded) refuses the load
naming the device and leaves nothing loaded; the safe state at load (SAFE
1234) and on stop (SAFE 1234, SAFE HOLD keeps the last value); the driver
removed while the task runs faults the task ("I/O device error" naming the
channel and the errno).  The guest's kernel log is checked for WARNING, BUG
and Oops by the guest fixture."""

from __future__ import annotations

import compileall
import json
import time
from pathlib import Path

import pytest

from kmod_helpers import gen_and_build, loaded_modules, pm

pytestmark = pytest.mark.qemu
HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
PROJECT = HERE / "projects" / "io_comedi"

# user space's view of a comedi channel: one INSN_READ through the ioctl
READ_CHANNEL = r"""
import ctypes, fcntl, os, sys
class Insn(ctypes.Structure):
    _fields_ = [("insn", ctypes.c_uint), ("n", ctypes.c_uint),
                ("data", ctypes.POINTER(ctypes.c_uint)), ("subdev", ctypes.c_uint),
                ("chanspec", ctypes.c_uint), ("unused", ctypes.c_uint * 3)]
INSN_READ = 0x04000000 | 0
COMEDI_INSN = (2 << 30) | (ctypes.sizeof(Insn) << 16) | (ord("d") << 8) | 12
fd = os.open("/dev/comedi0", os.O_RDWR)
out = []
for spec in sys.argv[1:]:
    sub, chan = map(int, spec.split("."))
    data = (ctypes.c_uint * 1)()
    insn = Insn(INSN_READ, 1, data, sub, chan & 0xffff)
    fcntl.ioctl(fd, COMEDI_INSN, insn)
    out.append(data[0])
print(" ".join(map(str, out)))
"""


def values(guest, *names) -> dict:
    out = pm(guest, "read", "--json", *names)[1]
    return {v["path"]: v["value"] for v in json.loads(out)}


def channels(guest, *specs) -> list:
    r = guest.pyrun(code=READ_CHANNEL, argv=list(specs), timeout=60)
    assert r.exit_code == 0, r.output
    return [int(x) for x in r.output.split()]


def wait_values(guest, want: dict, timeout=30.0, at_least=False) -> dict:
    """Polls until every name has its value (at_least: a value >= it)."""
    deadline = time.monotonic() + timeout
    while True:
        got = values(guest, *want)
        if all(got[k] >= v if at_least else got[k] == v for k, v in want.items()):
            return got
        assert time.monotonic() < deadline, f"{got}, want {want}"
        time.sleep(0.2)


def status_text(guest) -> str:
    return pm(guest, "status")[1]


def test_comedi_test_channels_in_the_cycle(guest, comedi, guest_workdir):
    tree = Path(guest_workdir) / "io_comedi"
    manifest = gen_and_build(PROJECT, tree)
    assert [(b["address"], b["device"], b["subdevice"], b["channel"], b["safe"])
            for b in manifest["io"]["Bench"]["bindings"]] == [
        ("%IW0", "daq", 0, 0, None), ("%IW2", "daq", 0, 1, None),
        ("%QW0", "daq", 1, 0, 1234), ("%QW2", "daq", 1, 1, "HOLD")]
    compileall.compile_dir(str(ROOT / "manager"), quiet=1)
    g = guest
    md = comedi("comedi_test")
    # comedi_test's loopback starts at half scale on every channel
    assert channels(g, "0.0", "0.1", "1.0", "1.1") == [32767] * 4

    # the device missing at load: refused, the device named, nothing left
    g.check_call("rmmod comedi_test")
    rc, out = pm(g, "load", tree, check=1)
    assert "resource Bench: device daq (/dev/comedi0, comedi_test) is missing" in out, out
    assert loaded_modules(g) == []
    g.check_call(f"insmod {md}/drivers/comedi_test.ko")

    # loaded, not started: the outputs are in their safe state
    pm(g, "load", "--no-start", tree)
    assert channels(g, "1.0", "1.1") == [1234, 32767]
    pm(g, "start")
    # each cycle reads AI 0, which gives back the AO 0 the previous cycle
    # wrote: the program's input changes every cycle, one behind its count
    wait_values(g, {"Bench.last_ain0": 5}, timeout=60, at_least=True)
    for _ in range(3):
        v = values(g, "Bench.n", "Bench.last_ain0", "Bench.ain0")
        assert v["Bench.last_ain0"] == v["Bench.n"] - 1 == v["Bench.ain0"], v
    assert values(g, "Bench.n")["Bench.n"] > v["Bench.n"]
    # a written analog output reaches the device and comes back as an input
    pm(g, "write", "Bench.setp", "4321")
    wait_values(g, {"Bench.ain1": 4321, "Bench.last_ain1": 4321})
    assert channels(g, "1.1", "0.1") == [4321, 4321]

    # stop: AO 0 to its SAFE value, AO 1 (SAFE HOLD) keeps its last one
    pm(g, "stop", "--keep-loaded")
    assert channels(g, "1.0", "1.1") == [1234, 4321]

    # the driver goes while the task runs: the task faults on its I/O
    n0 = values(g, "Bench.n")["Bench.n"]
    pm(g, "start")
    wait_values(g, {"Bench.last_ain0": n0 + 2}, timeout=60, at_least=True)  # running
    g.check_call("rmmod comedi_test")
    deadline = time.monotonic() + 30
    while "stopped on a fault" not in (text := status_text(g)):
        assert time.monotonic() < deadline, text
        time.sleep(0.2)
    assert "bench.fast: stopped on a fault: I/O device error in io daq.0.0 %IW0 errno 19" \
        in text, text
    pm(g, "stop")
    assert loaded_modules(g) == []
    log = g.run("dmesg").output
    assert "iec2kmod: task bench.fast stopped: I/O device error in io daq.0.0 %IW0 errno 19" \
        in log, log
