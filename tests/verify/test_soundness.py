"""Issue 22: the four unsound verdicts of `iec2kmod verify` (each one a
class, each program here one of the class), vacuity, the sim command of a
counterexample replayed to the violation, streaming verdicts and
--timeout.  A counterexample is replayed with the command verify prints,
in the compiled C engine, and the violation is read from sim's final
values."""

from __future__ import annotations

import re
import shlex
import textwrap

import pytest

try:
    import z3  # noqa: F401
except ImportError:
    z3 = None

from iec2kmod import cli


@pytest.fixture(autouse=True)
def _need_z3():
    if z3 is None:
        pytest.fail("z3-solver is not installed: pip install z3-solver (scripts/setup.sh)")


def project(tmp_path, body, name="p.st"):
    d = tmp_path / "proj"
    d.mkdir(exist_ok=True)
    (d / name).write_text(textwrap.dedent(body))
    return d


def verify(capsys, proj, tmp_path, *args):
    rc = cli.main(["verify", str(proj), "--cex-dir", str(tmp_path / "cex"), *map(str, args)])
    out = capsys.readouterr()
    return rc, out.out, out.err


def verdict(out, name):
    m = re.search(rf"^  {re.escape(name)}\s+(.*)$", out, re.M)
    assert m, out
    return m.group(1)


def replay(capsys, out, name, watch):
    """Runs the `replay:` command printed under the check `name` (with
    --watch added) and returns sim's final values {variable: text}."""
    lines = out.splitlines()
    i = next(n for n, ln in enumerate(lines) if ln.startswith(f"  {name} "))
    cmd = next(ln.split("replay: ", 1)[1] for ln in lines[i + 1:i + 4] if "replay: " in ln)
    argv = shlex.split(cmd)
    assert argv[:2] == ["iec2kmod", "sim"], cmd
    rc = cli.main(argv[1:] + ["--watch", ",".join(watch)])
    sim_out = capsys.readouterr().out
    final = dict(re.findall(r"^  (\S+)\s+(\S+)$", sim_out, re.M))
    return rc, final


PRESS = """
    PROGRAM PRESS
      VAR_INPUT GUARD_SHUT : BOOL; HAND_L : BOOL; HAND_R : BOOL; ESTOP : BOOL; END_VAR
      VAR_OUTPUT CLOSE : BOOL; OPEN : BOOL; END_VAR
      VAR ARMED : BOOL; T : TON; END_VAR
      ARMED := (GUARD_SHUT OR T.Q) AND HAND_L AND HAND_R AND NOT ESTOP;
      T(IN := ARMED, PT := T#200ms);
      CLOSE := T.Q AND ARMED;
      OPEN := NOT CLOSE;
    END_PROGRAM
    CONFIGURATION CELL
      VAR_GLOBAL
        GUARD AT %IX0.0 : BOOL; L AT %IX0.1 : BOOL; R AT %IX0.2 : BOOL; STOP AT %IX0.3 : BOOL;
        RAM_CLOSE AT %QX0.0 : BOOL; RAM_OPEN AT %QX0.1 : BOOL;
      END_VAR
      RESOURCE PLC1 ON CPU0
        TASK CYC (INTERVAL := T#10ms, PRIORITY := 1);
        PROGRAM P1 WITH CYC : PRESS (GUARD_SHUT := GUARD, HAND_L := L, HAND_R := R, ESTOP := STOP,
                                     CLOSE => RAM_CLOSE, OPEN => RAM_OPEN);
      END_RESOURCE
    END_CONFIGURATION
"""


