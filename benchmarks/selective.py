#!/usr/bin/env python3
"""Benchmark: selective execution (issue 11, seed 001) -- instructions per
scan, plain versus ``--selective``, same program, same inputs.

Three programs, written out by this script (--keep DIR keeps them):

    interlock  an interlock-heavy machine: 10 stations of 10 devices, each
               device an Interlock block (permissives, trip latch with
               first-out, alarm word, mode and command logic) reading its
               I/O structure through VAR_IN_OUT; 1,000 BOOL inputs
    plant      a process plant: 40 PID loops (P, I with anti-windup and
               bumpless manual, D on the error, output limits, deadband,
               alarms) on REAL; 120 inputs (PV, SP, manual flag)
    packaging  a packaging line: 60 conveyor sections (photo-eye edges,
               product counter, reject gate, downstream interlock), 12 of
               them with a jam timer (TON: always evaluated); 240 inputs

Each runs N cycles of its task in the host simulator (the generated C
compiled with -O2 -fno-strict-aliasing, as the kernel's Makefile compiles
the modules: --cflags changes the extra flags; without it gcc's type-based
alias analysis drops, after a plain call of a body that cannot fault, the
reload of ctx->fault that the kernel build keeps) under valgrind's callgrind with
--toggle-collect on the task function: the instructions of the programs
and everything they call, not the simulator's loop.  The input trace
changes a given percentage of the inputs every cycle (0, 1, 10, 50, 100 %;
BOOLs flip, REALs move within the loop's deadband around its setpoint),
from a fixed seed; the plain and the selective run read the same trace and
their traces of every global must be identical (checked).

    python3 benchmarks/selective.py [--cycles 400] [--rates 0,1,10,50,100] [--smoke]
                                    [--cflags=-fno-strict-aliasing]

Prints the whole table: instructions per scan plain and selective, their
ratio, and the share of blocks skipped.  Targets (issue 11): >= 5x fewer
instructions at <= 1 % change on the interlock program, <= 10 % more at
100 % change.  valgrind: apt-get install valgrind (scripts/setup.sh)."""

from __future__ import annotations

import argparse
import random
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from iec2kmod import sim  # noqa: E402
from iec2kmod.parse import frontend  # noqa: E402
from iec2kmod.compilation import Compilation  # noqa: E402
from iec2kmod.traces import read_trace  # noqa: E402

INTERVAL_MS = 10


