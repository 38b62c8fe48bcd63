"""`iec2kmod verify --engine explicit`: the explicit-state referee on small
hand-written programs -- proved, violated at the shortest cycle (its
counterexample replayed by `iec2kmod sim --engine interp`), vacuous, too large,
a fault that stops only its task, and the PRESS of issue 22."""

from __future__ import annotations

import csv
import textwrap

from iec2kmod import cli


def project(tmp_path, body, name="p.st"):
    d = tmp_path / "proj"
    d.mkdir(exist_ok=True)
    (d / name).write_text(textwrap.dedent(body))
    return d


def explicit(capsys, *args):
    rc = cli.main(["verify", "--engine", "explicit", *map(str, args)])
    out = capsys.readouterr()
    return rc, out.out, out.err


def verdict(out, name):
    for line in out.splitlines():
        if line.startswith(f"  {name} "):
            return line[len(name) + 2:].strip()
    raise AssertionError(f"no verdict for {name} in:\n{out}")


def sim_final(capsys, proj, trace, duration, watch, tmp_path):
    out_csv = tmp_path / "sim.csv"
    cli.main(["sim", "--engine", "interp", str(proj), "--inputs", str(trace), "--duration",
              duration, "--watch", ",".join(watch), "--csv", str(out_csv)])
    err = capsys.readouterr().err
    last = {}
    with open(out_csv) as fh:
        for row in csv.DictReader(fh):
            last.update({k: v for k, v in row.items() if v != ""})
    return last, err


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
        PROGRAM P1 WITH CYC : PRESS (GUARD_SHUT := GUARD, HAND_L := L, HAND_R := R,
                                     ESTOP := STOP, CLOSE => RAM_CLOSE, OPEN => RAM_OPEN);
      END_RESOURCE
    END_CONFIGURATION
