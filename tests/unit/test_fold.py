"""One constant folder (issue 24 item 3): the checker folds every literal
expression it types and sets Expr.const; constant expressions that name
constants are folded by the same rules (Declarer.const_value) and carry
their value too; the back ends read const instead of folding."""

from __future__ import annotations

from iec2kmod import ast
from iec2kmod.checks import check_project
from iec2kmod.diagnostics import Diagnostics, SourceFile
from iec2kmod.parse.parser import parse_source

SRC = """
PROGRAM p
VAR CONSTANT N : INT := 4; END_VAR
VAR i : INT := 2 * 3; b : BOOL; w : WORD; END_VAR
i := -(3 * 4) + 1;
i := i + 7 / 2;
w := NOT WORD#16#F0F0 AND 16#FF;
b := TRUE XOR FALSE;
CASE i OF N * 2 - 1: i := 0; END_CASE;
END_PROGRAM
"""


def _unit():
    diags = Diagnostics()
    unit = parse_source(SourceFile("t.st", SRC), diags)
    check_project([unit], diags)
    assert not diags.errors, [d.format() for d in diags.items]
    return unit


def test_the_checker_sets_the_value_of_every_literal_expression():
    body = _unit().pous[0].body
    v1, v2, v3, v4 = (s.value for s in body[:4])
    assert (v1.const, v1.left.const, v1.left.operand.const) == (-11, -12, 12)
    # a variable has no value: neither has what it is in; its literal part has
    assert (v2.const, v2.right.const) == (None, 3)
    assert v3.const == (~0xF0F0) & 0xFF
    assert v4.const is True


def test_constant_expressions_with_names_carry_their_value():
    unit = _unit()
    case = unit.pous[0].body[4]
    (label, _), = case.elements[0][0]
    assert label.const == 7 and label.left.const == 8
    init = unit.pous[0].blocks[1].decls[0].init
    assert init.const == 6


def test_the_folders_rules():
    from iec2kmod.checks import fold
    assert fold.binary("/", -7, 2) == -3 and fold.binary("MOD", -7, 2) == -1
    assert fold.unary("NOT", True) is False and fold.unary("NOT", 5) == ~5
    node = ast.BinOp(0, "/", ast.Lit(0, "1", "int", 1), ast.Lit(0, "0", "int", 0))
    node.left.const, node.right.const = 1, 0
    assert fold.node(node) is None        # a division by zero has no value
