#!/usr/bin/env python3
"""Our translation of PLCopen XML projects against Beremiz's own
XML-to-ST generator (issue 28).

    python3 benchmarks/plcopen_vs_beremiz.py --beremiz CHECKOUT [PATH...]
                                             [--cycles N] [--list]
    python3 benchmarks/plcopen_vs_beremiz.py --smoke [--beremiz CHECKOUT]

``--smoke``: this repository's tests/plcopen/cases and projects, 3 cycles.
Without a checkout (CI has none: Beremiz is not a package) our own
``export --st`` of each project stands in for Beremiz's generator, so the
run checks the comparison itself and the XML -> ST round trip, and says so.

CHECKOUT is a full Beremiz checkout the user fetched (GPL: nothing of it is
copied here).  Its PLCControler/PLCGenerator run headless in a subprocess
(its own fake_wx, and empty stand-ins for the GUI modules its imports
reach; the runtime library NativeLib.xml is given to the generator as the
IDE does), so no wxPython is needed.  PATH: Beremiz checkouts, directories
of ``plc.xml`` projects (OpenPLC Editor projects: the OpenPLC Editor is a
Beremiz fork and writes the same XML) or single files; default: CHECKOUT's
``exemples`` and ``tests/projects``.

For every project that checks clean here and has a periodic task, Beremiz's
ST is checked and both run N cycles in the interpreter (same inputs: none,
every variable at its initial value); every variable the two programs have
in common (our hidden temporaries left out) is compared after every cycle.
Printed per project: ``agree``, ``differ`` (first cycle, variable and both
values), or why it was not compared (ours refused, Beremiz's generator
failed, Beremiz's ST refused here); then the counts.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT.parent))

import plcopen_corpus as corpus  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("paths", nargs="*", type=Path)
    ap.add_argument("--beremiz", type=Path,
                    help="a full Beremiz checkout (holds PLCGenerator.py)")
    ap.add_argument("--cycles", type=int, default=20)
    ap.add_argument("--list", action="store_true", help="print our first error when refused")
    ap.add_argument("--smoke", action="store_true",
                    help="tests/plcopen's cases and projects, 3 cycles; without --beremiz our "
                         "own export --st stands in for Beremiz's generator")
    args = ap.parse_args(argv)
    if args.smoke:
        args.cycles = 3
        here = ROOT.parent / "tests" / "plcopen"
        args.paths = args.paths or sorted((here / "cases").glob("*.xml")) + [here / "projects"]
    if args.beremiz is None and not args.smoke:
        ap.error("--beremiz CHECKOUT is required (or --smoke)")
    if args.beremiz is None:
        bz = corpus.exported_st
        print("smoke: no Beremiz checkout; our export --st stands in for Beremiz's generator")
    else:
        bz = args.beremiz.resolve()
        if not (bz / "PLCGenerator.py").is_file() or not (bz / "fake_wx.py").is_file():
            ap.error(f"{bz}: not a Beremiz checkout (no PLCGenerator.py / fake_wx.py)")
    from iec2kmod.parse import frontend
    counts = Counter()
    for root in args.paths or [bz]:
        for proj in corpus.projects(root):
            t0 = time.perf_counter()
            rel = corpus.shown(root, proj)
            res = frontend.run([str(proj)], use_cache=False)
            if res.diags.errors:
                verdict = "ours refused: " + corpus.cause(res.diags.errors[0].message)
                detail = res.diags.errors[0].format().split("\n")[0]
            elif not any(t.interval_ns for c in res.project.configurations
                         for r in c.resources for t in r.tasks.values()):
                verdict, detail = "not compared: no periodic task", ""
            else:
                with tempfile.TemporaryDirectory() as tmp:
                    v = corpus.compare_generator(bz, proj, args.cycles, Path(tmp))
                verdict = "agree" + v[4:] if v.startswith("same") else v
                detail = ""
            kind = verdict.split(":")[0].split(" (")[0]
            counts[kind] += 1
            print(f"{str(rel):60} {verdict} ({time.perf_counter() - t0:.1f} s)")
            if args.list and detail:
                print(f"    {detail}")
    print("\n" + ", ".join(f"{n} {k}" for k, n in sorted(counts.items(), key=lambda kv: -kv[1])))
    if args.smoke and args.beremiz is None:
        # the stand-in is our own ST: anything but agreement is a defect, and
        # the comparison must see a planted difference (Idle := NOT Motor
        # made Idle := Motor in ld_rungs.xml's ST)
        def planted(proj, out):
            st, why = corpus.exported_st(proj, out)
            text = st.read_text(encoding="utf-8") if st else ""
            if "Idle := NOT (Motor);" not in text:
                return None, "the planted statement is not in the exported ST"
            st.write_text(text.replace("Idle := NOT (Motor);", "Idle := (Motor);"))
            return st, ""
        case = ROOT.parent / "tests" / "plcopen" / "cases" / "ld_rungs.xml"
        with tempfile.TemporaryDirectory() as tmp:
            v = corpus.compare_generator(planted, case, args.cycles, Path(tmp))
        print(f"planted difference in ld_rungs.xml: {v}")
        return 1 if set(counts) - {"agree"} or not v.startswith("differ") else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
