"""QEMU tier: the globals evolve in the kernel exactly as `iec2kmod sim`
predicts for the same program (tests/qemu/projects/sim_vs_kernel): every
program computes for a fixed number of cycles and then freezes, so the
final values do not depend on real timing."""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest

from iec2kmod import sim
from iec2kmod.parse import frontend
from kmod_helpers import gen_and_build, loaded_modules, status

pytestmark = pytest.mark.qemu
PROJECT = Path(__file__).resolve().parent / "projects" / "sim_vs_kernel"
GLOBALS = ["i_seed", "i_sum", "i_wrap", "i_hist", "i_mode", "handoff", "r_x", "r_y", "r_i",
           "r_seen", "r_big", "r_small", "r_nan"]


def manager(guest, *argv, timeout=300):
    r = guest.pyrun(script="plc-manager", argv=list(argv), timeout=timeout)
    return r


def test_kernel_globals_equal_the_simulation(guest, guest_workdir):
    tree = Path(guest_workdir) / "sim_vs_kernel"
    manifest = gen_and_build(PROJECT, tree)

    result = frontend.run([str(PROJECT)], use_cache=False)
    assert result.ok
    predicted = sim.run(result.project, 3_000_000_000, watch=GLOBALS).values_at()

    r = manager(guest, "load", str(tree))
    assert r.exit_code == 0, r.output
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            tasks = status(guest, manifest)["tasks"]
            if int(tasks["main.fast"]["cycles"]) > 450 and int(tasks["aux.slow"]["cycles"]) > 250:
                break
            time.sleep(1)
        else:
            pytest.fail(f"tasks too slow: {status(guest, manifest)['text']}")
        r = manager(guest, "read", "--json", *GLOBALS)
        assert r.exit_code == 0, r.output
        got = {v["path"]: v["value"] for v in json.loads(r.output)}
    finally:
        r = manager(guest, "stop")
        assert r.exit_code == 0, r.output
    assert loaded_modules(guest) == []
    # REAL -> integer out of range saturates, NaN gives 0 (iec_real.h), in both
    assert (predicted["r_big"], predicted["r_small"], predicted["r_nan"]) \
        == (2147483647, -9223372036854775808, 0)
    for name in GLOBALS:
        want = predicted[name]
        if isinstance(want, bool):
            want = bool(want)
        assert got[name] == want, f"{name}: kernel {got[name]!r}, simulation {want!r}"
