#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""What the user-space I/O provider's loop through a Python daemon costs,
in the PREEMPT_RT guest (issue 26).

A project like tests/qemu/projects/io_user (one task, %QD0 echoed to %ID0
by the reference daemon, manager/iodaemon.py) is built at each task
interval; in the guest the daemon runs in-process for N cycles and every
output record it reads says which output cycle the inputs of that cycle
answered (in_tag), so the loop latency is exact, in cycles:

    lag = cycle - in_tag     1: the output of a cycle is an input of the next
                             (the best a cycle-based exchange can do)

Printed per interval: lag min/median/p99/max (cycles), the share of cycles
in step (lag 1), cycles whose outputs the daemon never saw, and the
daemon's reaction time (wake-up by read() -> inputs written, microseconds
of the guest's clock).

    python benchmarks/io_user_latency.py [--intervals 20,10,5] [--cycles 500]
        [--clock tcg|icount]

tcg: the normal guest on wall-clock time (an emulated CPU many times slower
than the host: Python's per-cycle work is what limits); icount: virtual
time, one instruction = 1 ns (host load does not matter; figures as for a
~1 GIPS CPU).
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
NODE = "/dev/iec_io_bench_r_fb"

ST = """PROGRAM Echo
  VAR_EXTERNAL back : DINT; count : DINT; n : DINT; END_VAR
  n := n + 1;
  count := back + 1;
END_PROGRAM
CONFIGURATION Bench
  RESOURCE R ON CPU0
    VAR_GLOBAL back AT %ID0 : DINT; count AT %QD0 : DINT; n : DINT; END_VAR
    TASK fast (INTERVAL := T#{ms}ms, PRIORITY := 1);
    PROGRAM echo1 WITH fast : Echo;
  END_RESOURCE
END_CONFIGURATION
"""
IOMAP = "DEVICE fb : user INPUTS 1 OUTPUTS 1 STALE OFF\n%ID0 : fb.0\n%QD0 : fb.0\n"

GUEST_CODE = r"""
import json, sys
from plc_manager import iodaemon, ops
tree, node, cycles = sys.argv[1], sys.argv[2], int(sys.argv[3])
ops.load(tree, start=False)
try:
    with iodaemon.UserDevice(node) as dev:
        rules = iodaemon.parse_rules(dev, ["%ID0=%QD0"])
        ops.start()
        st = iodaemon.loop(dev, rules, cycles=50)          # warm-up
        st = iodaemon.loop(dev, rules, cycles=cycles)
        s = st.summary()
        s["in_step"] = sum(1 for x in st.lags if x == 1) / max(1, len(st.lags))
        ops.stop(keep_loaded=True)
finally:
    ops.stop()
print("RESULT " + json.dumps(s))
"""


def build(work: Path, ms: int) -> Path:
    src = work / f"src{ms}"
    src.mkdir(parents=True, exist_ok=True)
    (src / "echo.st").write_text(ST.format(ms=ms))
    (src / "echo.iomap").write_text(IOMAP)
    tree = work / f"t{ms}"
    for cmd in (["gen", str(src), "-o", str(tree)], ["build", str(tree)]):
        p = subprocess.run([sys.executable, "-m", "iec2kmod.cli", *cmd], cwd=ROOT,
                           capture_output=True, text=True, timeout=1800)
        if p.returncode:
            sys.exit(f"iec2kmod {cmd[0]} failed:\n{p.stdout}{p.stderr}")
    return tree


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--intervals", default="20,10,5", help="task intervals in ms")
    ap.add_argument("--cycles", type=int, default=500)
    ap.add_argument("--clock", choices=("tcg", "icount"), default="tcg")
    ap.add_argument("--smoke", action="store_true", help="one interval (20 ms), 60 cycles")
    a = ap.parse_args()
    if a.smoke:
        a.intervals, a.cycles = "20", 60
    from iec2kmod.testing.vm import Guest
    work = Path(tempfile.mkdtemp(prefix="io_user_latency."))
    intervals = [int(x) for x in a.intervals.split(",")]
    trees = {ms: build(work, ms) for ms in intervals}
    g = Guest(str(work), icount=(a.clock == "icount"), console_log=str(work / "console.log"))
    rows = []
    try:
        g.start()
        g.start_pyserver()
        for ms in intervals:
            t0 = time.monotonic()
            r = g.pyrun(GUEST_CODE, argv=[str(trees[ms]), NODE, str(a.cycles)],
                        timeout=120 + a.cycles * ms / 100)
            if r.exit_code != 0 or "RESULT " not in r.output:
                sys.exit(f"the benchmark failed in the guest:\n{r.output[-4000:]}")
            rows.append((ms, json.loads(r.output.split("RESULT ", 1)[1]),
                         time.monotonic() - t0))
        g.check_kernel_log()
    finally:
        g.close()
    shutil.rmtree(work, ignore_errors=True)
    print(f"\nuser I/O loop through the Python reference daemon, {a.cycles} cycles per "
          f"interval, guest clock: {a.clock}")
    print(f"{'interval':>9} {'lag cycles min/med/p99/max':>27} {'in step':>8} "
          f"{'not seen':>9} {'reaction us min/med/p99/max':>29}")
    for ms, s, _ in rows:
        lag, re = s["lag_cycles"], s["react_us"]
        print(f"{ms:>7}ms {lag['min']:>6}/{lag['median']:>5}/{lag['p99']:>5}/{lag['max']:>6}   "
              f"{100 * s['in_step']:7.1f}% {s['missed']:>9} "
              f"{re['min']:>8}/{re['median']:>7}/{re['p99']:>7}/{re['max']:>7}")


if __name__ == "__main__":
    main()
