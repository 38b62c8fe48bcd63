"""The soundness campaign of issue 22 in CI: 200 generated projects with
planted deep bugs (tests/verify/soundgen.py), each verified by the z3 engine
and by the explicit-state referee (`verify --engine explicit`); any
disagreement fails, naming the project and the checks.  A disagreement found
once is kept as a regression case in tests/verify/test_soundness_cases.py.
Any number of projects, deeper: benchmarks/verify_fuzz.py --referee explicit."""

from __future__ import annotations

import pytest

try:
    import z3  # noqa: F401
except ImportError:
    z3 = None

import soundgen

SEED = 22
COUNT = 200
# small enough for CI on two cores (about 4 minutes, measured); the
# benchmark runs deeper
DEPTH, TIMEOUT_MS, MAX_STATES = 5, 2000, 600

# disagreements the z3 engine's known bugs (issue 22, class 4: a fault in
# one task ended the model for every task) cause until their fix is merged
# from branch v1: {seed: number of checks}
KNOWN = {}


def test_campaign():
    if z3 is None:
        pytest.fail("z3-solver is not installed: pip install z3-solver (scripts/setup.sh)")
    seeds = [SEED * 1000 + i for i in range(COUNT)]
    res = soundgen.campaign(seeds, DEPTH, TIMEOUT_MS, MAX_STATES, jobs=2)
    assert len(res) == COUNT
    bad = [(r["seed"], p) for r in res for p in r["problems"]]
    decided = sum(1 for r in res for s, _ in r["explicit"].values() if s != "too_large")
    # the referee must decide most checks, or the campaign checks nothing
    assert decided >= COUNT, soundgen.summary(res)
    unexpected = [(s, p) for s, p in bad if s not in KNOWN]
    assert not unexpected, "\n".join(
        f"project {s} (python3 benchmarks/verify_fuzz.py --referee explicit --unit {s}): {p}"
        for s, p in unexpected)
