"""The fast paths of the parser against their references, on every file of
examples/ and tests/errors/, on the benchmark project and on small, broken
and fuzzed inputs; each must give the same iec2kmod.ast unit and the same
diagnostics, so a fast path can never silently diverge:

- the fast model builder (parser.FastBuilder) against textX's own
  model_from_str;
- the grammar with its fast-path tokens (SIMPLE_OPERAND) and the
  hand-written statement parser (iec2kmod/parse/stfast.py) against the grammar
  without them."""

import random
import re
import sys
from pathlib import Path

import pytest

from iec2kmod import ast
from iec2kmod.diagnostics import Diagnostics, SourceFile
from iec2kmod.parse.lexical import Pragma
from iec2kmod.parse.parser import fast_paths, metamodel, parse_source

pytestmark = pytest.mark.unit
ROOT = Path(__file__).resolve().parents[2]
FILES = sorted(p for d in ("examples", "tests/errors") for p in (ROOT / d).rglob("*")
               if p.suffix.lower() in (".st", ".il", ".iec"))
# an empty or shrunken list would pass as "skipped": fail at collection instead
assert len(FILES) >= 27, f"only {len(FILES)} source files under examples/ and tests/errors/"


def dump(x):
    """A canonical, comparable form of an AST: every slot of every node."""
    if isinstance(x, (ast.Node, ast.Expr, ast.Arg)):
        slots = []
        for k in type(x).__mro__:
            slots += [s for s in getattr(k, "__slots__", ()) if s not in slots]
        return (type(x).__name__,) + tuple((s, dump(getattr(x, s, "<unset>"))) for s in slots)
    if isinstance(x, (list, tuple)):
        return (type(x).__name__,) + tuple(dump(i) for i in x)
    if isinstance(x, dict):
        return ("dict",) + tuple((dump(k), dump(v)) for k, v in x.items())
    if isinstance(x, SourceFile):
        return ("SourceFile", x.path, x.text)
    if isinstance(x, Pragma):
        return ("Pragma", x.start, x.end, x.text, x.kind)
    assert x is None or isinstance(x, (str, int, float, bool)), type(x)
    return (type(x).__name__, x)


def result(text, path, reference=False):
    diags = Diagnostics()
    unit = parse_source(SourceFile(path, text), diags, reference=reference)
    return dump(unit), [(d.path, d.line, d.col, d.severity, d.message, d.source_line)
                        for d in diags.items]


def both(text, path="t.st"):
    """(reference, fast) results: model_from_str and the grammar without
    fast paths, against FastBuilder and the grammar with them."""
    with fast_paths(False):
        reference = result(text, path, reference=True)
    return reference, result(text, path)


@pytest.mark.parametrize("path", FILES, ids=[str(p.relative_to(ROOT)) for p in FILES])
def test_same_model_on_project_files(path):
    reference, fast = both(path.read_text(), str(path))
    assert fast == reference


def test_same_model_on_the_benchmark_project():
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        from gen_project import project
    finally:
        sys.path.remove(str(ROOT / "benchmarks"))
    # a quarter of the 10,000-line benchmark: every kind of block it makes
    # (ST and IL function blocks, programs, the configuration), in less time
    reference, fast = both(project(2500), "bench.st")
    assert reference[0][0] == "SourceUnit" and not reference[1]
    assert fast == reference


def test_the_fast_paths_are_used():
    with fast_paths(False):
        assert "SIMPLE_OPERAND" not in repr(metamodel()._parser_blueprint.clone().parse("""
            PROGRAM p x := a + 1; END_PROGRAM"""))
    assert "SIMPLE_OPERAND" in repr(metamodel()._parser_blueprint.clone().parse("""
        PROGRAM p x := a + 1; END_PROGRAM"""))


def test_simple_operand_is_var_path_or_literal():
    """SIMPLE_OPERAND repeats the VAR_PATH and LITERAL expressions: they
    must stay the same."""
    regex = {name: metamodel()[name]._tx_peg_rule.to_match_regex
             for name in ("SIMPLE_OPERAND", "VAR_PATH", "LITERAL")}
    assert regex["SIMPLE_OPERAND"] == (
        "(?>" + regex["VAR_PATH"] + r")(?![ \t\r\n]*(?:[\[({]|\*\*|\/\/))"
        r"|(?!NOT\b)(?>" + regex["LITERAL"] + r")(?![ \t\r\n]*(?:\*\*|\(\*|\/\/|\{))")


