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
{watchdog T#5ms} (* a comment between is a blank, as for {selective} *)
TASK u (INTERVAL := T#10ms, PRIORITY := 2);
{watchdog T#1ms}
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
                                              "watchdog", "watchdog", "watchdog"]


def test_watchdog_on_the_task_right_behind_it():
    t, u = _unit().configurations[0].resources[0].tasks
    assert [p.body.strip() for p in t.pragmas] == ["T#20ms, 2"]
    assert [p.body.strip() for p in u.pragmas] == ["T#5ms"]
    pc = _unit().configurations[0].resources[0].programs[0]
    assert pc.pragmas == ()          # a {watchdog} in front of a program instance: nothing


def test_verify_and_assume_on_their_pou_or_the_file():
    unit = _unit()
    fb, p = unit.pous
    assert [x.text for x in fb.pragmas] == ["{assume: x > 0}"]
    assert [x.text for x in p.pragmas] == ["{verify small: n < 10}"]
    assert [x.text for x in unit.outside] == ["{verify early: TRUE}", "{assume: TRUE}"]


# ------------------------------------------------------------------ {selective}
SEL = """\
{selective off} (* a comment *) // a line
{frobnicate} {{ inline C }}
FUNCTION_BLOCK V
VAR_INPUT x : INT; END_VAR
END_FUNCTION_BLOCK
{selective on}
PROGRAM P
{selective off} VAR RETAIN (* c *)
  a, b : V;
  {selective} (* c *) {verify ok: TRUE} c : V;
  d : V;
END_VAR
VAR {selective off} CONSTANT k : INT := 1; END_VAR
VAR_EXTERNAL g : INT; {selective off} END_VAR
VAR e, {selective off} f : V; END_VAR
{verify inside: TRUE}
{selective off} a(x := g);
END_PROGRAM
TYPE {selective off} S : STRUCT m : INT; END_STRUCT; END_TYPE
FUNCTION_BLOCK {selective off} W
VAR_INPUT x : INT; END_VAR
END_FUNCTION_BLOCK
CONFIGURATION c
VAR_GLOBAL {selective off} g : INT; END_VAR
RESOURCE r ON PLC
TASK t (INTERVAL := T#10ms, PRIORITY := 1);
{selective off} (* c *) PROGRAM i WITH t : P;
PROGRAM {selective off} j WITH t : P;
END_RESOURCE
END_CONFIGURATION
{selective off}
"""


def _sel_unit():
    diags = Diagnostics()
    unit = parse_source(SourceFile("s.st", SEL), diags)
    assert unit is not None, [d.format() for d in diags.items]
    return unit


def _texts(node):
    return [(p.kind, p.text) for p in node.pragmas]


def _at(p):
    """line:col of a pragma in SEL."""
    line = SEL.count("\n", 0, p.start) + 1
    return f"{line}:{p.start - (SEL.rfind(chr(10), 0, p.start) + 1) + 1}"


def test_selective_on_the_pou_behind_it_across_comments_and_other_pragmas():
    from iec2kmod.verify.props import scan_pragmas
    unit = _sel_unit()
    v, p, w = unit.pous
    assert _texts(v) == [("selective", "{selective off}")]
    # a POU's pragmas: the {selective} in front of it, the {verify} inside,
    # in the order written; the verify pass picks its own
    assert _texts(p) == [("selective", "{selective on}"), ("verify", "{verify ok: TRUE}"),
                         ("verify", "{verify inside: TRUE}")]
    assert _texts(w) == []               # between its keyword and its name

    class Project:
        units = [unit]
    props, bad = scan_pragmas(Project)
    assert [(x.name, x.program) for x in props] == [("ok", "P"), ("inside", "P")], props
    assert bad == []


def test_selective_on_the_declaration_behind_it_var_keywords_between():
    p = _sel_unit().pous[1]
    var, const, ext, ef = p.blocks
    ab, c, d = var.decls
    # in front of the block's keyword: its first declaration, both names
    assert [n for n, _ in ab.names] == ["a", "b"] and _texts(ab) == [
        ("selective", "{selective off}")]
    assert _texts(c) == [("selective", "{selective}")]   # comments, a {verify} between
    assert _texts(d) == []
    # between the keyword and the first name (a qualifier after it)
    assert _texts(const.decls[0]) == [("selective", "{selective off}")]
    assert _texts(ext.decls[0]) == [] and _texts(ef.decls[0]) == []


def test_selective_in_front_of_nothing_stays_on_the_unit():
    unit = _sel_unit()
    # before END_VAR, inside a name list, before a statement, inside a
    # TYPE, between a POU's keyword and its name, in a VAR_GLOBAL of the
    # configuration, between PROGRAM and the instance's name, at the end
    assert [_at(p) for p in unit.unattached] == [
        "14:23", "15:8", "17:1", "19:6", "20:16", "24:12", "28:9", "31:1"]
    assert {p.text for p in unit.unattached} == {"{selective off}"}


def test_selective_on_the_program_instance_behind_it():
    i, j = _sel_unit().configurations[0].resources[0].programs
    assert _texts(i) == [("selective", "{selective off}")]
    assert _texts(j) == []


def test_selective_plan_marks_every_name_of_the_declaration(tmp_path):
    """The selective pass reads the nodes: both instances of 'a, b : V'
    are off (only the first was, when the pass matched the text), and each
    name that is no instance has its warning at the pragma."""
    from iec2kmod.codegen.selective import SelectivePlan
    from iec2kmod.parse import frontend
    f = tmp_path / "m.st"
    f.write_text("FUNCTION_BLOCK V VAR_INPUT x : INT; END_VAR END_FUNCTION_BLOCK\n"
                 "PROGRAM P VAR {selective off} a, b : V; c : V;\n"
                 "{selective on} n, m : INT; END_VAR\n"
                 "a(x := 1); b(x := 2); c(x := 3); n := 1; m := 2; END_PROGRAM\n"
                 "CONFIGURATION C RESOURCE R ON PLC\n"
                 "TASK t (INTERVAL := T#10ms, PRIORITY := 1);\n"
                 "PROGRAM i WITH t : P; END_RESOURCE END_CONFIGURATION\n")
    r = frontend.run([str(f)], use_cache=False)
    assert r.ok, [d.format() for d in r.diags.items]
    plan = SelectivePlan(r.project, "all")
    p = r.project.pous["P"]
    assert {v.name: plan.var_mark.get(id(v)) for v in p.vars.values()} == {
        "a": False, "b": False, "c": None, "n": True, "m": True}
    assert [(src.text.count("\n", 0, at) + 1, msg) for src, at, msg in plan.warnings] == [
        (3, "selective pragma on 'n', which is not an instance of a user function block"),
        (3, "selective pragma on 'm', which is not an instance of a user function block")]
