#!/usr/bin/env python3
"""Soaks in the PREEMPT_RT guest (issue 9, item 5), with figures:

  swaps   N hot swaps of the 1 ms counter of tests/qemu/projects/mgr_plant
          back and forth between two builds (same interface), in virtual
          time (icount: host load cannot cause an overrun): overruns of the
          1 ms task during the swaps, the counter never going back, every
          swap running its new body, swap latency min/median/p99/max;
  cycles  N load/stop cycles of the plant: modules back to zero after each,
          Slab and SUnreclaim (/proc/meminfo) after every stop, their drift
          from the first cycle to the last (growth above 1 % fails);
  kills   N times the manager killed with SIGKILL at a random moment of
          `load`, `swap` or `stop` (uniform over the command's measured
          duration, counted once the process has imported what it needs),
          each followed by a plain `plc-manager stop` that must leave
          nothing loaded and a `load` that must work.

    python benchmarks/soak.py [--swaps 1000] [--cycles 100] [--kills 50] [--seed 9]
                              [--only swaps,cycles,kills] [--smoke]

The manager is this checkout's (a plc_manager link on the guest's
sys.path).  Exit status 1 when a soak's condition fails.
"""

from __future__ import annotations

import argparse
import compileall
import json
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PLANT = ROOT / "tests" / "qemu" / "projects" / "mgr_plant"
ALGO_A = ("count := count + 1;    (* ALGO *)", "algo := 1;             (* ALGO *)")
ALGO_B = ("count := count + 2;    (* ALGO *)", "algo := 2;             (* ALGO *)")

PRELUDE = r'''
import contextlib, io, json, os, random, subprocess, sys, time
sys.path.insert(0, PMDIR)
from plc_manager import kmod, ops
from plc_manager.cli import main
from plc_manager.netlink import Client

def pm(*args):
    buf, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(err):
        rc = main([str(a) for a in args])
    return rc, buf.getvalue() + err.getvalue()

def ours():
    return sorted(m for m in kmod.loaded() if m.startswith("iec_plant_"))

def pct(s, q):
    s = sorted(s)
    return s[min(len(s) - 1, int(q * len(s)))] if s else None
'''

SWAPS = r'''
A, B, tree, n = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
assert pm("load", tree)[0] == 0
c = Client()
vs = ops.Variables(c, c.status())
def fast():
    return next(t for t in c.status().tasks() if t.path == "main.fast")
def values():
    return {t.path: v for t, raw, v in vs.read(["count", "algo", "main.c1.cycles"])}
time.sleep(0.5)
t0 = fast()
prev = values()
lat, back, stale, t_start = [], 0, 0, time.monotonic()
cyc_prev = t0.cycles
for i in range(n):
    new, algo = (B, 2) if i % 2 == 0 else (A, 1)
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        rc = main(["swap", "--json", new])
    assert rc == 0, buf.getvalue()
    lat.append(json.loads(buf.getvalue())["steps"][0]["latency_ms"])
    deadline = time.monotonic() + 5
    while True:
        v = values()
        if v["algo"] == algo or time.monotonic() > deadline:
            break
        time.sleep(0.002)
    stale += v["algo"] != algo
    back += v["count"] < prev["count"] or v["main.c1.cycles"] < prev["main.c1.cycles"]
    cyc = fast().cycles
    back += cyc < cyc_prev
    prev, cyc_prev = v, cyc
t1 = fast()
c.close()
assert pm("stop")[0] == 0
print("RESULT " + json.dumps({
    "swaps": n, "seconds": time.monotonic() - t_start, "latency_ms": lat,
    "overruns": t1.overruns - t0.overruns, "cycles": t1.cycles - t0.cycles,
    "went_back": back, "new_body_not_seen": stale, "state": t1.state,
    "exec_max_ns": t1.exec_max_ns, "latency_max_ns": t1.latency_max_ns,
    "left": ours()}))
'''

CYCLES = r'''
tree, n = sys.argv[1], int(sys.argv[2])
def meminfo():
    d = {}
    for ln in open("/proc/meminfo"):
        k, v = ln.split(":")
        d[k] = int(v.split()[0])
    return d["Slab"], d["SUnreclaim"]
rows, bad = [], []
for i in range(n):
    rc, out = pm("load", tree)
    if rc:
        bad.append(f"load {i}: {out[-300:]}")
        break
    rc, out = pm("stop")
    left = ours()
    if rc or left:
        bad.append(f"stop {i}: rc {rc}, left {left}: {out[-300:]}")
        break
    with open("/proc/sys/vm/drop_caches", "w") as f:
        f.write("2\n")
    rows.append(meminfo())
print("RESULT " + json.dumps({"cycles": len(rows), "meminfo": rows, "bad": bad}))
'''