SNIPPETS = [
    "",
    "(* only a comment *)\n",
    "PROGRAM p\nEND_PROGRAM\n",
    "PROGRAM p\n x := 1 +;\nEND_PROGRAM\n",
    "PROGRAM p\n IF x THEN y := 1; END_WHILE\nEND_PROGRAM\n",
    "PROGRAM p\n x := 1\nEND_PROGRAM\n",
    "PROGRAM IF\nEND_PROGRAM\n",
    "PROGRAM p\nVAR a : INT; END_VAR\n a := 16#FFFFFFFFFFFFFFFFFF; a := T#1x;\nEND_PROGRAM\n",
    "PROGRAM p\n a.b[1](x := 1);\n y := s.c[2](3) + f(a, IN2 := 2, Q => y, NOT Q2 => z);\nEND_PROGRAM\n",
    "PROGRAM p\n x := -a ** 2 ** b + NOT c AND d OR e XOR f & g MOD 3;\nEND_PROGRAM\n",
    "PROGRAM p\n x := arr[i, j + 1].x.3; {pragma} y := %IX0.1;\nEND_PROGRAM\n",
    "TYPE\n E : (a, b := 3, c);\n R : INT (0..10) := 5;\n S : STRUCT m AT %QX0.0 : BOOL; n : ARRAY[1..2, 0..1] OF"
    " INT := [2(1), 3, 4]; END_STRUCT;\n W : WSTRING[20]; P : S := (n := [1, 2]);\nEND_TYPE\n",
    "FUNCTION_BLOCK fb\nVAR_INPUT CONSTANT x : BOOL R_EDGE; END_VAR\nVAR_OUTPUT q AT %QW3 : WORD; END_VAR\n"
    "  LD x\n  AND( y\n  OR z\n  )\n  ST q\nl1: CAL t(IN := x,\n    PT := T#1s)\n  JMPC l1\n"
    "  LIMIT 0, 10\n  )\n  ADD(\nEND_FUNCTION_BLOCK\n",
    "CONFIGURATION c\n VAR_GLOBAL g : INT; END_VAR\n RESOURCE r ON cpu\n  TASK t (INTERVAL := T#1ms,"
    " PRIORITY := 1);\n  PROGRAM RETAIN i WITH t : p (a := g, b => g);\n END_RESOURCE\n"
    " VAR_ACCESS v : r.i.x : INT READ_ONLY; END_VAR\n VAR_CONFIG r.i.y AT %IX1.0 : BOOL := TRUE; END_VAR\n"
    "END_CONFIGURATION\n",
    "PROGRAM p\n CASE x OF 1, 2..3: y := 1; ELSE y := 2; END_CASE\n FOR i := 1 TO 10 BY 2 DO EXIT; END_FOR"
    "\n WHILE a DO RETURN; END_WHILE\n REPEAT ; UNTIL b END_REPEAT\nEND_PROGRAM\n",
    "PROGRAM p\n x := " + "(" * 400 + "1" + ")" * 400 + ";\nEND_PROGRAM\n",
    "PROGRAM p\n x := a (* c *) [1] + b // c\n (2) + 3 (* c *) ** 2 + c {p} [3] + NOT#1 + d\f[1];\n"
    " y := a.b.3 + a.b[1].c + T#1s + INT#-5 + 16#FF + 'x' + \"w\" + 1.5e3 + TRUE + e1 ** 2 + f ();"
    "\nEND_PROGRAM\n",
    "PROGRAM p\n x := 1\nEND_PROGRAM\n",
    "PROGRAM p\n x := a\nEND_PROGRAM\n",
    "PROGRAM p\n x := a.b\nEND_PROGRAM\n",
    "PROGRAM p\n f(a, b c);\nEND_PROGRAM\n",
    "PROGRAM p\n IF a THEN ELSIF b THEN ELSE END_IF;\n WHILE a DO END_WHILE;\n CASE x OF 1: END_CASE;"
    "\nEND_PROGRAM\n",
    # the statements iec2kmod.parse.stfast parses, and their edges
    "PROGRAM p\nVAR a : INT; END_VAR\n a := 1;; ; IF a THEN ELSIF b THEN ; ELSE END_IF\n b := 2;"
    "\n if a then x := 1; elsif b then x := 2; else x := 3; end_if;\n IF a THEN x := 1; END_IF; ;"
    "\nEND_PROGRAM\n",
    "PROGRAM p\nVAR a : INT; END_VAR\n a.b.3 := NOT -x AND (a) OR - - 5 XOR NOT(b) & c <> d;\n"
    " x := (* c *) a (* d *) + {p} b // e\n * (c);\n y := a MOD b mod 2 / 1.5e3 - INT#-5 + T#1s + 16#FF"
    " + 'x' + TRUE + Color#Red + d.3 + e.f;\nEND_PROGRAM\n",
    "PROGRAM p\nVAR a : INT; END_VAR\n a := 1; LD a\n ST b\nEND_PROGRAM\n",
    "PROGRAM p\nVAR a : INT; END_VAR\n a := 1; b := INT#99999999; c := 2;\nEND_PROGRAM\n",
    "PROGRAM p\nVAR a : INT; END_VAR\n a := 1; b := f(1) + c[2]; c := a ** 2; d := %IW1 + 1;"
    " e := -a ** 2; IF a THEN RETURN; END_IF; f := 1\nEND_PROGRAM\n",
    "PROGRAM p\nVAR a : INT; END_VAR\n a := 1; IF a THEN b := 1; END_IF c := 2; IF a THEN b := 1;"
    " c := 3;\nEND_PROGRAM\n",
    "PROGRAM p\nVAR a : INT; END_VAR\n a := 1;\n INITIAL_STEP s0: x(N); END_STEP\n"
    " TRANSITION FROM s0 TO s1 := a; END_TRANSITION\n STEP s1: END_STEP\nEND_PROGRAM\n",
    "FUNCTION_BLOCK fb\nVAR a : INT; END_VAR\n a := a + 1;\nACTION act: a := 2; END_ACTION\n"
    "END_FUNCTION_BLOCK\nPROGRAM p\nVAR x : fb; y : INT; END_VAR\n y := y + 1; x(); y := y * 2;"
    "\nEND_PROGRAM\n",
    "FUNCTION f : INT\nVAR_INPUT a : INT; END_VAR\n f := a * 2;\nEND_FUNCTION\n"
    "TYPE t : INT; END_TYPE\nCONFIGURATION c\n RESOURCE r ON cpu\n  TASK t (INTERVAL := T#1ms);"
    "\n  PROGRAM i WITH t : p;\n END_RESOURCE\nEND_CONFIGURATION\n"
    "PROGRAM p\nVAR a : INT; END_VAR\n a := f(a); a := a - 1; IF a > 2 THEN a := 0; END_IF;\n"
    "END_PROGRAM\n",
    "PROGRAM p\nVAR a : INT; END_VAR\n a := 1 +\nEND_PROGRAM\n",
    "PROGRAM p\nVAR a : INT; END_VAR\n IF a THEN RETURN; ELSE EXIT; END_IF; RETURN ; return;exit;"
    " RETURN a := 1; EXIT\nEND_PROGRAM\n",
    "PROGRAM p\nVAR a : INT; END_VAR\n a := s.END_IF; b := 1;\nEND_PROGRAM\n",
    "PROGRAM p\nVAR a : INT; END_VAR\n a := x y; b := 1;\nEND_PROGRAM\n",
    "PROGRAM p\nVAR a : INT; END_VAR\n a := 1;\f b := 2;\nEND_PROGRAM\n",
]


