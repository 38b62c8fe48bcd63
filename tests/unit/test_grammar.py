"""Every construct of the grammar and the model it must produce."""

import pytest

from iec2kmod import ast
from helpers import body, expr, parse, parse_ok

pytestmark = pytest.mark.unit


# ---------------------------------------------------------------- expressions

@pytest.mark.parametrize("text, tree", [
    ("a + b * c", "(a + (b * c))"),
    ("a * b + c", "((a * b) + c)"),
    ("a - b - c", "((a - b) - c)"),
    ("a / b MOD c", "((a / b) MOD c)"),
    ("a ** b ** c", "((a ** b) ** c)"),
    ("-a ** 2", "(- (a ** 2))"),
    ("NOT a AND b", "((NOT a) AND b)"),
    ("a OR b XOR c AND d", "(a OR (b XOR (c AND d)))"),
    ("a & b", "(a AND b)"),
    ("a = b AND c <> d", "((a = b) AND (c <> d))"),
    ("a < b = c >= d", "((a < b) = (c >= d))"),
    ("a + b < c * d", "((a + b) < (c * d))"),
    ("(a + b) * c", "((a + b) * c)"),
    ("- - a", "(- (- a))"),
    ("not not x", "(NOT (NOT x))"),
    ("a mod 3", "(a MOD 3)"),
    ("arr[i, j + 1].x.3", "arr[i, (j + 1)].x.3"),
    ("s.pos.y", "s.pos.y"),
    ("LIMIT(0, x, 10)", "LIMIT(0, x, 10)"),
    ("SEL(G := c, IN0 := a, IN1 := b)", "SEL(G := c, IN0 := a, IN1 := b)"),
    ("f()", "f()"),
    ("16#FF AND w", "(16#FF AND w)"),
    ("T#1s + t", "(T#1s + t)"),
])
def test_expression_precedence(text, tree):
    assert repr(expr(text)) == tree


def test_expression_node_kinds():
    e = expr("f(a, IN2 := 2, Q => y, NOT Q2 => z)")
    assert isinstance(e, ast.Call) and e.name == "f"
    kinds = [(a.kind, a.name, a.negate) for a in e.args]
    assert kinds == [("pos", None, False), ("in", "IN2", False), ("out", "Q", False),
                     ("out", "Q2", True)]
    lit = expr("INT#16#7F")
    assert isinstance(lit, ast.Lit) and (lit.kind, lit.value, lit.type_name) == ("int", 127, "INT")
    ref = expr("a.b[1].c.7")
    assert [k for k, _, _ in ref.accessors] == ["member", "index", "member", "bit"]


def test_keywords_are_case_insensitive():
    stmts = body("if A then b := 1; elsif c THEN b := 2; Else b := 3; end_if;")
    assert isinstance(stmts[0], ast.If) and len(stmts[0].branches) == 2
    assert stmts[0].else_ is not None


# ----------------------------------------------------------------- statements

def test_every_st_statement():
    stmts = body("""
        x := 1;
        fb(IN := a, PT := T#5s, Q => q);
        f(1, 2);
        IF a THEN ; ELSIF b THEN x := 2; ELSE x := 3; END_IF;
        CASE x OF
          1, 2: y := 1;
          3..5, 7: y := 2;
          Red: y := 3;
        ELSE
          y := 0;
        END_CASE;
        FOR i := 10 TO 0 BY -2 DO EXIT; END_FOR;
        WHILE x < 10 DO x := x + 1; END_WHILE;
        REPEAT x := x - 1; UNTIL x = 0 END_REPEAT;
        RETURN;
        ;
    """)
    kinds = [type(s).__name__ for s in stmts]
    assert kinds == ["Assign", "CallStmt", "CallStmt", "If", "Case", "For", "While", "Repeat",
                     "Return", "Empty"]
    case = stmts[4]
    labels = [[(repr(lo), repr(hi) if hi is not None else None) for lo, hi in labs]
              for labs, _ in case.elements]
    assert labels == [[("1", None), ("2", None)], [("3", "5"), ("7", None)], [("Red", None)]]
    loop = stmts[5]
    assert (loop.var, repr(loop.start), repr(loop.end), repr(loop.step)) == ("i", "10", "0", "(- 2)")
    assert isinstance(loop.body[0], ast.Exit)
    call = stmts[1].call
    assert [(a.kind, a.name) for a in call.args] == [("in", "IN"), ("in", "PT"), ("out", "Q")]


