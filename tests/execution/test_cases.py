"""Every case under cases/ runs in the host simulator, plain and with
ASan+UBSan, and must show the values written in its EXPECT blocks (see
runner.py for the format).  The cases of an area share one simulator build."""

from __future__ import annotations

import pytest

import runner

pytestmark = pytest.mark.execution

CASES = runner.discover()
# an empty or shrunken list would pass as "skipped": fail at collection instead
assert len(CASES) >= 150, f"only {len(CASES)} execution cases under {runner.CASES}"
_RUNS: dict = {}


def _area_run(case, sanitize):
    """The run of the case's area (built once per area and mode)."""
    if case.standalone:
        key = (case.name, sanitize)
        group = [case]
    else:
        key = (case.area, sanitize)
        group = [c for c in CASES if c.area == case.area and not c.standalone]
    if key not in _RUNS:
        _RUNS[key] = runner.run_group(key[0].replace("/", "_").replace(".", "_"), group,
                                      sanitize)
    run = _RUNS[key]
    if run.error and len(group) > 1:
        # one bad case must not hide the others: run this one alone
        alone = (case.name, sanitize)
        if alone not in _RUNS:
            _RUNS[alone] = runner.run_group(
                case.name.replace("/", "_").replace(".", "_"), [case], sanitize)
        return _RUNS[alone]
    return run


@pytest.mark.parametrize("sanitize", [False, True], ids=["plain", "sanitize"])
@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_case(case, sanitize):
    problems = runner.verify(case, _area_run(case, sanitize), sanitize)
    assert not problems, f"{case.path}:\n  " + "\n  ".join(problems)



def test_enough_cases():
    assert len(CASES) >= 150
    il = sum(1 for c in CASES if c.path.suffix.lower() == ".il")
    assert il >= 15
