"""Tests of the execution harness itself: inputs broken on purpose (kept in
broken/) that the runner must reject.  Each one passed the harness before
its check was made strict."""

from __future__ import annotations

from pathlib import Path

import pytest

import runner

pytestmark = pytest.mark.execution

BROKEN = Path(__file__).resolve().parent / "broken"


# ------------------------------------------------------------------ pairs
@pytest.fixture(scope="module")
def broken_pairs():
    pairs = runner.discover_pairs(BROKEN / "pairs")
    assert sorted(p.name for p in pairs) == ["differs", "frozen", "one_idle"]
    res, traces, iface = runner.run_pairs(pairs)
    assert not res.faults, res.faults
    return {p.name: (p, traces[p.name], iface[p.name]) for p in pairs}


def test_pair_whose_outputs_never_change_fails(broken_pairs):
    pair, (st, il), iface = broken_pairs["frozen"]
    assert st == il
    # the old check counted inputs too: it passed this pair
    assert sum(1 for _, n, _ in st if n in {x.upper() for x in iface}) >= 100
    problems = runner.pair_problems(pair, st, il)
    assert any("the outputs change 0 times" in p for p in problems), problems


def test_pair_with_one_idle_output_fails(broken_pairs):
    pair, (st, il), _ = broken_pairs["one_idle"]
    assert st == il
    changes = runner.output_changes(st, pair.outputs)
    assert changes["COPY"] >= 50 and changes["STUCK"] == 0, changes
    problems = runner.pair_problems(pair, st, il)
    assert problems == [f"one_idle: outputs that change fewer than "
                        f"{runner.MIN_CHANGES_PER_OUTPUT} times: {{'STUCK': 0}}"], problems


def test_pair_whose_traces_differ_fails(broken_pairs):
    pair, (st, il), _ = broken_pairs["differs"]
    problems = runner.pair_problems(pair, st, il)
    assert len(problems) == 1 and "traces differ at change" in problems[0], problems
