"""`iec2kmod sim --engine interp` is a drop-in for the C engine on the command
line: the same stdout, --csv, --vcd and --list bytes, the same runtime fault
message and exit code, the same usage errors."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.execution

ROOT = Path(__file__).resolve().parents[2]
CASES = ROOT / "tests" / "execution" / "cases"


def sim(tmp_path, engine, *args):
    out = tmp_path / engine
    out.mkdir(exist_ok=True)
    p = subprocess.run([sys.executable, "-m", "iec2kmod.cli", "sim", *args,
                        "--csv", str(out / "o.csv"), "--vcd", str(out / "o.vcd"),
                        *(["--engine", engine] if engine != "c" else [])],
                       cwd=ROOT, capture_output=True, text=True, timeout=600)
    return p, (out / "o.csv"), (out / "o.vcd")


TRACES = {
    "traffic_light": "0,%IX0.0,TRUE\n700ms,%IX0.0,FALSE\n1500ms,plc.night_switch,TRUE\n",
    "watchdog_event": "".join(f"{t * 100}ms,plc.heartbeat_in,{'TRUE' if t % 2 else 'FALSE'}\n"
                              for t in range(1, 14)),
    "pid_loop": "0,%IX0.0,TRUE\n1s,%IW2,300\n",
}


@pytest.mark.parametrize("example", sorted(TRACES))
def test_same_output_files(example, tmp_path):
    trace = tmp_path / "in.csv"
    trace.write_text("time,variable,value\n" + TRACES[example])
    args = [f"examples/{example}", "--duration", "3s", "--inputs", str(trace)]
    c, c_csv, c_vcd = sim(tmp_path, "c", *args)
    v, v_csv, v_vcd = sim(tmp_path, "interp", *args)
    assert c.returncode == 0, c.stderr
    assert (v.returncode, v.stdout, v.stderr) == (c.returncode, c.stdout, c.stderr)
    assert v_csv.read_bytes() == c_csv.read_bytes()
    assert v_vcd.read_bytes() == c_vcd.read_bytes()
    assert c_csv.read_text().count("\n") > 5


def test_vm_is_an_alias_of_interp(tmp_path):
    """`--engine vm`, the interpreter's former name, still selects it."""
    args = ["examples/traffic_light", "--cycles", "5"]
    i, i_csv, _ = sim(tmp_path, "interp", *args)
    v, v_csv, _ = sim(tmp_path, "vm", *args)
    assert i.returncode == 0, i.stderr
    assert (v.returncode, v.stdout, v.stderr) == (i.returncode, i.stdout, i.stderr)
    assert v_csv.read_bytes() == i_csv.read_bytes()
    s = subprocess.run([sys.executable, "-m", "iec2kmod.cli", "sim", *args, "--engine", "vm",
                        "--sanitize"], cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert s.returncode == 2 and "--sanitize applies to the C engine only" in s.stderr


def test_same_list(tmp_path):
    run = [sys.executable, "-m", "iec2kmod.cli", "sim", "examples/batch_mixer", "--list",
           "--cycles", "1"]
    c = subprocess.run(run, cwd=ROOT, capture_output=True, text=True, timeout=600)
    v = subprocess.run(run + ["--engine", "interp"], cwd=ROOT, capture_output=True, text=True,
                       timeout=600)
    assert c.returncode == v.returncode == 0
    assert v.stdout == c.stdout and len(c.stdout.splitlines()) > 10


def test_same_fault_report(tmp_path):
    case = CASES / "faults" / "fault_other_task.st"
    c, _, _ = sim(tmp_path, "c", str(case), "--cycles", "6")
    v, _, _ = sim(tmp_path, "interp", str(case), "--cycles", "6")
    assert c.returncode == 1 and "runtime error:" in c.stderr
    assert (v.returncode, v.stdout, v.stderr) == (c.returncode, c.stdout, c.stderr)


def test_same_usage_errors(tmp_path):
    for args in (["examples/traffic_light", "--cycles", "3", "--watch", "no_such_var"],
                 ["examples/traffic_light", "--duration", "forever"]):
        c, _, _ = sim(tmp_path, "c", *args)
        v, _, _ = sim(tmp_path, "interp", *args)
        assert c.returncode == 2
        assert (v.returncode, v.stderr) == (c.returncode, c.stderr)


RANGE_ST = """TYPE Pct : INT (0..100); END_TYPE
PROGRAM P
VAR_INPUT u : USINT; p : Pct; w : WORD; i : SINT; END_VAR
VAR y : INT; END_VAR
  y := USINT_TO_INT(u) + p;
END_PROGRAM
CONFIGURATION C
  RESOURCE R ON PLC
    TASK T (INTERVAL := T#10ms, PRIORITY := 1);
    PROGRAM I WITH T : P;
  END_RESOURCE
END_CONFIGURATION
"""


@pytest.mark.parametrize("var,value,ok", [
    ("r.i.u", "255", True), ("r.i.u", "256", False), ("r.i.u", "-1", False),
    ("r.i.p", "100", True), ("r.i.p", "101", False), ("r.i.p", "-1", False),
    ("r.i.w", "16#FFFF", True), ("r.i.w", "65536", False),
    ("r.i.i", "-128", True), ("r.i.i", "128", False)])
def test_input_trace_values_out_of_range_are_refused(tmp_path, var, value, ok):
    """A value the variable cannot hold is an error naming the trace's line
    and the range, in both engines (as `plc-manager write` refuses it); it
    used to wrap silently."""
    src = tmp_path / "range.st"
    src.write_text(RANGE_ST)
    trace = tmp_path / "in.csv"
    trace.write_text(f"time,variable,value\n0,{var},{value}\n")
    c, _, _ = sim(tmp_path, "c", str(src), "--cycles", "1", "--inputs", str(trace))
    v, _, _ = sim(tmp_path, "interp", str(src), "--cycles", "1", "--inputs", str(trace))
    assert (v.returncode, v.stderr) == (c.returncode, c.stderr)
    if ok:
        assert c.returncode == 0, c.stderr
    else:
        assert c.returncode == 2 and f"in.csv:2: invalid value '{value}'" in c.stderr, c.stderr
        assert "out of range" in c.stderr, c.stderr


def test_vm_needs_no_c_compiler():
    env = {**__import__("os").environ, "CC": "no-such-compiler"}
    run = [sys.executable, "-m", "iec2kmod.cli", "sim", "examples/traffic_light", "--cycles", "3"]
    v = subprocess.run(run + ["--engine", "interp"], cwd=ROOT, capture_output=True, text=True,
                       timeout=600, env=env)
    assert v.returncode == 0 and "simulated" in v.stdout, v.stderr
    c = subprocess.run(run, cwd=ROOT, capture_output=True, text=True, timeout=600, env=env)
    assert c.returncode == 2 and "no C compiler" in c.stderr
