"""The ed.2 forms real code uses (issue 25), through the CLI and the checker:
a write to an input is a warning, an error under --strict (check, gen, sim);
an access specifier after a POU keyword gets a message naming it; MULTIME,
DIVTIME, CONSTANT without initial value, *_TO_BCD typed by its context, a
user POU with an ed.3-only standard name.  What they compute is in
tests/conformance/valid/realcode/ed2_forms.st (C and interpreter)."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from iec2kmod.checks import check_project
from iec2kmod.diagnostics import Diagnostics, SourceFile
from iec2kmod.parse.parser import parse_source

pytestmark = pytest.mark.unit
ROOT = Path(__file__).resolve().parents[2]

WRITES_INPUT = """FUNCTION_BLOCK Fb
VAR_INPUT sl : INT; END_VAR
VAR_OUTPUT y : INT; END_VAR
    sl := sl + 1;
    y := sl;
END_FUNCTION_BLOCK
PROGRAM Main
VAR f : Fb; o : INT; END_VAR
    f(sl := 1, y => o);
END_PROGRAM
CONFIGURATION C
  TASK t (INTERVAL := T#10ms, PRIORITY := 1);
  PROGRAM m WITH t : Main;
END_CONFIGURATION
"""


def run(*args):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    p = subprocess.run([sys.executable, "-m", "iec2kmod.cli", *args], env=env,
                       capture_output=True, text=True, timeout=300)
    return p.returncode, p.stdout, p.stderr


def diagnostics(text):
    diags = Diagnostics()
    unit = parse_source(SourceFile("t.st", text), diags)
    if unit is not None and not diags.errors:
        check_project([unit], diags)
    return [(d.line, d.col, d.severity, d.message) for d in diags.sorted()]


def test_write_to_input_is_a_warning_naming_the_rule(tmp_path):
    f = tmp_path / "w.st"
    f.write_text(WRITES_INPUT)
    code, _, err = run("check", "--no-cache", str(f))
    assert code == 0, err
    assert f"{f}:4:5: warning: write to input 'sl' inside its function block" in err
    assert "SA0037" in err and "--strict makes it an error" in err


@pytest.mark.parametrize("command", ["check", "gen", "sim"])
def test_strict_makes_the_write_to_an_input_an_error(tmp_path, command):
    f = tmp_path / "w.st"
    f.write_text(WRITES_INPUT)
    extra = {"check": ["--no-cache"], "gen": ["-o", str(tmp_path / "out")],
             "sim": ["--cycles", "1"]}[command]
    code, _, err = run(command, "--strict", *extra, str(f))
    assert code == 1, err
    assert f"{f}:4:5: error: write to input 'sl' inside its function block" in err
    assert "1 error(s)" in err
    assert not (tmp_path / "out").exists()


def test_for_control_variable_may_be_an_input_under_the_same_rule():
    got = diagnostics("FUNCTION F : INT\nVAR_INPUT n : INT; END_VAR\nVAR a : INT; END_VAR\n"
                      "FOR n := 1 TO 3 DO a := a + n; END_FOR;\nF := a;\nEND_FUNCTION\n")
    assert [(l, c, s) for l, c, s, _ in got] == [(4, 5, "warning")]
    assert got[0][3].startswith("write to input 'n' inside its function")
    # an output as control variable stays refused (not a local)
    got = diagnostics("FUNCTION_BLOCK B\nVAR_OUTPUT n : INT; END_VAR\n"
                      "FOR n := 1 TO 3 DO ; END_FOR;\nEND_FUNCTION_BLOCK\n")
    assert any(s == "error" and "must be a local variable" in m for _, _, s, m in got)


def test_write_to_a_part_of_an_input():
    got = diagnostics("TYPE A3 : ARRAY[1..3] OF INT; END_TYPE\nFUNCTION_BLOCK F\n"
                      "VAR_INPUT v : A3; END_VAR\nVAR_OUTPUT o : INT; END_VAR\nv[2] := 5;\n"
                      "o := v[2];\nEND_FUNCTION_BLOCK\n")
    assert [(l, s) for l, _, s, _ in got] == [(5, "warning")]
    assert got[0][3].startswith("write to a part of input 'v' inside its function block")


@pytest.mark.parametrize("decl, write", [("v : A3", "v[2] := 5"), ("v : A3", "v := v"),
                                         ("v : R", "v.a := 1"), ("v : STRING[4]", "v := 'x'")])
def test_a_functions_aggregate_input_is_copied_when_written(decl, write, tmp_path):
    """A function's ARRAY, STRUCT and STRING inputs are passed by reference;
    one the body writes is copied at the call (OSCAT POLYNOM_INT): a
    warning like any write to an input, and the generated C compiles (it
    did not: 'assignment of read-only location')."""
    text = ("TYPE A3 : ARRAY[1..3] OF INT; R : STRUCT a : INT; END_STRUCT; END_TYPE\n"
            f"FUNCTION F : INT\nVAR_INPUT {decl}; END_VAR\n{write};\nF := 1;\n"
            "END_FUNCTION\n")
    got = diagnostics(text)
    assert [(l, s) for l, _, s, _ in got] == [(4, "warning")], got
    assert "input 'v' inside its function" in got[0][3]
    src = tmp_path / "f.st"
    src.write_text(text + "PROGRAM P\nVAR x : " + decl.split(" : ")[1] + "; n : INT; END_VAR\n"
                   "n := F(x);\nEND_PROGRAM\nCONFIGURATION C RESOURCE Rs ON PLC TASK T "
                   "(INTERVAL := T#10ms, PRIORITY := 1); PROGRAM i WITH T : P; END_RESOURCE "
                   "END_CONFIGURATION\n")
    code, out, err = run("sim", "--cycles", "1", "--watch", "Rs.i.n", str(src))
    assert code == 0 and "Rs.i.n" in out, err[-2000:]


@pytest.mark.parametrize("word", ["PUBLIC", "PRIVATE", "INTERNAL", "PROTECTED", "FINAL",
                                  "ABSTRACT"])
@pytest.mark.parametrize("kind", ["FUNCTION_BLOCK", "PROGRAM"])
def test_access_specifier_is_named(word, kind):
    got = diagnostics(f"{kind} {word} P\nVAR_OUTPUT q : BOOL; END_VAR\nq := TRUE;\n"
                      f"END_{kind}\n")
    assert got == [(1, len(kind) + 2, "error",
                    f"access specifier {word} after {kind}: an IEC 61131-3 ed.3 / CODESYS "
                    f"object-oriented form, which iec2kmod does not support; remove {word} "
                    "(an ed.2 POU is visible to the whole project)")]


def test_ed2_names_and_forms_check_clean():
    got = diagnostics("""PROGRAM P
VAR CONSTANT c : INT; END_VAR
VAR t : TIME; b : BYTE; d : DWORD; x : INT; END_VAR
t := MULTIME(T#1s, 2); t := DIVTIME(t, 2);
b := INT_TO_BCD(c + 12); d := USINT_TO_BCD(USINT#99); x := c;
END_PROGRAM
""")
    assert got == []


def test_bcd_result_typed_by_context_only_for_bit_strings():
    got = diagnostics("PROGRAM P\nVAR i : INT; END_VAR\ni := INT_TO_BCD(12);\nEND_PROGRAM\n")
    assert [(l, s, m.split(':')[0]) for l, _, s, m in got] == \
        [(3, "error", "cannot assign WORD to 'i' of type INT")]


def test_ed3_only_name_replaced_by_a_user_pou_with_a_warning_other_names_refused():
    got = diagnostics("FUNCTION_BLOCK CTU_DINT\nVAR_OUTPUT q : BOOL; END_VAR\nq := TRUE;\n"
                      "END_FUNCTION_BLOCK\nFUNCTION SIN : REAL\nVAR_INPUT x : REAL; END_VAR\n"
                      "SIN := x;\nEND_FUNCTION\n")
    assert got == [
        (1, 1, "warning", "'CTU_DINT' is a standard function block of IEC 61131-3 ed.3 "
                          "only: this project's function block of that name (ed.2 code) "
                          "replaces it"),
        (5, 1, "error", "'SIN' is the name of a standard function or block")]


def test_matiec_inline_c_block_with_braces_is_one_pragma():
    """MatIEC's {{ ... }} holds C code whose braces end no pragma (OSCAT's
    OpenPLC translation, Beremiz's LOGGER block)."""
    got = diagnostics("FUNCTION_BLOCK L\nVAR_INPUT trig : BOOL; END_VAR\nVAR t0 : BOOL; END_VAR\n"
                      "IF trig AND NOT t0 THEN\n  {{\n   if (x) { f(1); }\n  }}\nEND_IF;\n"
                      "t0 := trig;\nEND_FUNCTION_BLOCK\n")
    assert got == [(5, 3, "warning", "pragma ignored")]


# the dialect forms of benchmarks/realcode.py's corpus: a refusal names the
# dialect (issue 25, deliverable 5)
@pytest.mark.parametrize("text,line,named", [
    ("PROGRAM P\nVAR p : POINTER TO INT; END_VAR\nEND_PROGRAM\n", 2,
     "POINTER TO, a CODESYS pointer type"),
    ("PROGRAM P\nVAR p : REFERENCE TO INT; END_VAR\nEND_PROGRAM\n", 2,
     "REFERENCE TO, a CODESYS reference type"),
    ("PROGRAM P\nVAR w : WORD; b : BOOL; END_VAR\nb := w.%X3;\nEND_PROGRAM\n", 3,
     "a partial access (.%X0, .%B1 ...), IEC 61131-3 ed.3"),
    ("PROGRAM P\nVAR b : BOOL; END_VAR\n/* ed.3 comment */\nb := TRUE;\nEND_PROGRAM\n", 3,
     "a /* */ comment, IEC 61131-3 ed.3"),
    ("VAR_GLOBAL\n  g : INT;\nEND_VAR\n", 1,
     "VAR_GLOBAL outside a CONFIGURATION, a CODESYS/TwinCAT global variable list"),
    ("PROGRAM P\nVAR t : UINT AT %MW0 := 20; END_VAR\nEND_PROGRAM\n", 2,
     "a location after the type, a form of some editors (ed.2 writes name AT %MW0 : UINT)"),
    ("PROGRAM P\nVAR n : INT; a : ARRAY[0..3] OF INT; END_VAR\nn := SIZEOF(a);\nEND_PROGRAM\n", 3,
     "SIZEOF is a CODESYS operator, not an IEC 61131-3 function"),
    ("PROGRAM P\nVAR n : INT; END_VAR\nn := __MOD(n, 2);\nEND_PROGRAM\n", 3,
     "a name beginning with '__' is no IEC 61131-3 identifier"),
    # OpenPLC Runtime v4's program.st: C code in (*DBG: ... *) comments
    ("PROGRAM P\nEND_PROGRAM\n(*DBG:    return (void *)&((__IEC_BOOL_t *) ptr)->value;*)\n", 3,
     "the comment opened on this line was ended by the '*)' inside it"),
])
def test_dialect_refusal_names_the_dialect(text, line, named):
    got = [d for d in diagnostics(text) if d[2] == "error"]
    assert got and got[0][0] == line and named in got[0][3], got


def test_overlap_of_two_sizes_names_openplc_tables():
    # OpenPLC's %QX0.0 and %QW0 are two things; here one byte array: the
    # message says so (github extralsc/openPLC_watertank, WaterTankPump.st)
    got = [d for d in diagnostics(
        "PROGRAM P\nVAR pump AT %QX0.0 : BOOL; level AT %QW0 : INT; END_VAR\n"
        "level := 3; pump := TRUE;\nEND_PROGRAM\n"
        "CONFIGURATION C RESOURCE R ON PLC TASK T (INTERVAL := T#10ms, PRIORITY := 1);\n"
        "PROGRAM i WITH T : P; END_RESOURCE END_CONFIGURATION\n") if d[2] == "error"]
    assert len(got) == 1 and "overlaps" in got[0][3] and \
        "OpenPLC keeps each size in a table of its own" in got[0][3], got
