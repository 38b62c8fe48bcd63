#!/usr/bin/env python3
"""Benchmark (issue 26): interrupt -> task start latency of an event task
woken by a hardware interrupt (an INTERRUPT binding of the I/O map,
kmod_templates/kernel/iec_io.c), next to a plain kernel thread woken by the
same interrupt the same way (benchmarks/irq_kthread/irqwake.c).

The interrupt: QEMU's emulated parallel port (LPT1, IRQ 7) driven by
comedi_parport (attached with its I/O base only).  The stimulus is the same
in both runs: resource Pulse toggles STROBE (control line 0) every
--period-us; each cycle that writes STROBE low makes the port raise IRQ 7
(the control register's interrupt enable is set by whoever requested the
line).  Both wakers use the same path: a primary handler in hard interrupt
context (IRQF_ONESHOT) that checks the enable, reads the status register
(QEMU's acknowledgement) and stamps the time, then the line's irq thread
(SCHED_FIFO 50) that wakes the woken thread (SCHED_FIFO 49: IEC PRIORITY 0
and the kthread alike).

  plc      resource Events: TASK onack (SINGLE := ack, PRIORITY := 0) with
           INTERRUPT %IX9.0 : lpt.ACK IRQ 7; its program counts
  kthread  irqwake.ko requests IRQ 7; its thread "irqwake" counts

Method, the same for both (ftrace in the guest, clock x86-tsc: under
icount the TSC advances one tick per virtual nanosecond, converted with the
kernel's tsc_khz): latency = the first sched_switch into the woken thread
after irq_handler_entry of IRQ 7 (the primary handler's start).  Printed:
n, min, median, p99, max, and each waker's own figure (stamp in the
primary handler -> the thread's first work after the wake-up: the PLC
task's release -> cycle start, its iec_latency histogram and maximum; the
kthread's histogram in the same buckets and exact min/max).

The guest runs in icount mode (-icount shift=0,sleep=off, one vCPU): the
figures are instruction-count budgets that repeat from run to run, not
bare-metal latencies; compare the two.

    python benchmarks/irq_latency.py [--interrupts 1000] [--period-us 1000] [--smoke]
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(ROOT / "tests" / "qemu"))
sys.path.insert(0, str(ROOT))

from kmod_helpers import gen_and_build, pm  # noqa: E402

import iec2kmod.testing.vm as vm  # noqa: E402
from iec2kmod import kbuild  # noqa: E402

LEGACY = ROOT / "tests" / "qemu" / "comedi_legacy.py"

PULSE = """
PROGRAM Pulse
  VAR_EXTERNAL strobe : BOOL; lows : UDINT; END_VAR
  strobe := NOT strobe;
  IF NOT strobe THEN
    lows := lows + 1;
  END_IF;
END_PROGRAM
PROGRAM OnAck
  VAR_EXTERNAL acks : UDINT; END_VAR
  acks := acks + 1;