def test_nested_statements():
    stmts = body("""
        FOR i := 1 TO 3 DO
          IF i = 2 THEN
            WHILE TRUE DO EXIT; END_WHILE;
          END_IF;
        END_FOR;""")
    inner = stmts[0].body[0].branches[0][1][0]
    assert isinstance(inner, ast.While) and isinstance(inner.body[0], ast.Exit)


# ---------------------------------------------------------------------- types

def test_type_declarations():
    unit = parse_ok("""
    TYPE
      Color : (Red, Green, Blue) := Green;
      Code : INT (Idle := 0, Run := 10, Stop);
      Level : INT (0..100) := 50;
      Grid : ARRAY[1..3, 0..1] OF REAL := [2(1.0), 4(0.0)];
      Point : STRUCT x : INT := 1; y : REAL; END_STRUCT;
      Name : STRING[20] := 'abc';
      WName : WSTRING(8);
      Speed : LREAL;
      Points : ARRAY[0..9] OF Point := [(x := 1, y := 2.0), 9((x := 0))];
    END_TYPE
    """)
    t = {td.name: td for td in unit.types}
    assert [v[0] for v in t["Color"].spec.values] == ["Red", "Green", "Blue"]
    assert repr(t["Color"].init) == "Green"
    code = t["Code"].spec
    assert code.base == "INT" and [(n, repr(v)) for n, v, _ in code.values] == [
        ("Idle", "0"), ("Run", "10"), ("Stop", "None")]
    lvl = t["Level"].spec
    assert isinstance(lvl, ast.SubrangeSpec) and (lvl.base, repr(lvl.low), repr(lvl.high)) == (
        "INT", "0", "100")
    grid = t["Grid"]
    assert [(repr(a), repr(b)) for a, b in grid.spec.ranges] == [("1", "3"), ("0", "1")]
    assert [(c, repr(v)) for c, v in grid.init.items] == [(2, "1.0"), (4, "0.0")]
    pt = t["Point"].spec
    assert [m.names[0][0] for m in pt.members] == ["x", "y"] and repr(pt.members[0].init) == "1"
    assert isinstance(t["Name"].spec, ast.StringSpec) and repr(t["Name"].spec.length) == "20"
    assert t["WName"].spec.wide and repr(t["WName"].spec.length) == "8"
    assert isinstance(t["Speed"].spec, ast.NamedSpec)
    pts = t["Points"].init.items
    assert pts[0][0] is None and isinstance(pts[0][1], ast.StructInit)
    assert pts[1][0] == 9 and [f[0] for f in pts[1][1].fields] == ["x"]


# --------------------------------------------------------------- declarations

def test_pou_declarations_and_var_sections():
    unit = parse_ok("""
    FUNCTION Scale : REAL
      VAR_INPUT raw : INT; lo, hi : REAL := 0.0; END_VAR
      VAR_TEMP t : REAL; END_VAR
      Scale := lo + INT_TO_REAL(raw) * (hi - lo);
    END_FUNCTION

    FUNCTION_BLOCK Edge
      VAR_INPUT clk : BOOL R_EDGE; fall : BOOL F_EDGE; END_VAR
      VAR_OUTPUT q : BOOL; END_VAR
      VAR_IN_OUT count : DINT; END_VAR
      VAR RETAIN n : DINT; END_VAR
      VAR NON_RETAIN m : DINT; END_VAR
      VAR CONSTANT k : DINT := 3; END_VAR
      q := clk;
    END_FUNCTION_BLOCK

    PROGRAM Main
      VAR_EXTERNAL run : BOOL; END_VAR
      VAR_EXTERNAL CONSTANT limit : INT; END_VAR
      VAR_GLOBAL shared : INT; END_VAR
      VAR in AT %I* : BOOL; END_VAR
      ;
    END_PROGRAM
    """)
    f, fb, prog = unit.pous
    assert (f.kind, f.name, f.result.name, f.language) == ("FUNCTION", "Scale", "REAL", "ST")
    assert [b.kind for b in f.blocks] == ["VAR_INPUT", "VAR_TEMP"]
    assert [n for n, _ in f.blocks[0].decls[1].names] == ["lo", "hi"]
    assert [b.kind for b in fb.blocks] == ["VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR", "VAR",
                                           "VAR"]
    assert [d.edge for d in fb.blocks[0].decls] == ["R_EDGE", "F_EDGE"]
    assert [b.qualifiers for b in fb.blocks[3:]] == [("RETAIN",), ("NON_RETAIN",), ("CONSTANT",)]
    assert prog.blocks[1].qualifiers == ("CONSTANT",)
    assert prog.blocks[3].decls[0].location == "%I*"