@pytest.mark.parametrize("text", SNIPPETS, ids=range(len(SNIPPETS)))
def test_same_model_on_snippets(text, tmp_path):
    path = tmp_path / "t.st"  # textX's model_from_str reads the file when text is empty
    path.write_text(text)
    reference, fast = both(text, str(path))
    assert fast == reference


def test_same_result_on_fuzzed_input():
    rng = random.Random(4321)
    words = ("PROGRAM END_PROGRAM VAR END_VAR := ; ( ) [ ] 'x' T#5s 16#F IF THEN ELSE END_IF x y "
             "1 2 . , : FUNCTION_BLOCK END_FUNCTION_BLOCK LD ST ADD( \n").split(" ")
    for _ in range(60):
        text = "PROGRAM p\n" + " ".join(rng.choice(words) for _ in range(40)) + "\nEND_PROGRAM\n"
        reference, fast = both(text)
        assert fast == reference, text


def test_same_result_on_mutated_files():
    """Token-level mutations of project files: mostly syntax errors next to
    operands, where the fast paths try less than the full rules."""
    rng = random.Random(99)
    token = re.compile(r"\(\*.*?\*\)|//[^\n]*|\{[^}]*\}|'(?:[^'$\n]|\$.)*'|\w+#[\w.#'-]+"
                       r"|\w+(?:\.\w+)*|:=|=>|\*\*|<>|<=|>=|\S|\n", re.S)
    vocab = [";", ":=", "=>", "(", ")", "[", "]", ",", ".", "**", "*", "+", "-", "NOT", "(* c *)",
             "// c\n", "{p}", "x", "a.b", "1", "T#1s", "16#FF", "'s'", "%IX0.1", "IF", "END_IF",
             "\n", "..", ":", "END_VAR", "LD", "ADD(", "&", "MOD", "=", "#", "\f"]
    for path in FILES[::3]:
        text = path.read_text()
        spans = [m.span() for m in token.finditer(text)]
        for _ in range(6):
            a, b = spans[rng.randrange(len(spans))]
            mutant = text[:a] + rng.choice(["", text[a:b] + " " + text[a:b], rng.choice(vocab),
                                             rng.choice(vocab) + " " + text[a:b]]) + text[b:]
            reference, fast = both(mutant, str(path))
            assert fast == reference, (path, a, mutant[max(0, a - 40):a + 40])