END_PROGRAM
CONFIGURATION Bench
  RESOURCE Pulse ON CPU0
    VAR_GLOBAL strobe AT %QX1.0 : BOOL; lows : UDINT; END_VAR
    TASK pulse (INTERVAL := T#{period}us, PRIORITY := 10);
    PROGRAM p1 WITH pulse : Pulse;
  END_RESOURCE
{events}END_CONFIGURATION
"""
EVENTS = """  RESOURCE Events ON CPU0
    VAR_GLOBAL ack AT %IX9.0 : BOOL; acks : UDINT; END_VAR
    TASK onack (SINGLE := ack, PRIORITY := 0);
    PROGRAM a1 WITH onack : OnAck;
  END_RESOURCE
"""
MAP = """RESOURCE Pulse
DEVICE lpt : comedi comedi_parport MINOR 0
%QX1.0 : lpt.2.0 SAFE HOLD
"""
MAP_EVENTS = """RESOURCE Events
DEVICE lpt : comedi comedi_parport MINOR 0
INTERRUPT %IX9.0 : lpt.ACK IRQ 7
"""

TRACING = "/sys/kernel/tracing"


def project(dir: Path, period_us: int, events: bool) -> Path:
    dir.mkdir(parents=True)
    (dir / "bench.st").write_text(PULSE.replace("{period}", str(period_us))
                                  .replace("{events}", EVENTS if events else ""))
    (dir / "lpt.iomap").write_text(MAP + (MAP_EVENTS if events else ""))
    return dir


def values(g, *names) -> dict:
    return {v["path"]: v["value"] for v in json.loads(pm(g, "read", "--json", *names)[1])}


def trace_on(g, comm_glob: str) -> str:
    """Traces IRQ 7 and the switches into the woken thread; returns the
    buffer size before (trace_off restores it)."""
    size = g.check_call(f"cat {TRACING}/buffer_size_kb").strip()
    m = re.search(r"expanded: (\d+)", size)
    size = m.group(1) if m else size.split()[0]
    g.check_call(
        f"cd {TRACING} && echo 0 > tracing_on && echo x86-tsc > trace_clock && "
        "echo 16384 > buffer_size_kb && "
        "echo 'irq == 7' > events/irq/irq_handler_entry/filter && "
        "echo 1 > events/irq/irq_handler_entry/enable && "
        f"echo 'next_comm ~ \"{comm_glob}\"' > events/sched/sched_switch/filter && "
        "echo 1 > events/sched/sched_switch/enable && echo > trace && echo 1 > tracing_on")
    return size


def trace_off(g, size: str) -> str:
    """The trace; tracing as it was before trace_on (the guest may be
    shared: tests/qemu/test_benchmarks_qemu_smoke.py)."""
    g.check_call(f"echo 0 > {TRACING}/tracing_on")
    out = g.check_call(f"cat {TRACING}/trace", timeout=600)
    g.check_call(f"cd {TRACING} && echo 0 > events/enable && echo > trace && "
                 "echo 0 > events/irq/irq_handler_entry/filter && "
                 "echo 0 > events/sched/sched_switch/filter && "
                 f"echo local > trace_clock && echo {size} > buffer_size_kb && "
                 "echo 1 > tracing_on")
    return out


_EV = re.compile(r"\s(\d+):\s+(irq_handler_entry|sched_switch):")


def latencies(trace: str, ns_per_tick: float) -> tuple[list, int, int]:
    """[ns] from each IRQ 7 entry to the next switch into the woken thread;
    the interrupts counted, and those followed by another before a switch."""
    out, pending, irqs, merged = [], None, 0, 0
    for line in trace.splitlines():
        m = _EV.search(line)
        if not m:
            continue
        ts = int(m.group(1))
        if m.group(2) == "irq_handler_entry":
            irqs += 1
            if pending is not None:
                merged += 1
            pending = ts
        elif pending is not None:
            out.append((ts - pending) * ns_per_tick)
            pending = None
    return out, irqs, merged


def pct(xs, p):
    s = sorted(xs)
    return s[min(len(s) - 1, max(0, int(round(p / 100 * len(s) + 0.5)) - 1))]


def row(name, xs):
    us = [x / 1000 for x in xs]
    return (f"{name:<28} {len(us):>6} {min(us):>8.2f} {statistics.median(us):>8.2f} "
            f"{pct(us, 99):>8.2f} {max(us):>8.2f}")


def hist_summary(hist, n):
    """min bucket, median and p99 bucket upper bounds (us) of iec2kmod's
    log-linear histogram (1 us buckets below 32 us)."""
    def bounds(b):
        if b < 32:
            return b, b + 1
        o, s = divmod(b - 32, 4)
        return (32 << o) * (4 + s) // 4, (32 << o) * (5 + s) // 4
    seen, res = 0, {}
    lo = next(b for b, c in enumerate(hist) if c)
    for b, c in enumerate(hist):
        seen += c
        for p in (50, 99):
            if p not in res and seen >= p / 100 * n:
                res[p] = bounds(b)[1]
    return bounds(lo)[0], res[50], res[99]


def run_variant(g, tree, manifest, n, kind, irqwake_ko=None):
    if irqwake_ko:
        g.insmod(irqwake_ko)
    pm(g, "load", "--no-start", tree)
    size = trace_on(g, "iec/events*" if kind == "plc" else "irqwake")
    pm(g, "start")
    deadline = time.monotonic() + 1800
    while values(g, "Pulse.lows")["Pulse.lows"] < n + 5:
        if time.monotonic() > deadline:
            raise SystemExit("the pulse task did not produce the interrupts within 30 min")
        time.sleep(1)
    pm(g, "stop", "--keep-loaded", "--resource", "Pulse")
    lows = values(g, "Pulse.lows")["Pulse.lows"]
    own = None
    if kind == "plc":
        deadline = time.monotonic() + 60
        while values(g, "Events.acks")["Events.acks"] < lows:
            if time.monotonic() > deadline:
                raise SystemExit("onack did not count every interrupt")
            time.sleep(0.5)
        acks = values(g, "Events.acks")["Events.acks"]
        mod = next(m["name"] for m in manifest["modules"]
                   if m["kind"] == "resource" and m["name"].endswith("_events"))
        text = g.check_call(f"cat /sys/module/{mod}/iec_latency")
        m = re.search(r"onack cycles (\d+) overruns \d+ max_ns (\d+) sum_ns (\d+) hist ([\d ]+)",
                      text)
        cycles, mx, sm = int(m.group(1)), int(m.group(2)), int(m.group(3))
        hist = [int(x) for x in m.group(4).split()]
        lo, med, p99 = hist_summary(hist, cycles)
        own = (f"own: release (IRQ stamp) -> cycle start: n {cycles} min >= {lo} us, "
               f"median < {med} us, p99 < {p99} us, max {mx / 1000:.2f} us, "
               f"avg {sm / cycles / 1000:.2f} us; acks {acks} of {lows} STROBE-low writes")
    trace = trace_off(g, size)
    pm(g, "stop")
    if irqwake_ko:
        mark = g.log_mark()
        g.rmmod("irqwake")
        line = next(l for l in g.dmesg(mark).splitlines() if "irqwake: irqs" in l)
        m = re.search(r"irqs (\d+) wakes (\d+) min_ns (\d+) max_ns (\d+) sum_ns (\d+) hist ([\d ]+)",
                      line)
        irqs, wakes, mn, mx, sm = (int(m.group(i)) for i in range(1, 6))
        hist = [int(x) for x in m.group(6).split()]
        _, med, p99 = hist_summary(hist, wakes)
        own = (f"own: IRQ stamp -> thread: n {wakes} min {mn / 1000:.2f} us, median < {med} us, "
               f"p99 < {p99} us, max {mx / 1000:.2f} us, avg {sm / wakes / 1000:.2f} us; "
               f"irqs {irqs} of {lows} STROBE-low writes")
    return trace, own


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--interrupts", type=int, default=1000)
    ap.add_argument("--period-us", type=int, default=1000)
    ap.add_argument("--no-icount", action="store_true", help="plain TCG (2 vCPUs)")
    ap.add_argument("--smoke", action="store_true", help="20 interrupts (the test's size)")
    a = ap.parse_args(argv)
    if a.smoke:
        a.interrupts = 20
    work = Path(tempfile.mkdtemp(prefix="iec2kmod-irqlat-"))
    try:
        trees = {}
        for kind in ("plc", "kthread"):
            src = project(work / f"src_{kind}", a.period_us, kind == "plc")
            trees[kind] = (work / kind, gen_and_build(src, work / kind))
        kt = work / "irq_kthread"
        shutil.copytree(HERE / "irq_kthread", kt)
        kbuild.build_modules(str(kt)).check()
        lpt = work / "lpt1.bin"
        lpt.write_bytes(b"")
        with vm.Guest(str(work), icount=not a.no_icount, parallel=str(lpt)) as g:
            md = "/host" + g.kernel.moddir + "/drivers/comedi"
            g.check_call(f"insmod {md}/comedi.ko comedi_num_legacy_minors=1 && "
                         f"insmod {md}/kcomedilib/kcomedilib.ko && "
                         f"insmod {md}/drivers/comedi_parport.ko")
            legacy = LEGACY.read_text()
            g.pyrun(code=legacy, argv=["config", "/dev/comedi0", "comedi_parport", "0x378"],
                    check=True)
            g.pyrun(code=legacy, argv=["bits", "/dev/comedi0", "2", "0xc", "0xc"], check=True)
            khz = re.findall(r"tsc: (?:Refined TSC clocksource calibration|Detected): "
                             r"?([\d.]+) MHz", g.check_call("dmesg"))
            mhz = float(khz[-1]) if khz else None
            if not mhz:
                raise SystemExit("no TSC frequency in the guest's kernel log")
            results = {}
            for kind in ("plc", "kthread"):
                tree, manifest = trees[kind]
                trace, own = run_variant(g, tree, manifest, a.interrupts, kind,
                                         str(kt / "irqwake.ko") if kind == "kthread" else None)
                results[kind] = (latencies(trace, 1000.0 / mhz), own)
            # the drivers go (the guest may be shared)
            g.check_call("rmmod comedi_parport kcomedilib comedi")
            g.check_kernel_log()
        mode = "icount (shift=0, 1 vCPU)" if not a.no_icount else "plain TCG"
        print(f"interrupt -> task start, QEMU {mode}, TSC {mhz} MHz, stimulus every "
              f"{2 * a.period_us} us")
        print(f"{'woken thread':<28} {'n':>6} {'min us':>8} {'median':>8} {'p99':>8} "
              f"{'max':>8}")
        for kind, label in (("plc", "IEC task onack (PRIO 0)"), ("kthread", "kthread irqwake")):
            (xs, irqs, merged), own = results[kind]
            print(row(label, xs) + f"   ({irqs} IRQ 7 entries, {merged} merged)")
        for kind in ("plc", "kthread"):
            print(f"{kind}: {results[kind][1]}")
        med = [statistics.median(results[k][0][0]) for k in ("plc", "kthread")]
        print(f"median ratio plc/kthread: {med[0] / med[1]:.2f}")
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
