# SPDX-License-Identifier: MIT
"""The netlink fuzzer (tests/qemu/netlink_fuzz.py) with any number of
messages, in a guest of its own: the same project, oracle and checks as
tests/qemu/test_netlink_fuzz.py (CI: 20,000 messages, seed 2323).

    python3 benchmarks/netlink_fuzz.py [--messages 200000] [--seed S] [--rounds R] [--smoke]

Each round sends --messages messages from seed S + round number, then
checks: no message the kernel must refuse was acknowledged, every task
runs and has not faulted, cycles advance, every variable holds a value of
its type, CONSTANTs unchanged, the kernel log is clean.  At the end
`plc-manager stop` must leave no module.  Exit status 1 on any problem.
"""

from __future__ import annotations

import argparse
import compileall
import random
import shutil
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "qemu"))

import netlink_fuzz as nf  # noqa: E402
from kmod_helpers import gen_and_build  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--messages", type=int, default=100_000, help="per round")
    ap.add_argument("--seed", type=int, default=None, help="default: random (printed)")
    ap.add_argument("--rounds", type=int, default=1)
    ap.add_argument("--icount", action="store_true", help="icount guest (one vCPU)")
    ap.add_argument("--workdir", help="keep the build here (default: a temporary directory)")
    ap.add_argument("--smoke", action="store_true",
                    help="a few seconds' run at a small size (CI: tests/qemu): 500 messages, seed 1")
    a = ap.parse_args()
    if a.smoke:
        a.messages, a.rounds = 500, 1
        a.seed = 1 if a.seed is None else a.seed
    seed = a.seed if a.seed is not None else random.SystemRandom().randrange(1 << 31)
    from iec2kmod.testing.vm import Guest
    work = Path(a.workdir or tempfile.mkdtemp(prefix="iec2kmod-nlfuzz-")).resolve()
    work.mkdir(parents=True, exist_ok=True)
    tree = work / "tree"
    manifest = gen_and_build(ROOT / "tests" / "qemu" / "projects" / "nl_fuzz", tree)
    compileall.compile_dir(str(ROOT / "manager"), quiet=1)
    print(f"seed {seed}, {a.rounds} round(s) of {a.messages} messages", flush=True)
    g = Guest(str(work), icount=a.icount, console_log=str(work / "console.log"))
    failed = False
    try:
        g.start()
        r = g.pyrun(script="plc-manager", argv=["load", str(tree)], timeout=600)
        if r.exit_code:
            print(f"plc-manager load failed:\n{r.output}")
            return 1
        for k in range(a.rounds):
            t0 = time.monotonic()
            res, before = nf.run(g, work, manifest, seed + k, a.messages,
                                 timeout=max(1800, a.messages / 20))
            print(res.summary())
            problems = [f"message {i} acknowledged, must be refused: {why}"
                        for i, why in res.violations[:40]]
            if res.unanswered:
                problems.append(f"{res.unanswered} messages got no answer")
            problems += nf.check_after(g, manifest, before)
            try:
                g.check_kernel_log()
            except Exception as e:        # KernelLogError: report it with the rest
                problems.append(str(e))
            print(f"round {k + 1} (seed {seed + k}): {time.monotonic() - t0:.0f} s, "
                  f"{len(problems)} problems", flush=True)
            for p in problems:
                print("  " + p)
            if res.file and res.file.exists():
                print(f"  messages kept in {res.file} (netlink_fuzz.describe(file, index))")
            failed |= bool(problems)
        r = g.pyrun(script="plc-manager", argv=["stop"], timeout=600)
        left = [ln.split()[0] for ln in g.run("cat /proc/modules").output.splitlines()
                if ln.startswith("iec_")]
        print(f"plc-manager stop: exit {r.exit_code}; modules left: {left or 'none'}")
        failed |= bool(r.exit_code or left)
    finally:
        g.close()
    if not a.workdir and not failed:
        shutil.rmtree(work, ignore_errors=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