# ------------------------------------------------------------------ programs
def interlock(stations=10, devices=10):
    fields = ["auto_mode", "start_cmd", "stop_cmd", "guard_ok", "pressure_ok", "temp_ok",
              "level_ok", "fb_running", "reset", "bypass"]
    units = "\n".join(f"    d{k}(io := io.dev[{k}]);" for k in range(1, devices + 1))
    run_sum = " +\n        ".join(f"BOOL_TO_INT(d{k}.run_cmd)" for k in range(1, devices + 1))
    trip_sum = " +\n        ".join(f"BOOL_TO_INT(d{k}.tripped)" for k in range(1, devices + 1))
    alarms = " OR\n        ".join(f"d{k}.alarm_word" for k in range(1, devices + 1))
    text = f"""
TYPE
    DeviceIO : STRUCT
{chr(10).join(f"        {f} : BOOL;" for f in fields)}
    END_STRUCT;
    StationIO : STRUCT
        dev : ARRAY[1..{devices}] OF DeviceIO;
    END_STRUCT;
END_TYPE

FUNCTION_BLOCK Interlock
VAR_IN_OUT io : DeviceIO; END_VAR
VAR_OUTPUT
    run_cmd, permissive, tripped, discrepancy : BOOL;
    first_out : INT;
    alarm_word : WORD;
    status : INT;
    trip_count : UDINT;
END_VAR
VAR_EXTERNAL estop_chain, line_enable : BOOL; END_VAR
VAR
    process_ok : BOOL;
    start_edge : R_TRIG;
    reset_edge : R_TRIG;
END_VAR
    process_ok := (io.pressure_ok AND io.temp_ok AND io.level_ok) OR io.bypass;
    permissive := estop_chain AND line_enable AND io.guard_ok AND process_ok;
    start_edge(CLK := io.start_cmd);
    reset_edge(CLK := io.reset);
    IF NOT tripped THEN
        IF NOT estop_chain THEN
            first_out := 5;
        ELSIF NOT io.guard_ok THEN
            first_out := 1;
        ELSIF NOT (io.pressure_ok OR io.bypass) THEN
            first_out := 2;
        ELSIF NOT (io.temp_ok OR io.bypass) THEN
            first_out := 3;
        ELSIF NOT (io.level_ok OR io.bypass) THEN
            first_out := 4;
        ELSIF run_cmd AND NOT io.fb_running THEN
            first_out := 6;
        ELSE
            first_out := 0;
        END_IF;
        IF run_cmd AND first_out <> 0 THEN
            tripped := TRUE;
            trip_count := trip_count + 1;
        END_IF;
    ELSIF reset_edge.Q AND permissive THEN
        tripped := FALSE;
        first_out := 0;
    END_IF;
    discrepancy := run_cmd <> io.fb_running;
    IF tripped OR NOT permissive OR io.stop_cmd THEN
        run_cmd := FALSE;
    ELSIF io.auto_mode AND start_edge.Q THEN
        run_cmd := TRUE;
    END_IF;
    alarm_word := 0;
    IF NOT io.guard_ok THEN alarm_word := alarm_word OR 16#0001; END_IF;
    IF NOT io.pressure_ok THEN alarm_word := alarm_word OR 16#0002; END_IF;
    IF NOT io.temp_ok THEN alarm_word := alarm_word OR 16#0004; END_IF;
    IF NOT io.level_ok THEN alarm_word := alarm_word OR 16#0008; END_IF;
    IF io.bypass THEN alarm_word := alarm_word OR 16#0010; END_IF;
    IF tripped THEN alarm_word := alarm_word OR 16#0020; END_IF;
    IF discrepancy THEN alarm_word := alarm_word OR 16#0040; END_IF;
    IF NOT estop_chain THEN alarm_word := alarm_word OR 16#0080; END_IF;
    IF tripped THEN
        status := 100 + first_out;
    ELSIF run_cmd THEN
        status := 2;
    ELSIF permissive THEN
        status := 1;
    ELSE
        status := 0;
    END_IF;
END_FUNCTION_BLOCK

FUNCTION_BLOCK Station
VAR_IN_OUT io : StationIO; END_VAR
VAR_OUTPUT running, tripped : INT; alarms : WORD; END_VAR
VAR d{', d'.join(str(k) for k in range(1, devices + 1))} : Interlock; END_VAR
{units}
    running := {run_sum};
    tripped := {trip_sum};
    alarms := {alarms};
END_FUNCTION_BLOCK

PROGRAM Machine
VAR_EXTERNAL
    st : ARRAY[1..{stations}] OF StationIO;
    running, tripped : INT;
    alarms : ARRAY[1..{stations}] OF WORD;
END_VAR
VAR s{', s'.join(str(k) for k in range(1, stations + 1))} : Station; END_VAR
{chr(10).join(f"    s{k}(io := st[{k}]);" for k in range(1, stations + 1))}
    running := {' + '.join(f's{k}.running' for k in range(1, stations + 1))};
    tripped := {' + '.join(f's{k}.tripped' for k in range(1, stations + 1))};
{chr(10).join(f"    alarms[{k}] := s{k}.alarms;" for k in range(1, stations + 1))}
END_PROGRAM

CONFIGURATION Press
VAR_GLOBAL
    estop_chain : BOOL := TRUE;
    line_enable : BOOL := TRUE;
    st : ARRAY[1..{stations}] OF StationIO;
    running, tripped : INT;
    alarms : ARRAY[1..{stations}] OF WORD;
END_VAR
RESOURCE main ON CPU0
    TASK scan (INTERVAL := T#{INTERVAL_MS}ms, PRIORITY := 1);
    PROGRAM machine WITH scan : Machine;
END_RESOURCE
END_CONFIGURATION
"""
    inputs = [(f"st[{s}].dev[{d}].{f}", "bool", None) for s in range(1, stations + 1)
              for d in range(1, devices + 1) for f in fields]
    start = {p: "TRUE" for p, _, _ in inputs
             if p.rsplit(".", 1)[1] in ("auto_mode", "guard_ok", "pressure_ok", "temp_ok",
                                        "level_ok", "fb_running")}
    return text, inputs, start


