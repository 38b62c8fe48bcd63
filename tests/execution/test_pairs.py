"""The ST and IL versions of the same POU (pairs/<name>.st and .il) give
identical traces: every VAR_INPUT/VAR_OUTPUT change at the same simulated
time, over many cycles with the same pseudo-random inputs.  All pairs run in
one simulator build, plain and with ASan+UBSan.  The traces must show
behaviour: the outputs alone (inputs do not count) change at least
runner.MIN_OUTPUT_CHANGES times, and every output at least
runner.MIN_CHANGES_PER_OUTPUT times."""

from __future__ import annotations

import pytest

import runner

pytestmark = pytest.mark.execution

PAIRS = runner.discover_pairs()
# an empty or shrunken list would pass as "skipped": fail at collection instead
assert len(PAIRS) >= 10, f"only {len(PAIRS)} ST/IL pairs under {runner.PAIRS}"
_RUNS: dict = {}


def _run(sanitize):
    if sanitize not in _RUNS:
        try:
            _RUNS[sanitize] = runner.run_pairs(PAIRS, sanitize)
        except Exception as exc:  # noqa: BLE001 - reported by every test
            _RUNS[sanitize] = exc
    r = _RUNS[sanitize]
    if isinstance(r, Exception):
        pytest.fail(f"{type(r).__name__}: {r}")
    return r


def test_enough_pairs():
    assert len(PAIRS) >= 10


@pytest.mark.parametrize("sanitize", [False, True], ids=["plain", "sanitize"])
@pytest.mark.parametrize("pair", PAIRS, ids=[p.name for p in PAIRS])
def test_same_trace(pair, sanitize):
    res, traces, _ = _run(sanitize)
    if sanitize:
        assert not runner.SANITIZER_REPORT.search(res.stderr or ""), res.stderr[:3000]
    assert not res.faults, res.faults
    st, il = traces[pair.name]
    problems = runner.pair_problems(pair, st, il)
    assert not problems, "\n".join(problems)