def test_located_declarations():
    unit = parse_ok("""
    CONFIGURATION c
      VAR_GLOBAL
        a AT %IX0.0 : BOOL;
        b AT %QW4 : WORD;
        m AT %MD10 : DINT;
        deep AT %IX1.2.3 : BOOL;
      END_VAR
      VAR_GLOBAL CONSTANT k : INT := 5; END_VAR
      VAR_GLOBAL RETAIN r : INT; END_VAR
      TASK t (INTERVAL := T#10ms, PRIORITY := 1);
      PROGRAM p WITH t : P;
    END_CONFIGURATION
    """)
    cfg = unit.configurations[0]
    assert [d.location for d in cfg.blocks[0].decls] == ["%IX0.0", "%QW4", "%MD10", "%IX1.2.3"]
    assert cfg.blocks[1].qualifiers == ("CONSTANT",) and cfg.blocks[2].qualifiers == ("RETAIN",)
    # a configuration without RESOURCE has one implicit resource
    assert len(cfg.resources) == 1 and cfg.resources[0].name is None


def test_configuration_resources_tasks_programs():
    unit = parse_ok("""
    CONFIGURATION Plant
      VAR_GLOBAL level : INT; alarm AT %QX0.1 : BOOL; END_VAR
      RESOURCE r1 ON CPU0
        VAR_GLOBAL local : REAL; END_VAR
        TASK fast (INTERVAL := T#1ms, PRIORITY := 0);
        TASK ev (SINGLE := trigger, PRIORITY := 2);
        PROGRAM p1 WITH fast : Ctrl (sp := 10, in := %IW2, out => level, q => %QX0.0);
        PROGRAM RETAIN p2 WITH ev : Logger;
        PROGRAM p3 : Idle;
      END_RESOURCE
      RESOURCE r2 ON CPU1
        TASK slow (INTERVAL := T#100ms, PRIORITY := 5);
        PROGRAM p4 WITH slow : Ctrl;
      END_RESOURCE
      VAR_ACCESS
        lvl : r1.p1.level : INT READ_ONLY;
        al : alarm : BOOL READ_WRITE;
      END_VAR
      VAR_CONFIG
        r1.p1.x AT %QX2.0 : BOOL := TRUE;
      END_VAR
    END_CONFIGURATION
    """)
    cfg = unit.configurations[0]
    r1, r2 = cfg.resources
    assert (r1.name, r1.processor, r2.processor) == ("r1", "CPU0", "CPU1")
    assert [t.name for t in r1.tasks] == ["fast", "ev"]
    assert sorted(r1.tasks[0].props) == ["INTERVAL", "PRIORITY"]
    assert repr(r1.tasks[1].props["SINGLE"][0]) == "trigger"
    p1, p2, p3 = r1.programs
    assert (p1.name, p1.task, p1.type) == ("p1", "fast", "Ctrl")
    assert [(c.name, c.direction, repr(c.value)) for c in p1.connections] == [
        ("sp", "in", "10"), ("in", "in", "%IW2"), ("out", "out", "level"),
        ("q", "out", "%QX0.0")]
    assert p2.retain == "RETAIN" and p3.task is None
    access, config = cfg.access
    assert [(d.name, d.path, d.direction) for d in access.decls] == [
        ("lvl", "r1.p1.level", "READ_ONLY"), ("al", "alarm", "READ_WRITE")]
    assert (config.decls[0].path, config.decls[0].location) == ("r1.p1.x", "%QX2.0")


