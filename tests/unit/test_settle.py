"""The checker decides the type every standard call is computed in (issue
24 item 3): ``sig`` on each standard function call and arithmetic operator
(checks/settle.py), the context's type for an untyped one, and no back end
works it out again."""

from __future__ import annotations

import re
from pathlib import Path

from iec2kmod import ast
from iec2kmod.checks import check_project
from iec2kmod.diagnostics import Diagnostics, SourceFile
from iec2kmod.parse.parser import parse_source

ROOT = Path(__file__).resolve().parents[2]


def _checked(text):
    diags = Diagnostics()
    unit = parse_source(SourceFile("t.st", text), diags)
    assert unit is not None
    check_project([unit], diags)
    assert not diags.errors, [d.format() for d in diags.items]
    return unit


def _calls(node, out):
    """Every standard call and arithmetic operator under node, by text."""
    if isinstance(node, (ast.Call, ast.BinOp)) and (
            getattr(node, "fn", None) is not None or
            getattr(getattr(node, "target", None), "standard", False)):
        out[repr(node)] = node
    if isinstance(node, (list, tuple)):
        for x in node:
            _calls(x, out)
    elif isinstance(node, (ast.Node, ast.Expr, ast.Arg)):
        for k in type(node).__slots__ + ("left", "right", "operand", "args", "value"):
            if k != "pos" and hasattr(node, k):
                _calls(getattr(node, k), out)
    return out


def _sig(node):
    def name(t):
        return "literal" if type(t).__name__ in ("LiteralT", "AnyIntResult") else t.name
    res, pts = node.sig
    return name(res), [name(t) for t in pts]


PROGRAM = """
PROGRAM p
VAR i : INT; l : LINT; r : REAL; b : BOOL; w : DWORD; END_VAR
i := ABS(-3) + 1;
l := TRUNC(1.0E10) + 1;
r := SQRT(2.0) * 2.0;
b := (1 + 2) > i;
w := SHL(1, 2);
i := i * (2 + 3);
IF MAX(1, 2) = 2 THEN i := 0; END_IF;
END_PROGRAM
"""


def test_every_standard_call_has_the_types_of_its_context():
    unit = _checked(PROGRAM)
    calls = _calls(unit.pous[0].body, {})
    got = {text: _sig(n) for text, n in calls.items()}
    assert got == {
        # an untyped call takes its context's type, down to its operands
        "(ABS((- 3)) + 1)": ("INT", ["INT", "INT"]),
        "ABS((- 3))": ("INT", ["INT"]),
        "(TRUNC(1.0E10) + 1)": ("LINT", ["LINT", "LINT"]),
        "TRUNC(1.0E10)": ("LINT", ["LREAL"]),
        "(SQRT(2.0) * 2.0)": ("REAL", ["REAL", "REAL"]),
        "SQRT(2.0)": ("REAL", ["REAL"]),
        # a comparison computes its untyped operand in the other's type
        "(1 + 2)": ("INT", ["INT", "INT"]),
        "SHL(1, 2)": ("DWORD", ["DWORD", "DINT"]),
        "(i * (2 + 3))": ("INT", ["INT", "INT"]),
        "(2 + 3)": ("INT", ["INT", "INT"]),
        # no context: MAX takes the literal's own type
        "MAX(1, 2)": ("DINT", ["DINT", "DINT"]),
    }, got


def test_a_comparison_of_literals_computes_them_in_their_own_type():
    unit = _checked("PROGRAM p\nVAR b : BOOL; END_VAR\nb := 7 / 2 * 2 = 6;\nEND_PROGRAM\n")
    calls = _calls(unit.pous[0].body, {})
    assert {t: _sig(n) for t, n in calls.items()} == {
        "((7 / 2) * 2)": ("DINT", ["DINT", "DINT"]),
        "(7 / 2)": ("DINT", ["DINT", "DINT"]),
    }


def test_il_operators_carry_the_checkers_function():
    unit = _checked("PROGRAM p\nVAR i : INT; END_VAR\nLD i\nADD 2\nGT 3\nEND_PROGRAM\n")
    instrs = [x for x in unit.pous[0].body if x.op in ("ADD", "GT")]
    assert [(x.std.family, _sig(x)) for x in instrs] == [
        ("ADD", ("INT", ["INT", "INT"])), ("GT", ("BOOL", ["INT", "INT"]))]