"""


def test_press_violated_at_the_shortest_cycle_and_replays(capsys, tmp_path):
    # issue 22 case 1: the timer's output latches the arming; GUARD, L, R
    # TRUE for 21 cycles (T.Q at 200 ms), GUARD dropped at cycle 22
    proj = project(tmp_path, PRESS)
    cex = tmp_path / "cex"
    rc, out, err = explicit(capsys, proj, "-p", "NOT (RAM_CLOSE AND NOT GUARD)",
                            "--cex-dir", cex)
    assert rc == 3, out + err
    assert verdict(out, "property 1").startswith("violated at cycle 22"), out
    assert verdict(out, "no runtime error").startswith("proved"), out
    assert "--duration 210ms" in out
    last, _ = sim_final(capsys, proj, cex / "cex_property_1.csv", "210ms",
                        ["RAM_CLOSE", "GUARD"], tmp_path)
    assert last["RAM_CLOSE"] == "TRUE" and last["GUARD"] == "FALSE", last
    assert (cex / "cex_property_1.vcd").stat().st_size > 0
    # the closing needs GUARD at the start: proved over every reachable state
    rc, out, err = explicit(capsys, proj, "-p", "NOT RAM_CLOSE OR L", "--cex-dir", cex)
    assert rc == 0 and verdict(out, "property 1").startswith("proved"), out


COUNTER = """
    PROGRAM Cnt
    VAR_INPUT go : BOOL; END_VAR
    VAR_OUTPUT n : SINT; END_VAR
    IF go AND n < 9 THEN n := n + 1; END_IF;
    END_PROGRAM
    CONFIGURATION C RESOURCE R ON CPU0
      TASK t (INTERVAL := T#10ms, PRIORITY := 1);
      PROGRAM p WITH t : Cnt (go := %IX0.0);
    END_RESOURCE END_CONFIGURATION
"""


def test_counter_proved_and_shortest_violation(capsys, tmp_path):
    proj = project(tmp_path, COUNTER)
    rc, out, err = explicit(capsys, proj, "-p", "R.p.n <= 9", "-p", "R.p.n < 7",
                            "--cex-dir", tmp_path / "cex")
    assert rc == 3, out + err
    assert verdict(out, "property 1") == "proved (every reachable state explored: 19)", out  # n, and the copy of go
    # n = 7 after 7 cycles with go: not before
    assert verdict(out, "property 2").startswith("violated at cycle 7"), out
    rows = list(csv.reader(open(tmp_path / "cex" / "cex_property_2.csv")))
    assert rows == [["time", "variable", "value"], ["0ns", "%IX0.0", "TRUE"]], rows


def test_assumption_read_with_the_inputs_of_the_step(capsys, tmp_path):
    # issue 22 case 2: {assume: go} holds on the value the cycle read, so
    # n counts from cycle 1 and FALSE is violated at cycle 1
    proj = project(tmp_path, COUNTER.replace("VAR_OUTPUT", "{assume: go}\nVAR_OUTPUT"))
    rc, out, err = explicit(capsys, proj, "-p", "R.p.n = 0", "-p", "FALSE",
                            "--cex-dir", tmp_path / "cex")
    assert rc == 3, out + err
    assert verdict(out, "property 1").startswith("violated at cycle 1"), out
    assert verdict(out, "property 2").startswith("violated at cycle 1"), out


def test_vacuous(capsys, tmp_path):
    proj = project(tmp_path, COUNTER)
    rc, out, err = explicit(capsys, proj, "--assume", "%IX0.0 AND NOT %IX0.0", "-p", "FALSE")
    assert rc == 5, out + err
    assert verdict(out, "property 1") == \
        "vacuous: the assumptions allow no run longer than 0 cycles", out
    # a run-blocking assumption: n < 3 after the cycle, n counts every cycle
    rc, out, err = explicit(capsys, proj, "--assume", "R.p.go AND R.p.n < 3",
                            "-p", "R.p.n < 4")
    assert rc == 5, out + err
    assert verdict(out, "property 1") == \
        "vacuous: the assumptions allow no run longer than 2 cycles", out
    assert "assuming: R.p.go AND R.p.n < 3" in out
    # an assumption some runs satisfy forever is no vacuity
    rc, out, err = explicit(capsys, proj, "--assume", "R.p.n < 3", "-p", "R.p.n < 3")
    assert rc == 0 and verdict(out, "property 1").startswith("proved"), out


def test_too_large(capsys, tmp_path):
    proj = project(tmp_path, """
        PROGRAM P
        VAR_INPUT x : INT; END_VAR
        VAR_OUTPUT y : INT; END_VAR
        y := x;
        END_PROGRAM
        CONFIGURATION C RESOURCE R ON CPU0
          TASK t (INTERVAL := T#10ms, PRIORITY := 1);
          PROGRAM p WITH t : P (x := %IW0);
        END_RESOURCE END_CONFIGURATION
    """)
    rc, out, err = explicit(capsys, proj, "-p", "R.p.y < 100")
    assert rc == 4, out + err
    assert verdict(out, "property 1") == "too large: 65536 input valuations per step (more " \
                                         "than --max-inputs 4096)", out
    proj = project(tmp_path, COUNTER.replace("n < 9", "n < 100"))
    rc, out, err = explicit(capsys, proj, "--max-states", 50, "-p", "R.p.n < 120")
    assert rc == 4, out + err
    assert verdict(out, "property 1") == "too large: more than 50 states (--max-states); " \
                                         "every run of 25 cycles explored", out
    # a violation found before the bound is still reported
    rc, out, err = explicit(capsys, proj, "--max-states", 50, "-p", "R.p.n < 5",
                            "--cex-dir", tmp_path / "cex")
    assert rc == 3 and verdict(out, "property 1").startswith("violated at cycle 5"), out


def test_a_fault_stops_only_its_task(capsys, tmp_path):
    # issue 22 case 4: Fast faults at cycle 4 (k = 4); Slow (every third
    # step) keeps counting: m = 5 at step 13
    proj = project(tmp_path, """
        PROGRAM Fast
        VAR_INPUT a : BOOL; END_VAR
        VAR_OUTPUT k : SINT; END_VAR
        VAR d : SINT; END_VAR
        IF a THEN k := k + 1; END_IF;
        IF k > 3 THEN d := 10 / (k - k); END_IF;
        END_PROGRAM
        PROGRAM Slow
        VAR_OUTPUT m : USINT; END_VAR
        IF m < 200 THEN m := m + 1; END_IF;
        END_PROGRAM
        CONFIGURATION C RESOURCE R ON CPU0
          TASK tf (INTERVAL := T#10ms, PRIORITY := 1);
          TASK ts (INTERVAL := T#30ms, PRIORITY := 2);
          PROGRAM f WITH tf : Fast (a := %IX0.0);
          PROGRAM s WITH ts : Slow;
        END_RESOURCE END_CONFIGURATION
    """)
    rc, out, err = explicit(capsys, proj, "-p", "R.s.m < 5", "-p", "R.f.k < 6",
                            "--cex-dir", tmp_path / "cex")
    assert rc == 3, out + err
    assert verdict(out, "no runtime error").startswith(
        "violated at cycle 4: division by zero in Fast at "), out
    assert verdict(out, "property 1").startswith("violated at cycle 13"), out
    assert verdict(out, "property 2").startswith("proved"), out
    last, err = sim_final(capsys, proj, tmp_path / "cex" / "cex_property_1.csv", "120ms",
                          ["R.s.m"], tmp_path)
    assert last["R.s.m"] == "5", (last, err)


def test_refusals_and_usage(capsys, tmp_path):
    proj = project(tmp_path, COUNTER)
    rc, out, err = explicit(capsys, proj, "-p", "R.p.n / 0 = 1")
    assert rc == 1 and "error: verify: the property faults (division by zero)" in err, err
    rc, out, err = explicit(capsys, proj, "--max-states", 0)
    assert rc == 2 and "--max-states" in err