# ---------------------------------------------------------- instruction list

def test_every_il_operator():
    ops = ["LD", "LDN", "ST", "STN", "S", "R", "AND", "ANDN", "OR", "ORN", "XOR", "XORN", "ADD",
           "SUB", "MUL", "DIV", "MOD", "GT", "GE", "EQ", "NE", "LE", "LT"]
    lines = "\n".join(f"  {op} x" for op in ops)
    prog = parse_ok(f"PROGRAM p\n{lines}\n  NOT\n  JMP l\n  JMPC l\n  JMPCN l\nl:  RET\n"
                    "  RETC\n  RETCN\n  CAL t\n  CALC t(IN := a)\n  CALCN t\nEND_PROGRAM\n")
    il = prog.pous[0].body
    assert prog.pous[0].language == "IL"
    assert [i.op for i in il] == ops + ["NOT", "JMP", "JMPC", "JMPCN", "RET", "RETC", "RETCN",
                                        "CAL", "CALC", "CALCN"]
    assert il[len(ops) + 4].label == "l"
    assert [i.fb for i in il[-3:]] == ["t", "t", "t"]
    assert [(a.name, repr(a.value)) for a in il[-2].args] == [("IN", "a")]


def test_il_deferred_operations_nest_to_any_depth():
    il = parse_ok("""PROGRAM p
      LD a
      AND( b
      OR( c
      ANDN( d
      XOR e
      )
      )
      )
      ST q
      ADD(
        LD 1
        MUL 2
      )
    END_PROGRAM""").pous[0].body
    assert [i.op for i in il] == ["LD", "AND", "ST", "ADD"]
    level1 = il[1]
    assert level1.deferred and repr(level1.operand) == "b"
    level2 = level1.nested[0]
    assert level2.op == "OR" and level2.deferred and repr(level2.operand) == "c"
    level3 = level2.nested[0]
    assert level3.op == "ANDN" and [i.op for i in level3.nested] == ["XOR"]
    assert il[3].operand is None and [i.op for i in il[3].nested] == ["LD", "MUL"]


def test_il_calls_functions_labels_and_fb_input_operators():
    il = parse_ok("""PROGRAM p
    start: LD x
      CAL tmr(IN := x,
              PT := T#2s)
      LD y
      LIMIT 0, 100
      ST z
      SEL( G := c, IN0 := 1, IN1 := 2)
    next:
      LD TRUE
      S1 ff
      R1 ff
      CLK trig
      CU ctr
      CD ctr
      PV ctr
      IN tmr
      PT tmr
      & a
      &N b
    END_PROGRAM""").pous[0].body
    assert il[0].label == "start" and il[0].op == "LD"
    assert il[1].op == "CAL" and [a.name for a in il[1].args] == ["IN", "PT"]
    assert il[3].fn == "LIMIT" and [repr(o) for o in il[3].operands] == ["0", "100"]
    assert il[5].fn == "SEL" and [a.name for a in il[5].args] == ["G", "IN0", "IN1"]
    assert il[6].label == "next"
    assert [i.op for i in il[7:]] == ["S1", "R1", "CLK", "CU", "CD", "PV", "IN", "PT", "AND",
                                      "ANDN"]


def test_il_unbalanced_parentheses_are_errors():
    unit, diags = parse("PROGRAM p\n  LD a\n  AND( b\n  ST c\nEND_PROGRAM\n")
    assert ["3:3: error: 'AND(' is never closed with ')'"] == [
        f"{d.line}:{d.col}: {d.severity}: {d.message}" for d in diags.items]
    unit, diags = parse("PROGRAM p\n  LD a\n  )\nEND_PROGRAM\n")
    assert [d.message for d in diags.items] == ["')' without a deferred operation to close"]


# ------------------------------------------------------ comments and pragmas

def test_comments_and_pragmas():
    unit, diags = parse("""(* header
    comment *)
    PROGRAM p // line comment
    VAR x : INT; END_VAR (* inline *)
    { pragma for another tool }
    x := 1; // done
    (* s := '{not a pragma}'; *)
    END_PROGRAM
    """)
    assert unit is not None and not diags.errors
    assert [(d.line, d.col, d.severity, d.message) for d in diags.items] == [
        (5, 5, "warning", "pragma ignored")]


