"""Constructs of the standard that real programs (the standard's Annex F
examples, OpenPLC Editor and Beremiz output) use and that were refused
(issue 10): each accepted with the standard's meaning, its model checked
here; their execution is in tests/execution/cases (C and interpreter)."""

import pytest

from iec2kmod import ast
from helpers import check, errors, expr, parse_ok

pytestmark = pytest.mark.unit


# ---------------------------------------------- 1. a comment after a type name

@pytest.mark.parametrize("text", [
    "TYPE T : INT (* c *) ; END_TYPE",
    "TYPE T : INT (* c *) := 5; END_TYPE",
    "TYPE S : STRUCT a : INT (* c *) ; b : BOOL // c\n; END_STRUCT; END_TYPE",
    "FUNCTION F : WORD (* BCD encoded *)\nVAR_INPUT x : INT (* c *) ; END_VAR\n"
    "F := INT_TO_WORD(x);\nEND_FUNCTION",
    "FUNCTION F : INT\n(* a comment on the next line *)\nVAR_INPUT x : INT; END_VAR\n"
    "F := x;\nEND_FUNCTION",
    "FUNCTION_BLOCK B\nVAR t : TON (* c *) ; x : INT (* c *) := 3; END_VAR\nEND_FUNCTION_BLOCK",
    "PROGRAM P\nVAR x : INT (* c *) ; y : INT(0..10) (* c *) ; END_VAR\nx := y;\nEND_PROGRAM",
])
def test_comment_after_a_type_name(text):
    assert errors(text) == []


def test_comment_after_a_type_name_model():
    unit = parse_ok("TYPE T : INT (* c *) ; R : INT (0..9) ; END_TYPE\n"
                    "FUNCTION F : WORD (* c *)\nF := 0;\nEND_FUNCTION")
    t, r = unit.types
    assert isinstance(t.spec, ast.NamedSpec) and t.spec.name.upper() == "INT"
    assert isinstance(r.spec, ast.SubrangeSpec)      # INT (...) is still a subrange
    assert unit.pous[0].result.name.upper() == "WORD"


# --------------------------------------- 2. IL CAL with a comment, then a line

def test_il_cal_with_comment_then_instruction():
    unit = parse_ok("PROGRAM P\nVAR T : TON; q : BOOL; END_VAR\n"
                    "CAL T (* run timer *)\nLD T.Q\nST q\n"
                    "CAL T // again\nCAL T(IN := q,\n  PT := T#1s) (* c *)\nEND_PROGRAM")
    ops = [(i.op, i.fb, len(i.args or [])) for i in unit.pous[0].body]
    assert ops == [("CAL", "T", 0), ("LD", None, 0), ("ST", None, 0), ("CAL", "T", 0),
                   ("CAL", "T", 2)]


# ---------------------------------------- 3. untyped literal reaching a label

STACK_PATTERN = """PROGRAM P
VAR OUT : {t}; c : BOOL; v : {t}; END_VAR
LD c
JMPC ZRO
LD v
JMP SET
ZRO: LD {lit}
SET: ST OUT
END_PROGRAM
"""


@pytest.mark.parametrize("t, lit", [("INT", "0"), ("SINT", "-128"), ("REAL", "0.5"),
                                    ("UINT", "65535")])
def test_literal_takes_the_type_of_the_label(t, lit):
    assert check(STACK_PATTERN.format(t=t, lit=lit)) == []


@pytest.mark.parametrize("t, lit, other", [("SINT", "300", "DINT"), ("INT", "0.5", "LREAL"),
                                           ("UINT", "-1", "DINT")])
def test_literal_that_does_not_fit_the_label_is_a_conflict(t, lit, other):
    errs = errors(STACK_PATTERN.format(t=t, lit=lit))
    assert len(errs) == 1 and "after label 'SET'" in errs[0] and other in errs[0] and t in errs[0]


def test_two_typed_paths_still_conflict():
    text = STACK_PATTERN.format(t="INT", lit="v").replace("v : INT", "v : INT; w : DINT") \
        .replace("ZRO: LD v", "ZRO: LD w")
    errs = errors(text)
    assert len(errs) == 1 and ("DINT or INT" in errs[0] or "INT or DINT" in errs[0]), errs


# ------------------------------------- 4. function forms of MOD AND OR XOR

