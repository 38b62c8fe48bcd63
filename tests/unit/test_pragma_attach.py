"""Pragmas hang on the nodes they apply to (issue 24 item 4): the parser's
last step (parse/lexical.attach) puts a {watchdog} on its Task and a
{verify}/{assume} on the POU it is written in or on the file, so that the
watchdog and verify passes read nodes, not the text."""

from __future__ import annotations

from iec2kmod.diagnostics import Diagnostics, SourceFile
from iec2kmod.parse.parser import parse_source

SRC = """\
{verify early: TRUE}
FUNCTION_BLOCK fb
VAR x : INT; END_VAR
{assume: x > 0}
x := 1;
END_FUNCTION_BLOCK
PROGRAM p
VAR n : INT; END_VAR
{verify small: n < 10}
n := n + 1;
END_PROGRAM
{assume: TRUE}
CONFIGURATION c
RESOURCE r ON PLC
{watchdog T#20ms, 2}
TASK t (INTERVAL := T#10ms, PRIORITY := 1);
{watchdog T#5ms} (* a comment between: applies to nothing *)
TASK u (INTERVAL := T#10ms, PRIORITY := 2);
PROGRAM i WITH t : p;
END_RESOURCE
END_CONFIGURATION
"""


def _unit():
    diags = Diagnostics()
    unit = parse_source(SourceFile("t.st", SRC), diags)
    assert unit is not None, [d.format() for d in diags.items]
    return unit


def test_every_pragma_of_the_file_is_on_the_unit_in_order():
    unit = _unit()
    assert [p.kind for p in unit.pragmas] == ["verify", "assume", "verify", "assume",
                                              "watchdog", "watchdog"]


def test_watchdog_on_the_task_right_behind_it():
    t, u = _unit().configurations[0].resources[0].tasks
    assert [p.body.strip() for p in t.pragmas] == ["T#20ms, 2"]
    assert u.pragmas == ()


def test_verify_and_assume_on_their_pou_or_the_file():
    unit = _unit()
    fb, p = unit.pous
    assert [x.text for x in fb.pragmas] == ["{assume: x > 0}"]
    assert [x.text for x in p.pragmas] == ["{verify small: n < 10}"]
    assert [x.text for x in unit.outside] == ["{verify early: TRUE}", "{assume: TRUE}"]
