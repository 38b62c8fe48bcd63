"""One large POU is parsed on every core (frontend.split_statements): its
ST body is cut between top-level statements, the pieces are parsed apart
and their statements joined.  The result must be the serial parse's, AST
and diagnostics, whatever the body holds; anything the cut cannot handle
(IL, a syntax error, keywords in comments and strings) gives the serial
parse's result too."""

import pytest

from iec2kmod.parse import frontend
from iec2kmod.diagnostics import SourceFile

from test_fast_builder import dump

pytestmark = pytest.mark.unit


def serial(src):
    return _norm(frontend._merge(src, [frontend._parse_one(src)]))


def cut(src, pieces):
    parts = frontend.split_statements(src, pieces)
    if parts is None:
        return None, serial(src)
    for p in parts:
        assert len(p.text) == len(src.text) and p.text.count("\n") == src.text.count("\n")
    got = frontend._merge_statements(src, [frontend._parse_one(p) for p in parts])
    return parts, _norm(frontend._merge(src, [got if got is not None
                                               else frontend._parse_one(src)]))


def _norm(r):
    unit, items = r
    return dump(unit), [(d.path, d.line, d.col, d.severity, d.message, d.source_line)
                        for d in items]


STATEMENTS = [
    "x := (a + b * 3) - (c - d) / 2 + e MOD 4;",
    "IF a > 1 AND b < c THEN x := x + 1; ELSIF a < 0 THEN x := 0; ELSE x := 2; END_IF;",
    "(* a comment with ; IF and END_IF; inside *) y := x;",
    "s := 'a string; with IF inside';",
    "CASE x OF 1: y := 1; 2..3: y := 2; ELSE y := 3; END_CASE;",
    "FOR k := 1 TO 3 DO y := y + k; IF y > 9 THEN EXIT; END_IF; END_FOR;",
    "IF a = b THEN y := 1; END_IF",                    # no ';' after END_IF
    "WHILE y > 0 DO y := y - 1; END_WHILE;",
    "REPEAT y := y + 1; UNTIL y > 3 END_REPEAT;",
    "// a line comment ; END_IF\n    y := -x ** 2;",
    "t(IN := a > b, PT := T#1s); q := t.Q;",
    "{pragma} x := 1;",
]


def program(n, extra=""):
    body = "\n".join("    " + STATEMENTS[k % len(STATEMENTS)] for k in range(n))
    return f"""PROGRAM Big
VAR a, b, c, d, e, x, y : DINT; k : INT; s : STRING; t : TON; q : BOOL; END_VAR
VAR_TEMP z : INT; END_VAR
{body}
{extra}END_PROGRAM
"""


@pytest.mark.parametrize("pieces", [2, 3, 5])
def test_cut_body_parses_as_the_whole(pieces):
    src = SourceFile("big.st", program(120))
    parts, got = cut(src, pieces)
    assert parts is not None and len(parts) >= 2
    assert got == serial(src)


def test_function_and_function_block_bodies():
    for head, end in (("FUNCTION F : DINT", "END_FUNCTION"),
                      ("FUNCTION_BLOCK FB", "END_FUNCTION_BLOCK")):
        text = program(60).replace("PROGRAM Big", head).replace("END_PROGRAM", end)
        if head.startswith("FUNCTION F"):
            text = text.replace("t : TON;", "").replace("t(IN := a > b, PT := T#1s); q := t.Q;",
                                                        "q := a > b;")
        src = SourceFile("f.st", text)
        parts, got = cut(src, 3)
        assert parts is not None
        assert got == serial(src)


def test_a_syntax_error_in_a_piece_gives_the_serial_diagnostics():
    src = SourceFile("bad.st", program(80).replace("y := x;", "y := x +;", 1))
    parts, got = cut(src, 3)
    assert parts is not None
    assert got == serial(src)
    assert any(d[3] == "error" for d in got[1])


def test_what_is_not_cut():
    il = """FUNCTION_BLOCK F
VAR a : INT; END_VAR
""" + "    LD a\n    ADD 1\n    ST a\n" * 40 + "END_FUNCTION_BLOCK\n"
    two = program(40) + program(40).replace("Big", "Other")
    unbalanced = program(40).replace("END_IF;", "", 1)   # an error the cut must not hide
    for text in (il, two, "TYPE T : INT; END_TYPE\n" + program(40)):
        assert frontend.split_statements(SourceFile("x.st", text), 3) is None
    src = SourceFile("u.st", unbalanced)
    assert cut(src, 3)[1] == serial(src)


def test_the_parallel_front_end_cuts_one_large_pou():
    """Through parse_all on two processes, as `iec2kmod check` runs it."""
    src = SourceFile("big.st", program(500))
    assert len(src.text) >= 20000 and frontend.split_statements(src, 4) is not None
    (unit, items), = frontend.parse_all([src], jobs=2)
    assert _norm((unit, items)) == serial(src)