@pytest.mark.parametrize("text, tree", [
    ("MOD(b + 1, 128)", "MOD((b + 1), 128)"),
    ("mod (IN1 := b, IN2 := 3)", "MOD(IN1 := b, IN2 := 3)"),
    ("AND(x, y, z)", "AND(x, y, z)"),
    ("OR(x, y) AND XOR(x, y)", "(OR(x, y) AND XOR(x, y))"),
    ("NOT(IN := c) AND NOT (c)", "(NOT(IN := c) AND (NOT c))"),   # formal: the function
    ("a MOD (b)", "(a MOD b)"),              # still the operator after an operand
    ("a AND (b OR c)", "(a AND (b OR c))"),
])
def test_keyword_function_forms(text, tree):
    e = expr(text)
    assert repr(e) == tree


def test_keyword_function_forms_check():
    assert errors("PROGRAM P\nVAR a, b : INT; x, y : WORD; c : BOOL; END_VAR\n"
                  "a := MOD(b + 1, 128);\nx := AND(x, y);\nx := OR(x, y, 16#F);\n"
                  "x := XOR(x, y);\nc := AND(c, NOT c);\nEND_PROGRAM") == []
    errs = errors("PROGRAM P\nVAR a : INT; r : REAL; END_VAR\na := MOD(a);\nr := AND(r, r);\n"
                  "END_PROGRAM")
    assert len(errs) == 2, errs


# ------------------------------------------- 5. ENO inside a function body

def _project(text):
    from iec2kmod.checks import check_project
    from iec2kmod.diagnostics import Diagnostics, SourceFile
    from iec2kmod.parser import parse_source
    diags = Diagnostics()
    unit = parse_source(SourceFile("t.st", text), diags)
    project = check_project([unit], diags)
    assert not diags.errors, [d.format() for d in diags.items]
    return project


@pytest.mark.parametrize("body", ["IF x < 0 THEN ENO := FALSE; END_IF;\nF := x;",
                                  "LD x\nLT 0\nNOT\nST ENO\nLD x\nST F"])
def test_eno_in_a_function_body_is_its_implicit_output(body):
    p = _project(f"FUNCTION F : INT\nVAR_INPUT x : INT; END_VAR\n{body}\nEND_FUNCTION\n"
                 "PROGRAM P\nVAR a : INT; ok : BOOL; END_VAR\na := F(a, ENO => ok);\nEND_PROGRAM")
    f = p.pous["F"]
    eno = f.var("ENO")
    assert eno.section == "VAR_OUTPUT" and eno.type.name == "BOOL" and eno.init.value is True
    assert f.outputs == [eno]
    call = p.pous["P"].node.body[0].value
    assert call.bound["ENO"].kind == "out"        # the call's ENO => receives it


def test_eno_is_not_added_where_unused():
    p = _project("FUNCTION F : INT\nVAR_INPUT x : INT; END_VAR\nF := x;\nEND_FUNCTION\n"
                 "FUNCTION_BLOCK B\nVAR_INPUT x : INT; END_VAR\nEND_FUNCTION_BLOCK\n"
                 "PROGRAM P\nVAR a : INT; ok : BOOL; END_VAR\na := F(a, ENO => ok);\n"
                 "END_PROGRAM")
    assert p.pous["F"].var("ENO") is None and p.pous["B"].var("ENO") is None


def test_eno_in_a_program_is_still_unknown():
    errs = errors("PROGRAM P\nENO := FALSE;\nEND_PROGRAM")
    assert errs == ["2:1: error: unknown variable 'ENO'"]


# ------------------------------- 6. untyped real literal typed by its context

def test_real_literal_takes_the_type_of_its_context():
    assert errors("PROGRAM P\nVAR X : REAL; L : LREAL; b : BOOL; END_VAR\nX := SQRT(2.0);\n"
                  "L := SQRT(2.0);\nb := ABS(X - 1.4142135) < 1.0E-6;\nX := SIN(0.5) + X;\n"
                  "X := ATAN2(1.0, 2.0);\nb := SQRT(2.0) > X;\nEND_PROGRAM") == []
    p = _project("PROGRAM P\nVAR X : REAL; END_VAR\nX := SQRT(2.0);\nEND_PROGRAM")
    call = p.pous["P"].node.body[0].value
    assert call.type.name == "REAL"            # decided by X, not LREAL


def test_typed_arguments_still_decide():
    errs = errors("PROGRAM P\nVAR X : REAL; L : LREAL; END_VAR\nX := SQRT(L);\nEND_PROGRAM")
    assert len(errs) == 1 and "cannot assign LREAL to 'X' of type REAL" in errs[0]


# --------------------------------------------------- 7. VAR_ACCESS in a PROGRAM

