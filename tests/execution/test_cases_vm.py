"""Every case under cases/ runs in the reference interpreter
(`iec2kmod sim --engine interp`, iec2kmod/interp) and must show the values and
faults written in its EXPECT blocks -- the same expectations the compiled C
simulator meets (test_cases.py).  No C compiler is involved."""

from __future__ import annotations

import pytest

import runner

pytestmark = pytest.mark.execution

CASES = runner.discover()
# an empty or shrunken list would pass as "skipped": fail at collection instead
assert len(CASES) >= 150, f"only {len(CASES)} execution cases under {runner.CASES}"
_RUNS: dict = {}

# cases whose expectation the interpreter does not meet, with the reason
# (each names the difference between the C simulator and the standard)
XFAIL: dict = {
}


def _area_run(case):
    if case.standalone:
        key, group = case.name, [case]
    else:
        key = case.area
        group = [c for c in CASES if c.area == case.area and not c.standalone]
    if key not in _RUNS:
        _RUNS[key] = runner.run_group(key.replace("/", "_").replace(".", "_") + "_vm", group,
                                      engine="vm")
    run = _RUNS[key]
    if run.error and len(group) > 1:
        alone = case.name
        if alone not in _RUNS:
            _RUNS[alone] = runner.run_group(alone.replace("/", "_").replace(".", "_") + "_vm",
                                            [case], engine="vm")
        return _RUNS[alone]
    return run


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_case_vm(case):
    if case.name in XFAIL:
        pytest.xfail(XFAIL[case.name])
    problems = runner.verify(case, _area_run(case))
    assert not problems, f"{case.path}:\n  " + "\n  ".join(problems)
