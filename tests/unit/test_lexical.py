"""iec2kmod.parse.lexical (the one pragma registry and lexical skip rules)
and iec2kmod.parse.parser.parse_expression (issue 24, item 4)."""

import re

import pytest

from iec2kmod import ast
from iec2kmod.diagnostics import Diagnostics, SourceFile
from iec2kmod.parse import frontend, lexical
from iec2kmod.parse.parser import metamodel, parse_expression, parse_source


def test_registry_names_every_pragma_a_pass_reads():
    assert set(lexical.PRAGMAS) == {"watchdog", "selective", "verify", "assume"}
    for kind in lexical.PRAGMAS.values():
        assert kind.syntax.startswith("{" + kind.name)
        assert kind.where and kind.attaches_to and kind.reader


def test_skip_rules_are_the_grammars_comment_rule():
    """What the raw-text scanners skip is what the parser skips as blanks."""
    grammar = metamodel()["Comment"]._tx_peg_rule.regex
    ours = re.compile(lexical.COMMENT + "|" + lexical.INLINE_C + "|" + lexical.PRAGMA, re.S)
    for text in ("(* a\n*) x", "// line\nx", "{{ if (a) { b; } }} x", "{watchdog T#5ms} x",
                 "{ unknown 'q } x", "(* { *) }"):
        g, o = grammar.match(text), ours.match(text)
        assert (g and g.group()) == (o and o.group()), text


def test_pragmas_are_scanned_once_with_their_kind_and_offsets():
    text = ("(* {watchdog T#1s} in a comment *) 'a {selective} in a string'\n"
            "{ Selective off} {{ inline { C } {verify: x} }} {verify P: a AND\n b} {foo}")
    got = [(p.kind, text[p.start:p.end]) for p in lexical.pragmas(text)]
    assert got == [("selective", "{ Selective off}"),
                   (None, "{{ inline { C } {verify: x} }}"),
                   ("verify", "{verify P: a AND\n b}"),
                   (None, "{foo}")]
    v = lexical.of_kind(text, "verify")[0]
    assert v.body == " P: a AND\n b" and text[v.body_start:].startswith(" P:")


def test_in_front_of_only_across_blanks():
    text = ("{watchdog T#5ms}\n  TASK t; {watchdog T#1s} (* c *) // d\n TASK u;"
            " {watchdog T#2s} PROGRAM p WITH u : P; TASK v;")
    t = text.index("TASK t")
    u = text.index("TASK u")
    v = text.index("TASK v")
    assert lexical.in_front_of(text, t, "watchdog").start == 0
    assert lexical.in_front_of(text, t, "selective") is None
    assert lexical.in_front_of(text, u, "watchdog").text == "{watchdog T#1s}"
    assert lexical.in_front_of(text, v, "watchdog") is None


def test_parser_warns_at_pragmas_no_pass_reads():
    text = ("{selective}\nFUNCTION_BLOCK FB VAR_INPUT a : BOOL; END_VAR {{ x }}\n"
            "{frobnicate} {watchdog-ish} END_FUNCTION_BLOCK\n")
    diags = Diagnostics()
    parse_source(SourceFile("p.st", text), diags)
    assert [(d.line, d.col, d.message) for d in diags.warnings] == [
        (2, 47, "pragma ignored"), (3, 1, "pragma ignored")]


def test_watchdog_in_inline_c_is_not_a_pragma(tmp_path):
    """A {watchdog} written inside MatIEC inline C is C text, as the
    parser reads it: no 'applies to nothing' warning (it had one)."""
    p = tmp_path / "w.st"
    p.write_text("PROGRAM P VAR x : INT; END_VAR x := x + 1; {{ /* {watchdog T#5ms} */ }}\n"
                 "END_PROGRAM\nCONFIGURATION C RESOURCE R ON PLC\n"
                 "TASK t (INTERVAL := T#10ms, PRIORITY := 1);\n"
                 "PROGRAM i WITH t : P; END_RESOURCE END_CONFIGURATION\n")
    r = frontend.run([str(p)], use_cache=False)
    assert r.ok, [d.format() for d in r.diags.items]
    assert [d.message for d in r.diags.warnings] == ["pragma ignored"]


# ---------------------------------------------------------------- parse_expression
def test_expression_positions_are_those_of_its_own_text():
    e = parse_expression("a AND b.c[1] > 3")
    assert isinstance(e, ast.BinOp) and e.op == "AND"
    assert (e.pos, e.left.pos, e.right.pos, e.right.right.pos) == (0, 0, 6, 15)


def test_expression_positions_within_an_origin():
    src = SourceFile("f.st", "(* x *) {verify: NOT %QX0.1 OR ABS(y) < 3}")
    start = src.text.index("NOT")
    e = parse_expression(src.text[start:-1], (src, start), Diagnostics(), "property")
    assert e.pos == start and e.right.pos == src.text.index("ABS")
    assert e.right.left.args[0].value.pos == src.text.index("y)")


@pytest.mark.parametrize("text, col, message", [
    ("a AND", 17, "in a property: expected unary operator, identifier, literal, '(' or "
                  "direct address, found end of property"),
    ("a b", 14, "in a property: expected '[', '(', '**', operator or end of property, "
                "found 'b'"),
    ("a; b := c", 13, "in a property: expected '[', '(', '**', operator or end of "
                      "property, found ';'"),
])
def test_expression_errors_at_file_line_col(text, col, message):
    src = SourceFile("f.st", "\nxx{verify: " + text + "}")
    diags = Diagnostics()
    assert parse_expression(text, (src, 12), diags, "property") is None
    assert [(d.path, d.line, d.col, d.message) for d in diags.errors] == [
        ("f.st", 2, col, message)]