def plant(loops=40):
    calls = "\n".join(
        f"    pid{k}(pv := pv[{k}], sp := sp[{k}], manual := man[{k}], manual_out := 20.0,\n"
        f"           kp := {1.0 + 0.05 * k:.2f}, ti := {5.0 + k:.1f}, td := 0.5, dt := 0.01,\n"
        f"           out_lo := 0.0, out_hi := 100.0, deadband := 0.5, alarm_dev := 5.0);\n"
        f"    cv[{k}] := pid{k}.out;\n"
        f"    IF pid{k}.dev_alarm THEN n_alarms := n_alarms + 1; END_IF;"
        for k in range(1, loops + 1))
    text = f"""
FUNCTION_BLOCK PID
VAR_INPUT
    pv, sp : REAL;
    manual : BOOL;
    manual_out, kp, ti, td, dt, out_lo, out_hi, deadband, alarm_dev : REAL;
END_VAR
VAR_OUTPUT
    out : REAL;
    dev_alarm, sat_hi, sat_lo : BOOL;
END_VAR
VAR
    integral, prev_err, err, p_term, d_term, unclamped : REAL;
END_VAR
    err := sp - pv;
    IF ABS(err) < deadband THEN
        err := 0.0;
    END_IF;
    dev_alarm := ABS(sp - pv) > alarm_dev;
    IF manual THEN
        out := LIMIT(out_lo, manual_out, out_hi);
        (* bumpless: the integral follows the manual output *)
        integral := out - kp * err;
        prev_err := err;
        sat_hi := FALSE;
        sat_lo := FALSE;
        RETURN;
    END_IF;
    p_term := kp * err;
    IF ti > 0.0 THEN
        integral := integral + kp * err * dt / ti;
    END_IF;
    IF td > 0.0 THEN
        d_term := kp * td * (err - prev_err) / dt;
    ELSE
        d_term := 0.0;
    END_IF;
    prev_err := err;
    unclamped := p_term + integral + d_term;
    sat_hi := unclamped > out_hi;
    sat_lo := unclamped < out_lo;
    IF sat_hi THEN
        out := out_hi;
        integral := out_hi - p_term - d_term;     (* anti-windup *)
    ELSIF sat_lo THEN
        out := out_lo;
        integral := out_lo - p_term - d_term;
    ELSE
        out := unclamped;
    END_IF;
END_FUNCTION_BLOCK

PROGRAM Plant
VAR_EXTERNAL
    pv, sp, cv : ARRAY[1..{loops}] OF REAL;
    man : ARRAY[1..{loops}] OF BOOL;
    n_alarms : INT;
END_VAR
VAR pid{', pid'.join(str(k) for k in range(1, loops + 1))} : PID; END_VAR
    n_alarms := 0;
{calls}
END_PROGRAM

CONFIGURATION Plant
VAR_GLOBAL
    pv, sp, cv : ARRAY[1..{loops}] OF REAL;
    man : ARRAY[1..{loops}] OF BOOL;
    n_alarms : INT;
END_VAR
RESOURCE main ON CPU0
    TASK scan (INTERVAL := T#{INTERVAL_MS}ms, PRIORITY := 1);
    PROGRAM plant WITH scan : Plant;
END_RESOURCE
END_CONFIGURATION
"""
    inputs = []
    start = {}
    for k in range(1, loops + 1):
        setpoint = 40.0 + k
        inputs.append((f"pv[{k}]", "real", setpoint))
        inputs.append((f"sp[{k}]", "real", setpoint))
        inputs.append((f"man[{k}]", "bool", None))
        start[f"pv[{k}]"] = repr(setpoint)
        start[f"sp[{k}]"] = repr(setpoint)
    return text, inputs, start