KILLS = r'''
A, B, tree, n, seed = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]), int(sys.argv[5])
rng = random.Random(seed)
# the manager in a process of its own: imports first (seconds under
# emulation), "ready", then the command; the kill moments are drawn over
# the command's own duration, from "ready" to its end, measured here first
cmd = [sys.executable, "-c",
       "import sys; sys.path.insert(0, %r)\n"
       "from plc_manager.cli import main\n"
       "from plc_manager import kmod, netlink, ops, project\n"
       "import pyroute2.netlink.generic\n"
       "print('ready', flush=True)\n"
       "sys.exit(main(sys.argv[1:]))" % PMDIR]
def start(*args):
    p = subprocess.Popen(cmd + [str(a) for a in args], stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, text=True)
    assert p.stdout.readline().strip() == "ready"
    return p
def timed(*args):
    p = start(*args)
    t = time.monotonic()
    out = p.stdout.read()
    p.wait()
    return time.monotonic() - t, p.returncode, out
dur = {}
dur["load"], rc, out = timed("load", tree); assert rc == 0, out
dur["swap"], rc, out = timed("swap", B); assert rc == 0, out
dur["stop"], rc, out = timed("stop"); assert rc == 0, out
log, bad = [], []
for i in range(n):
    what = ("load", "swap", "stop")[i % 3]
    if what != "load":
        rc, out = pm("load", tree)
        assert rc == 0, out
        if what == "swap" and i % 2:          # back and forth between the builds
            assert pm("swap", B)[0] == 0
    args = {"load": ["load", tree], "swap": ["swap", A if i % 2 else B], "stop": ["stop"]}[what]
    at = rng.uniform(0.0, dur[what])
    p = start(*args)
    time.sleep(at)
    p.kill()
    p.stdout.read()
    p.wait()
    before = ours()
    rc, out = pm("stop")
    after = ours()
    ok_stop = not after and (rc == 0 or "nothing is loaded" in out)
    rc2, out2 = pm("load", tree)
    rc3, out3 = pm("stop")
    ok = ok_stop and rc2 == 0 and rc3 == 0 and not ours()
    log.append([what, round(at, 3), p.returncode, len(before), rc, ok])
    if not ok:
        bad.append(f"{i} {what} killed at {at:.3f} s: stop rc {rc} left {after}: "
                   f"{out.strip()[-200:]} / load rc {rc2}: {out2.strip()[-200:]}")
        if ours():
            break
print("RESULT " + json.dumps({"durations": dur, "kills": log, "bad": bad}))
'''


def gen_build(src: Path, out: Path):
    for args in (["gen", str(src), "-o", str(out)], ["build", str(out)]):
        p = subprocess.run([sys.executable, "-m", "iec2kmod.cli", *args], cwd=ROOT,
                           capture_output=True, text=True)
        if p.returncode:
            sys.exit(f"iec2kmod {' '.join(args)}:\n{p.stdout}{p.stderr}")


def variant(dest: Path, replace) -> Path:
    dest.mkdir(parents=True, exist_ok=True)
    text = (PLANT / "plant.st").read_text()
    for old, new in replace:
        text = text.replace(old, new)
    (dest / "plant.st").write_text(text)
    return dest


def counter(tree: Path) -> Path:
    (d,) = [p for p in tree.iterdir() if p.name.startswith("iec_plant_p_counter_")]
    return d / f"{d.name}.ko"