def test_induction_does_not_prove_a_latch_broken_by_an_input(tmp_path, capsys):
    """Class 1: k-induction kept the states of its path pairwise distinct
    INCLUDING the state after the violating cycle.  The violation reads
    that cycle's input (GUARD drops while the latch holds), so the
    shortest counterexample ends in a state it was in before (T.Q, CLOSE
    latched): the constraint cut every counterexample of length >= 2 and
    'proved' the property."""
    proj = project(tmp_path, PRESS)
    rc, out, err = verify(capsys, proj, tmp_path, "--property", "NOT (RAM_CLOSE AND NOT GUARD)",
                          "--depth", "40")
    v = verdict(out, "property 1")
    assert rc == 3 and v.startswith("violated at cycle 22"), out + err
    rc, final = replay(capsys, out, "property 1", ["GUARD", "RAM_CLOSE"])
    assert final == {"GUARD": "FALSE", "RAM_CLOSE": "TRUE"}, final


CNT = """
    PROGRAM Cnt
    VAR_INPUT go : BOOL; END_VAR
    VAR_OUTPUT n : INT; END_VAR
    {ASSUME}
    {verify never_counts: n = 0}
    {verify absurd: FALSE}
    IF go AND n < 1000 THEN n := n + 1; END_IF;
    END_PROGRAM
    CONFIGURATION C RESOURCE R ON CPU0
      TASK t (INTERVAL := T#10ms, PRIORITY := 1);
      PROGRAM p WITH t : Cnt (go := %IX0.0);
    END_RESOURCE END_CONFIGURATION
"""


@pytest.mark.parametrize("pragma,cli_assume", [("{assume: go}", []),
                                               ("", ["--assume", "R.p.go"])])
def test_assumption_on_a_connected_input_reads_this_steps_copy(tmp_path, capsys, pragma,
                                                                cli_assume):
    """Class 2: assumptions were evaluated on the state before the cycle,
    where a program input connected to an address still held the previous
    cycle's copy (its initial FALSE in cycle 1): `go` assumed TRUE made
    every run end before cycle 1, and everything was 'proved'."""
    proj = project(tmp_path, CNT.replace("{ASSUME}", pragma))
    rc, out, err = verify(capsys, proj, tmp_path, *cli_assume)
    assert rc == 3, out + err
    for name in ("R.p.never_counts", "R.p.absurd"):
        assert verdict(out, name).startswith("violated at cycle 1"), out
        # the replay runs exactly cycle 1 (n = 1, not 2), with go TRUE: the
        # counterexample satisfies the assumption
        rc, final = replay(capsys, out, name, ["R.p.go", "R.p.n"])
        assert final == {"R.p.go": "TRUE", "R.p.n": "1"}, final


def test_counterexample_respects_an_assumption_against_the_input(tmp_path, capsys):
    """`--assume "NOT R.p.go"` gave a counterexample with go TRUE in cycle 1."""
    proj = project(tmp_path, CNT.replace("{ASSUME}", ""))
    rc, out, err = verify(capsys, proj, tmp_path, "--assume", "NOT R.p.go")
    assert verdict(out, "R.p.never_counts").startswith("proved"), out
    assert verdict(out, "R.p.absurd").startswith("violated at cycle 1"), out
    rc, final = replay(capsys, out, "R.p.absurd", ["R.p.go", "R.p.n"])
    assert final == {"R.p.go": "FALSE", "R.p.n": "0"}, final


@pytest.mark.parametrize("assume,longest", [("%IX0.0 AND NOT %IX0.0", 0),
                                            ("R.p.go AND R.p.n < 3", 2)])
def test_assumptions_that_block_runs_are_vacuous(tmp_path, capsys, assume, longest):
    """Class 3: contradictory assumptions (no run at all), or ones that
    block every run after a few cycles, proved everything: the solver's
    path constraints were unsatisfiable, and an unsatisfiable induction
    query reads as 'proved'.  Now the runs the assumptions allow are
    measured first (bounded model checking of the assumptions alone) and
    a verdict about longer runs is 'vacuous', exit status 5."""
    proj = project(tmp_path, CNT.replace("{ASSUME}", ""))
    rc, out, err = verify(capsys, proj, tmp_path, "--assume", assume, "--property", "FALSE",
                          "--property", "R.p.n < 4")
    want = (f"vacuous: the assumptions allow no run longer than {longest} "
            f"cycle{'s' if longest != 1 else ''} (assuming {assume})")
    assert verdict(out, "property 2") == want, out
    assert verdict(out, "no runtime error") == want, out
    if longest == 0:
        assert rc == 5, out + err
        assert verdict(out, "property 1") == want, out
    else:
        # FALSE is violated in the runs the assumptions allow (cycle 1):
        # violated wins over vacuous
        assert rc == 3, out + err
        assert verdict(out, "property 1").startswith("violated at cycle 1"), out
    assert "proved" not in out, out