# MatIEC's inline C (Beremiz's LOGGER and python_eval blocks, OSCAT's plc.st):
# a pragma opened by {{ runs to the first }}, so the C code in it may hold
# braces, semicolons and keywords
MATIEC_INLINE_C = """FUNCTION_BLOCK logger
  VAR_INPUT trig : BOOL; level : INT; END_VAR
  VAR trig0 : BOOL; END_VAR
  IF trig AND NOT trig0 THEN
  {{
   if (level > 0) { LogMessage(GetFbVar(LEVEL)); } /* END_IF; x := 1; */
  }}
  END_IF;
  trig0 := trig;
END_FUNCTION_BLOCK
FUNCTION_BLOCK poll
  VAR_OUTPUT ack : BOOL; END_VAR
  {extern void __PythonEvalFB(int, void*);__PythonEvalFB(1, data__);}
  {{ struct { int a; } s; s.a = 0; }} ack := TRUE;
END_FUNCTION_BLOCK
"""


@pytest.mark.parametrize("reference", [False, True], ids=["fast", "textx"])
def test_matiec_inline_c_pragma_is_one_pragma(reference):
    from iec2kmod.diagnostics import Diagnostics, SourceFile
    from iec2kmod.parse.parser import parse_source
    diags = Diagnostics()
    unit = parse_source(SourceFile("t.st", MATIEC_INLINE_C), diags, reference=reference)
    assert unit is not None and not diags.errors, [d.format() for d in diags.items]
    assert [(d.line, d.col, d.message) for d in diags.items] == [
        (5, 3, "pragma ignored"), (13, 3, "pragma ignored"), (14, 3, "pragma ignored")]
    logger, poll = unit.pous
    assert [type(s).__name__ for s in logger.body] == ["If", "Assign"]
    assert [type(s).__name__ for s in poll.body] == ["Assign"]


def test_string_literals_may_contain_comment_and_pragma_characters():
    e = expr("'(* not a comment *) {nor a pragma} // nor this'")
    assert e.value == "(* not a comment *) {nor a pragma} // nor this"


# --------------------------------------------------------------- syntax errors

@pytest.mark.parametrize("text, expected", [
    ("PROGRAM p\n x := 1 +;\nEND_PROGRAM\n", "2:10: expected unary operator, identifier, "
     "literal, '(' or direct address, found ';'"),
    ("PROGRAM p\n IF x THEN y := 1; END_WHILE\nEND_PROGRAM\n", "2:20: expected"),
    ("PROGRAM p\n x := 1\nEND_PROGRAM\n", "3:1: expected"),
    ("FUNCTION_BLOCK f\nVAR x : INT END_VAR\nEND_FUNCTION_BLOCK\n", "2:13: expected"),
    ("PROGRAM IF\nEND_PROGRAM\n", "1:9: expected identifier, found 'IF'"),
])
def test_syntax_errors_point_at_the_token(text, expected):
    unit, diags = parse(text)
    assert unit is None
    d = diags.errors[0]
    assert f"{d.line}:{d.col}: {d.message}".startswith(expected)


def test_empty_statement_lists():
    stmts = body("IF x THEN ELSIF y THEN ELSE END_IF; FOR i := 1 TO 2 DO END_FOR; "
                 "WHILE x DO END_WHILE; REPEAT UNTIL x END_REPEAT; CASE i OF 1: ELSE END_CASE;")
    assert [type(s).__name__ for s in stmts] == ["If", "For", "While", "Repeat", "Case"]
    assert stmts[0].branches[0][1] == [] and stmts[1].body == [] and stmts[3].body == []
    assert stmts[4].elements[0][1] == []


def test_il_negative_constant_operands():
    il = parse_ok("PROGRAM p\n  LD -7\n  ADD +3\n  MUL -2.5E1\nEND_PROGRAM\n").pous[0].body
    assert [(i.op, i.operand.kind, i.operand.value) for i in il] == [
        ("LD", "int", -7), ("ADD", "int", 3), ("MUL", "real", -25.0)]