def packaging(sections=60, jam_every=5):
    calls = []
    for k in range(1, sections + 1):
        kind = "JamSection" if k % jam_every == 0 else "Section"
        calls.append(
            f"    c{k}(eye := eye[{k}], enable := en[{k}], downstream_ok := "
            f"{'ready' if k == sections else f'c{k + 1}.ready'}, reject_req := rej[{k}],\n"
            f"        speed_ref := {1000 + 10 * k});\n"
            f"    motor[{k}] := c{k}.motor; count[{k}] := c{k}.count;")
        calls[-1] = (kind, calls[-1])
    decl = "\n".join(f"    c{k} : {kind};" for k, (kind, _) in enumerate(calls, 1))
    body = "\n".join(c for _, c in calls)
    text = f"""
FUNCTION_BLOCK Section
VAR_INPUT
    eye, enable, downstream_ok, reject_req : BOOL;
    speed_ref : INT;
END_VAR
VAR_OUTPUT
    motor, ready, gate : BOOL;
    speed : INT;
    count, rejects : UDINT;
    state : INT;
END_VAR
VAR
    arrive : R_TRIG;
    leave : F_TRIG;
    occupied : BOOL;
END_VAR
    arrive(CLK := eye);
    leave(CLK := eye);
    IF arrive.Q THEN
        occupied := TRUE;
        IF reject_req THEN
            gate := TRUE;
            rejects := rejects + 1;
        ELSE
            count := count + 1;
        END_IF;
    END_IF;
    IF leave.Q THEN
        occupied := FALSE;
        gate := FALSE;
    END_IF;
    motor := enable AND (downstream_ok OR NOT occupied);
    IF motor THEN
        speed := speed_ref;
        IF gate THEN speed := speed_ref / 2; END_IF;
    ELSE
        speed := 0;
    END_IF;
    ready := enable AND NOT occupied;
    IF NOT enable THEN
        state := 0;
    ELSIF occupied AND NOT motor THEN
        state := 3;
    ELSIF occupied THEN
        state := 2;
    ELSE
        state := 1;
    END_IF;
END_FUNCTION_BLOCK

FUNCTION_BLOCK JamSection
VAR_INPUT
    eye, enable, downstream_ok, reject_req : BOOL;
    speed_ref : INT;
END_VAR
VAR_OUTPUT
    motor, ready, jam : BOOL;
    count : UDINT;
END_VAR
VAR
    s : Section;
    jam_timer : TON;
END_VAR
    s(eye := eye, enable := enable AND NOT jam, downstream_ok := downstream_ok,
      reject_req := reject_req, speed_ref := speed_ref);
    jam_timer(IN := eye AND s.motor, PT := T#2s);
    IF jam_timer.Q THEN jam := TRUE; END_IF;
    IF NOT enable THEN jam := FALSE; END_IF;
    motor := s.motor;
    ready := s.ready AND NOT jam;
    count := s.count;
END_FUNCTION_BLOCK

PROGRAM Line
VAR_EXTERNAL
    eye, en, rej, motor : ARRAY[1..{sections}] OF BOOL;
    count : ARRAY[1..{sections}] OF UDINT;
    ready : BOOL;
END_VAR
VAR
{decl}
END_VAR
{body}
END_PROGRAM

CONFIGURATION Packaging
VAR_GLOBAL
    eye, en, rej, motor : ARRAY[1..{sections}] OF BOOL;
    count : ARRAY[1..{sections}] OF UDINT;
    ready : BOOL := TRUE;
END_VAR
RESOURCE main ON CPU0
    TASK scan (INTERVAL := T#{INTERVAL_MS}ms, PRIORITY := 1);
    PROGRAM line WITH scan : Line;
END_RESOURCE
END_CONFIGURATION
"""
    inputs = [(f"{v}[{k}]", "bool", None) for k in range(1, sections + 1)
              for v in ("eye", "en", "rej")]
    # every section enabled at the start
    start = {f"en[{k}]": "TRUE" for k in range(1, sections + 1)}
    return text, inputs, start