def test_proved_names_its_assumptions(tmp_path, capsys):
    proj = project(tmp_path, CNT.replace("{ASSUME}", "{assume: go}"))
    rc, out, err = verify(capsys, proj, tmp_path, "--property", "R.p.n <= 1000",
                          "--assume", "R.p.n >= 0")
    assert rc == 3, out + err       # the pragmas never_counts and absurd
    assert re.fullmatch(r"proved \(induction over \d+ cycles?, [0-9.]+ s; assuming go "
                        r"\(in R\.p\); R\.p\.n >= 0(; they allow runs of 20 cycles, .*)?\)",
                        verdict(out, "property 1")), out
    rc, out, err = verify(capsys, project(tmp_path, PRESS), tmp_path,
                          "--property", "RAM_OPEN = NOT RAM_CLOSE")
    assert rc == 0 and "no assumptions)" in verdict(out, "property 1"), out


TWO_TASKS = """
    PROGRAM Faulty
    VAR_EXTERNAL g : INT; END_VAR
    VAR z : INT; END_VAR
    VAR_OUTPUT q : INT; END_VAR
    g := 7;
    q := 100 / z;
    END_PROGRAM
    PROGRAM Counter
    VAR_OUTPUT n : INT; END_VAR
    IF n < 100 THEN n := n + 1; END_IF;
    END_PROGRAM
    CONFIGURATION C
    VAR_GLOBAL out_q : INT; g : INT; END_VAR
    RESOURCE R ON CPU0
      TASK fast (INTERVAL := T#10ms, PRIORITY := 1);
      TASK slow (INTERVAL := T#20ms, PRIORITY := 2);
      PROGRAM f WITH slow : Faulty (q => out_q);
      PROGRAM c WITH fast : Counter;
    END_RESOURCE END_CONFIGURATION
"""


def test_a_fault_stops_only_its_task(tmp_path, capsys):
    """Class 4: a runtime fault ended the run for every task (the
    properties were checked on fault-free runs only), so with a task that
    always faults in cycle 1 every property of the other task was proved,
    FALSE included.  Now a hidden bit per task stops the faulting one, its
    faulting cycle publishes nothing (g and out_q stay 0), and the other
    task goes on."""
    proj = project(tmp_path, TWO_TASKS)
    rc, out, err = verify(capsys, proj, tmp_path, "--property", "R.c.n < 5", "--property",
                          "FALSE", "--property", "g <> 7 AND out_q = 0")
    assert rc == 3, out + err
    assert verdict(out, "no runtime error").startswith(
        "violated at cycle 1: division by zero in Faulty"), out
    assert verdict(out, "property 1") == "violated at cycle 5", out
    assert verdict(out, "property 2") == "violated at cycle 1", out
    assert verdict(out, "property 3").startswith("proved"), out
    rc, final = replay(capsys, out, "property 1", ["R.c.n", "g", "out_q"])
    assert final == {"R.c.n": "5", "g": "0", "out_q": "0"}, final


