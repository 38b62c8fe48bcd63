"""The Annex F tally (issue 10): how many of the standard's Annex F examples
(tests/conformance/annexf, transcribed from IEC 61131-3 ed.2) the front end
accepts, each checked with the examples it depends on given in the same
call, as a new user would.  Prints one line per file and the total.

    python3 benchmarks/annexf_tally.py                    # this checkout
    python3 benchmarks/annexf_tally.py --root OLD_CHECKOUT  # e.g. git archive of a commit
    python3 benchmarks/annexf_tally.py --smoke            # three files (CI)
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]
ANNEXF = HERE / "tests" / "conformance" / "annexf"

# file -> the files it needs (function blocks it instantiates)
DEPENDS = {
    "f3_fwd_rev_mon.st": ["f2_cmd_monitor.st"],
    "f6_03_average.st": ["f6_02_delay.st"],
    "f6_07_limits_alarm.st": ["f6_06_hysteresis.st"],
    "f6_08_analog_monitor.st": ["f6_07_limits_alarm.st", "f6_06_hysteresis.st"],
    "f6_09_pid.st": ["f6_04_integral.st", "f6_05_derivative.st"],
}


def files() -> list[Path]:
    return sorted(p for p in ANNEXF.iterdir() if p.suffix in (".st", ".il"))


def check(path: Path, root: Path) -> tuple[bool, str]:
    """(accepted, first error line) of one example with its dependencies,
    checked by the iec2kmod of checkout *root*."""
    args = [str(path)] + [str(ANNEXF / d) for d in DEPENDS.get(path.name, [])]
    env = dict(os.environ, PYTHONPATH=str(root))
    p = subprocess.run([sys.executable, "-m", "iec2kmod.cli", "check", *args], cwd=root,
                       env=env, capture_output=True, text=True, timeout=300)
    first = next((ln for ln in p.stderr.splitlines() if ": error: " in ln), "")
    if p.returncode not in (0, 1):
        first = first or (p.stderr.strip().splitlines() or ["?"])[-1]
    return p.returncode == 0, first


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--root", type=Path, default=HERE,
                    help="the checkout whose iec2kmod checks the files (default: this one)")
    ap.add_argument("--smoke", action="store_true",
                    help="a few seconds' run at a small size (CI: tests/benchmarks): three "
                         "files")
    a = ap.parse_args()
    root = a.root.resolve()
    ok = 0
    all_files = files()[:3] if a.smoke else files()
    for f in all_files:
        accepted, why = check(f, root)
        ok += accepted
        print(f"{'accepted' if accepted else 'REFUSED '}  {f.name:28} "
              f"{'' if accepted else why.split(': error: ', 1)[-1]}")
    print(f"Annex F: {ok} of {len(all_files)} files accepted")
    return 0


if __name__ == "__main__":
    sys.exit(main())
