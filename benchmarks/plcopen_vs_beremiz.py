#!/usr/bin/env python3
"""Our translation of PLCopen XML projects against Beremiz's own
XML-to-ST generator (issue 28).

    python3 benchmarks/plcopen_vs_beremiz.py --beremiz CHECKOUT [PATH...]
                                             [--cycles N] [--list]

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
    ap.add_argument("--beremiz", type=Path, required=True,
                    help="a full Beremiz checkout (holds PLCGenerator.py)")
    ap.add_argument("--cycles", type=int, default=20)
    ap.add_argument("--list", action="store_true", help="print our first error when refused")
    args = ap.parse_args(argv)
    bz = args.beremiz.resolve()
    if not (bz / "PLCGenerator.py").is_file() or not (bz / "fake_wx.py").is_file():
        ap.error(f"{bz}: not a Beremiz checkout (no PLCGenerator.py / fake_wx.py)")
    from iec2kmod.parse import frontend
    counts = Counter()
    for root in args.paths or [bz]:
        for proj in corpus.projects(root):
            t0 = time.perf_counter()
            rel = proj.relative_to(root) if proj.is_relative_to(root) else proj
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
    return 0


if __name__ == "__main__":
    sys.exit(main())