def test_guards_narrow_the_interval_invariants(tmp_path, capsys):
    """`x := x + 1; IF x > 9 THEN x := 0; END_IF` is If(x + 1 <= 9, x + 1, 0):
    the guard cuts its own branch to [.., 9], so the candidate 0 <= x <= 9
    exists, Houdini proves it, and disp <= 90 is proved (it only 'held up
    to 20 cycles')."""
    proj = project(tmp_path, """
        PROGRAM Disp
        VAR x : INT; END_VAR
        VAR_OUTPUT disp : INT; END_VAR
        x := x + 1;
        IF x > 9 THEN x := 0; END_IF;
        disp := x * 10;
        END_PROGRAM
        CONFIGURATION C RESOURCE R ON CPU0
          TASK t (INTERVAL := T#10ms, PRIORITY := 1);
          PROGRAM p WITH t : Disp;
        END_RESOURCE END_CONFIGURATION
    """)
    rc, out, err = verify(capsys, proj, tmp_path, "--property", "R.p.disp <= 90",
                          "--property", "R.p.disp >= 0")
    assert rc == 0, out + err
    assert verdict(out, "property 1").startswith("proved"), out
    assert verdict(out, "property 2").startswith("proved"), out


def test_verdicts_stream_and_timeout_keeps_the_decided_ones(tmp_path):
    """Each verdict is printed when it is decided (a time-out lost verdicts
    decided in seconds); --timeout is the deadline of the whole run: what
    is not decided by then is 'unknown (timeout)', the others are kept."""
    import os
    import subprocess
    import sys
    import time
    from pathlib import Path
    proj = project(tmp_path, """
        PROGRAM Cnt
        VAR_OUTPUT n : DINT; END_VAR
        n := n + 1;
        END_PROGRAM
        CONFIGURATION C RESOURCE R ON CPU0
          TASK t (INTERVAL := T#10ms, PRIORITY := 1);
          PROGRAM p WITH t : Cnt;
        END_RESOURCE END_CONFIGURATION
    """)
    root = Path(__file__).resolve().parents[2]
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(root)] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]))
    t0 = time.monotonic()
    # property 2 is violated only at cycle 1000000: bounded model checking
    # cannot get there in 4 s
    p = subprocess.Popen([sys.executable, "-m", "iec2kmod", "verify", str(proj),
                          "--cex-dir", str(tmp_path / "cex"), "--depth", "2000000",
                          "--timeout", "4", "-p", "R.p.n = R.p.n", "-p", "R.p.n <> 1000000",
                          "-p", "TRUE"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    import threading
    killer = threading.Timer(60, p.kill)       # nothing waits forever
    killer.start()
    seen = {}
    for line in p.stdout:
        seen[line.split("  ")[1] if line.startswith("  ") else line] = \
            (time.monotonic() - t0, line.rstrip())
    rc = p.wait(timeout=60)
    killer.cancel()
    end = time.monotonic() - t0
    err = p.stderr.read()
    assert rc == 4, (seen, err)
    assert seen["property 1"][1].split("  ")[-1].startswith("proved"), seen
    # printed as soon as decided: seconds before the run ended at its deadline
    assert end - seen["property 1"][0] > 2.5, (end, seen)
    assert seen["property 2"][1].split("  ")[-1].startswith(
        "unknown (timeout): holds up to "), seen
    assert seen["property 3"][1].split("  ")[-1] == "unknown (timeout)", seen
    assert 3.5 < end < 30, end


def test_replay_refuses_a_trace_that_breaks_an_assumption(tmp_path):
    """The replay in the interpreter (before any violation is reported)
    checks the assumptions at every step of the trace, at the documented
    point: a counterexample breaking its own assumption (class 2) is not
    confirmed."""
    from iec2kmod.cli import front_end
    from iec2kmod.verify import verify as run_verify
    from iec2kmod.verify.cex import replay, write_trace
    proj = project(tmp_path, CNT.replace("{ASSUME}", "{assume: go}"))
    out = run_verify(front_end([str(proj)]), depth=3)
    r = next(r for r in out.results if r.name == "R.p.absurd")
    assert r.status == "violated" and r.cycle == 1
    good = tmp_path / "good.csv"
    write_trace(out, r, good)
    assert replay(out, r, str(good)) == (True, "the property is FALSE after that cycle")
    bad = tmp_path / "bad.csv"
    bad.write_text("time,variable,value\n0ns,%IX0.0,FALSE\n")
    ok, why = replay(out, r, str(bad))
    assert not ok and "breaks the assumption 'go' at step 1" in why, why
