"""Textual SFC in the front end and the code generator: diagnostics as
``file:line:col: error:`` with the source line and a caret, syntax errors
without tracebacks, the checked model, the C of the cycle model and its
determinism.  Execution: tests/execution/cases/sfc (both engines); the
refused programs with every message: tests/errors/sfc.st."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from iec2kmod.checks import check_project
from iec2kmod.checks.sfc import STEP_T
from iec2kmod.codegen import generate
from iec2kmod.diagnostics import Diagnostics, SourceFile
from iec2kmod.parse.parser import parse_source

pytestmark = pytest.mark.unit
ROOT = Path(__file__).resolve().parents[2]

GOOD = """PROGRAM Seq
VAR go, lamp : BOOL; n : INT; tv : TIME := T#20ms; END_VAR
INITIAL_STEP Idle: END_STEP
TRANSITION t1 (PRIORITY := 2) FROM Idle TO (Run, Watch) := go;
END_TRANSITION
STEP Run: Work(N); lamp(D, tv); Once(P0); END_STEP
STEP Watch: END_STEP
TRANSITION FROM (Run, Watch) TO Idle :
    LD Run.T
    GE T#100ms
END_TRANSITION
ACTION Work:
    n := n + 1;
END_ACTION
ACTION Once:
    LD n
    ADD 100
    ST n
END_ACTION
END_PROGRAM
"""


def check_text(text, name="t.st"):
    diags = Diagnostics()
    unit = parse_source(SourceFile(name, text), diags)
    project = check_project([unit], diags) if unit is not None and not diags.errors else None
    return project, diags


def run_cli(*args):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    p = subprocess.run([sys.executable, "-m", "iec2kmod.cli", *args], env=env,
                       capture_output=True, text=True, timeout=120)
    return p.returncode, p.stdout + p.stderr


def test_checked_model():
    project, diags = check_text(GOOD)
    assert not diags.errors, [d.message for d in diags.items]
    pou = project.pous["SEQ"]
    assert [v.name for v in pou.sfc.steps] == ["Idle", "Run", "Watch"]
    assert all(v.type is STEP_T for v in pou.sfc.steps)
    assert pou.var("Idle").init is not None and pou.var("Run").init is None
    (t1, t2) = pou.sfc.transitions
    assert t1.priority == 2 and [v.name for v in t1.targets] == ["Run", "Watch"]
    assert t2.priority is None and [v.name for v in t2.sources] == ["Run", "Watch"]
    acts = {a.name: a for a in pou.sfc.actions}
    assert set(acts) == {"Work", "Once", "lamp"}
    assert acts["lamp"].var is pou.var("lamp") and acts["Work"].var is None
    assert [(a.step.name, a.qualifier) for a in acts["lamp"].assocs] == [("Run", "D")]
    assert acts["lamp"].assocs[0].time.name == "tv"


def test_diagnostic_has_position_source_line_and_caret(tmp_path):
    bad = GOOD.replace("TO (Run, Watch)", "TO (Run, Wach)")
    f = tmp_path / "bad.st"
    f.write_text(bad)
    rc, out = run_cli("check", "--no-cache", str(f))
    assert rc == 1, out
    lines = out.splitlines()
    i = next(k for k, ln in enumerate(lines) if "undeclared step 'Wach'" in ln)
    assert lines[i] == f"{f}:4:50: error: undeclared step 'Wach' in TO"
    assert lines[i + 1] == "TRANSITION t1 (PRIORITY := 2) FROM Idle TO (Run, Wach) := go;"
    assert lines[i + 2] == " " * 49 + "^"
    assert "Traceback" not in out


@pytest.mark.parametrize("text, message", [
    ("INITIAL_STEP S0: A(N) END_STEP", "expected"),                  # ';' missing
    ("INITIAL_STEP S0: A(X); END_STEP", "expected"),                 # unknown qualifier
    ("INITIAL_STEP S0: END_STEP TRANSITION FROM TO S0 := TRUE; END_TRANSITION", "expected"),
    ("INITIAL_STEP S0: END_STEP TRANSITION FROM S0 TO S0 :\nEND_TRANSITION", "expected"),
    ("INITIAL_STEP S0:", "expected"),
    ("INITIAL_STEP S0: END_STEP ACTION A: n := ; END_ACTION", "expected"),
    ("STEP S0: END_STEP TRANSITION FROM S0 TO S0 := TRUE; END_TRANSITION",
     "no INITIAL_STEP in the network of step 'S0'"),
    ("INITIAL_STEP S0: A(L, 5); END_STEP ACTION A: END_ACTION",
     "qualifier L needs a time: write A(L, T#1s)"),
])
def test_bad_sfc_gives_an_error_not_a_traceback(text, message):
    # the front end's own entry points: any exception here is a traceback
    _, diags = check_text(f"PROGRAM P\nVAR n : INT; END_VAR\n{text}\nEND_PROGRAM\n", "p.st")
    errors = [d for d in diags.items if d.severity == "error"]
    assert errors, "no error reported"
    first = errors[0].format()
    assert first.startswith("p.st:") and ": error: " in first and message in first, first
    lines = first.splitlines()
    assert len(lines) == 3 and lines[2].strip() == "^", first


def test_c_of_the_cycle_model_is_deterministic():
    a, _ = check_text(GOOD)
    b, _ = check_text(GOOD)
    ca, cb = generate(a, "x"), generate(b, "x")
    assert ca.bodies == cb.bodies and ca.header == cb.header
    body = ca.bodies["SEQ"][1]
    # the phases of the cycle model, in their order
    marks = ["self->h_sfc_started = 1;", "self->v_idle.v_t = ", "sfc_tc0 = 0;",
             "iec_fb_action_control(&self->h_sfc_ac0, ctx);", "if (self->h_sfc_ac0.a) {"]
    where = [body.index(m) for m in marks]
    assert where == sorted(where), body
    # PRIORITY := 2 is evaluated before the transition without priority
    assert body.index("if (self->v_idle.v_x) {") < body.index(
        "if (self->v_run.v_x && self->v_watch.v_x) {")
    assert "struct iec_fb_action_control h_sfc_ac2;" in ca.header
    assert "struct t___sfc_step v_idle;" in ca.header


def test_sfc_words_stay_usable_as_names():
    # STEP, TRANSITION, FROM, INITIAL_STEP are keywords only inside an SFC
    # body: ST and IL bodies may still use them as variable names
    _, diags = check_text("""PROGRAM p
VAR step, transition, from : INT; initial_step : BOOL; END_VAR
step := 1;
transition := step + 1;
from := 2;
initial_step := TRUE;
END_PROGRAM
PROGRAM q
VAR step : INT; END_VAR
  LD step
  ADD 1
  ST step
END_PROGRAM
""")
    assert not diags.errors, [d.format() for d in diags.items]
