#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Measure the accuracy of the runtime's REAL/LREAL math functions
(kmod_templates/runtime/iec_math.c) against glibc's libm.

Compiles benchmarks/math_accuracy_driver.c together with iec_math.c and
-lm, runs it over random inputs in several ranges and over a list of edge
cases, and prints a table: the maximum error in ULP of the reference value
(for REAL, against glibc's double result, so a correctly rounded REAL shows
<= 0.5).  Where mpmath is installed, the worst input of each row is also
evaluated exactly, giving our error and glibc's error against the true
value there (glibc is not always right: e.g. cos(0x1.6ac5b262ca1ffp+849)).

    python benchmarks/math_accuracy.py [--samples N] [--json] [--smoke]
"""
import argparse
import json
import math
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
RUNTIME = REPO / "kmod_templates" / "runtime"
DRIVER = Path(__file__).resolve().parent / "math_accuracy_driver.c"

# (function, type, distribution, lo, hi) -- "log": +-10^U(lo, hi),
# "posl": 10^U(lo, hi), "lin": U(lo, hi), "edge": the driver's edge list
CASES = []
for t in ("lreal", "real"):
    big = 300 if t == "lreal" else 37
    CASES += [
        ("sqrt", t, "posl", -big, big),
        ("exp", t, "lin", -745 if t == "lreal" else -103, 709 if t == "lreal" else 88),
        ("exp", t, "lin", -1, 1),
        ("ln", t, "posl", -big, big),
        ("ln", t, "lin", 0.5, 2),
        ("log", t, "posl", -big, big),
        ("log", t, "lin", 0.5, 2),
        ("expt", t, "lin", 0, 10),
        ("expt", t, "posl", -3, 3),
        ("sin", t, "lin", -math.pi, math.pi),
        ("sin", t, "lin", -1e4, 1e4),
        ("sin", t, "log", 5, big),
        ("cos", t, "lin", -math.pi, math.pi),
        ("cos", t, "lin", -1e4, 1e4),
        ("cos", t, "log", 5, big),
        ("tan", t, "lin", -math.pi, math.pi),
        ("tan", t, "lin", -1e4, 1e4),
        ("tan", t, "log", 5, big),
        ("asin", t, "lin", -1, 1),
        ("acos", t, "lin", -1, 1),
        ("atan", t, "log", -10, 10),
        ("atan2", t, "log", -10, 10),
    ]
    for f in ("sqrt", "exp", "ln", "log", "expt", "sin", "cos", "tan",
              "asin", "acos", "atan", "atan2"):
        CASES.append((f, t, "edge", 0, 0))


def build(outdir):
    exe = Path(outdir) / "math_accuracy_driver"
    cmd = ["gcc", "-std=gnu11", "-O2", "-Wall", "-Wextra", "-Werror",
           "-I", str(RUNTIME), str(DRIVER), str(RUNTIME / "iec_math.c"),
           "-lm", "-o", str(exe)]
    subprocess.run(cmd, check=True)
    return exe


def exact_ulp_errors(func, typ, x, y, got, ref):
    """Our and glibc's error in ULP against mpmath at one input."""
    try:
        import mpmath as mp
    except ImportError:
        return None
    mp.mp.prec = 2000
    X, Y = mp.mpf(x), mp.mpf(y)
    try:
        f = {"sqrt": lambda: mp.sqrt(X), "exp": lambda: mp.exp(X),
             "ln": lambda: mp.log(X), "log": lambda: mp.log10(X),
             "sin": lambda: mp.sin(X), "cos": lambda: mp.cos(X),
             "tan": lambda: mp.tan(X), "asin": lambda: mp.asin(X),
             "acos": lambda: mp.acos(X), "atan": lambda: mp.atan(X),
             "atan2": lambda: mp.atan2(X, Y), "expt": lambda: mp.power(X, Y)}[func]
        v = f()
        if not mp.isfinite(v) or v == 0 or mp.im(v) != 0:
            return None
        v = mp.re(v)
    except (ValueError, ZeroDivisionError):
        return None
    e = int(mp.floor(mp.log(abs(v), 2)))
    ulp = mp.mpf(2) ** (max(e, -126 if typ == "real" else -1022) -
                        (23 if typ == "real" else 52))
    return (float(abs(mp.mpf(got) - v) / ulp),
            float(abs(mp.mpf(ref) - v) / ulp) if typ == "lreal" else None)


def measure(samples=200000, seed=1):
    rows = []
    with tempfile.TemporaryDirectory() as d:
        exe = build(d)
        for i, (f, t, dist, lo, hi) in enumerate(CASES):
            out = subprocess.run(
                [str(exe), f, t, dist, repr(lo), repr(hi), str(samples),
                 str(seed + i)], check=True, capture_output=True,
                text=True).stdout.split()
            maxu, wx, wy, got, ref = (float(out[0]), float.fromhex(out[1]),
                                      float.fromhex(out[2]),
                                      float.fromhex(out[3]),
                                      float.fromhex(out[4]))
            row = {"func": f, "type": t, "dist": dist, "lo": lo, "hi": hi,
                   "max_ulp_vs_glibc": maxu, "worst_x": wx, "worst_y": wy,
                   "mismatches": int(out[5]), "count": int(out[6])}
            ex = exact_ulp_errors(f, t, wx, wy, got, ref) if maxu > 0 else None
            if ex:
                row["ours_vs_exact_at_worst"] = ex[0]
                row["glibc_vs_exact_at_worst"] = ex[1]
            rows.append(row)
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=200000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--smoke", action="store_true",
                    help="a few seconds' run at a small size (CI: tests/benchmarks): 2,000 "
                         "samples")
    a = ap.parse_args()
    if a.smoke:
        a.samples = 2000
    rows = measure(a.samples, a.seed)
    if a.json:
        json.dump(rows, sys.stdout, indent=1)
        print()
        return 0
    print(f"{'function':8} {'type':5} {'inputs':22} {'max ULP':>8} "
          f"{'worst x':>24} {'ours/glibc vs exact':>20} {'mism':>4}")
    for r in rows:
        rng = r["dist"] if r["dist"] == "edge" else \
            f"{r['dist']} [{r['lo']:g}, {r['hi']:g}]"
        ex = ""
        if "ours_vs_exact_at_worst" in r:
            g = r["glibc_vs_exact_at_worst"]
            ex = f"{r['ours_vs_exact_at_worst']:.2f}/" + \
                ("-" if g is None else f"{g:.2f}")
        print(f"{r['func']:8} {r['type']:5} {rng:22} "
              f"{r['max_ulp_vs_glibc']:8.3f} {r['worst_x']:24.17g} "
              f"{ex:>20} {r['mismatches']:4d}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
