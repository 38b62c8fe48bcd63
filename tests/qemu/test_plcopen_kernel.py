"""QEMU tier: a PLCopen XML project (LD and FBD, tests/qemu/projects/plcopen_ld)
runs in the PREEMPT_RT kernel from its plc.xml and ends in the state
`iec2kmod sim` computes (issue 28).  Its program counts 200 cycles and then
freezes every value, so the final state does not depend on real timing;
tests/plcopen/test_graphic_cases.py checks the same project's values,
written by hand, in both simulation engines."""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest

from iec2kmod import sim
from iec2kmod.parse import frontend
from kmod_helpers import gen_and_build, loaded_modules, status

pytestmark = pytest.mark.qemu
PROJECT = Path(__file__).resolve().parent / "projects" / "plcopen_ld"
GLOBALS = ["cnt", "half", "lamp", "toggle", "rises"]


def manager(guest, *argv, timeout=300):
    return guest.pyrun(script="plc-manager", argv=list(argv), timeout=timeout)


def test_plcopen_ld_project_in_the_kernel(guest, guest_workdir):
    tree = Path(guest_workdir) / "plcopen_ld"
    manifest = gen_and_build(PROJECT, tree)
    result = frontend.run([str(PROJECT)], use_cache=False)
    assert result.ok
    predicted = sim.run(result.project, 3_000_000_000, watch=GLOBALS).values_at()
    assert (predicted["cnt"], predicted["rises"], bool(predicted["toggle"])) == (200, 100, False)

    r = manager(guest, "load", str(tree))
    assert r.exit_code == 0, r.output
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            if int(status(guest, manifest)["tasks"]["res.fast"]["cycles"]) > 250:
                break
            time.sleep(1)
        else:
            pytest.fail(f"task too slow: {status(guest, manifest)['text']}")
        r = manager(guest, "read", "--json", *GLOBALS)
        assert r.exit_code == 0, r.output
        got = {v["path"]: v["value"] for v in json.loads(r.output)}
    finally:
        r = manager(guest, "stop")
        assert r.exit_code == 0, r.output
    assert loaded_modules(guest) == []
    for name in GLOBALS:
        want = predicted[name]
        if isinstance(want, bool):
            want = bool(want)
        assert got[name] == want, f"{name}: kernel {got[name]!r}, simulation {want!r}"
