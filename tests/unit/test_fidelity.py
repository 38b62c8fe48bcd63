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
    from iec2kmod.parse.parser import parse_source
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
    # a program's VAR may locate a variable (ed.2 located_var_declarations,
    # issue 25) and its statements may name an address (ed.2 B.1.4); a
    # function block's complete address or direct variable in a statement
    # and a located VAR_INPUT stay refused, each with its fix
    errs = errors("FUNCTION_BLOCK Ctrl\nVAR_OUTPUT m : BOOL; END_VAR\n"
                  "m := %IX0.1;\nEND_FUNCTION_BLOCK\n"
                  "FUNCTION_BLOCK B\nVAR w AT %IW4 : WORD; END_VAR\nEND_FUNCTION_BLOCK\n"
                  "PROGRAM P2\nVAR_INPUT i AT %IX0.2 : BOOL; END_VAR\nEND_PROGRAM")
    assert len(errs) == 3
    assert "%IX0.1 used in a function block: only a PROGRAM's statements" in errs[0] and \
        "(name AT %IX0.1 : ...)" in errs[0] and "(x := %IX0.1)" in errs[0]
    assert "'w' AT %IW4 in a function block" in errs[1] and "(w AT %I* : WORD)" in errs[1] \
        and "VAR_CONFIG" in errs[1]
    assert "'i' AT %IX0.2 in VAR_INPUT" in errs[2] and \
        "PROGRAM inst WITH task : P2 (i := %IX0.2)" in errs[2]


def test_direct_variables_in_a_program_are_its_located_variables():
    # ed.2 B.1.4 variable ::= direct_variable | symbolic_variable, and
    # located_var_decl ::= [variable_name] location: an address in a
    # program's statement is the variable the program locates there, or one
    # the use declares; the one-address rule covers them
    ok = ("PROGRAM P\nVAR q AT %QX0.1 : BOOL; AT %IW3 : INT; END_VAR\n"
          "q := %IX0.1;\n%QX0.2 := %IW3 > 0 AND q;\n%QX0.1 := FALSE;\nEND_PROGRAM\n")
    cfg = ("CONFIGURATION C RESOURCE R ON PLC TASK T (INTERVAL := T#10ms, PRIORITY := 1);\n"
           "PROGRAM a WITH T : P; {} END_RESOURCE END_CONFIGURATION\n")
    assert errors(ok + cfg.format("")) == []
    errs = errors(ok + cfg.format("PROGRAM b WITH T : P;"))
    assert len(errs) == 1 and "a second instance 'b' of program 'P'" in errs[0]
    errs = errors(ok + "PROGRAM P3\n%QX0.2 := TRUE;\nEND_PROGRAM\n"
                  + cfg.format("PROGRAM c WITH T : P3;"))
    assert len(errs) == 1 and "address %QX0.2 is already used by" in errs[0]
    errs = errors("PROGRAM P\n%QW0 := 1;\n%QX0.3 := TRUE;\nEND_PROGRAM\n" + cfg.format(""))
    assert len(errs) == 1 and "%QX0.3 overlaps %QW0" in errs[0]


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


# ------------------------------- named constants in constant expressions (ed.3)

def _checked(text):
    from iec2kmod.checks import check_project
    from iec2kmod.diagnostics import Diagnostics
    from iec2kmod.parse.parser import SourceFile, parse_source
    diags = Diagnostics()
    unit = parse_source(SourceFile("t.st", text), diags)
    project = check_project([unit], diags)
    return project, [f"{d.line}:{d.col}: {d.severity}: {d.message}" for d in diags.sorted()]


def test_named_constants_size_arrays_strings_and_subranges():
    project, diags = _checked("""PROGRAM P
VAR a : ARRAY[1..N, 0..W] OF INT; s : STRING[W]; r : SINT (-N..N); x : INT := N + 1; END_VAR
VAR CONSTANT W : INT := N * 2; N : INT := 3; T1 : TIME := T#1s; T2 : TIME := T1 * 2; END_VAR
a[1, 0] := x; s := 'abc'; r := 0;
END_PROGRAM""")
    # no error, and constants used only in bounds are used (T2 is not)
    assert diags == ["3:65: warning: unused variable 'T2'"]
    v = project.pous["P"].vars
    assert v["A"].type.dims == [(1, 3), (0, 6)]
    assert v["S"].type.length == 6
    assert (v["R"].type.low, v["R"].type.high) == (-3, 3)
    # initial values that name constants reach the code generators as literals
    assert isinstance(v["X"].init, ast.Lit) and v["X"].init.value == 4
    assert isinstance(v["W"].init, ast.Lit) and v["W"].init.value == 6
    assert v["T2"].init.kind == "time" and v["T2"].init.value == 2_000_000_000


def test_named_constants_label_case_branches():
    project, diags = _checked("""FUNCTION F : INT
VAR_INPUT code : INT; END_VAR
VAR CONSTANT IDLE : INT := 0; LO : INT := 10; HI : INT := LO + 9; END_VAR
CASE code OF IDLE: F := 1; LO..HI: F := 2; END_CASE;
END_FUNCTION""")
    assert diags == []
    case = project.pous["F"].node.body[0]
    assert case.values == [[(0, 0)], [(10, 19)]]


