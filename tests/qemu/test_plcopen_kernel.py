"""QEMU tier: a PLCopen XML project (LD and FBD, tests/qemu/projects/plcopen_ld)
runs in the PREEMPT_RT kernel from its plc.xml and ends in the state
`iec2kmod sim` computes (issue 28).  Its program counts 200 cycles and then
freezes every value, so the final state does not depend on real timing;
tests/plcopen/test_graphic_cases.py checks the same project's values,
written by hand, in both simulation engines.  Every case of
tests/plcopen/cases also runs in the kernel against the simulation (below)."""

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


# ---------------------------------------------------------------------------
# Every hand-written case of tests/plcopen/cases runs in the kernel for a
# fixed time (`run all MS`: every periodic task stops by itself before its
# first release MS ms after the common start, so it runs a known number of
# cycles whatever the guest's speed) and ends in the state the simulation
# computes for the same sources up to the same instant (no inputs on either
# side), as tests/qemu/test_exec_kernel.py does for the ST cases.  The same
# run serves benchmarks/plcopen_kernel.py on the IEC-only projects of a
# Beremiz checkout.

CASES = sorted((Path(__file__).resolve().parents[1] / "plcopen" / "cases").glob("*.xml"))
RUN_MS = 200
# the values that follow RTC's clock, the wall clock in the kernel and the
# simulated time from DT#1970-01-01 in the simulation: checked apart
WALL = {"fbd_clock": {"RES.INST.NOW", "RES.INST.EL1", "RES.INST.EL2", "RES.INST.EARLY",
                      "RES.INST.CLK.CDT", "RES.INST._TMP_SUB7_OUT"}}


def run_and_compare(guest, source: Path, tree: Path, ms: int = RUN_MS, wall=frozenset()):
    """(problems, values) of `source` run `ms` ms in the kernel against the
    simulation; the paths in `wall` are not compared (returned in values)."""
    import sys
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from test_exec_kernel import compare_group, run_in_kernel  # noqa: E402

    from iec2kmod.compilation import Compilation
    gen_and_build(source, tree)
    result = frontend.run([str(source)], use_cache=False)
    assert result.ok, source
    paths = [e.path for e in Compilation(result.project).plan.table]
    tasks, values = run_in_kernel(guest, tree, ms, paths)
    problems = compare_group(source.stem, result.project, ms, tasks, values)
    problems = [p for p in problems
                if not any(p.startswith(f"{source.stem}: {w} ") or
                           p.upper().startswith(f"{source.stem.upper()}: {w} ") for w in wall)]
    return problems, values


@pytest.mark.parametrize("case", CASES, ids=[c.stem for c in CASES])
def test_plcopen_case_in_the_kernel(guest, guest_workdir, case):
    wall = WALL.get(case.stem, set())
    before = int(guest.run("date +%s").output.strip())
    problems, values = run_and_compare(guest, case, Path(guest_workdir) / "plcopen_cases" /
                                       case.stem, wall=wall)
    after = int(guest.run("date +%s").output.strip())
    assert not problems, "\n".join(problems)
    if wall:
        # Set is FALSE (no inputs): CDT is the guest's wall clock at the
        # last release, el = CDT - start (DT#2024-03-01-12:00:00) both ways
        now = values["RES.INST.NOW"][1]
        start = 1709294400 * 10**9
        assert isinstance(now, int), values["RES.INST.NOW"]
        assert (before - 2) * 10**9 <= now <= (after + 2) * 10**9, (before, now, after)
        assert values["RES.INST.EL1"][1] == values["RES.INST.EL2"][1] == now - start, values
        assert values["RES.INST.EARLY"][1] in (False, 0), values
