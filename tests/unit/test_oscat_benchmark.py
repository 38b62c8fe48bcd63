"""benchmarks/oscat.py at smoke size, on a stand-in written here in the shape
of OSCAT's OpenPLC translation (chapters with build/generated_plc.st, each
with its own program0 and Config0, POUs repeated across chapters, a copy
that lost its VAR_INPUT, a POU outside ed.2 and its caller).  No OSCAT
source is used: CI has no copy of it; the real run is
``python3 benchmarks/oscat.py --oscat PATH``.  The smoke run of the script
(tests/benchmarks/test_benchmarks_smoke.py names this file for it) is
test_smoke_run_checks_everything_and_runs_three_cases_in_c."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.unit
ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "benchmarks" / "oscat.py"

BOILERPLATE = """
PROGRAM program0
  VAR
    LocalVar0 : DINT;
    LocalVar1 : DINT;
  END_VAR
  LocalVar1 := LocalVar0;
END_PROGRAM


CONFIGURATION Config0

  RESOURCE Res0 ON PLC
    TASK task0(INTERVAL := T#20ms,PRIORITY := 0);
    PROGRAM instance0 WITH task0 : program0;
  END_RESOURCE
END_CONFIGURATION
"""

CHAPTER_1 = """TYPE
  PAIR : STRUCT
    A : INT;
    B : INT;
  END_STRUCT;
  SMALL : INT;
END_TYPE

FUNCTION TWICE : INT
  VAR_INPUT
    X : INT;
  END_VAR
  TWICE := X * 2;
END_FUNCTION

FUNCTION HALF : INT
  VAR
    X : INT;
  END_VAR
  HALF := X / 2;
END_FUNCTION

FUNCTION_BLOCK EDGECOUNT
  VAR_INPUT
    CLK : BOOL;
  END_VAR
  VAR_OUTPUT
    N : INT;
  END_VAR
  VAR
    trig : R_TRIG;
  END_VAR
  trig(CLK := CLK);
  IF trig.Q THEN
    N := N + 1;
  END_IF;
  (* a comment with END_FUNCTION_BLOCK in it *)
END_FUNCTION_BLOCK

FUNCTION_BLOCK HEXOF
  VAR_INPUT
    IN : BYTE;
  END_VAR
  VAR_OUTPUT
    _HEXOF : STRING;
  END_VAR
  _HEXOF := BYTE_TO_STRING(IN, '%02X');
END_FUNCTION_BLOCK

FUNCTION_BLOCK SHOWHEX
  VAR_OUTPUT
    S : STRING;
  END_VAR
  VAR
    h : HEXOF;
  END_VAR
  h(IN := BYTE#16#2A);
  S := h._HEXOF;
END_FUNCTION_BLOCK
""" + BOILERPLATE

CHAPTER_2 = """FUNCTION TWICE : INT
  VAR_INPUT
    X : INT;
  END_VAR
  TWICE := X * 2;
END_FUNCTION

FUNCTION HALF : INT
  VAR_INPUT
    X : INT;
  END_VAR
  HALF := X / 2;
END_FUNCTION

FUNCTION QUARTER : INT
  VAR_INPUT
    X : INT;
  END_VAR
  QUARTER := HALF(HALF(X));
END_FUNCTION
""" + BOILERPLATE

# what Beremiz puts in front of every plc.st: MatIEC inline C in {{ }}
LOGGER = """FUNCTION_BLOCK LOGGER
  VAR_INPUT
    TRIG : BOOL;
    MSG : STRING;
  END_VAR
  VAR
    TRIG0 : BOOL;
  END_VAR
  IF TRIG AND NOT TRIG0 THEN
  {{
   LogMessage(GetFbVar(LEVEL),(char*)GetFbVar(MSG, .body),GetFbVar(MSG, .len));
  }}
  END_IF;
  TRIG0:=TRIG;
END_FUNCTION_BLOCK

"""

CASES = '''
from dataclasses import dataclass, field


@dataclass
class Case:
    name: str
    pou: str
    outputs: list
    doc: str
    calls: list = field(default_factory=list)
    tol: float = 1e-5
    note: str = ""
    needs: tuple = ()
    known: str = ""

    @property
    def kind(self):
        return "FB" if self.calls else "F"


CASES = [
    Case("TWICE", "TWICE", [("TWICE(21)", "INT", 42)], "doubles X"),
    Case("QUARTER", "QUARTER", [("QUARTER(X := 40)", "INT", WANT_QUARTER)], "a quarter of X"),
    Case("EDGECOUNT", "EDGECOUNT", [("N", "INT", 2)], "counts rising edges of CLK",
         calls=["CLK := TRUE", "CLK := FALSE", "CLK := TRUE", "CLK := TRUE"]),
]
KNOWN_REFUSALS = {"HEXOF": "a printf format argument to BYTE_TO_STRING"}
'''


def _standin(tmp_path: Path) -> Path:
    top = tmp_path / "OSCAT_OpenPLC" / "OSCAT BASIC 3.33"
    for name, text in (("OSCAT BASIC 3.33-1 First", CHAPTER_1),
                       ("OSCAT BASIC 3.33-2 Second", CHAPTER_2)):
        build = top / name / "build"
        build.mkdir(parents=True)
        (build / "generated_plc.st").write_text(text)
        (build / "plc.st").write_text(LOGGER + text)
    return top


def _run(*args, timeout=600):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    p = subprocess.run([sys.executable, str(SCRIPT), *args], capture_output=True, text=True,
                       env=env, timeout=timeout)
    return p.returncode, p.stdout, p.stderr


def test_standin_library_checks_and_cases_agree_in_every_engine(tmp_path):
    top = _standin(tmp_path)
    cases = tmp_path / "cases.py"
    cases.write_text(CASES.replace("WANT_QUARTER", "10"))
    rc, out, err = _run("--oscat", str(top.parent), "--cases-file", str(cases),
                        "--json", str(tmp_path / "r.json"))
    assert rc == 0, out + err
    lines = out.splitlines()
    # chapter 1: TWICE, HALF, EDGECOUNT, SHOWHEX, program0 accepted; HEXOF refused
    assert any("OSCAT BASIC 3.33-1 First" in s and "5/6   POUs accepted  (1 errors" in s for s in lines), out
    assert "      refused FUNCTION_BLOCK HEXOF: line 47: BYTE_TO_STRING takes 1 argument, " \
           "2 given" in lines, out
    assert any("OSCAT BASIC 3.33-2 Second" in s and "4/4   POUs accepted  (0 errors" in s for s in lines), out
    assert "  total: 9/10 POUs accepted, 1 refused" in lines, out
    # the library: TWICE once, HALF's copy with its input kept, no program0
    assert "== library: 6 POUs and 2 types after removing 1 identical repetitions; " \
           "1 conflicting definitions" in lines, out
    assert "    conflict: FUNCTION HALF of OSCAT BASIC 3.33-1 First differs from the one of " \
           "OSCAT BASIC 3.33-2 Second (kept: the copy declaring 1 parameters; this one " \
           "declares 0)" in lines, out
    assert "  errors of the whole library by cause (1):" in lines, out
    assert "       1  BYTE_TO_STRING takes 1 argument, 2 given" in lines, out
    assert "  4/6 POUs check clean together; left out 2:" in lines, out
    assert "    FUNCTION_BLOCK HEXOF (OSCAT BASIC 3.33-1 First): BYTE_TO_STRING takes 1 " \
           "argument, 2 given" in lines, out
    assert "        outside ed.2: a printf format argument to BYTE_TO_STRING" in lines, out
    assert "    FUNCTION_BLOCK SHOWHEX (OSCAT BASIC 3.33-1 First): calls HEXOF, left out" \
        in lines, out
    assert "  c: 3/3 cases agree with the documentation (0 not run)" in lines, out
    assert any(s.startswith("  vm: 3/3") or s.startswith("  interp: 3/3") for s in lines), out
    assert (tmp_path / "r.json").stat().st_size > 0


def test_a_wrong_expectation_fails_and_says_it_is_unexplained(tmp_path):
    top = _standin(tmp_path)
    cases = tmp_path / "cases.py"
    cases.write_text(CASES.replace("WANT_QUARTER", "11"))
    engine = "vm" if "vm" in subprocess.run(
        [sys.executable, "-m", "iec2kmod", "sim", "--help"], capture_output=True, text=True,
        env=dict(os.environ, PYTHONPATH=str(ROOT))).stdout else "interp"
    rc, out, err = _run("--oscat", str(top), "--cases-file", str(cases), "--engines", engine)
    assert rc == 1, out + err
    assert f"  DIFFERS QUARTER [{engine}]: got QUARTER(X := 40)=10; documented " \
           "QUARTER(X := 40)=11" in out.splitlines(), out
    assert "      why: not yet explained" in out.splitlines(), out
    assert f"  {engine}: 2/3 cases agree with the documentation (0 not run)" in out.splitlines()


def test_a_case_that_does_not_check_is_reported_not_run(tmp_path):
    top = _standin(tmp_path)
    cases = tmp_path / "cases.py"
    cases.write_text(CASES.replace("WANT_QUARTER", "10").replace(
        '"TWICE(21)"', '"TWICE(TRUE)"'))
    rc, out, err = _run("--oscat", str(top), "--cases-file", str(cases), "--engines", "c")
    assert rc == 1, out + err
    assert any(s.startswith("  NOT RUN TWICE: ") for s in out.splitlines()), out
    assert "  c: 2/2 cases agree with the documentation (1 not run)" in out.splitlines(), out


@pytest.mark.parametrize("what", ["missing", "empty"])
def test_without_a_copy_of_oscat_it_fails_saying_what_to_provide(tmp_path, what):
    path = tmp_path / "nowhere"
    if what == "empty":
        path.mkdir()
    rc, out, err = _run("--oscat", str(path), "--no-run")
    assert rc == 2 and out == ""
    assert ("not a directory (give a copy of github.com/wonka929/OSCAT_OpenPLC)" in err
            if what == "missing" else "no <chapter>/build/generated_plc.st under" in err), err


def test_plc_st_with_matiec_inline_c_checks_like_generated_plc_st(tmp_path):
    top = _standin(tmp_path)
    cases = tmp_path / "cases.py"
    cases.write_text(CASES.replace("WANT_QUARTER", "10"))
    rc, out, err = _run("--oscat", str(top), "--plc-st", "--no-run", "--cases-file", str(cases))
    assert rc == 0, out + err
    lines = out.splitlines()
    assert lines[0] == "== chapters (2, plc.st)"
    assert any("OSCAT BASIC 3.33-1 First" in s and "6/7   POUs accepted  (1 errors" in s
               for s in lines), out
    assert "  total: 11/12 POUs accepted, 1 refused" in lines, out


def test_smoke_run_checks_everything_and_runs_three_cases_in_c(tmp_path):
    top = _standin(tmp_path)
    cases = tmp_path / "cases.py"
    cases.write_text(CASES.replace("WANT_QUARTER", "10").replace(
        "KNOWN_REFUSALS", 'CASES.append(Case("TWICE2", "TWICE", [("TWICE(2)", "INT", 5)], "x"))'
        "\nKNOWN_REFUSALS"))
    rc, out, err = _run("--oscat", str(top), "--cases-file", str(cases), "--smoke")
    assert rc == 0, out + err
    lines = out.splitlines()
    assert "  total: 9/10 POUs accepted, 1 refused" in lines, out
    assert "  4/6 POUs check clean together; left out 2:" in lines, out
    # the fourth case (a wrong expectation) is not run, nor any engine but C
    assert "== 3 cases (3 values) from OSCAT's documentation, engines c" in lines, out
    assert "  c: 3/3 cases agree with the documentation (0 not run)" in lines, out
    assert not any(s.startswith(("  vm:", "  interp:")) for s in lines), out


def test_the_case_table_names_each_case_once_and_repeats_no_call():
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        import oscat_cases
    finally:
        sys.path.remove(str(ROOT / "benchmarks"))
    names = [c.name for c in oscat_cases.CASES]
    assert len(names) == len(set(names)), sorted(n for n in names if names.count(n) > 1)
    calls = [o[0].replace(" ", "").upper() for c in oscat_cases.CASES if c.kind == "F"
             for o in c.outputs]
    assert len(calls) == len(set(calls)), sorted(c for c in calls if calls.count(c) > 1)
    assert all(c.doc for c in oscat_cases.CASES)
    assert oscat_cases.t("T#1d2h24m") == (26 * 3600 + 24 * 60) * 10**9
    assert oscat_cases.d(2008, 2, 29) == 1204243200 and oscat_cases.tod(12, 6) == 43560000
