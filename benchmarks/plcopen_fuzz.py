#!/usr/bin/env python3
"""Random LD/FBD networks through PLCopen XML against a referee written in ST
by the generator (tests/differential/graphic_gen.py, issue 28).

    python3 benchmarks/plcopen_fuzz.py [--count N] [--seed S] [--engine interp|c]
                                       [--keep DIR] [--smoke]

Prints the projects that disagree (translation vs referee: the first cycle
and outputs that differ, or the error), then the counts and the time; exit
1 when any disagrees.  --keep DIR keeps each failing project's plc.xml,
ref.st and input trace under DIR/<seed>."""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "differential"))

import graphic_diff  # noqa: E402
import graphic_gen  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--count", type=int, default=500)
    ap.add_argument("--seed", type=int, default=28_000)
    ap.add_argument("--engine", choices=("interp", "c"), default="interp")
    ap.add_argument("--keep", type=Path)
    ap.add_argument("--smoke", action="store_true", help="10 projects")
    args = ap.parse_args(argv)
    if args.smoke:
        args.count = 10
    t0 = time.time()
    bad = 0
    kinds = {"LD": 0, "FBD": 0}
    with tempfile.TemporaryDirectory(prefix="plcopen_fuzz.") as tmp:
        for i in range(args.count):
            seed = args.seed + i
            p = graphic_gen.generate(seed)
            kinds[p.kind] += 1
            work = Path(tmp) / str(seed)
            why = graphic_diff.compare(p, args.engine, work)
            if why:
                bad += 1
                print(f"seed {seed} ({p.kind}): {why[:800]}")
                if args.keep:
                    dest = args.keep / str(seed)
                    shutil.rmtree(dest, ignore_errors=True)
                    shutil.copytree(work, dest, ignore=shutil.ignore_patterns("sim"))
            shutil.rmtree(work, ignore_errors=True)
    dt = time.time() - t0
    print(f"{args.count} projects ({kinds['LD']} LD, {kinds['FBD']} FBD) in {dt:.0f} s "
          f"({args.engine}): {args.count - bad} agree, {bad} disagree")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
