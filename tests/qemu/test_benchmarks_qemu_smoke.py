# SPDX-License-Identifier: MIT
"""The benchmarks that boot the QEMU guest, at their smoke size (``--smoke``),
so that none rots unseen: each must exit 0 and print its figures.  Each
script boots its own guest (most of them the icount guest, which the
session guest of this tier is not), so these cost a guest boot each; the
host-only benchmarks are in tests/benchmarks/test_benchmarks_smoke.py."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from test_benchmarks_smoke import NUM, QEMU_ONLY, check_figures, run_smoke  # noqa: E402

pytestmark = pytest.mark.qemu

GUEST = {
    "swap_latency": [rf"^load \(total, tasks running\) +{NUM} +{NUM} +{NUM} +{NUM}$",
                     rf"^    command -> new body running +{NUM} +{NUM}",
                     r"^overruns of the 10 tasks during 3 swaps: 0 \(1 loads, 3 swaps\)$"],
    "netlink_fuzz": [r"^netlink fuzz: seed 1, 500 messages in .*; 0 accepted that must not "
                     r"be; 0 unanswered",
                     r"^round 1 \(seed 1\): \d+ s, 0 problems$",
                     r"^plc-manager stop: exit 0; modules left: none$"],
    "jitter": [rf"^iec2kmod ms1 alone \(overruns 0\) +n= +\d+ +min +{NUM} +median +{NUM}",
               r"^cyclictest loaded \(FIFO 48\) +n= +\d+ ",
               rf"^timerlat unloaded .* p99 +{NUM}",
               rf"^FPU cost: 100-iteration loop +DINT avg {NUM} us, +LREAL avg {NUM} us"],
    "netlink_flood": [rf"^idle +{NUM} +\d+ +\d+ +{NUM} +{NUM} +{NUM} +{NUM}$",
                      rf"^flood +{NUM} +\d+ +\d+ +{NUM} +{NUM} +{NUM} +{NUM}$",
                      rf"^commands: 200 in {NUM} s",
                      r"^additional overruns under the flood: \d+ \(target 0\)"],
    "soak": [r"^swaps: 3 under the 1 ms task \(icount\) .*; overruns 0 over \d+ cycles",
             r"^ +command to new body running: min .* modules left \[\]$",
             r"^cycles: 2 load/stop, modules back to 0 after each; Slab first \d+",
             r"^kills: 2 SIGKILLs "],
    "serve_load": [r"^250 variables subscribed \(100 ms\), 10 writes/s asked, "
                   rf"{NUM} s, guest clock tcg$",
                   rf"^server CPU: {NUM}% of one CPU$",
                   rf"^notifications: {NUM}/s; writes done {NUM}/s \(\d+ behind schedule\)$",
                   rf"^cycle end -> client \(ms\) +p50 +{NUM} +p99 +{NUM} +max +{NUM} "
                   r"+\(n=\d+\)$",
                   # on a loaded machine a 6 s run may see no write come back
                   rf"^write -> echo notified \(ms\) +(p50 +{NUM} +p99 +{NUM} +max +{NUM} "
                   r"+\(n=\d+\)|no sample \(n=0\))$",
                   r"^task t10: alone \d+ cycles, \d+ overruns; with the server \d+ cycles, "
                   r"\d+ overruns$"],
    "scale": [rf"^ +4 +\d+ +{NUM} +{NUM} +{NUM} +configuration x1: ",
              rf"^  load \(command, tasks running\) min +{NUM} ",
              rf"^  stop \(command, all removed\) +min +{NUM} "],
}


def test_every_guest_benchmark_is_here():
    assert set(GUEST) == QEMU_ONLY | {"scale"}


@pytest.mark.parametrize("script", sorted(GUEST))
def test_guest_benchmark_smoke(script):
    extra = ("--guest", "4") if script == "scale" else ()
    p, secs = run_smoke(script, *extra, timeout=1800)
    assert p.returncode == 0, f"{script} --smoke: exit {p.returncode} after {secs:.0f} s\n" \
                              f"{p.stdout[-3000:]}\n{p.stderr[-3000:]}"
    check_figures(script, p.stdout, GUEST[script])
