# SPDX-License-Identifier: MIT
"""Every benchmark under benchmarks/ that runs on the host, at its smoke size
(``--smoke``: a few cycles or projects, seconds each), so that none rots
unseen: each must exit 0 and print its figures.  The benchmarks that boot
the QEMU guest are in tests/qemu/test_benchmarks_qemu_smoke.py, the ones
whose smoke test needs a stand-in input in the file ELSEWHERE names, and a
data module (no main block) is not a benchmark of its own.  The smoke
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
    "plcopen_fuzz": [r"^10 projects \(\d+ LD, \d+ FBD\) in \d+ s \(interp\): 10 agree, "
                     r"0 disagree$"],
    "plcopen_corpus": [r"^mixed/plc\.xml +IEC only +runs \(", r"^IEC-only projects: 1$",
                       r"^ +1 +runs$"],
    "plcopen_vs_beremiz": [r"^smoke: no Beremiz checkout; our export --st stands in",
                           r"^8 agree$",
                           r"^planted difference in ld_rungs\.xml: differ after cycle 1: "],
    "realcode": [r"^12 files: [1-9]\d* same, 0 differ, 0 failed, \d+ checked, \d+ refused$",
                 r"^refusals by cause:$"],
    "verify_encode_diff": [rf"^2 programs x 20 expressions, \d+ cycles compared, 0 differ, "
                           rf"{NUM} s$"],
}

QEMU_ONLY = {"io_user_latency", "irq_latency", "jitter", "netlink_flood", "netlink_fuzz",
             "plcopen_kernel", "serve_load", "soak", "swap_latency"}


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


# scripts whose smoke test needs more than the script's own output (a
# stand-in input, checks of its report): where that test is; it must run
# the script with --smoke
ELSEWHERE = {"mutate": "tests/unit/test_mutate_smoke.py",
             "oscat": "tests/unit/test_oscat_benchmark.py"}


def is_script(path: Path) -> bool:
    """A benchmark is a script (it runs); a module without a main block is a
    benchmark's data (benchmarks/oscat_cases.py), imported, not run."""
    return re.search(r"^if __name__ == [\"']__main__[\"']:", path.read_text(), re.M) is not None


def test_every_benchmark_has_a_smoke_test():
    scripts = {p.stem for p in BENCH.glob("*.py") if is_script(p)}
    owned = set(HOST) | QEMU_ONLY | set(ELSEWHERE)
    assert scripts == owned, (
        f"benchmarks without a smoke test: {sorted(scripts - owned)}; "
        f"smoke tests of missing scripts: {sorted(owned - scripts)}")
    assert not set(HOST) & set(ELSEWHERE) and not QEMU_ONLY & set(ELSEWHERE)
    for s in sorted(scripts):
        assert "--smoke" in (BENCH / f"{s}.py").read_text(), f"{s}.py has no --smoke option"
    for s, test in sorted(ELSEWHERE.items()):
        text = (ROOT / test).read_text() if (ROOT / test).is_file() else None
        assert text is not None, f"the smoke test of {s}.py, {test}, does not exist"
        assert f"{s}.py" in text and re.search(r"[\"']--smoke[\"']", text), \
            f"{test} does not run benchmarks/{s}.py with --smoke"


def test_a_data_module_is_not_a_script(tmp_path):
    (tmp_path / "data.py").write_text('"""cases"""\nCASES = []\n')
    (tmp_path / "run.py").write_text('import sys\n\n\nif __name__ == "__main__":\n'
                                     '    sys.exit(0)\n')
    assert not is_script(tmp_path / "data.py") and is_script(tmp_path / "run.py")


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