def test_no_back_end_works_out_a_calls_types():
    """interp, verify and codegen read sig; the rule lives in checks/."""
    rule = re.compile(r"\bcall_types\(|\bstdlib\.resolve\(")
    hits = []
    for sub in ("interp", "verify", "codegen"):
        for f in sorted((ROOT / "iec2kmod" / sub).rglob("*.py")):
            for n, line in enumerate(f.read_text().splitlines(), 1):
                if rule.search(line):
                    hits.append(f"{f.relative_to(ROOT)}:{n}: {line.strip()}")
    assert not hits, hits


def test_a_comparison_carries_the_type_its_operands_are_compared_in():
    unit = _checked("PROGRAM p\nVAR b : BOOL; i : INT; r : LREAL; END_VAR\n"
                    "b := (1 + 2) > i;\nb := r = 1;\nb := 3 = 4;\nEND_PROGRAM\n")
    got = [_sig(s.value) for s in unit.pous[0].body]
    assert got == [("BOOL", ["INT", "INT"]), ("BOOL", ["LREAL", "LREAL"]),
                   ("BOOL", ["DINT", "DINT"])]


def test_a_literal_argument_keeps_its_value_where_every_argument_is_untyped():
    # MAX(0, 4000000000): the arguments' common type (types.common) has no
    # value; a literal given that type was made concrete as a DINT by the
    # interpreter and verify (4000000000 stored as -294967296) while C
    # computed MAX in LINT.  Each literal keeps its own value, in the common
    # category (LIMIT(0, 5, 1.5): every argument a real literal)
    from iec2kmod.checks.types import concrete
    unit = _checked("PROGRAM p\nVAR l : LINT; r : LREAL; END_VAR\n"
                    "l := MAX(0, 4000000000);\nr := LIMIT(0, 5, 1.5);\nEND_PROGRAM\n")
    mx, lim = [s.value for s in unit.pous[0].body]
    got = [[(type(a.value.type).__name__, a.value.type.cat, a.value.type.value,
             concrete(a.value.type).name) for a in c.args] for c in (mx, lim)]
    assert got == [
        [("LiteralT", "int", 0, "DINT"), ("LiteralT", "int", 4000000000, "LINT")],
        [("LiteralT", "real", 0.0, "LREAL"), ("LiteralT", "real", 5.0, "LREAL"),
         ("LiteralT", "real", 1.5, "LREAL")],
    ], got


def test_mux_computes_an_untyped_input_in_its_result_type():
    # the inputs are of MUX's result type (LINT here), K of its own: the
    # checker gave 2147483647 * 2 a DINT (-2) where the back ends converted
    # MUX's inputs to LINT, and verify's encoding failed on the widths
    unit = _checked("PROGRAM p\nVAR l : LINT; END_VAR\nl := MUX(1, 5, 2147483647 * 2);\n"
                    "END_PROGRAM\n")
    calls = _calls(unit.pous[0].body, {})
    assert {t: _sig(n) for t, n in calls.items()} == {
        "MUX(1, 5, (2147483647 * 2))": ("LINT", ["DINT", "LINT", "LINT"]),
        "(2147483647 * 2)": ("LINT", ["LINT", "LINT"]),
    }


def test_an_initial_value_is_the_checkers_fold():
    # an initial value is never typed by the body checker: its operators have
    # no sig, and the C emitter stopped on them (AttributeError, an internal
    # error); it emits the value checks/fold.py gave, as the interpreter does
    from iec2kmod.codegen import generate
    diags = Diagnostics()
    unit = parse_source(SourceFile("t.st", "PROGRAM p\nVAR k : INT := 2 + 3; "
                                   "l : LINT := 2147483647 + 1; r : LREAL := -(1 + 1); END_VAR\n"
                                   "k := k + 1;\nEND_PROGRAM\n"), diags)
    project = check_project([unit], diags)
    assert not diags.errors
    inits = [ln.strip() for ln in generate(project).header.splitlines()
             if ln.strip().startswith("self->v_")]
    assert inits == ["self->v_k = ((iec_int)5);", "self->v_l = ((iec_lint)2147483648LL);",
                     "self->v_r = (-((iec_lreal)2.0));"], inits


def test_literal_arithmetic_in_a_context_it_cannot_be_computed_in_is_exact():
    # a bit string, BOOL, MOD into a REAL: no context (stdlib.NUMERIC_CONTEXT);
    # the call was computed in BYTE / LREAL, which C has no function for
    unit = _checked("PROGRAM p\nVAR x : BYTE; r : LREAL; b : BOOL; i : INT; END_VAR\n"
                    "x := 1 + 2;\nr := 7 MOD 2;\nb := 1 + 0;\ni := 1 + 2;\nEND_PROGRAM\n")
    got = [_sig(s.value) for s in unit.pous[0].body]
    assert got == [("literal", ["literal", "literal"])] * 3 + [("INT", ["INT", "INT"])], got
