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


# ------------------------------------------------------ annotation typos
# A case with one correct EXPECT and one mistyped annotation: before the
# parser was strict, the mistyped one was an ordinary comment and the case
# passed on the correct one alone.
TEMPLATE = """PROGRAM typo
VAR
    n : INT;
    expected_n : INT;
    s : STRING := '(* EXPECTED after 1 cycles: n = 99 *) // EXPECT';
END_VAR
    n := n + 1;
    expected_n := n;
    n := 100 / (n - 5) * 0 + n;
END_PROGRAM
(* EXPECT after 3 cycles: n = 3 *)
%s
"""
MALFORMED = "malformed annotation"
IN_OTHER_COMMENT = "an annotation in a"
OWN_COMMENT = "an annotation must start its own (* *) comment"
TYPOS = [
    ("(* EXPECTED after 3 cycles: n = 999 *)", MALFORMED),
    ("(* EXPECTS after 3 cycles: n = 999 *)", MALFORMED),
    ("(* EXPCT after 3 cycles: n = 999 *)", MALFORMED),
    ("(* EXEPCT after 3 cycles: n = 999 *)", MALFORMED),
    ("(* expect after 3 cycles: n = 999 *)", MALFORMED),
    ("(* Expect after 3 cycles: n = 999 *)", MALFORMED),
    ("(* EXPECT 3 cycles: n = 999 *)", MALFORMED),
    ("(* EXPECT at 3 cycles: n = 999 *)", MALFORMED),
    ("(* EXPECT after 3 cycles n = 999 *)", MALFORMED),
    ("(* EXPECT after three cycles: n = 999 *)", MALFORMED),
    ("(* EXPECT AFTER 3 CYCLES: n = 999 *)", MALFORMED),
    ("(*EXPECT after 3 cycle s: n = 999 *)", MALFORMED),
    ("(* INPUTS at cycle 2: n = 50 *)", MALFORMED),
    ("(* INPUT at 2: n = 50 *)", MALFORMED),
    ("(* input at cycle 2: n = 50 *)", MALFORMED),
    ("(* IMPUT at cycle 2: n = 50 *)", MALFORMED),
    ("(* EXPECT FAULT in cycle 5 at line 9 *)", MALFORMED),
    ("(* EXPECT FAULT in cycle 5 at line 9: *)", "EXPECT FAULT needs the fault's exact name"),
    ("(* EXPECT FAULT in cycle 5 at line 9: division *)",
     "EXPECT FAULT needs the fault's exact name"),
    ("(* EXPECT FAULT in cycle 5 at line 9: Division by zero *)",
     "EXPECT FAULT needs the fault's exact name"),
    ("(* EXPECT FAULT at cycle 5 in line 9: division by zero *)", MALFORMED),
    ("(* @intervall T#100ms *)", MALFORMED),
    ("(* @Interval T#100ms *)", MALFORMED),
    ("(* interval T#100ms *)", MALFORMED),
    ("(* @interval fast *)", "is not a time"),
    ("(* @interval T#0ms *)", "one @interval, greater than zero"),
    ("(* @interval T#5ms *)\n(* @interval T#10ms *)", "one @interval, greater than zero"),
    ("(* EXPECT after 3 cycles: *)", "the annotation lists no values"),
    ("(* EXPECT after 3 cycles: n *)", "cannot read 'n'"),
    ("(* EXPECT after 3 cycles: n = 9 9 *)", "cannot read the value '9 9'"),
    ("(* EXPECT after 3 cycles: n = -TRUE *)", "cannot read the value '-TRUE'"),
    ("(* EXPECT after 0 cycles: n = 0 *)", "cycles count from 1"),
    ("// EXPECT after 3 cycles: n = 999", IN_OTHER_COMMENT),
    ("//EXPECTED after 3 cycles: n = 999", IN_OTHER_COMMENT),
    ("{ EXPECT after 3 cycles: n = 999 }", IN_OTHER_COMMENT),
    ("// INPUT at cycle 2: n = 50", IN_OTHER_COMMENT),
    ("(* EXPECT after 2 cycles: n = 2;\n   EXPECT after 4 cycles: n = 999 *)", OWN_COMMENT),
    ("(* The counter counts cycles.\n   EXPECT after 4 cycles: n = 999 *)", OWN_COMMENT),
    ("(* The counter counts cycles.\n   EXPECTED after 4 cycles: n = 999 *)", OWN_COMMENT),
    ("(* The counter counts cycles.\n * INPUT at cycle 2: n = 50 *)", OWN_COMMENT),
]
# comments that only look a little like annotations stay comments
ACCEPTED = [
    "(* EXPT: the power function; EXP: e to the x *)",
    "(* Integer inputs are INT; INT is 16 bits *)",
    "(* the expected value of n is 3 *)",
    "(* Except for n, nothing changes *)",
    "// the EXPECT above checks n\n{ pragma }",
    "(* EXPECT after 2 cycles: expected_n = 2;\n   n = 2 *)",
    "(* INPUT at cycle 2: n = 50 *)\n(* EXPECT after 2 cycles: n = 51 *)",
    "(* @interval T#100ms *)",
]


def _write(tmp_path, annotation):
    f = tmp_path / "typo.st"
    f.write_text(TEMPLATE % annotation)
    return f