PROGRAMS = {"interlock": interlock, "plant": plant, "packaging": packaging}
# --smoke: the same programs, small
SMOKE_SIZES = {"interlock": {"stations": 2, "devices": 4}, "plant": {"loops": 6},
               "packaging": {"sections": 10, "jam_every": 5}}


# --------------------------------------------------------------------- trace
def trace(inputs, start, rate, cycles, seed):
    """CSV rows: the start values at t=0, then per cycle rate % of the
    inputs changed (a fractional count carried to the next cycle)."""
    rnd = random.Random(seed)
    state = {p: (start.get(p, "FALSE") if kind == "bool" else start.get(p, "0.0"))
             for p, kind, _ in inputs}
    rows = [f"0ms,{p},{v}" for p, v in state.items()]
    carry = 0.0
    paths = sorted({p for p, _, _ in inputs})
    kinds = {p: (kind, centre) for p, kind, centre in inputs}
    for c in range(1, cycles):
        carry += len(paths) * rate / 100.0
        n = int(carry)
        carry -= n
        for p in rnd.sample(paths, min(n, len(paths))):
            kind, centre = kinds[p]
            if kind == "bool":
                state[p] = "FALSE" if state[p] == "TRUE" else "TRUE"
            else:
                while True:
                    v = repr(round(centre + rnd.uniform(-0.4, 0.4), 3))
                    if v != state[p]:
                        break
                state[p] = v
            rows.append(f"{c * INTERVAL_MS}ms,{p},{state[p]}")
    return "\n".join(rows) + "\n"


# ------------------------------------------------------------------ measure
KERNEL_CFLAGS = "-fno-strict-aliasing"
EXTRA_CFLAGS = KERNEL_CFLAGS.split()


def _build(comp, work):
    saved = list(sim.CFLAGS)
    sim.CFLAGS[:] = [f if f != "-O1" else "-O2" for f in saved] + EXTRA_CFLAGS
    try:
        return sim.build(comp, work / "build")
    finally:
        sim.CFLAGS[:] = saved


def measure(project, exe, plan, trace_path, cycles, work):
    """(instructions per scan inside the task, (evaluated, skipped))."""
    events = read_trace(str(trace_path), plan.table)
    ev = work / "events.txt"
    with open(ev, "w") as fh:
        for t, _, i, kind, value in events:
            fh.write(f"{t} {i} {kind} {value!r}\n" if kind == "f" else f"{t} {i} {kind} {value}\n")
    out = work / "callgrind.out"
    end = (cycles - 1) * INTERVAL_MS * 1_000_000
    p = subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
                        "--toggle-collect=task_0", str(exe), str(end), str(ev)],
                       capture_output=True, text=True)
    if p.returncode != 0:
        raise SystemExit(f"valgrind failed: {p.stderr[-2000:]}")
    m = re.search(r"^(?:summary|totals): (\d+)", out.read_text(), re.M)
    sel = re.findall(r"^s \S+ (\d+) (\d+)$", p.stdout, re.M)
    n = re.findall(r"^n \S+ (\d+)$", p.stdout, re.M)
    assert n and int(n[0]) == cycles, p.stdout[-500:]
    counts = (sum(int(a) for a, _ in sel), sum(int(b) for _, b in sel))
    return int(m.group(1)) / cycles, counts