def test_configuration_constants_size_pou_types_through_var_external_constant():
    project, diags = _checked("""FUNCTION_BLOCK B
VAR_EXTERNAL CONSTANT DEPTH : INT; END_VAR
VAR h : ARRAY[1..DEPTH] OF INT; END_VAR
h[1] := 1;
END_FUNCTION_BLOCK
PROGRAM P VAR b : B; END_VAR b(); END_PROGRAM
CONFIGURATION C
VAR_GLOBAL CONSTANT DEPTH : INT := LEN_ + 1; LEN_ : INT := 4; CYCLE : TIME := T#20ms; END_VAR
VAR_GLOBAL g : ARRAY[0..DEPTH] OF BOOL; END_VAR
RESOURCE R ON CPU0
    VAR_GLOBAL CONSTANT K : INT := DEPTH * 2; END_VAR
    VAR_GLOBAL rg : ARRAY[1..K] OF INT; END_VAR
    TASK t (INTERVAL := CYCLE, PRIORITY := 1);
    PROGRAM p WITH t : P;
END_RESOURCE
END_CONFIGURATION""")
    assert [d for d in diags if "error" in d] == []
    assert project.pous["B"].vars["H"].type.dims == [(1, 5)]
    cfg = project.configurations[0]
    assert cfg.globals["G"].type.dims == [(0, 5)]
    res = cfg.resources[0]
    assert res.globals["RG"].type.dims == [(1, 10)]
    assert res.tasks["T"].interval_ns == 20_000_000


def test_named_constants_refused_with_the_reason():
    diags = errors("""FUNCTION_BLOCK B
VAR_EXTERNAL CONSTANT K : INT; END_VAR
VAR h : ARRAY[1..K] OF INT; END_VAR
h[1] := 1;
END_FUNCTION_BLOCK
PROGRAM P
VAR n : INT; a : ARRAY[1..n] OF INT; b : B; END_VAR
VAR CONSTANT X : INT := Y; Y : INT := X; R : REAL := 1.5; END_VAR
VAR c : ARRAY[1..R] OF INT; END_VAR
b(); a[1] := n; c[1] := X;
END_PROGRAM
CONFIGURATION C
RESOURCE Res ON CPU0
    VAR_GLOBAL CONSTANT K : INT := 3; END_VAR
    TASK t (INTERVAL := T#10ms, PRIORITY := 1);
    PROGRAM p WITH t : P;
END_RESOURCE
END_CONFIGURATION""")
    text = "\n".join(diags)
    assert "3:18: error: array bound: VAR_EXTERNAL CONSTANT 'K' takes its value from the " \
           "configuration's VAR_GLOBAL CONSTANT K; a resource's constant of that name cannot " \
           "give it (a POU type has one layout for all its instances)" in text
    assert "7:27: error: array bound must be a constant expression: 'n' is a variable" in text
    assert "is defined in terms of itself" in text
    assert "9:18: error: array bound must be an integer constant" in text


# ------------------------------------ ed.3 syntax outside the language: said so

@pytest.mark.parametrize("text, hint", [
    ("INTERFACE I\nEND_INTERFACE\n", "this line uses INTERFACE, IEC 61131-3 ed.3 object "
                                     "orientation, which iec2kmod does not support"),
    ("FUNCTION_BLOCK F\nVAR x : INT; END_VAR\nMETHOD PUBLIC inc : INT\nx := x + 1;\n"
     "END_METHOD\nEND_FUNCTION_BLOCK\n", "this line uses METHOD"),
    ("FUNCTION_BLOCK B EXTENDS A\nVAR x : INT; END_VAR\nx := 1;\nEND_FUNCTION_BLOCK\n",
     "this line uses EXTENDS"),
    ("PROGRAM P\nVAR r : REF_TO INT; END_VAR\nEND_PROGRAM\n", "this line uses REF_TO, "
                                                          "IEC 61131-3 ed.3 references"),
    ("PROGRAM P\nVAR x : INT; END_VAR\nTHIS^.x := 1;\nEND_PROGRAM\n",
     "this line uses '^', an ed.3 dereference"),
    ("FUNCTION S : INT\nVAR_IN_OUT a : ARRAY[*] OF INT; END_VAR\nS := 0;\nEND_FUNCTION\n",
     "this line uses ARRAY[*], an ed.3 array of variable length"),
    ("PROGRAM P\nVAR x : INT; END_VAR (* a (* nested *) comment *)\nx := 1;\nEND_PROGRAM\n",
     "a '*)' outside a comment: nested comments are not supported"),
    ("PROGRAM P\nVAR c : CHAR; END_VAR\nEND_PROGRAM\n",
     "unknown type 'CHAR' (CHAR and WCHAR are ed.3 types that iec2kmod does not support"),
])
def test_ed3_syntax_is_named_in_the_error(text, hint):
    errs = errors(text)
    assert errs and hint in errs[0], errs


def test_no_ed3_hint_on_ordinary_syntax_errors():
    # names that are ed.3 keywords elsewhere stay plain ed.2 variables
    errs = errors("PROGRAM P\nVAR final, ref, this : INT; END_VAR\nfinal := ref + ;\n"
                  "END_PROGRAM\n")
    assert errs and "ed.3" not in errs[0] and "not support" not in errs[0], errs
