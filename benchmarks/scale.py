# SPDX-License-Identifier: MIT
"""Plant-scale figures (issue 14): `iec2kmod check`, `gen` and `build` of
the plant configuration (benchmarks/plant.py: 10 program types, 2
resources, 16 tasks, 10 plain INT globals and 3 connected ones per
program instance) at 100, 1,000 and 10,000 program instances, and the
size of every kind of module, so that growth is visible (it should be at
most linear).  With --guest N, `plc-manager load` and `stop` of the
N-instance build are timed in the icount QEMU guest (one guest, a few
runs: it is heavy).

    python benchmarks/scale.py [--sizes 100,1000,10000] [--build-upto 1000]
                               [--guest 1000 --runs 3] [--workdir DIR] [--smoke]
"""

from __future__ import annotations

import argparse
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
sys.path.insert(0, str(Path(__file__).resolve().parent))
from plant import project  # noqa: E402


def timed(*args, env=None) -> float:
    t = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "iec2kmod.cli", *map(str, args)], cwd=ROOT,
                       capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t
    if p.returncode:
        sys.exit(f"iec2kmod {' '.join(map(str, args))} failed ({p.returncode}):\n"
                 f"{p.stdout[-3000:]}{p.stderr[-3000:]}")
    return wall


def sizes(tree: Path, manifest: dict) -> dict:
    """kind -> (count, median .ko bytes, largest .ko bytes, median text+data bytes)."""
    by_kind: dict[str, list] = {}
    for m in manifest["modules"]:
        ko = tree / m["dir"] / f"{m['name']}.ko"
        if not ko.exists():
            continue
        alloc = _alloc(ko)
        by_kind.setdefault(m["kind"], []).append((ko.stat().st_size, alloc))
    return {k: (len(v), statistics.median(s for s, _ in v), max(s for s, _ in v),
                statistics.median(a for _, a in v)) for k, v in by_kind.items()}


def _alloc(ko: Path) -> int:
    """Bytes the module occupies once loaded: text + data + bss as `size`
    counts them (allocated sections), not its debug information."""
    p = subprocess.run(["size", str(ko)], capture_output=True, text=True, check=True)
    return int(p.stdout.splitlines()[1].split()[3])


GUEST_CODE = r'''
import contextlib, io, json, sys, time
from plc_manager.cli import main
tree, runs = sys.argv[1], int(sys.argv[2])
res = {"load": [], "stop": [], "load_inside": []}
def quiet(argv):
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        rc = main(argv)
    assert rc == 0, buf.getvalue()
    return buf.getvalue()
for i in range(runs):
    t0 = time.perf_counter()
    out = quiet(["load", tree] if i == runs - 1 else ["load", "--json", tree])
    res["load"].append((time.perf_counter() - t0) * 1000)
    if i < runs - 1:
        res["load_inside"].append(json.loads(out)["total_ms"])
    else:
        res["load_steps"] = out
    time.sleep(0.5)
    t0 = time.perf_counter()
    out = quiet(["stop"])
    res["stop"].append((time.perf_counter() - t0) * 1000)
    res["stop_steps"] = out
print("RESULT " + json.dumps(res))
'''


def dist(xs) -> str:
    xs = sorted(xs)
    p99 = xs[min(len(xs) - 1, int(round(0.99 * (len(xs) - 1))))]
    return (f"min {xs[0]:8.1f}  median {statistics.median(xs):8.1f}  p99 {p99:8.1f}  "
            f"max {xs[-1]:8.1f}")


def guest(tree: Path, work: Path, runs: int) -> None:
    from iec2kmod.testing.vm import Guest
    print(f"\nplc-manager load / stop of {tree.name} in the icount guest ({runs} runs)",
          flush=True)
    g = Guest(str(work), icount=True, console_log=str(work / "console.log"))
    try:
        g.start()
        g.start_pyserver()
        r = g.pyrun(GUEST_CODE, argv=[str(tree), str(runs)], timeout=3600)
        if r.exit_code != 0 or "RESULT " not in r.output:
            sys.exit(f"the benchmark failed in the guest:\n{r.output[-4000:]}")
        res = json.loads(r.output.split("RESULT ", 1)[1])
        g.check_kernel_log()
    finally:
        g.close()
    print("  ms of virtual time (icount: 1 instruction = 1 ns)")
    print(f"  load (command, tasks running) {dist(res['load'])}")
    if res["load_inside"]:
        print(f"    inside the manager          {dist(res['load_inside'])}")
    print(f"  stop (command, all removed)   {dist(res['stop'])}")
    print("  the last load, step by step:")
    print("".join(f"    {ln}\n" for ln in res["load_steps"].splitlines()), end="")
    print("  the last stop, step by step:")
    print("".join(f"    {ln}\n" for ln in res["stop_steps"].splitlines()), end="")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", default="100,1000,10000")
    ap.add_argument("--build-upto", type=int, default=1000,
                    help="build only configurations up to this many instances")
    ap.add_argument("--guest", type=int, help="time load/stop of this size in the guest")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--workdir")
    ap.add_argument("--smoke", action="store_true",
                    help="a few seconds' run at a small size (CI: tests/benchmarks, "
                         "tests/qemu): 4 and 8 instances, the 4 built (with --guest: "
                         "load/stop of the 4, one run)")
    a = ap.parse_args()
    if a.smoke:
        a.sizes, a.build_upto, a.runs = "4,8", 4, 1
        a.guest = 4 if a.guest else None
    work = Path(a.workdir or tempfile.mkdtemp(prefix="iec2kmod-scale-")).resolve()
    work.mkdir(parents=True, exist_ok=True)
    print(f"{os.cpu_count()} cores, load average "
          f"{' '.join(f'{x:.2f}' for x in os.getloadavg())}; work in {work}")
    print(f"{'instances':>9} {'lines':>7} {'check s':>8} {'gen s':>7} {'build s':>8}   "
          "module sizes (.ko median / largest; loaded text+data+bss median), KB")
    env = dict(os.environ, IEC2KMOD_CACHE=str(work / "cache"))
    for n in [int(x) for x in a.sizes.split(",")]:
        src = work / f"src{n}"
        src.mkdir(exist_ok=True)
        text = project(n, plain=10 * n)
        (src / "plant.st").write_text(text)
        tree = work / f"plant{n}"
        if tree.exists():
            shutil.rmtree(tree)
        shutil.rmtree(work / "cache", ignore_errors=True)
        t_check = timed("check", "--no-cache", src, env=env)
        t_gen = timed("gen", src, "-o", tree, env=env)
        t_build = timed("build", tree, env=env) if n <= a.build_upto else None
        manifest = json.loads((tree / "manifest.json").read_text())
        sz = sizes(tree, manifest)
        desc = "; ".join(f"{k} x{c}: {med / 1024:.0f} / {big / 1024:.0f} ({alloc / 1024:.0f})"
                         for k, (c, med, big, alloc) in sz.items()) or "not built"
        print(f"{n:9} {text.count(chr(10)):7} {t_check:8.2f} {t_gen:7.2f} "
              f"{t_build if t_build is not None else float('nan'):8.1f}   {desc}", flush=True)
    if a.guest:
        tree = work / f"plant{a.guest}"
        if not (tree / "manifest.json").exists() or not sizes(
                tree, json.loads((tree / "manifest.json").read_text())):
            sys.exit(f"--guest {a.guest}: that size was not generated and built")
        guest(tree, work, a.runs)
    if not a.workdir:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