@pytest.mark.parametrize("annotation, message", TYPOS, ids=[a for a, _ in TYPOS])
def test_mistyped_annotation_is_rejected(tmp_path, annotation, message):
    f = _write(tmp_path, annotation)
    with pytest.raises(runner.CaseError) as exc:
        runner.load_case(f, "harness")
    assert message in str(exc.value), str(exc.value)
    # the message points at the file and line of the bad annotation (in the
    # multi-line examples, their second line)
    if message != "cycles count from 1":
        line = TEMPLATE.split("\n").index("%s") + 1 + ("\n" in annotation)
        assert str(exc.value).startswith(f"{f}:{line}: "), str(exc.value)


@pytest.mark.parametrize("annotation", ACCEPTED)
def test_ordinary_comments_and_good_annotations_are_accepted(tmp_path, annotation):
    case = runner.load_case(_write(tmp_path, annotation), "harness")
    assert case.checkpoints[0][0] == 3 and case.checkpoints[0][1][0].text == "3"


def test_good_annotations_are_read(tmp_path):
    case = runner.load_case(_write(tmp_path, ACCEPTED[-2] + "\n" + ACCEPTED[-1] + "\n"
                                   "(* EXPECT FAULT in cycle 5 at line 9: division by zero *)"),
                            "harness")
    assert case.inputs == [(2, "n", "50")]
    assert [c for c, _ in case.checkpoints] == [3, 2]
    assert case.faults == [(5, 9, "division by zero")]
    assert case.interval_ns == 100_000_000


def test_fault_names_come_from_the_runtime():
    assert "division by zero" in runner.FAULT_NAMES
    assert "array index out of range" in runner.FAULT_NAMES
    assert len(runner.FAULT_NAMES) == len(set(runner.FAULT_NAMES)) >= 7


# ------------------------------------------------------- typed expectations
@pytest.fixture(scope="module")
def verify_run():
    cases = {f.stem: runner.load_case(f, "harness") for f in sorted((BROKEN / "verify").glob("*.st"))}
    assert sorted(cases) == ["bool_as_int", "other_types", "right_types", "string_vs_enum",
                             "wrong_fault"]
    run = runner.run_group("harness_verify", list(cases.values()))
    assert run.error is None, run.error
    return cases, run


def test_right_types_pass(verify_run):
    cases, run = verify_run
    assert runner.verify(cases["right_types"], run) == []


def test_bool_expected_as_1_or_0_fails(verify_run):
    cases, run = verify_run
    # the values are there and equal as numbers: only the typing rejects them
    vals = run.result.values_at(0)
    assert vals["bool_as_int.b"] is True and vals["bool_as_int.z"] is False
    problems = runner.verify(cases["bool_as_int"], run)
    assert len(problems) == 2 and all("is BOOL" in p and "TRUE or FALSE" in p
                                      for p in problems), problems


def test_string_and_enum_names_do_not_match_each_other(verify_run):
    cases, run = verify_run
    problems = runner.verify(cases["string_vs_enum"], run)
    assert len(problems) == 2, problems
    assert problems[0].startswith("s is STRING: the expected value RED is not a literal")
    assert problems[1].startswith("c is Lamp: the expected value 'RED' is not a literal")


def test_other_wrong_types_fail(verify_run):
    cases, run = verify_run
    problems = runner.verify(cases["other_types"], run)
    assert [p.split(":")[0] for p in problems] == ["t is TIME", "i is INT", "m is Mode",
                                                   "r is REAL", "i is INT", "w is WSTRING"]
    assert "not one of its values (IDLE, BUSY)" in problems[2]
    assert "'==' (exact) is for REAL/LREAL" in problems[4]


def test_wrong_fault_name_fails(verify_run):
    cases, run = verify_run
    problems = runner.verify(cases["wrong_fault"], run)
    assert len(problems) == 1, problems
    assert problems[0].startswith("expected fault 'array index out of range' in cycle 2 at "
                                  "line 10; got 'division by zero' at wrong_fault.st:10")


def test_unknown_path_fails(verify_run):
    cases, run = verify_run
    case = runner.Case(cases["right_types"].path, "harness", "right_types",
                       checkpoints=[(1, [runner.Check("no_such_var", "TRUE")])])
    assert runner.verify(case, run) == ["after 1 cycles: no variable no_such_var"]


@pytest.mark.parametrize("value, message", [
    ("1", "start is BOOL: the expected value 1 is not a literal of that type"),
    ("TRUE; nothing = 3", "INPUT at cycle 2: no variable nothing"),
])
def test_mistyped_input_is_rejected(tmp_path, value, message):
    """An INPUT of 1 for a BOOL was written as TRUE by the simulator."""
    f = tmp_path / "typed_input.st"
    f.write_text("PROGRAM typed_input\nVAR start : BOOL; n : INT; END_VAR\n"
                 "    IF start THEN n := n + 1; END_IF;\nEND_PROGRAM\n"
                 f"(* INPUT at cycle 2: start = {value} *)\n(* EXPECT after 3 cycles: n = 2 *)\n")
    run = runner.run_group("harness_typed_input", [runner.load_case(f, "harness")])
    assert run.error and message in run.error, run.error
