# SPDX-License-Identifier: MIT
"""QEMU tier, issue 26: comedi_parport on QEMU's emulated parallel port.

The session guest has LPT1 (I/O base 0x378, IRQ 7) on a file of the host
(Guest(parallel=...), guest.parallel); comedi is loaded for the test (the
comedi fixture, tests/qemu/conftest.py, removes it after) with one legacy
minor and
comedi_parport attached to /dev/comedi0 with the COMEDI_DEVCONFIG ioctl
(tests/qemu/comedi_legacy.py: what comedi_config does), its I/O base only.
Project projects/io_parport: resource Lights drives a traffic light on the
data lines and toggles STROBE every 10 ms; QEMU writes the data register to
the file on each rising STROBE, so the host reads the light's sequence, one
byte per two cycles.  Each cycle that writes STROBE low makes the port raise
IRQ 7 (the control register's interrupt enable is set by resource Events,
whose INTERRUPT binding requests the line); every interrupt runs event task
onack once: its count equals the cycles that wrote STROBE low, the kernel's
count of the line, the handler's count `plc-manager status` shows with the
interrupt (from the module's iec_io file) and the one logged at unload.  After the
unload, comedi_parport re-attached with its own IRQ makes the load fail,
naming the interrupt.  The status lines (comedi_parport's DI subdevice) are not bound: with a file chardev
QEMU's port emulates them itself (a printer handshake) and nothing outside
can set them, and reading them acknowledges the emulated interrupt."""

from __future__ import annotations

import compileall
import json
import re
import time
from pathlib import Path

import pytest

from kmod_helpers import gen_and_build, loaded_modules, pm

pytestmark = pytest.mark.qemu
HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
PROJECT = HERE / "projects" / "io_parport"
LEGACY = HERE / "comedi_legacy.py"

# the light's step per byte (lights.st): bits 0..5 = main R Y G, side R Y G
STEPS = [0b001100] * 3 + [0b001010, 0b001001] + [0b100001] * 3 + [0b010001, 0b001001]


def values(guest, *names) -> dict:
    out = pm(guest, "read", "--json", *names)[1]
    return {v["path"]: v["value"] for v in json.loads(out)}


def irq7(guest) -> int:
    """The kernel's count of IRQ 7 (every CPU), 0 when nobody holds it."""
    for line in guest.run("cat /proc/interrupts").output.splitlines():
        words = line.split()
        if words and words[0] == "7:":
            return sum(int(w) for w in words[1:] if w.isdigit())
    return 0


def parport_setup(guest, comedi):
    """comedi_parport attached to the session guest's LPT1 at /dev/comedi0
    (the comedi fixture removes the modules after the test)."""
    comedi("comedi_parport", legacy_minors=1)
    legacy = LEGACY.read_text()
    guest.pyrun(code=legacy, argv=["config", "/dev/comedi0", "comedi_parport", "0x378"],
                check=True)
    # INIT and SELECT (control lines 2, 3) high: QEMU's port prints then
    r = guest.pyrun(code=legacy, argv=["bits", "/dev/comedi0", "2", "0xc", "0xc"], check=True)
    assert r.output.split() == ["12"], r.output


def test_traffic_light_bytes_and_ack_interrupts(guest, comedi, guest_workdir):
    tree = Path(guest_workdir) / "io_parport"
    manifest = gen_and_build(PROJECT, tree)
    assert manifest["io"]["Events"]["interrupts"] == [
        {"address": "%IX9.0", "device": "lpt", "source": "ACK", "irq": 7, "tasks": ["onack"]}]
    compileall.compile_dir(str(ROOT / "manager"), quiet=1)
    g = guest
    lpt = Path(g.parallel)
    start = lpt.stat().st_size        # the port's bytes so far (a test before)
    parport_setup(g, comedi)

    pm(g, "load", "--no-start", tree)
    assert re.search(r"^\s*7:.*iec2kmod$", g.run("cat /proc/interrupts").output, re.M)
    assert lpt.read_bytes()[start:] == b""
    n0 = irq7(g)
    pm(g, "start")
    deadline = time.monotonic() + 60
    while values(g, "Lights.bytes")["Lights.bytes"] < 25:
        assert time.monotonic() < deadline
        time.sleep(0.3)
    pm(g, "stop", "--keep-loaded", "--resource", "Lights")
    v = values(g, "Lights.bytes", "Lights.lows")
    # outside the guest: one byte per rising STROBE, the light's steps in order
    data = lpt.read_bytes()[start:]
    assert len(data) == v["Lights.bytes"], (len(data), v)
    assert list(data) == [STEPS[i % 10] for i in range(len(data))], data.hex()
    # every STROBE-low write raised one interrupt, which ran onack once
    deadline = time.monotonic() + 30
    while (acks := values(g, "Events.acks")["Events.acks"]) < v["Lights.lows"]:
        assert time.monotonic() < deadline, (acks, v)
        time.sleep(0.2)
    assert acks == v["Lights.lows"] == irq7(g) - n0 > 10, (acks, v, irq7(g), n0)
    print(f"parport: {len(data)} bytes {data[:12].hex()}..., {v['Lights.lows']} STROBE-low "
          f"writes, {irq7(g) - n0} IRQ 7, {acks} onack cycles")
    status = g.run("cat /sys/kernel/iec2kmod/crossing/status").output
    m = re.search(r"task events\.onack .*?cycles (\d+)", status)
    assert m and int(m.group(1)) == acks, status
    # plc-manager status lists the interrupt: the line's own count, the task
    text = pm(g, "status")[1]
    rows = [ln.split() for ln in text.split("interrupts (COUNT: taken since the load", 1)[-1]
            .splitlines() if ln.startswith("Events ")]
    assert rows == [["Events", "%IX9.0", "Events.ack", "lpt.ACK", "7", "onack", str(acks)]], text
    assert [(q["address"], q["irq"], q["tasks"], q["count"])
            for q in json.loads(pm(g, "status", "--json")[1])["interrupts"]] == [
        ("%IX9.0", 7, ["onack"], acks)]

    # unload with the line requested: freed before the threads stop
    pm(g, "stop")
    assert loaded_modules(g) == []
    assert "iec2kmod" not in g.run("cat /proc/interrupts").output
    log = g.run("dmesg").output
    assert f"iec2kmod: resource Events: IRQ 7 (lpt.ACK) released after {acks} interrupts" \
        in log, log

    # comedi_parport attached with its own IRQ holds the line: load refused
    legacy = LEGACY.read_text()
    g.pyrun(code=legacy, argv=["detach", "/dev/comedi0"], check=True)
    g.pyrun(code=legacy, argv=["config", "/dev/comedi0", "comedi_parport", "0x378", "7"],
            check=True)
    rc, out = pm(g, "load", tree, check=1)
    assert ("resource Events: interrupt lpt.ACK (IRQ 7) of %IX9.0: comedi_parport was attached "
            "with an IRQ and holds it") in out, out
    assert loaded_modules(g) == []
