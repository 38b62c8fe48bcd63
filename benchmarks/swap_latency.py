# SPDX-License-Identifier: MIT
"""Hot-swap latency and load time of plc-manager, in the PREEMPT_RT guest.

A configuration with 10 program types and 50 program instances (two
resources, five periodic tasks each: 1, 2, 5, 10 and 20 ms) is generated,
built on the host, and run in a QEMU guest:

  load     `plc-manager load` (insert 13 modules, confirm the slots, start
           the 10 tasks and see every periodic one complete a cycle);
  swap     of one program type (5 instances, in tasks of 1 to 20 ms), back
           and forth between two builds of its algorithm, in two halves:
           `plc-manager swap --prepare` (checks, insert staged: the slow
           half, timed apart) then `plc-manager swap --publish` (the quick
           half), both in one resident manager process: publish command ->
           publication (the slot's timestamp, kernel clock), publication ->
           the new body's first cycle (stamped by the kernel), the publish
           command's own duration (grace period, confirmation, removal of
           the old module), and with --oneshot a plain `swap` (both halves
           in one command);
  stop     `plc-manager stop` (stop, remove 13 modules).

Guest clock: ``--clock icount`` (default) runs the guest in virtual time
(QEMU -icount shift=0,sleep=off: one instruction = 1 ns, host load has no
effect: reproducible figures of a ~1 GHz in-order machine); ``--clock tcg``
runs the normal TCG guest on wall-clock time (slower emulation, host-load
dependent); ``both`` runs both.

    python benchmarks/swap_latency.py [--swaps 40] [--loads 3] [--clock icount|tcg|both] [--smoke]
"""

from __future__ import annotations

import argparse
import compileall
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

TYPES = 10
INSTANCES = 50
TASKS = [("t1", 1, 1), ("t2", 2, 2), ("t5", 5, 3), ("t10", 10, 4), ("t20", 20, 5)]


def program(k: int, algo: int) -> str:
    return f"""PROGRAM P{k}
VAR_INPUT gain : INT; END_VAR
VAR_OUTPUT y : DINT; END_VAR
VAR n, acc : DINT; i : INT; t : TON; edge : R_TRIG; END_VAR
    n := n + 1;
    acc := 0;
    FOR i := 1 TO 8 DO
        acc := acc + (n MOD INT_TO_DINT(i + {k + 1})) * INT_TO_DINT(gain);
    END_FOR;
    t(IN := NOT t.Q, PT := T#100ms);
    edge(CLK := t.Q);
    y := acc + {algo};    (* the algorithm the benchmark swaps *)
END_PROGRAM

"""


