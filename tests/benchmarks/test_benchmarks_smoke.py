# SPDX-License-Identifier: MIT
"""Every benchmark under benchmarks/ that runs on the host, at its smoke size
(``--smoke``: a few cycles or projects, seconds each), so that none rots
unseen: each must exit 0 and print its figures.  The benchmarks that boot
the QEMU guest are in tests/qemu/test_benchmarks_smoke.py.  The smoke
sizes do not measure anything worth comparing: run the scripts without
--smoke for the figures."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
BENCH = ROOT / "benchmarks"
NUM = r"[-+]?\d[\d,.]*(?:e[-+]?\d+)?"

# script -> the figures its smoke run must print (one regex per line kind)
HOST = {
    "annexf_tally": [r"^Annex F: 3 of 3 files accepted$"],
    "check_throughput": [rf"^cold check: +{NUM} s +\({NUM} lines/s\)", rf"^repeat check: +{NUM} s",
                         rf"^single file: +{NUM} s", rf"^cold check: +min +{NUM} +median",
                         rf"^on one core: +{NUM} s"],
    "gen_project": [r"^project: \d+ lines; iec2kmod check: exit 0 in",
                    r"^dense POU: \d+ lines; iec2kmod check: exit 0 in"],
    "plant": [r"^plant of 20 instances: \d+ lines; iec2kmod check: exit 0 in"],
    "math_accuracy": [rf"^sqrt +lreal +posl .* {NUM} +{NUM}", rf"^atan2 +real +.* {NUM}",
                      r"^tan +lreal +edge "],
    "scan_cost": [rf"^{p} +{NUM} +{NUM} +{NUM}$" for p in ("interlock", "pid", "recipe")]
                 + [r"^target <= 1.3: (met|NOT met)$"],
    "verify": [r"^examples/traffic_light \(example\): \d+ state variables",
               r"^tests/verify/broken/crossing_latched_green \(broken\): .*",
               r"plc\.crossing\.one_main_lamp +violated at cycle \d+",
               rf"^total: {NUM} s wall, {NUM} s CPU"],
    "selective": [rf"^{p} +{r} +{NUM} +{NUM} +{NUM} +{NUM}%$"
                  for p in ("interlock", "plant", "packaging") for r in ("0", "100")],
    "selective_writer_side": [rf"^ +{r} +{NUM} +{NUM} +{NUM} +{NUM} +{NUM}$" for r in ("0", "100")],
    "fuzz_diff": [r"^3 projects in \d+ s: ok 3$", r"^constructs reached: \d+"],
    "verify_fuzz": [r"^2 projects in \d+ s$", r"^ +internal +0$", r"^ +contradicted +0$",
                    r"^property verdicts .*: proved \d+"],
    "scale": [rf"^ +4 +\d+ +{NUM} +{NUM} +{NUM} +configuration x1: ",
              rf"^ +8 +\d+ +{NUM} +{NUM} +nan +not built$"],
}

QEMU_ONLY = {"jitter", "netlink_flood", "netlink_fuzz", "soak", "swap_latency"}


def run_smoke(script: str, *extra: str, timeout: float = 900):
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(
        [str(ROOT / ".pypath"), str(ROOT), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    t0 = time.monotonic()
    p = subprocess.run([sys.executable, str(BENCH / f"{script}.py"), "--smoke", *extra],
                       cwd=ROOT, env=env, capture_output=True, text=True, timeout=timeout)
    return p, time.monotonic() - t0


def check_figures(script: str, out: str, patterns) -> None:
    missing = [rx for rx in patterns if not re.search(rx, out, re.M)]
    assert not missing, f"{script} --smoke did not print {missing}:\n{out[-3000:]}"


def test_every_benchmark_has_a_smoke_test():
    scripts = {p.stem for p in BENCH.glob("*.py")}
    assert scripts == set(HOST) | QEMU_ONLY, (
        f"benchmarks without a smoke test: {sorted(scripts - set(HOST) - QEMU_ONLY)}; "
        f"smoke tests of missing scripts: {sorted(set(HOST) - scripts)}")
    for s in sorted(scripts):
        assert "--smoke" in (BENCH / f"{s}.py").read_text(), f"{s}.py has no --smoke option"


@pytest.mark.execution
@pytest.mark.parametrize("script", sorted(HOST))
def test_benchmark_smoke(script):
    p, secs = run_smoke(script)
    assert p.returncode == 0, f"{script} --smoke: exit {p.returncode} after {secs:.0f} s\n" \
                              f"{p.stdout[-3000:]}\n{p.stderr[-3000:]}"
    check_figures(script, p.stdout, HOST[script])


def test_the_figure_check_can_fail():
    with pytest.raises(AssertionError, match="did not print"):
        check_figures("scan_cost", "interlock 1.0 2.0 0.5\n", HOST["scan_cost"])