def same_traces(plain, sel, trace_path, cycles, work):
    """The plain and the selective simulation (two Compilations of one
    project) agree on every global."""
    end = (cycles - 1) * INTERVAL_MS * 1_000_000
    a = sim.run(plain, end, inputs=str(trace_path), build_dir=work / "build")
    b = sim.run(sel, end, inputs=str(trace_path), build_dir=work / "build")
    if a.changes != b.changes or a.faults != b.faults:
        raise SystemExit("plain and selective traces differ: a bug of selective execution")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cycles", type=int, default=400)
    ap.add_argument("--rates", default="0,1,10,50,100")
    ap.add_argument("--programs", default=",".join(PROGRAMS))
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument("--keep", metavar="DIR", help="keep the programs, traces and builds here")
    ap.add_argument("--cflags", default=KERNEL_CFLAGS,
                    help="flags added to -O2 (default: the kernel's %(default)s; '' for none)")
    ap.add_argument("--smoke", action="store_true",
                    help="a few seconds' run at a small size (CI: tests/benchmarks): 30 cycles "
                         "at 0 and 100 %% of small instances of the programs; the traces "
                         "still checked, the targets printed, not enforced")
    a = ap.parse_args(argv)
    if a.smoke:
        a.cycles, a.rates = 30, "0,100"
    EXTRA_CFLAGS[:] = a.cflags.split()
    if shutil.which("valgrind") is None:
        raise SystemExit("valgrind not found: apt-get install valgrind (scripts/setup.sh)")
    rates = [float(r) for r in a.rates.split(",")]
    work_root = Path(a.keep) if a.keep else Path(tempfile.mkdtemp(prefix="selbench-"))
    rows = []
    print(f"generated C: -O2 {' '.join(EXTRA_CFLAGS)}; {a.cycles} cycles", flush=True)
    print(f"{'program':10} {'change %':>8} {'plain Ir/scan':>14} {'selective Ir/scan':>18} "
          f"{'plain/sel':>9} {'blocks skipped':>15}", flush=True)
    for name in a.programs.split(","):
        text, inputs, start = PROGRAMS[name](**(SMOKE_SIZES[name] if a.smoke else {}))
        work = work_root / name
        work.mkdir(parents=True, exist_ok=True)
        (work / f"{name}.st").write_text(text)
        res = frontend.run([str(work / f"{name}.st")], use_cache=False)
        if not res.ok:
            raise SystemExit("\n".join(d.format() for d in res.diags.sorted()))
        project = res.project
        plain, sel = Compilation(project), Compilation(project, "all")
        plan = plain.plan
        plain_exe, _ = _build(plain, work)
        sel_exe, _ = _build(sel, work)
        for rate in rates:
            tp = work / f"trace_{rate:g}.csv"
            tp.write_text(trace(inputs, start, rate, a.cycles, a.seed))
            if rate in (rates[0], rates[-1]) or rate == 1:
                same_traces(plain, sel, tp, min(a.cycles, 120), work)
            ip, _ = measure(project, plain_exe, plan, tp, a.cycles, work)
            isel, (ev, sk) = measure(project, sel_exe, plan, tp, a.cycles, work)
            share = 100.0 * sk / (ev + sk) if ev + sk else 0.0
            rows.append((name, rate, ip, isel))
            print(f"{name:10} {rate:8g} {ip:14.1f} {isel:18.1f} {ip / isel:9.2f} "
                  f"{share:14.1f}%", flush=True)
    if not a.keep:
        shutil.rmtree(work_root, ignore_errors=True)
    fail = []
    for name, rate, ip, isel in rows:
        if name == "interlock" and rate <= 1 and ip / isel < 5:
            fail.append(f"interlock at {rate:g} %: {ip / isel:.2f}x fewer (target >= 5x)")
        if rate == 100 and isel > 1.10 * ip:
            fail.append(f"{name} at 100 %: {100 * (isel / ip - 1):.1f} % more (target <= 10 %)")
    for f in fail:
        print("target missed: " + f)
    return 1 if fail and not a.smoke else 0


if __name__ == "__main__":
    sys.exit(main())