def run(g, code, pmdir, *argv, timeout):
    r = g.pyrun(f"PMDIR = {str(pmdir)!r}\n" + PRELUDE + code, argv=[str(a) for a in argv],
                timeout=timeout)
    if "RESULT " not in r.output:
        sys.exit(f"the guest script failed (exit {r.exit_code}):\n{r.output[-3000:]}")
    return json.loads(r.output.split("RESULT ", 1)[1].splitlines()[0])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--swaps", type=int, default=1000)
    ap.add_argument("--cycles", type=int, default=100)
    ap.add_argument("--kills", type=int, default=50)
    ap.add_argument("--seed", type=int, default=9)
    ap.add_argument("--only", default="swaps,cycles,kills")
    ap.add_argument("--smoke", action="store_true",
                    help="a few seconds' run at a small size (CI: tests/qemu): 3 swaps, 2 load/stop cycles, 2 kills")
    args = ap.parse_args()
    if args.smoke:
        args.swaps, args.cycles, args.kills = 3, 2, 2
    only = set(args.only.split(","))
    from iec2kmod import kbuild
    from iec2kmod.testing.vm import Guest
    work = Path(tempfile.mkdtemp(prefix="iec2kmod-soak-"))
    failed = []
    try:
        a = work / "a"
        gen_build(PLANT, a)
        b = work / "b"
        subprocess.run([sys.executable, "-m", "iec2kmod.cli", "gen",
                        str(variant(work / "src_b", zip(ALGO_A, ALGO_B))), "-o", str(b)],
                       cwd=ROOT, check=True, capture_output=True)
        kbuild.build_modules(str(counter(b).parent), extra_args=[
            f"KBUILD_EXTRA_SYMBOLS={a / 'Module.symvers'}"]).check()
        pmdir = work / "pm"
        pmdir.mkdir()
        (pmdir / "plc_manager").symlink_to(ROOT / "manager")
        compileall.compile_dir(str(ROOT / "manager"), quiet=1)
        ka, kb = counter(a), counter(b)

        if "swaps" in only:
            g = Guest(str(work), icount=True, smp=1)
            g.start()
            try:
                r = run(g, SWAPS, pmdir, ka, kb, a, args.swaps,
                        timeout=args.swaps * 30 + 600)
                g.check_kernel_log()
            finally:
                g.close()
            lat = sorted(r["latency_ms"])
            print(f"swaps: {r['swaps']} under the 1 ms task (icount) in {r['seconds']:.0f} s "
                  f"of guest time; overruns {r['overruns']} over {r['cycles']} cycles; "
                  f"counters went back {r['went_back']} times; new body not seen "
                  f"{r['new_body_not_seen']}; task {r['state']}, exec max "
                  f"{r['exec_max_ns'] / 1000:.1f} us, release latency max "
                  f"{r['latency_max_ns'] / 1000:.1f} us")
            print(f"       command to new body running: min {lat[0]:.1f} / median "
                  f"{lat[len(lat) // 2]:.1f} / p99 {lat[min(len(lat) - 1, int(.99 * len(lat)))]:.1f}"
                  f" / max {lat[-1]:.1f} ms; modules left {r['left']}")
            if r["overruns"] or r["went_back"] or r["new_body_not_seen"] or r["left"]:
                failed.append("swaps")

        if only & {"cycles", "kills"}:
            g = Guest(str(work))
            g.start()
            try:
                if "cycles" in only:
                    r = run(g, CYCLES, pmdir, a, args.cycles, timeout=args.cycles * 120 + 600)
                    rows = r["meminfo"]
                    if rows:
                        slab = [x[0] for x in rows]
                        sun = [x[1] for x in rows]
                        ds = 100.0 * (slab[-1] - slab[0]) / slab[0]
                        du = 100.0 * (sun[-1] - sun[0]) / sun[0]
                        print(f"cycles: {r['cycles']} load/stop, modules back to 0 after each; "
                              f"Slab first {slab[0]} last {slab[-1]} min {min(slab)} max "
                              f"{max(slab)} kB ({ds:+.2f} %); SUnreclaim first {sun[0]} last "
                              f"{sun[-1]} min {min(sun)} max {max(sun)} kB ({du:+.2f} %)")
                        # a leak grows: memory given back (a cache the
                        # kernel shrank between the first and the last
                        # stop) is no failure; stop 34's CI saw Slab -1.01 %
                        if du > 1.0 or ds > 1.0:
                            failed.append("cycles (growth above 1 %)")
                    for x in r["bad"]:
                        print("  " + x)
                    if r["bad"]:
                        failed.append("cycles")
                if "kills" in only:
                    r = run(g, KILLS, pmdir, ka, kb, a, args.kills, args.seed,
                            timeout=args.kills * 180 + 600)
                    d = r["durations"]
                    by = {}
                    for what, at, rc, before, stop_rc, ok in r["kills"]:
                        by.setdefault(what, []).append((before, ok))
                    print(f"kills: {len(r['kills'])} SIGKILLs (commands take load "
                          f"{d['load']:.1f} s, swap {d['swap']:.1f} s, stop {d['stop']:.1f} s "
                          f"here); " + "; ".join(
                              f"{w}: {len(v)} killed, {sum(1 for b, _ in v if b)} left modules "
                              f"behind, {sum(1 for _, ok in v if ok)} recovered by stop + load"
                              for w, v in sorted(by.items())))
                    for x in r["bad"]:
                        print("  " + x)
                    if r["bad"]:
                        failed.append("kills")
                g.check_kernel_log()
            finally:
                g.close()
    finally:
        shutil.rmtree(work, ignore_errors=True)
    if failed:
        print("FAILED: " + ", ".join(failed))
        sys.exit(1)


if __name__ == "__main__":
    main()
