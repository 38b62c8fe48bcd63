#!/usr/bin/env python3
"""Benchmark (issue 4): release jitter of our 1 ms task next to cyclictest
(rt-tests) and the kernel's timerlat, in the same QEMU guest and run, and
the cost of REAL/LREAL (kernel FPU sections) next to the same arithmetic in
DINT.

The guest runs in icount mode (`-icount shift=0,sleep=off`, one vCPU): one
instruction is 1 ns of virtual time, so the figures repeat from run to run
and do not depend on the host's load.  They are instruction-count budgets,
not bare-metal latencies; compare ratios.

    python benchmarks/jitter.py [--seconds 10]
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HERE = Path(__file__).resolve().parent


def percentile_from_hist(hist, q):
    total = sum(hist)
    if not total:
        return 0
    acc = 0
    for us, n in enumerate(hist):
        acc += n
        if acc >= q * total:
            return us
    return len(hist) - 1


def summary(name, samples_ns):
    s = sorted(samples_ns)
    if not s:
        return f"{name:28} no samples"
    pick = lambda q: s[min(len(s) - 1, int(q * len(s)))]
    return (f"{name:28} n={len(s):6}  min {s[0] / 1000:7.2f}  avg {sum(s) / len(s) / 1000:7.2f}"
            f"  p99 {pick(0.99) / 1000:7.2f}  max {s[-1] / 1000:7.2f} us"), sum(s) / len(s), s[-1]


def cli(*args):
    p = subprocess.run([sys.executable, "-m", "iec2kmod.cli", *args], cwd=ROOT,
                       capture_output=True, text=True)
    if p.returncode:
        sys.exit(f"iec2kmod {' '.join(args)} failed:\n{p.stderr}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, default=10.0)
    args = ap.parse_args()
    from iec2kmod.vm import Guest
    work = Path(tempfile.mkdtemp(prefix="iec2kmod-jitter-"))
    tree = work / "tree"
    cli("gen", str(HERE / "projects" / "jitter"), "-o", str(tree))
    cli("build", str(tree))
    manifest = json.loads((tree / "manifest.json").read_text())
    g = Guest(str(work), icount=True, smp=1)
    g.start()
    try:
        for m in manifest["load_order"]:
            g.check_call(f"insmod {tree / m / (m + '.ko')}")
        cfg = manifest["configuration"].lower()
        g.check_call(f"echo start all > /sys/kernel/iec2kmod/{cfg}/control")
        time.sleep(1)
        g.run(f"sleep {args.seconds}", timeout=args.seconds * 20 + 60)
        res = next(m["name"] for m in manifest["modules"] if m["kind"] == "resource")
        lat = g.check_call(f"cat /sys/module/{res}/iec_latency")
        status = g.check_call(f"cat /sys/kernel/iec2kmod/{cfg}/status")
        g.check_call(f"echo stop all > /sys/kernel/iec2kmod/{cfg}/control")
        # cyclictest: same period, same FIFO priority as IEC priority 0 (49)
        loops = int(args.seconds * 1000)
        ct = g.run(f"cyclictest -m -p 49 -i 1000 -l {loops} -q -h 200", chroot=True,
                   timeout=args.seconds * 40 + 120).output
        # timerlat: the kernel's own periodic RT thread woken by an hrtimer
        tr = "/sys/kernel/tracing"
        g.run(f"mountpoint -q {tr} || mount -t tracefs nodev {tr}")
        g.check_call(f"echo 1000 > {tr}/osnoise/timerlat_period_us && "
                     f"echo timerlat > {tr}/current_tracer && echo > {tr}/trace")
        g.run(f"sleep {args.seconds}", timeout=args.seconds * 20 + 60)
        tl = g.run(f"cat {tr}/trace; echo nop > {tr}/current_tracer", timeout=300).output
    finally:
        g.close()
        shutil.rmtree(work, ignore_errors=True)

    # ours: histogram in 1 us buckets
    line = next(ln for ln in lat.splitlines() if ln.startswith("ms1 "))
    words = line.split()
    cycles, maxns, sumns = int(words[2]), int(words[6]), int(words[8])
    hist = [int(x) for x in words[10:]]
    ours_avg = sumns / max(cycles, 1)
    print(f"guest: icount (1 instruction = 1 ns virtual), 1 vCPU, {args.seconds:g} s per tool")
    print(f"{'iec2kmod task (1 ms)':28} n={cycles:6}  avg {ours_avg / 1000:7.2f}  p99 "
          f"{percentile_from_hist(hist, 0.99):7.2f}  max {maxns / 1000:7.2f} us  "
          f"(overruns {words[4]})")
    # cyclictest histogram: lines "000012 000345" (us, count) and "# Max Latencies"
    ct_samples = []
    for ln in ct.splitlines():
        m = re.match(r"^(\d{6})\s+(\d+)", ln)
        if m:
            ct_samples += [int(m.group(1)) * 1000] * int(m.group(2))
    text, ct_avg, ct_max = summary("cyclictest (1 ms, FIFO 49)", ct_samples) if ct_samples \
        else ("cyclictest: no output", 0, 0)
    print(text)
    tl_samples = [int(m.group(1)) for m in
                  re.finditer(r"context\s+thread\s+timer_latency\s+(\d+) ns", tl)]
    text, tl_avg, tl_max = summary("timerlat (thread, 1 ms)", tl_samples) if tl_samples \
        else ("timerlat: no samples", 0, 0)
    print(text)
    if ct_avg and tl_avg:
        print(f"ratios  ours/cyclictest: avg {ours_avg / ct_avg:.2f} max {maxns / ct_max:.2f};"
              f"  ours/timerlat: avg {ours_avg / tl_avg:.2f} max {maxns / tl_max:.2f}")
    # FPU cost: the same loop in DINT and in LREAL
    ex = {}
    for ln in status.splitlines():
        m = re.match(r"task \S+\.(ints|reals) .* exec_min_ns (\d+) exec_max_ns (\d+) "
                     r"exec_avg_ns (\d+)", ln)
        if m:
            ex[m.group(1)] = (int(m.group(2)), int(m.group(3)), int(m.group(4)))
    if "ints" in ex and "reals" in ex:
        print(f"FPU cost: 100-iteration loop  DINT avg {ex['ints'][2] / 1000:.2f} us,  "
              f"LREAL avg {ex['reals'][2] / 1000:.2f} us (kernel_fpu_begin/end included)")


if __name__ == "__main__":
    main()
