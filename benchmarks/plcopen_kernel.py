#!/usr/bin/env python3
"""The IEC-only PLCopen projects of a Beremiz checkout (or of any directory
of plc.xml projects) in the PREEMPT_RT guest kernel (issue 28), each against
the simulation.

    python3 benchmarks/plcopen_kernel.py PATH [PATH...] [--ms 500]
    python3 benchmarks/plcopen_kernel.py --smoke     # one of tests/plcopen/cases, 100 ms

PATH as for benchmarks/plcopen_corpus.py: a checkout the user fetched (its
``exemples/*/plc.xml`` and ``tests/projects/*/plc.xml``); nothing is copied
into this repository (Beremiz is GPL).  A project is taken when it is IEC
only (no ``NAME@KIND`` extension directory) and checks clean.  One guest is
booted; each project is generated and built (``iec2kmod gen`` + ``build``),
its modules inserted, run for MS ms (``run all MS``: every periodic task
stops by itself before its first release MS ms after the common start, so
it runs a known number of cycles however slow the guest is), stopped, and
every task's cycle count and fault and every variable are compared with
``iec2kmod sim`` of the same sources up to the same instant (the run and
the comparison of tests/qemu/test_exec_kernel.py; no inputs either side).
The programs' clock is the release time in both, so timers agree to the
nanosecond.  RTC's clock is the wall clock in the kernel and the simulated
time from DT#1970-01-01 in the simulation: in a project holding an RTC the
DT, DATE and TOD variables are not compared (counted as "wall clock");
durations computed from two readings of the clock are compared.

Printed: one line per project (same / N differences / failed: why), the
first differences, the totals; the kernel log must stay clean.  Exit 1
when a project differs or fails.  The CI test on this repository's own
cases is tests/qemu/test_plcopen_kernel.py.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))
sys.path.insert(0, str(ROOT / "tests" / "qemu"))

WALL_TYPES = {"DT", "DATE", "TOD", "LDT", "LDATE", "LTOD", "DATE_AND_TIME", "TIME_OF_DAY"}


def candidates(paths):
    from plcopen_corpus import extensions, projects, shown
    from iec2kmod.parse import frontend
    out = []
    for root in paths:
        for proj in projects(root):
            rel = shown(root, proj)
            if extensions(proj):
                continue
            res = frontend.run([str(proj)], use_cache=False)
            if res.diags.errors:
                print(f"{str(rel):50} refused: {res.diags.errors[0].message}")
                continue
            if not res.project.configurations:
                print(f"{str(rel):50} no configuration")
                continue
            out.append((rel, proj, res.project))
    return out


def wall_paths(project) -> set[str]:
    from iec2kmod.checks.types import concrete
    from iec2kmod.compilation import Compilation
    from iec2kmod.verify.clockfb import clock_user
    if clock_user(project) is None:
        return set()
    return {e.path.upper() for e in Compilation(project).plan.table
            if getattr(concrete(e.type), "name", "").upper() in WALL_TYPES}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("paths", nargs="*", type=Path)
    ap.add_argument("--ms", type=int, default=500, help="length of each run (default 500)")
    ap.add_argument("--smoke", action="store_true",
                    help="without PATH: the LD case of tests/plcopen/cases, 100 ms")
    args = ap.parse_args(argv)
    if args.smoke and not args.paths:
        args.paths, args.ms = [ROOT / "tests" / "plcopen" / "cases" / "ld_rungs.xml"], 100
    if not args.paths:
        ap.error("give the PATH of a checkout or of plc.xml projects (or --smoke)")
    for p in args.paths:
        xsd = p / "plcopen" / "tc6_xml_v201.xsd"
        if xsd.is_file() and "IEC2KMOD_TC6_XSD" not in os.environ:
            os.environ["IEC2KMOD_TC6_XSD"] = str(xsd)
    todo = candidates(args.paths)
    if not todo:
        print("no IEC-only project checks clean")
        return 1
    from iec2kmod.testing.vm import Guest
    from test_plcopen_kernel import run_and_compare
    work = Path(tempfile.mkdtemp(prefix="plcopen-kernel-", dir=os.environ.get("TMPDIR")))
    g = Guest(str(work), console_log=str(work / "console.log"))
    bad = 0
    t0 = time.monotonic()
    try:
        g.start()
        g.start_pyserver()
        print(f"guest ready in {time.monotonic() - t0:.0f} s", flush=True)
        for rel, proj, project in todo:
            t1 = time.monotonic()
            wall = wall_paths(project)
            # kbuild takes no blank in a module directory (M=): OpenPLC
            # Editor v4 builds under "build/OpenPLC Runtime v4/src"
            name = re.sub(r"[^A-Za-z0-9_-]", "_", str(rel))
            try:
                problems, values = run_and_compare(g, proj, work / name, args.ms, wall)
            except (Exception, AssertionError) as exc:  # noqa: BLE001 - reported per project
                bad += 1
                print(f"{str(rel):50} failed: {str(exc).strip()[:400]}", flush=True)
                continue
            except BaseException as exc:  # pytest.fail's Failed, from the shared run
                if isinstance(exc, KeyboardInterrupt):
                    raise
                bad += 1
                print(f"{str(rel):50} failed: {str(exc).strip()[:400]}", flush=True)
                continue
            note = f", {len(wall)} wall-clock values not compared" if wall else ""
            secs = time.monotonic() - t1
            if problems:
                bad += 1
                print(f"{str(rel):50} {len(problems)} differences ({secs:.0f} s)", flush=True)
                for p in problems[:10]:
                    print(f"    {p}")
            else:
                print(f"{str(rel):50} same: {len(values)} variables after {args.ms} ms"
                      f"{note} ({secs:.0f} s)", flush=True)
        g.check_kernel_log()
        print("kernel log clean")
    finally:
        g.close()
    print(f"\n{len(todo) - bad} of {len(todo)} IEC-only projects ran in the kernel as "
          f"simulated ({time.monotonic() - t0:.0f} s)")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
