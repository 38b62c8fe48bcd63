"""Selective execution (``sim --selective``, iec2kmod/codegen/selective.py):
hand-written cases for the edge cases of issue 11.  Each project runs plain
and selective on the same input trace; every variable of the table (globals,
program and FB instance variables) must change at the same simulated times
to the same values, faults included, and the selective run must actually
have skipped blocks where the case says so (a selective build that never
skips would pass the comparison for nothing).

The random-program campaign (tests/differential, engine ``selective``) is
the wide proof; these are the cases written on purpose."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from iec2kmod import sim
from iec2kmod.parse import frontend
from iec2kmod.codegen import generate
from iec2kmod.codegen.plan import build_plan
from iec2kmod.compilation import selective_plan
from iec2kmod.codegen.selective import SelectivePlan

pytestmark = pytest.mark.execution

ROOT = Path(__file__).resolve().parents[2]
MS = 1_000_000


def _project(tmp_path, text, name="case.st"):
    f = tmp_path / name
    f.write_text(text)
    res = frontend.run([str(f)], use_cache=False)
    assert res.ok, [d.format() for d in res.diags.sorted()]
    return res.project


def _trace(tmp_path, rows):
    p = tmp_path / "trace.csv"
    p.write_text("".join(f"{t}ms,{v},{x}\n" for t, v, x in rows))
    return str(p)


def _both(tmp_path, text, rows, duration_ms, mode="all"):
    """(plain result, selective result) of the same project and trace;
    asserts the traces are identical."""
    project = _project(tmp_path, text)
    watch = [e.path for e in build_plan(project).table]
    trace = _trace(tmp_path, rows)
    a = sim.run(project, duration_ms * MS, watch=watch, inputs=trace)
    b = sim.run(project, duration_ms * MS, watch=watch, inputs=trace, selective=mode)
    assert not a.selective, "the plain build counted selective blocks"
    assert a.names == b.names
    assert a.faults == b.faults, (a.faults, b.faults)
    assert a.cycles == b.cycles
    if a.changes != b.changes:
        first = next(i for i, (x, y) in enumerate(zip(a.changes, b.changes)) if x != y) \
            if any(x != y for x, y in zip(a.changes, b.changes)) else min(len(a.changes),
                                                                           len(b.changes))
        ca = a.changes[first] if first < len(a.changes) else None
        cb = b.changes[first] if first < len(b.changes) else None
        pytest.fail(f"traces differ at change {first}: plain "
                    f"{ca and (ca[0], a.names[ca[1]], ca[2])}, selective "
                    f"{cb and (cb[0], b.names[cb[1]], cb[2])}")
    return a, b


def _skipped(res):
    return sum(sk for _, sk in res.selective.values())


def _evaluated(res):
    return sum(ev for ev, _ in res.selective.values())


CONFIG = """
CONFIGURATION c
VAR_GLOBAL {globals} END_VAR
RESOURCE r ON CPU0
  TASK t (INTERVAL := T#10ms, PRIORITY := 1);
  PROGRAM p WITH t : Main;
END_RESOURCE
END_CONFIGURATION
"""


def test_skipped_block_output_overwritten_later(tmp_path):
    """A block writes a global (VAR_EXTERNAL) and an output bound to a
    global; code after it overwrites both.  When its inputs do not change
    it is skipped, yet the global must hold what plain execution rewrites
    every cycle: the overwritten external is in the block's argument set,
    the output binding is the caller's statement."""
    text = """
FUNCTION_BLOCK Put
VAR_INPUT x : INT; END_VAR
VAR_OUTPUT q : INT; END_VAR
VAR_EXTERNAL g : INT; END_VAR
g := x * 2;
q := x + 1;
END_FUNCTION_BLOCK

FUNCTION_BLOCK Pure
VAR_INPUT a, b : BOOL; END_VAR
VAR_OUTPUT y : BOOL; END_VAR
y := a AND NOT b;
END_FUNCTION_BLOCK

PROGRAM Main
VAR_EXTERNAL g, h, sel : INT; END_VAR
VAR put1 : Put; pure1 : Pure; END_VAR
put1(x := sel, q => h);
pure1(a := sel > 0, b := FALSE);
IF sel = 3 THEN g := 100; h := -1; END_IF;
END_PROGRAM
""" + CONFIG.format(globals="g, h, sel : INT;")
    rows = [(0, "sel", 1), (50, "sel", 3), (120, "sel", 3), (200, "sel", 2), (300, "sel", 3)]
    a, b = _both(tmp_path, text, rows, 500)
    final = b.values_at()
    assert final["g"] == 100 and final["h"] == -1
    assert b.values_at(250 * MS)["g"] == 4
    assert _skipped(b) > 20, b.selective


def test_timer_runs_out_while_inputs_do_not_change(tmp_path):
    """A block containing a TON depends on time: it is evaluated every
    cycle, so its Q rises PT after IN although no input changes; a
    time-independent block beside it is skipped."""
    text = """
FUNCTION_BLOCK Delay
VAR_INPUT start : BOOL; END_VAR
VAR_OUTPUT done : BOOL; END_VAR
VAR t : TON; END_VAR
t(IN := start, PT := T#200ms);
done := t.Q;
END_FUNCTION_BLOCK

FUNCTION_BLOCK Latch
VAR_INPUT s, r : BOOL; END_VAR
VAR_OUTPUT q : BOOL; END_VAR
q := (q OR s) AND NOT r;
END_FUNCTION_BLOCK

PROGRAM Main
VAR_EXTERNAL go, out, held : BOOL; END_VAR
VAR d : Delay; l : Latch; END_VAR
d(start := go);
out := d.done;
l(s := go, r := FALSE);
held := l.q;
END_PROGRAM
""" + CONFIG.format(globals="go, out, held : BOOL;")
    a, b = _both(tmp_path, text, [(100, "go", "TRUE")], 600)
    rises = [t for t, i, v in b.changes if b.names[i] == "out" and v is True]
    assert rises == [300 * MS], rises
    plan = selective_plan(_project(tmp_path, text), "all")
    report = "\n".join(plan.report())
    assert "function_block Delay: always evaluated: depends on time (contains TON)" in report
    assert "function_block Latch: selective" in report
    assert "program Main: always evaluated: depends on time" in report
    assert _skipped(b) > 40, b.selective        # the latch, after its input settled


def test_block_reads_global_written_by_another_task(tmp_path):
    """A slow task's block reads a global that a fast task writes now and
    then: the block is evaluated when the global changed, skipped
    otherwise; the program instance as a whole is skipped too."""
    text = """
FUNCTION_BLOCK Scale
VAR_INPUT k : INT; END_VAR
VAR_OUTPUT y : INT; END_VAR
VAR_EXTERNAL level : INT; END_VAR
y := level * k;
END_FUNCTION_BLOCK

PROGRAM Fast
VAR_EXTERNAL level, tick : INT; END_VAR
tick := tick + 1;
IF tick MOD 20 = 0 THEN level := level + 1; END_IF;
END_PROGRAM

PROGRAM Slow
VAR_EXTERNAL scaled : INT; END_VAR
VAR s : Scale; END_VAR
s(k := 3);
scaled := s.y;
END_PROGRAM

CONFIGURATION c
VAR_GLOBAL level, tick, scaled : INT; END_VAR
RESOURCE r ON CPU0
  TASK fast (INTERVAL := T#10ms, PRIORITY := 1);
  TASK slow (INTERVAL := T#30ms, PRIORITY := 2);
  PROGRAM f WITH fast : Fast;
  PROGRAM s WITH slow : Slow;
END_RESOURCE
END_CONFIGURATION
"""
    a, b = _both(tmp_path, text, [], 1000)
    assert b.values_at()["scaled"] == 3 * b.values_at()["level"]
    ev, sk = b.selective["r.slow"]
    assert sk > 10 and ev > 10, b.selective
    assert b.selective["r.fast"][1] == 0       # a counter never settles


def test_counter_and_writes_into_instances(tmp_path):
    """A block that counts (its state feeds back) never settles; a value
    written into an instance's internal variable from outside (the trace,
    like the manager) is seen although no input changed (the epoch)."""
    text = """
FUNCTION_BLOCK Count
VAR_INPUT ena : BOOL; END_VAR
VAR_OUTPUT n : DINT; END_VAR
IF ena THEN n := n + 1; END_IF;
END_FUNCTION_BLOCK

FUNCTION_BLOCK Hold
VAR_INPUT x : INT; END_VAR
VAR_OUTPUT y : INT; END_VAR
VAR offset : INT; END_VAR
y := x + offset;
END_FUNCTION_BLOCK

PROGRAM Main
VAR_EXTERNAL run : BOOL; total : DINT; out : INT; END_VAR
VAR c : Count; h : Hold; END_VAR
c(ena := run);
total := c.n;
h(x := 5);
out := h.y;
END_PROGRAM
""" + CONFIG.format(globals="run : BOOL; total : DINT; out : INT;")
    rows = [(0, "run", "TRUE"), (200, "run", "FALSE"), (300, "r.p.h.offset", 10),
            (400, "r.p.h.offset", 20)]
    a, b = _both(tmp_path, text, rows, 600)
    assert b.values_at()["total"] == 20
    assert b.values_at()["out"] == 25
    assert b.values_at(350 * MS)["out"] == 15
    assert _skipped(b) > 20


def test_fault_on_the_same_arguments_is_not_hidden(tmp_path):
    """A block that divides by its input faults in the cycle the input
    becomes 0, skipped or not before; and a block whose loop uses part of
    the cycle's budget is charged that part when skipped, so a later loop
    exhausts the budget in the same cycle and at the same line as in plain
    execution."""
    text = """
FUNCTION_BLOCK Divide
VAR_INPUT d : INT; END_VAR
VAR_OUTPUT q : INT; END_VAR
q := 1000 / d;
END_FUNCTION_BLOCK

FUNCTION_BLOCK Spin
VAR_INPUT n : DINT; END_VAR
VAR_OUTPUT s : DINT; END_VAR
VAR i : DINT; END_VAR
s := 0;
FOR i := 1 TO n DO
  s := s + 1;
END_FOR;
END_FUNCTION_BLOCK

PROGRAM Main
VAR_EXTERNAL d : INT; n1, n2 : DINT; q : INT; END_VAR
VAR a : Divide; big, grow : Spin; END_VAR
a(d := d);
q := a.q;
big(n := n1);
grow(n := n2);
END_PROGRAM

PROGRAM Other
VAR_EXTERNAL d2 : INT; q2 : INT; END_VAR
VAR a : Divide; END_VAR
a(d := d2);
q2 := a.q;
END_PROGRAM

CONFIGURATION c
VAR_GLOBAL d, d2, q, q2 : INT; n1, n2 : DINT; END_VAR
RESOURCE r ON CPU0
  TASK t (INTERVAL := T#10ms, PRIORITY := 1);
  TASK u (INTERVAL := T#10ms, PRIORITY := 2);
  PROGRAM p WITH t : Main;
  PROGRAM o WITH u : Other;
END_RESOURCE
END_CONFIGURATION
"""
    budget = sim.LOOP_BUDGET
    rows = [(0, "d", 4), (0, "d2", 5), (0, "n1", budget // 2 + 10), (0, "n2", 10),
            (200, "n2", budget // 4), (300, "n2", budget // 2), (400, "d2", 0)]
    a, b = _both(tmp_path, text, rows, 600)
    assert [(t // MS, task, f) for t, task, f, *_ in b.faults] == \
        [(300, "r.t", "endless loop (loop budget exhausted)"),
         (400, "r.u", "division by zero")], b.faults
    assert _skipped(b) > 20, b.selective


def test_pragmas_select_blocks(tmp_path):
    """{selective off} on an instance and on a program instance keeps them
    evaluated; --selective=marked skips only what {selective on} marks."""
    text = """
{selective on}
FUNCTION_BLOCK Marked
VAR_INPUT x : INT; END_VAR
VAR_OUTPUT y : INT; END_VAR
y := x * 3;
END_FUNCTION_BLOCK

FUNCTION_BLOCK Other
VAR_INPUT x : INT; END_VAR
VAR_OUTPUT y : INT; END_VAR
y := x - 1;
END_FUNCTION_BLOCK

PROGRAM Main
VAR_EXTERNAL x, y1, y2, y3 : INT; END_VAR
VAR
  m : Marked;
  {selective off} m_off : Marked;
  o : Other;
END_VAR
m(x := x); y1 := m.y;
m_off(x := x); y2 := m_off.y;
o(x := x); y3 := o.y;
END_PROGRAM

CONFIGURATION c
VAR_GLOBAL x, y1, y2, y3 : INT; END_VAR
RESOURCE r ON CPU0
  TASK t (INTERVAL := T#10ms, PRIORITY := 1);
  {selective off} PROGRAM p WITH t : Main;
END_RESOURCE
END_CONFIGURATION
"""
    rows = [(0, "x", 2), (300, "x", 5)]
    cycles = 51
    _, every = _both(tmp_path, text, rows, 500, mode="all")
    # the program instance is off: each cycle evaluates it plainly; m and o
    # are skipped except after a change; m_off is never counted
    ev, sk = every.selective["r.t"]
    assert ev + sk == 2 * cycles and sk >= 2 * cycles - 8, every.selective
    _, marked = _both(tmp_path, text, rows, 500, mode="marked")
    ev, sk = marked.selective["r.t"]
    assert ev + sk == cycles and sk >= cycles - 4, marked.selective
    project = _project(tmp_path, text)
    plan = selective_plan(project, "marked")
    main = project.pous["MAIN"]
    kinds = {v.name: plan.call_kind(main, v) for v in main.vars.values()
             if v.section == "VAR"}
    assert kinds == {"m": "sel", "m_off": "plain", "o": None}


def test_pragma_warnings_and_cli(tmp_path):
    """A selective pragma that precedes nothing it can apply to, or says
    something else than on/off, is a warning with file:line:col and a caret;
    `sim --selective` prints how many blocks it evaluated and skipped."""
    text = """
FUNCTION_BLOCK F
VAR_INPUT x : INT; END_VAR
VAR_OUTPUT y : INT; {selective off} END_VAR
y := x;
END_FUNCTION_BLOCK

PROGRAM Main
VAR_EXTERNAL x, y : INT; END_VAR
VAR {selective maybe} f : F; {selective off} n : INT; END_VAR
f(x := x); y := f.y + n;
END_PROGRAM
""" + CONFIG.format(globals="x, y : INT;")
    (tmp_path / "p.st").write_text(text)
    cmd = [sys.executable, "-m", "iec2kmod.cli", "sim", str(tmp_path / "p.st"), "--cycles", "20",
           "--selective"]
    p = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
    assert p.returncode == 0, p.stderr
    err = p.stderr
    assert f"{tmp_path / 'p.st'}:4:21: warning: selective pragma applies to nothing" in err, err
    assert "p.st:10:5: warning: unknown selective pragma" in err, err
    assert "p.st:10:30: warning: selective pragma on 'n', which is not an instance" in err, err
    assert "^" in err
    assert "pragma ignored" not in err
    assert "selective blocks: r.t 2 evaluated 19 skipped" in p.stdout, p.stdout
    plain = subprocess.run(cmd[:-1], capture_output=True, text=True, cwd=ROOT)
    assert plain.returncode == 0 and "selective" not in plain.stdout + plain.stderr


def test_generated_code_deterministic_and_plain_unchanged(tmp_path):
    """The selective C is the same bytes every time; without --selective
    nothing of it appears (the plain output is the plain output)."""
    project = _project(tmp_path, (ROOT / "examples" / "hvac" / "hvac.st").read_text())
    one = generate(project, selective=selective_plan(project, "all"))
    two = generate(project, selective=selective_plan(project, "all"))
    plain = generate(project)
    assert one.header == two.header and one.bodies == two.bodies
    assert "sel" in one.header and "_run(" in "".join(b for _, b in one.bodies.values())
    blob = plain.header + "".join(b for _, b in plain.bodies.values())
    assert "iec_sel" not in blob and "_run(" not in blob and "IEC_SEL_TOKEN" not in blob


def test_state_read_in_an_assignment_target(tmp_path):
    """A member read only inside an assignment's target (``b[k] := ...``)
    is read (the written-state analysis must see it: k is assigned whole
    right after, so it would otherwise be left out): its change keeps the
    block from settling.  Here k changes
    from 0 to 3 in the first evaluation while nothing else of the written
    state changes; the second (plain) evaluation clears b[3], so a skip
    there would leave b[3] TRUE.  And a caller that reads a nested
    instance's output in an index before calling it (feedback through a
    target) is told every evaluation of it."""
    text = """
FUNCTION_BLOCK Stale
VAR_INPUT go : BOOL; END_VAR
VAR_OUTPUT b : ARRAY[0..9] OF BOOL := [FALSE, FALSE, FALSE, TRUE]; END_VAR
VAR k : INT; END_VAR
b[k] := FALSE;
k := 3;
END_FUNCTION_BLOCK

FUNCTION_BLOCK Inner
VAR_INPUT x : INT; END_VAR
VAR_OUTPUT q : INT; END_VAR
q := x;
END_FUNCTION_BLOCK

FUNCTION_BLOCK Outer
VAR_INPUT x : INT; END_VAR
VAR_OUTPUT flags : ARRAY[0..9] OF BOOL; END_VAR
VAR d : Inner; END_VAR
flags[d.q] := TRUE;
d(x := x);
END_FUNCTION_BLOCK

PROGRAM Main
VAR_EXTERNAL sel : INT; hit : BOOL; seen : WORD; END_VAR
VAR s : Stale; o : Outer; i : INT; END_VAR
s(go := TRUE);
hit := s.b[3];
o(x := sel);
seen := 0;
FOR i := 0 TO 9 DO
    IF o.flags[i] THEN seen := seen OR SHL(WORD#1, i); END_IF;
END_FOR;
END_PROGRAM
""" + CONFIG.format(globals="sel : INT; hit : BOOL; seen : WORD;")
    rows = [(0, "sel", 0), (50, "sel", 3), (150, "sel", 5), (250, "sel", 5)]
    a, b = _both(tmp_path, text, rows, 400)
    assert b.values_at()["hit"] is False
    assert b.values_at()["seen"] == (1 << 0) | (1 << 3) | (1 << 5)
    assert _skipped(b) > 20, b.selective


def test_written_state_leaves_out_what_is_assigned_before_it_is_read(tmp_path):
    """The written state of a block (rule 4) leaves out the outputs and
    internals it assigns whole on every path before anything reads them
    (through IF and CASE with an ELSE) and keeps those read first on some
    path; the skipped runs stay invisible.  (first counts up: Dev is not
    idempotent, rule 8, so it has a written state at all.)"""
    text = """
FUNCTION_BLOCK Dev
VAR_INPUT a, b : BOOL; n : INT; END_VAR
VAR_OUTPUT st, w, latch, first : INT; END_VAR
VAR tmp : INT; END_VAR
tmp := n * 2;
IF a THEN st := 1; ELSIF b THEN st := 2; ELSE st := 0; END_IF;
CASE n OF 1: w := tmp; ELSE w := st; END_CASE;
IF a THEN first := first + 5; END_IF;
IF first > latch THEN latch := first; END_IF;
END_FUNCTION_BLOCK

PROGRAM Main
VAR_EXTERNAL x : INT; fa, fb : BOOL; out : INT; END_VAR
VAR d : Dev; END_VAR
d(a := fa, b := fb, n := x);
out := d.st + d.w + d.latch;
END_PROGRAM
""" + CONFIG.format(globals="x : INT; fa, fb : BOOL; out : INT;")
    project = _project(tmp_path, text)
    plan = selective_plan(project, "all")
    dev = next(b for b in plan.blocks.values() if b.pou.name == "Dev")
    assert [m for m, _ in plan._written(dev.pou)] == ["v_latch", "v_first"]
    # rule 8 narrows it further: latch := first changes nothing a second
    # evaluation reads, first's count does
    assert [m for m, _ in dev.written] == ["v_first"], dev.written
    rows = [(0, "x", 1), (40, "fa", "TRUE"), (80, "fa", "FALSE"), (120, "fb", "TRUE"),
            (200, "x", 2), (260, "fb", "FALSE")]
    a, b = _both(tmp_path, text, rows, 400)
    assert _skipped(b) > 5, b.selective


def test_plain_runs_of_a_busy_block_keep_its_caller_unsettled(tmp_path):
    """A block whose arguments kept changing runs plainly for a while
    (rule 4); a full evaluation of its caller during that time must not
    settle, or the caller would be skipped and a block that never settles
    (a counter) would stop.  The phases give the inner counter short busy
    periods (its level was reset while only x changed) that outlast the
    long one of its caller: the caller's full evaluation at the end of
    its period meets the counter still running plainly."""
    text = """
FUNCTION_BLOCK Count
VAR_INPUT y : INT; END_VAR
VAR_OUTPUT n : DINT; END_VAR
n := n + 1;
END_FUNCTION_BLOCK

FUNCTION_BLOCK Wrap
VAR_INPUT x, y : INT; END_VAR
VAR_OUTPUT n : DINT; s : INT; END_VAR
VAR c : Count; END_VAR
s := x;
c(y := y);
n := c.n;
END_FUNCTION_BLOCK

PROGRAM Main
VAR_EXTERNAL x, y : INT; out : DINT; END_VAR
VAR w : Wrap; END_VAR
w(x := x, y := y);
out := w.n;
END_PROGRAM
""" + CONFIG.format(globals="x, y : INT; out : DINT;")
    rows, c, x, y = [], 0, 0, 0
    for phase, n in (("y", 40), ("x", 30), ("xy", 20)):
        for _ in range(n):
            for v in phase:
                x, y = (x + 1, y) if v == "x" else (x, y + 1)
                rows.append((c * 10, v, x if v == "x" else y))
            c += 1
    cycles = c + 600
    a, b = _both(tmp_path, text, rows, cycles * 10 - 5)
    assert b.values_at()["out"] == cycles
    assert _evaluated(b) >= 2 * cycles, b.selective


IDEMPOTENT = """
FUNCTION_BLOCK Guard
VAR_INPUT start, stop, ok : BOOL; END_VAR
VAR_OUTPUT run, alarm : BOOL; code : INT; END_VAR
VAR seal : SR; END_VAR
seal(S1 := start AND ok, R := stop OR NOT ok);
run := seal.Q1;
IF NOT ok THEN code := 2; ELSIF stop THEN code := 1; ELSE code := 0; END_IF;
alarm := NOT ok AND start;
END_FUNCTION_BLOCK

PROGRAM Main
VAR_EXTERNAL a, b, c, run : BOOL; code : INT; END_VAR
VAR g : Guard; END_VAR
g(start := a, stop := b, ok := c);
run := g.run;
code := g.code;
END_PROGRAM
""" + CONFIG.format(globals="a, b, c, run : BOOL; code : INT;")
IDEMPOTENT_ROWS = [(0, "c", "TRUE"), (100, "a", "TRUE"), (200, "a", "FALSE"),
                   (300, "b", "TRUE"), (400, "c", "FALSE"), (500, "b", "FALSE")]


def test_idempotent_block_settles_in_one_evaluation(tmp_path):
    """Rule 8: Guard (an SR seal-in and combinational logic) is proved
    idempotent, so an evaluation on new arguments settles it: no confirm
    run the next cycle.  Main writes globals (not idempotent: its own
    confirm run stays).  Per input change Guard is evaluated once; Main
    once when what it writes stays as it was, else three times (its
    arguments include the globals it wrote, so the next evaluation is a
    fast one, rule 4, and the one after it settles).  Without rule 8:
    24 evaluations."""
    project = _project(tmp_path, IDEMPOTENT)
    plan = selective_plan(project, "all")
    guard = next(b for b in plan.blocks.values() if b.pou.name == "Guard")
    main = next(b for b in plan.blocks.values() if b.pou.name == "Main")
    assert guard.idempotent and guard.written == [], guard.idem_note
    assert not main.idempotent and main.idem_note == "writes run", main.idem_note
    assert "function_block Guard: selective, idempotent" in "\n".join(plan.report())
    a, b = _both(tmp_path, IDEMPOTENT, IDEMPOTENT_ROWS, 700)
    assert b.values_at(150 * MS)["run"] is True and b.values_at(350 * MS)["run"] is False
    # the first cycle: Main, Guard, Main's confirm; then per change
    # (a rises: run; a falls: nothing; b: run, code; c: code; b: nothing)
    assert _evaluated(b) == 3 + 4 + 2 + 4 + 4 + 2, b.selective
    assert _skipped(b) > 60, b.selective


EDGE = """
FUNCTION_BLOCK Pulse
VAR_INPUT x, ena : BOOL; END_VAR
VAR_OUTPUT n : INT; lit : BOOL; END_VAR
VAR t : R_TRIG; END_VAR
t(CLK := x);
IF t.Q AND ena THEN n := n + 1; END_IF;
lit := x AND ena;
END_FUNCTION_BLOCK

PROGRAM Main
VAR_EXTERNAL a, e : BOOL; n : INT; END_VAR
VAR p : Pulse; END_VAR
p(x := a, ena := e);
n := p.n;
END_PROGRAM
""" + CONFIG.format(globals="a, e : BOOL; n : INT;")


def test_edge_detector_inside_a_block_is_not_idempotent(tmp_path):
    """An R_TRIG inside a block: the second evaluation on the same
    arguments drops t.Q (a variable of the table), so the type is not
    idempotent and its confirm run stays; the comparison is narrowed to
    the R_TRIG's memory (n, lit, t.CLK and t.Q unchanged or not, a second
    evaluation changes nothing when the memory stayed).
    Taking it for idempotent would leave p.t.Q TRUE in the trace."""
    project = _project(tmp_path, EDGE)
    plan = selective_plan(project, "all")
    pulse = next(b for b in plan.blocks.values() if b.pou.name == "Pulse")
    assert not pulse.idempotent and "$self.t.Q" in pulse.idem_note, pulse.idem_note
    assert [m for m, _ in pulse.written] == ["v_t.prev"], pulse.written
    rows = [(0, "e", "TRUE"), (100, "a", "TRUE"), (200, "a", "FALSE"), (250, "a", "TRUE"),
            (400, "e", "FALSE"), (450, "a", "FALSE"), (500, "a", "TRUE")]
    a, b = _both(tmp_path, EDGE, rows, 700)
    falls = [t for t, i, v in b.changes if b.names[i] == "r.p.p.t.Q" and v is False]
    assert 110 * MS in falls, falls
    assert b.values_at()["n"] == 2
    assert _skipped(b) > 50, b.selective


FAULT_LATER = """
FUNCTION_BLOCK Arm
VAR_INPUT d : INT; END_VAR
VAR_OUTPUT armed : BOOL; END_VAR
VAR_TEMP t : INT; END_VAR
IF armed THEN t := 100 / d; END_IF;
armed := TRUE;
END_FUNCTION_BLOCK

PROGRAM Main
VAR_EXTERNAL d : INT; ok : BOOL; END_VAR
VAR arm : Arm; END_VAR
arm(d := d);
ok := arm.armed;
END_PROGRAM
""" + CONFIG.format(globals="d : INT; ok : BOOL;")


def test_second_evaluation_that_faults_is_not_idempotent(tmp_path):
    """Arm's second evaluation leaves the state as the first left it, but
    divides by d: idempotence needs the second evaluation to be free of
    faults too.  Plain execution faults in the second cycle; so must the
    selective one."""
    project = _project(tmp_path, FAULT_LATER)
    plan = selective_plan(project, "all")
    arm = next(b for b in plan.blocks.values() if b.pou.name == "Arm")
    assert not arm.idempotent and arm.idem_note == "a second evaluation changes a fault", \
        arm.idem_note
    a, b = _both(tmp_path, FAULT_LATER, [(0, "d", 0)], 100)
    assert [f[2] for f in b.faults][:1] == ["division by zero"], b.faults


def test_settle_rule_refusals(tmp_path):
    """Rule 8 refuses what its model cannot stand for: a loop, REAL
    state, writes to a global; those keep the confirm run."""
    text = """
FUNCTION_BLOCK Loopy
VAR_INPUT n : INT; END_VAR
VAR_OUTPUT s : INT; END_VAR
VAR i : INT; END_VAR
s := 0;
FOR i := 1 TO n DO s := s + i; END_FOR;
END_FUNCTION_BLOCK

FUNCTION_BLOCK Flt
VAR_INPUT x : REAL; END_VAR
VAR_OUTPUT y : REAL; END_VAR
y := x * 2.0;
END_FUNCTION_BLOCK

FUNCTION_BLOCK Put
VAR_INPUT x : INT; END_VAR
VAR_EXTERNAL g : INT; END_VAR
g := x;
END_FUNCTION_BLOCK

PROGRAM Main
VAR_EXTERNAL g : INT; r : REAL; END_VAR
VAR l : Loopy; f : Flt; p : Put; END_VAR
l(n := g);
f(x := r);
p(x := 3);
END_PROGRAM
""" + CONFIG.format(globals="g : INT; r : REAL;")
    plan = selective_plan(_project(tmp_path, text), "all")
    notes = {b.pou.name: b.idem_note for b in plan.blocks.values()}
    assert notes["Loopy"].startswith("a loop"), notes
    assert "REAL" in notes["Flt"], notes
    assert notes["Put"] == "writes g", notes
    assert not any(b.idempotent for b in plan.blocks.values())


def test_marked_mode_takes_instance_marks_on_unmarked_types(tmp_path):
    """--selective=marked with {selective on} on an instance (its type not
    marked) and on a program instance: those are skipped, the unmarked ones
    not (issue 29's mutation benchmark: `inst.pou is pou` flipped to `is
    not` in SelectivePlan._type_wanted gave the selective layout to the
    types of the other program instances instead of the marked one's, and
    passed every test)."""
    text = """
FUNCTION_BLOCK F
VAR_INPUT x : INT; END_VAR
VAR_OUTPUT y : INT; END_VAR
y := x * 3;
END_FUNCTION_BLOCK

PROGRAM Main
VAR_EXTERNAL x, y1, y2 : INT; END_VAR
VAR
  {selective on} m : F;
  n : F;
END_VAR
m(x := x); y1 := m.y;
n(x := x); y2 := n.y;
END_PROGRAM

PROGRAM Other
VAR_EXTERNAL x, y3 : INT; END_VAR
y3 := x + 1;
END_PROGRAM

CONFIGURATION c
VAR_GLOBAL x, y1, y2, y3 : INT; END_VAR
RESOURCE r ON CPU0
  TASK t (INTERVAL := T#10ms, PRIORITY := 1);
  PROGRAM p WITH t : Main;
  {selective on} PROGRAM q WITH t : Other;
END_RESOURCE
END_CONFIGURATION
"""
    project = _project(tmp_path, text)
    plan = SelectivePlan(project, "marked")
    main = project.pous["MAIN"]
    kinds = {v.name: plan.call_kind(main, v) for v in main.vars.values()
             if v.section == "VAR"}
    assert kinds == {"m": "sel", "n": "plain"}, kinds
    rows = [(0, "x", 2), (300, "x", 5)]
    _, marked = _both(tmp_path, text, rows, 500, mode="marked")
    ev, sk = marked.selective["r.t"]
    # m and the program instance q are counted (2 x 51 runs), most skipped
    assert ev + sk == 2 * 51 and sk > 51, marked.selective


def test_settle_refused_for_inout_beside_a_written_input(tmp_path):
    """Rule 8 refuses a block with an in-out whose body writes one of its
    inputs.  Today the checker refuses every write to a VAR_INPUT, so the
    clause is unreachable (the mutation benchmark's survivor
    selective.py `pou.node.body or []` -> `and []` is equivalent for that
    reason); once a write to an input is only a warning (the real-users'
    branch), this pins the clause."""
    text = """
FUNCTION_BLOCK F
VAR_INPUT a : INT; END_VAR
VAR_IN_OUT io : INT; END_VAR
VAR_OUTPUT o : INT; END_VAR
a := a + io;
o := a;
END_FUNCTION_BLOCK
"""
    f = tmp_path / "w.st"
    f.write_text(text)
    res = frontend.run([str(f)], use_cache=False)
    if not res.ok:
        assert any("input 'a'" in d.message for d in res.diags.errors), \
            [d.format() for d in res.diags.sorted()]
        pytest.skip("a write to a VAR_INPUT is an error: the clause cannot be reached")
    plan = SelectivePlan(res.project, "all")
    b = plan.blocks[res.project.pous["F"].key]
    assert plan._settle_refused(b) == "an in-out beside a body that writes its inputs"


def test_instances_that_keep_their_eno(tmp_path):
    """f.ENO read (checks/declare.fb_eno): the instances keep the ENO of
    their last call, which the caller writes (TRUE before the body, FALSE
    when EN = FALSE skips it) -- a user block (Latch, whose ENO the program
    reads) and standard blocks inside it (R_TRIG, SR: the runtime's struct
    inside one with ENO, compared field by field by rule 8).  Selective and
    plain traces identical, and blocks skipped while the inputs stand."""
    text = """
FUNCTION_BLOCK Latch
VAR_INPUT x, go : BOOL; END_VAR
VAR_OUTPUT q, rise_eno, hold_eno : BOOL; END_VAR
VAR t : R_TRIG; hold : SR; END_VAR
t(EN := go, CLK := x);
hold(EN := go, S1 := t.Q, R := NOT x);
q := hold.Q1;
rise_eno := t.ENO;
hold_eno := hold.ENO;
END_FUNCTION_BLOCK

PROGRAM Main
VAR_EXTERNAL a, e : BOOL; le : BOOL; END_VAR
VAR l : Latch; END_VAR
l(EN := e, x := a, go := a OR e);
le := l.ENO;
END_PROGRAM
""" + CONFIG.format(globals="a, e, le : BOOL;")
    rows = [(0, "e", "TRUE"), (40, "a", "TRUE"), (150, "e", "FALSE"), (260, "e", "TRUE"),
            (330, "a", "FALSE"), (420, "e", "FALSE")]
    a, b = _both(tmp_path, text, rows, 500)
    assert [b.values_at(t * MS)["le"] for t in (30, 200, 300, 490)] == \
        [True, False, True, False]
    assert b.values_at(100 * MS)["r.p.l.q"] is True, b.names
    assert b.values_at(360 * MS)["r.p.l.rise_eno"] is True
    assert _skipped(b) > 10, b.selective