def project(algo0: int) -> str:
    out = [program(k, algo0 if k == 0 else 0) for k in range(TYPES)]
    out.append("CONFIGURATION Bench\n    VAR_GLOBAL\n")
    out.append("".join(f"        out{n} : DINT;\n" for n in range(INSTANCES)))
    out.append("    END_VAR\n")
    per_res = INSTANCES // 2
    for r in range(2):
        out.append(f"    RESOURCE r{r} ON board\n")   # unpinned: icount has one CPU
        for name, ms, prio in TASKS:
            out.append(f"        TASK {name} (INTERVAL := T#{ms}ms, PRIORITY := {prio});\n")
        for n in range(r * per_res, (r + 1) * per_res):
            task = TASKS[(n // 5) % len(TASKS)][0]
            out.append(f"        PROGRAM i{n} WITH {task} : P{n % TYPES} "
                       f"(gain := {n % 7 + 1}, y => out{n});\n")
        out.append("    END_RESOURCE\n")
    out.append("END_CONFIGURATION\n")
    return "".join(out)


def iec2kmod(*args) -> None:
    p = subprocess.run([sys.executable, "-m", "iec2kmod.cli", *map(str, args)], cwd=ROOT,
                       capture_output=True, text=True)
    if p.returncode:
        sys.exit(f"iec2kmod {' '.join(map(str, args))} failed:\n{p.stdout}{p.stderr}")


def build(work: Path):
    """Two builds: A (all modules) and B (P0's module only, algorithm 1)."""
    from iec2kmod import kbuild
    for name, algo in (("a", 0), ("b", 1)):
        src = work / f"src_{name}"
        src.mkdir(parents=True, exist_ok=True)
        (src / "bench.st").write_text(project(algo))
        tree = work / name
        if tree.exists():
            shutil.rmtree(tree)
        t0 = time.monotonic()
        iec2kmod("gen", src, "-o", tree)
        if name == "a":
            iec2kmod("build", tree)
        else:
            m = json.loads((tree / "manifest.json").read_text())
            p0 = next(t["module"] for t in m["program_types"] if t["name"] == "P0")
            kbuild.build_modules(str(tree / p0), extra_args=[
                f"KBUILD_EXTRA_SYMBOLS={work / 'a' / 'Module.symvers'}"]).check()
        print(f"  built {name}: {time.monotonic() - t0:.0f} s", flush=True)
    ma = json.loads((work / "a" / "manifest.json").read_text())
    mb = json.loads((work / "b" / "manifest.json").read_text())
    pa = next(t for t in ma["program_types"] if t["name"] == "P0")
    pb = next(t for t in mb["program_types"] if t["name"] == "P0")
    assert pa["interface_hash"] == pb["interface_hash"] and pa["build_id"] != pb["build_id"]
    ko = lambda tree, t: tree / t["module"] / f"{t['module']}.ko"   # noqa: E731
    return ma, ko(work / "a", pa), ko(work / "b", pb)


GUEST_CODE = r'''
import contextlib, io, json, sys, time
from plc_manager import ops
from plc_manager.cli import main
from plc_manager.netlink import Client
tree, A, B, loads, swaps = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]), int(sys.argv[5])
oneshot = sys.argv[6] == "1"
res = {"load": [], "stop": [], "swap": [], "overruns": None}
def quiet(argv):
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        rc = main(argv)
    assert rc == 0, buf.getvalue()
    return buf.getvalue()
for i in range(loads):
    rep = json.loads(quiet(["load", "--json", tree]))
    res["load"].append([rep["total_ms"], sum(m["insert_ms"] for m in rep["modules"]),
                        rep["start_ms"], len(rep["modules"])])
    if i == loads - 1:
        with Client() as c:
            o0 = sum(t.overruns for t in c.status().tasks())
        for k in range(swaps):
            new = B if k % 2 == 0 else A
            if oneshot:
                rep = json.loads(quiet(["swap", "--json", new]))
                prep = rep
            else:
                prep = json.loads(quiet(["swap", "--prepare", "--json", new]))
                time.sleep(0.05)
                rep = json.loads(quiet(["swap", "--publish", "--json"]))
            s = rep["steps"][0]
            res["swap"].append([s["latency_ms"], s["perform_ms"], prep["steps"][0]["insert_ms"],
                                s["confirm_ms"], s["publication_to_first_ms"], s["remove_ms"],
                                prep["check_ms"], prep["prepare_ms"], rep["total_ms"],
                                rep.get("phases", {})])
        with Client() as c:
            st = c.status()
            res["overruns"] = sum(t.overruns for t in st.tasks()) - o0
            res["tasks"] = len(st.tasks())
            res["slots"] = len(st.slots)
        if swaps % 2:
            quiet(["swap", A])
    t0 = time.perf_counter()
    quiet(["stop"])
    res["stop"].append((time.perf_counter() - t0) * 1000)
print("RESULT " + json.dumps(res))
'''


def stats(xs):
    xs = sorted(x for x in xs if x is not None)
    if not xs:
        return "-"
    p99 = xs[min(len(xs) - 1, int(round(0.99 * (len(xs) - 1))))]
    return (f"{xs[0]:8.2f} {statistics.median(xs):8.2f} {p99:8.2f} "
            f"{xs[-1]:8.2f}")


def run(clock: str, work: Path, ma, ko_a: Path, ko_b: Path, loads: int, swaps: int,
        oneshot: bool = False) -> None:
    from iec2kmod.testing.vm import Guest
    print(f"\n[{clock}] booting the guest", flush=True)
    g = Guest(str(work), icount=(clock == "icount"),
              console_log=str(work / f"console-{clock}.log"))
    try:
        t0 = time.monotonic()
        g.start()
        g.start_pyserver()
        print(f"[{clock}] guest and Python ready in {time.monotonic() - t0:.0f} s", flush=True)
        r = g.pyrun(GUEST_CODE, argv=[str(work / "a"), str(ko_a), str(ko_b), str(loads),
                                      str(swaps), "1" if oneshot else "0"], timeout=3600)
        if r.exit_code != 0 or "RESULT " not in r.output:
            sys.exit(f"the benchmark failed in the guest:\n{r.output[-4000:]}")
        res = json.loads(r.output.split("RESULT ", 1)[1])
        g.check_kernel_log()
    finally:
        g.close()
    unit = "ms of virtual time" if clock == "icount" else "ms of wall-clock time (TCG)"
    print(f"\n[{clock}] {len(ma['program_types'])} program types, "
          f"{len(ma['instances'])} program instances, {res['tasks']} tasks, "
          f"{len(ma['load_order'])} modules; all figures in {unit}")
    print(f"{'':34}{'min':>8} {'median':>8} {'p99':>8} {'max':>8}")
    print(f"{'load (total, tasks running)':34}{stats([x[0] for x in res['load']])}")
    print(f"{'  insert 13 modules':34}{stats([x[1] for x in res['load']])}")
    print(f"{'  start 10 tasks':34}{stats([x[2] for x in res['load']])}")
    print(f"{'stop (stop, remove 13 modules)':34}{stats(res['stop'])}")
    sw = res["swap"]
    how = "swap (one command)" if oneshot else "swap --prepare, then swap --publish"
    print(how)
    print(f"{'  prepare (checks, insert staged)':34}{stats([x[7] for x in sw])}")
    print(f"{'    checks before inserting':34}{stats([x[6] for x in sw])}")
    print(f"{'    insert staged':34}{stats([x[2] for x in sw])}")
    print(f"{'  perform: command -> publication':34}{stats([x[1] for x in sw])}")
    print(f"{'    publication -> 1st new cycle':34}{stats([x[4] for x in sw])}")
    print(f"{'    command -> new body running':34}{stats([x[0] for x in sw])}")
    print(f"{'    whole command (confirm, rm)':34}{stats([x[8] for x in sw])}")
    print(f"{'      confirm slot':34}{stats([x[3] for x in sw])}")
    print(f"{'      remove old module':34}{stats([x[5] for x in sw])}")
    phases = [p for p in sw[0][9]] if sw and len(sw[0]) > 9 else []
    if phases:
        print("    where the whole command's time goes:")
        for p in phases:
            print(f"{'      ' + p:34}{stats([x[9].get(p) for x in sw])}")
    print("target: publication -> first new cycle <= 2 task periods + one grace period "
          "(1 ms task: ~2-3 ms); whole command <= 50 ms")
    print(f"overruns of the 10 tasks during {len(sw)} swaps: {res['overruns']} "
          f"({len(res['load'])} loads, {len(sw)} swaps)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--swaps", type=int, default=40)
    ap.add_argument("--loads", type=int, default=3)
    ap.add_argument("--clock", choices=("icount", "tcg", "both"), default="icount")
    ap.add_argument("--oneshot", action="store_true",
                    help="plain `swap` (both halves in one command) instead of --prepare/--publish")
    ap.add_argument("--workdir", help="keep the builds here (default: a temporary directory)")
    ap.add_argument("--smoke", action="store_true",
                    help="a few seconds' run at a small size (CI: tests/qemu): 3 swaps, 1 load")
    a = ap.parse_args()
    if a.smoke:
        a.swaps, a.loads = 3, 1
    work = Path(a.workdir or tempfile.mkdtemp(prefix="iec2kmod-swapbench-")).resolve()
    work.mkdir(parents=True, exist_ok=True)
    print(f"building the benchmark configuration in {work}", flush=True)
    ma, ko_a, ko_b = build(work)
    compileall.compile_dir(str(ROOT / "manager"), quiet=1)
    for clock in (("icount", "tcg") if a.clock == "both" else (a.clock,)):
        run(clock, work, ma, ko_a, ko_b, a.loads, a.swaps, a.oneshot)
    if not a.workdir:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    os.environ.setdefault("PYTHONDONTWRITEBYTECODE", "1")
    main()