def test_parallel_parse_is_the_sequential_parse():
    """parse_all over forked workers, with big files cut into parts, gives
    the units and diagnostics of parsing each file whole, and leaves the
    cyclic garbage collector as it found it."""
    import gc

    from iec2kmod.parse.frontend import parse_all
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        from gen_project import project
    finally:
        sys.path.remove(str(ROOT / "benchmarks"))
    text = project(2500)
    broken = text.replace("acc := acc + 2;", "acc := acc + ;", 1)
    sources = [SourceFile("a.st", text), SourceFile("b.st", broken),
               SourceFile("c.st", (ROOT / "examples/pid_loop/pid.st").read_text())]
    assert gc.isenabled()
    parallel = parse_all(sources, jobs=2)
    assert gc.isenabled()
    sequential = parse_all(sources, jobs=1)
    canon = [(dump(unit), [(d.path, d.line, d.col, d.message, d.source_line) for d in items])
             for unit, items in parallel]
    assert canon == [(dump(unit), [(d.path, d.line, d.col, d.message, d.source_line)
                                   for d in items]) for unit, items in sequential]
    assert canon[1][0] == ("NoneType", None) and canon[1][1][0][3].startswith("expected")


def _progen():
    sys.path.insert(0, str(ROOT / "tests" / "differential"))
    try:
        from progen import generate_unit
    finally:
        sys.path.remove(str(ROOT / "tests" / "differential"))
    return generate_unit


def test_same_model_on_random_programs():
    """The programs of the differential campaign (every construct its
    generator knows), whole and with random statements mutated."""
    generate_unit = _progen()
    rng = random.Random(7)
    vocab = [";", ":=", "(", ")", "[1]", "**", "+", "NOT", "(* c *)", "x", "1", "IF", "THEN",
             "END_IF", "ELSE", "f(1)", "&", "MOD", "=", "\f"]
    for seed in range(24):
        text = generate_unit(seed, size=0.5).standalone()
        reference, fast = both(text, f"random{seed}.st")
        assert reference[0][0] == "SourceUnit" and not [d for d in reference[1] if d[3] == "error"]
        assert fast == reference, seed
        lines = text.split("\n")
        k = rng.randrange(len(lines))
        words = lines[k].split(" ")
        words[rng.randrange(len(words))] = rng.choice(vocab)
        mutant = "\n".join(lines[:k] + [" ".join(words)] + lines[k + 1:])
        reference, fast = both(mutant, f"random{seed}.st")
        assert fast == reference, (seed, k, lines[k], " ".join(words))


def test_the_statement_parser_takes_expression_dense_code():
    """iec2kmod.parse.stfast parses every statement of the dense benchmark POU
    (textX sees only its declarations), with textX's own result."""
    from iec2kmod.parse.parser import statement_parser
    from iec2kmod.parse.stfast import fast_statements
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        from gen_project import dense_pou
    finally:
        sys.path.remove(str(ROOT / "benchmarks"))
    text = dense_pou(300)
    rest, taken = fast_statements(text, statement_parser())
    statements = [line for line in text.splitlines() if line.startswith("    ")]
    assert [len(v) for v in taken.values()] == [len(statements)] and len(statements) >= 290
    assert ":=" not in rest and rest.count("\n") == text.count("\n") and len(rest) == len(text)
    reference, fast = both(text, "dense.st")
    assert not reference[1] and fast == reference
