#!/usr/bin/env python3
"""Benchmark: time to prove each example's properties with `iec2kmod verify`
(the {verify} pragmas in its sources), and time to find the bug of each
deliberately broken variant (tests/verify/broken).

For every property: its verdict, the induction depth or the violating
cycle, the wall time and the CPU time of deciding it (cone of influence,
Houdini invariants, BMC and k-induction).  Per project: the time to build
the transition system (front end excluded).  The machine is shared: the load
average is printed with the figures.

    python benchmarks/verify.py [--depth 20] [--only traffic_light,...] [--smoke]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

PROJECTS = [
    ("examples/traffic_light", "example"),
    ("examples/motor_il", "example"),
    ("examples/conveyor_counter", "example"),
    ("examples/packaging_il_st", "example"),
    ("examples/tank_level", "example"),
    ("examples/elevator", "example"),
    ("examples/hvac", "example"),
    ("examples/two_resources", "example"),
    ("examples/pid_loop", "example"),
    ("examples/watchdog_event", "example"),
    ("examples/alarm_handler", "example"),
    ("examples/batch_mixer", "example"),
    ("tests/verify/diff/press.il", "example (IL, tests)"),
    ("tests/verify/broken/star_delta_no_interlock", "broken"),
    ("tests/verify/broken/crossing_latched_green", "broken"),
    ("tests/verify/broken/conveyor_slot_index", "broken"),
]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--depth", type=int, default=20)
    ap.add_argument("--only", help="comma-separated project names")
    ap.add_argument("--smoke", action="store_true",
                    help="a few seconds' run at a small size (CI: tests/benchmarks): depth 3, "
                         "traffic_light and one broken project")
    args = ap.parse_args(argv)
    if args.smoke:
        args.depth, args.only = 3, "traffic_light,crossing_latched_green"
    from iec2kmod.diagnostics import Diagnostics
    from iec2kmod.parse.frontend import run
    from iec2kmod.verify import build
    from iec2kmod.verify.engine import check
    from iec2kmod.verify.terms import Refuse
    only = set(args.only.split(",")) if args.only else None
    print(f"iec2kmod verify benchmark, depth {args.depth}; load average "
          + " ".join(f"{x:.2f}" for x in os.getloadavg()))
    total_wall = total_cpu = 0.0
    for rel, kind in PROJECTS:
        name = Path(rel).name.split(".")[0]
        if only and name not in only:
            continue
        fe = run([str(ROOT / rel)], use_cache=False)
        if not fe.ok:
            print(f"{rel}: front end errors")
            continue
        w0, c0 = time.perf_counter(), time.process_time()
        try:
            out = build(fe.project, [], [], None, Diagnostics())
        except Refuse as exc:
            print(f"\n{rel} ({kind}): refused: {exc.message}")
            continue
        wb, cb = time.perf_counter() - w0, time.process_time() - c0
        print(f"\n{rel} ({kind}): {out.leaves} state variables, {out.inputs} inputs, "
              f"{len(out.system.props)} properties; encoding {wb:.2f} s ({cb:.2f} s CPU)")
        w0, c0 = time.perf_counter(), time.process_time()
        try:
            results, _ = check(out.system, args.depth, 300_000)
        except Refuse as exc:
            print(f"  refused: {exc.message}")
            continue
        wall, cpu = time.perf_counter() - w0, time.process_time() - c0
        for r in results:
            if r.status == "proved":
                verdict = f"proved (k={r.k})"
            elif r.status == "violated":
                verdict = f"violated at cycle {r.cycle}"
            else:
                verdict = f"{r.status} to {r.cycle} cycles"
            free = f"  (free: {'; '.join(r.free)})" if r.free else ""
            print(f"  {r.name:<48} {verdict:<24} {r.seconds:7.2f} s{free}")
        print(f"  {'all properties':<48} {'':<24} {wall:7.2f} s wall, {cpu:.2f} s CPU")
        total_wall += wall + wb
        total_cpu += cpu + cb
    print(f"\ntotal: {total_wall:.1f} s wall, {total_cpu:.1f} s CPU; load average "
          + " ".join(f"{x:.2f}" for x in os.getloadavg()))


if __name__ == "__main__":
    main()
