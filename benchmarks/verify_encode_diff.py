#!/usr/bin/env python3
"""The verifier's encoding against the reference interpreter on random
expressions over every numeric type (tests/verify/exprgen.py), any number
of programs: the CI tier (tests/verify/test_encode_diff.py) runs 6.

    python3 benchmarks/verify_encode_diff.py --count 50 --seed 1 --outputs 60 --cycles 12
    python3 benchmarks/verify_encode_diff.py --smoke   (CI: 2 programs x 20 expressions)

Prints one line per program that differs (output, both values, its
expression) and a summary: programs, expressions, cycles compared, time."""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "verify"))

import diffverify  # noqa: E402
import exprgen  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--count", type=int, default=20)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--outputs", type=int, default=60)
    ap.add_argument("--cycles", type=int, default=12)
    ap.add_argument("--smoke", action="store_true",
                    help="CI size: 2 programs x 20 expressions, 4 cycles (seconds)")
    a = ap.parse_args(argv)
    if a.smoke:
        a.count, a.outputs, a.cycles = 2, 20, 4
    from iec2kmod.cli import front_end
    t0 = time.time()
    bad = cycles = 0
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(a.count):
            seed = a.seed + k
            d = Path(tmp) / f"p{seed}"
            d.mkdir()
            text = exprgen.Gen(seed).program(a.outputs)
            (d / "p.st").write_text(text)
            project = front_end([str(d)])
            if project is None:
                print(f"seed {seed}: the generator wrote a program the front end refuses")
                bad += 1
                continue
            diffs, done = diffverify.run(project, a.cycles, seed, values=exprgen.boundary_value)
            cycles += done
            if diffs:
                bad += 1
                lines = text.splitlines()
                for cyc, name, theirs, mine in diffs[:3]:
                    out = name.split(".")[-1]
                    src = next((ln for ln in lines if ln.startswith(out + " :=")), "")
                    print(f"seed {seed} cycle {cyc}: {name}: interpreter {theirs!r}, "
                          f"encoding {mine!r}  [{src}]")
    dt = time.time() - t0
    print(f"{a.count} programs x {a.outputs} expressions, {cycles} cycles compared, "
          f"{bad} differ, {dt:.1f} s")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