def test_program_access_paths_are_recorded():
    p = _project("TYPE R : STRUCT a : INT; END_STRUCT; END_TYPE\n"
                 "PROGRAM P\nVAR x : INT; t : TON; r : R; END_VAR\n"
                 "VAR_ACCESS ax : x : INT READ_WRITE; aq : t.Q : BOOL READ_ONLY;\n"
                 "  ar : r.a : INT; END_VAR\nx := 1;\nEND_PROGRAM")
    pou = p.pous["P"]
    assert [(n, path, v.name, d) for n, path, v, d in pou.access] == [
        ("ax", "x", "x", "READ_WRITE"), ("aq", "t.Q", "t", "READ_ONLY"),
        ("ar", "r.a", "r", "READ_WRITE")]


# ------------------------------------- the rule of directly represented variables

def test_located_variable_message_names_the_rule_and_the_fix():
    errs = errors("PROGRAM Ctrl\nVAR_OUTPUT m : BOOL; END_VAR\nVAR q AT %QX0.1 : BOOL; END_VAR\n"
                  "m := %IX0.1;\nq := m;\nEND_PROGRAM")
    assert len(errs) == 2
    assert "rule of located variables" in errs[0] and \
        "VAR_GLOBAL q AT %QX0.1 : BOOL; END_VAR" in errs[0] and \
        "PROGRAM inst WITH task : Ctrl (q => %QX0.1)" in errs[0]
    assert "rule of located variables" in errs[1] and "(x := %IX0.1)" in errs[1]


# -------------------------- 8. calls on array elements, LDATE#, generic TRUNC

def test_call_of_an_array_element_of_fb_instances():
    p = _project("PROGRAM P\nVAR t : ARRAY[1..2] OF TON; x, q : BOOL; i : INT := 1; END_VAR\n"
                 "t[1](IN := x, PT := T#1s);\nt[i + 1](IN := NOT x);\nq := t[i].Q;\n"
                 "END_PROGRAM")
    c = p.pous["P"].node.body[0].call
    assert c.ref is not None and repr(c.ref) == "t[1]" and c.ref.type.name == "TON"
    assert c.target.name == "t" and set(c.bound) == {"IN", "PT"}


@pytest.mark.parametrize("stmt, msg", [
    ("a[1](IN := x);", "'a[1]' is INT, not a function block instance: it cannot be called"),
    ("t[1].Q(IN := x);", "'t[1].Q' cannot be called: only an element of an array of function "
                         "block instances can be called this way"),
    ("t[3](IN := x);", "index 3 is out of bounds 1..2"),
    ("t[1](IN := 5);", "5 is out of range for BOOL"),
])
def test_call_of_an_array_element_errors(stmt, msg):
    errs = errors("PROGRAM P\nVAR t : ARRAY[1..2] OF TON; a : ARRAY[1..2] OF INT; x : BOOL; "
                  f"END_VAR\n{stmt}\nEND_PROGRAM")
    assert len(errs) == 1 and msg in errs[0], errs


@pytest.mark.parametrize("text, type_name", [
    ("LDATE#2020-01-01", "LDATE"), ("LD#2020-01-01", "LDATE"),
    ("LTIME_OF_DAY#12:30:00.5", "LTOD"), ("LDATE_AND_TIME#2021-03-04-05:06:07", "LDT"),
])
def test_long_date_prefixes(text, type_name):
    e = expr(text)
    assert isinstance(e, ast.Lit) and e.type_name == type_name


def test_trunc_result_type_comes_from_the_context():
    assert errors("PROGRAM P\nVAR r : REAL; l : LREAL; i : INT; s : SINT; u : UDINT; "
                  "li : LINT; END_VAR\ni := TRUNC(r);\ns := TRUNC(r);\nu := TRUNC(l);\n"
                  "li := TRUNC(l) + 1;\nEND_PROGRAM") == []
    errs = errors("PROGRAM P\nVAR r : REAL; b : BOOL; x : REAL; i : INT; END_VAR\n"
                  "b := TRUNC(r);\nx := TRUNC(r);\ni := TRUNC(i);\nEND_PROGRAM")
    assert [e.split(": error: ")[1] for e in errs] == [
        "TRUNC gives an integer (ANY_INT), and BOOL is not one: convert it explicitly "
        "(e.g. DINT_TO_BOOL)",
        "TRUNC gives an integer (ANY_INT), and REAL is not one: convert it explicitly "
        "(e.g. DINT_TO_REAL)",
        "argument 1 of TRUNC must be REAL or LREAL (ANY_REAL), not INT"]
