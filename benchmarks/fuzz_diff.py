#!/usr/bin/env python3
"""Differential campaign: random valid IEC 61131-3 projects (tests/differential/progen.py)
run in the C simulator, the C simulator under ASan+UBSan and the reference
interpreter (`iec2kmod sim --engine vm`, when available); traces must agree.

    python3 benchmarks/fuzz_diff.py --count 300 --seed 1
    python3 benchmarks/fuzz_diff.py --count 50 --seed 7 --engines c,vm --keep /tmp/found
    python3 benchmarks/fuzz_diff.py --unit 1000003 --keep /tmp/found    (one project again)
    python3 benchmarks/fuzz_diff.py --smoke                            (3 projects, CI)

Prints one line per project (its seed and result), a summary, and for every
failure the path of the minimised project (delta debugging over statements
and declarations) and the first differing trace line.  Exit status 1 if
anything disagreed, crashed, was reported by a sanitizer or was rejected."""

from __future__ import annotations

import argparse
import collections
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests" / "differential"))

import difftest  # noqa: E402
import progen  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--count", type=int, default=100, help="number of projects")
    ap.add_argument("--seed", type=int, default=1, help="campaign seed")
    ap.add_argument("--unit", type=int, action="append", help="run this project seed only")
    ap.add_argument("--engines", default=None,
                    help="comma list of c,sanitize,vm (default: every available one)")
    ap.add_argument("--keep", metavar="DIR", help="write failing and minimised projects here")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--batch", type=int, default=10, help="projects per simulator build")
    ap.add_argument("--cycles", type=int, default=100, help="cycles of 10 ms per project")
    ap.add_argument("--size", type=float, default=1.0, help="body size factor of the projects")
    ap.add_argument("--no-minimise", action="store_true")
    ap.add_argument("--budget", type=int, default=250, help="runs per minimisation")
    ap.add_argument("--smoke", action="store_true",
                    help="a few seconds' run at a small size (CI: tests/benchmarks): 3 "
                         "projects of 20 cycles, one batch, no minimising")
    a = ap.parse_args(argv)
    if a.smoke:
        a.count, a.cycles, a.batch, a.no_minimise = 3, 20, 3, True
    engines = a.engines.split(",") if a.engines else difftest.available_engines()
    for e in engines:
        if e not in difftest.ALL_ENGINES:
            ap.error(f"unknown engine {e}")
    if "vm" in engines and not difftest.vm_available():
        ap.error("`iec2kmod sim --engine vm` is not available in this checkout")
    seeds = a.unit or [difftest.unit_seed(a.seed, i) for i in range(a.count)]
    print(f"engines: {','.join(engines)}; {len(seeds)} projects; {a.cycles} cycles each",
          flush=True)
    t0 = time.time()

    def progress(batch):
        for s, r in batch.items():
            if r.ok:
                print(f"{s}: ok", flush=True)
            else:
                for kind, eng, text in r.problems:
                    first = (text or "").strip().splitlines()[0][:300] if text else ""
                    print(f"{s}: {kind} [{eng}] {first}", flush=True)
    results = difftest.campaign(seeds, engines, jobs=a.jobs, batch=a.batch, cycles=a.cycles,
                                progress=progress, size=a.size)
    dt = time.time() - t0
    kinds = collections.Counter()
    feats = collections.Counter()
    for r in results:
        feats.update(r.features)
        if r.ok:
            kinds["ok"] += 1
        else:
            kinds.update({k for k, _, _ in r.problems})
    print(f"\n{len(results)} projects in {dt:.0f} s: " +
          ", ".join(f"{k} {n}" for k, n in sorted(kinds.items())))
    print(f"constructs reached: {len(feats)} ({', '.join(sorted(feats))})")
    if "selective" in engines:
        ev = sum(r.selective[0] for r in results)
        sk = sum(r.selective[1] for r in results)
        some = sum(1 for r in results if r.selective[1])
        print(f"selective engine: {ev} block evaluations, {sk} skipped "
              f"({100.0 * sk / max(1, ev + sk):.1f} %); {some} of {len(results)} projects "
              "skipped at least one block")
    bad = [r for r in results if not r.ok]
    if bad and a.keep:
        keep = Path(a.keep)
        keep.mkdir(parents=True, exist_ok=True)
        for r in bad:
            u = progen.generate_unit(r.seed, 0, a.cycles, a.size)
            (keep / f"p{r.seed}.st").write_text(u.standalone())
            (keep / f"p{r.seed}.csv").write_text(u.trace_csv())
            if a.no_minimise:
                continue
            print(f"minimising {r.seed} ...", flush=True)
            m = difftest.minimise_unit(r.seed, engines, a.cycles, keep / f"work{r.seed}",
                                       budget=a.budget, size=a.size)
            if m is None:
                print(f"  {r.seed}: does not fail alone (batch interaction?)")
                continue
            small, sig, first, _ = m
            path = keep / f"p{r.seed}_min.st"
            path.write_text(small)
            print(f"  {r.seed}: {sig[0]} [{sig[1]}] -> {path} "
                  f"({len(small.splitlines())} lines)\n    first difference: {first}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
