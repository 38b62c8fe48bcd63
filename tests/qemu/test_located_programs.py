# SPDX-License-Identifier: MIT
"""QEMU tier: an OpenPLC-shaped program (its I/O located in the PROGRAM's
VAR: %IX, %IW, %QX, %QW, %MW, a function block's %Q* completed by
VAR_CONFIG, a located configuration global) in the PREEMPT_RT guest, its
I/O written, read and forced through plc-manager by address and by name
(issue 25).  The project is the conformance file that the C simulator and
the interpreter run with the same inputs."""

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
PROJECT = ROOT / "tests" / "conformance" / "valid" / "realcode" / "openplc_located.st"


def values(guest, *names) -> list:
    """[(path, value)] of the names (addresses or paths), in their order."""
    out = pm(guest, "read", "--json", *names)[1]
    return [(v["path"], v["value"]) for v in json.loads(out)]


def wait_for(guest, name, want, timeout=20.0):
    deadline = time.monotonic() + timeout
    while True:
        ((_, v),) = values(guest, name)
        if v == want:
            return
        assert time.monotonic() < deadline, f"{name} = {v!r}, want {want!r}"
        time.sleep(0.2)


def test_openplc_program_io_by_address_and_by_name(guest, guest_workdir):
    tree = Path(guest_workdir) / "located_programs"
    manifest = gen_and_build(PROJECT, tree)
    assert manifest["addresses"]["%IW2"] == "Res0.instance0.Level"
    assert manifest["addresses"]["%QX1.0"] == "Res0.instance0.p1.motor"
    assert manifest["addresses"]["%QX3.0"] == "alarm"
    compileall.compile_dir(str(ROOT / "manager"), quiet=1)
    pm(guest, "load", tree)
    try:
        # an address reads its variable, under the variable's name
        assert values(guest, "%MW2")[0][0] == "Res0.instance0.Count"
        pm(guest, "write", "%IW2", "40")
        pm(guest, "write", "%IX0.0", "TRUE")
        wait_for(guest, "%QX0.0", True)
        wait_for(guest, "%QW2", 80)
        wait_for(guest, "%QX1.0", True)                       # p1.motor, VAR_CONFIG
        assert values(guest, "Res0.instance0.Valve", "%QX3.0", "%QX1.1") == [
            ("Res0.instance0.Valve", True), ("alarm", False),
            ("Res0.instance0.p2.motor", False)]
        pm(guest, "write", "%IX0.0", "FALSE")
        # forced by address: held at the task's cycle boundaries, the name shows it
        pm(guest, "force", "%IW2", "150")
        wait_for(guest, "%QX3.0", True)
        wait_for(guest, "Res0.instance0.Setpoint", 300)
        wait_for(guest, "%QX1.1", True)
        out = json.loads(pm(guest, "read", "--json", "Res0.instance0.Level")[1])
        assert out[0]["value"] == 150 and out[0]["forced"] is True
        rc, out = pm(guest, "write", "Res0.instance0.Level", "1", check=1)
        assert "is forced: unforce it first" in out
        pm(guest, "unforce", "Res0.instance0.Level")
        pm(guest, "write", "%IW2", "10")
        wait_for(guest, "%QX3.0", False)
        wait_for(guest, "%QW2", 20)
        # the latch holds the valve until Stop
        assert values(guest, "%QX0.0") == [("Res0.instance0.Valve", True)]
        pm(guest, "write", "Res0.instance0.Stop", "TRUE")
        wait_for(guest, "%QX0.0", False)
        rc, out = pm(guest, "read", "%IW99", check=1)
        assert "unknown variable '%IW99'" in out
    finally:
        pm(guest, "stop", check=None)
    assert loaded_modules(guest) == []
