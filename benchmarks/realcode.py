#!/usr/bin/env python3
"""Real code through iec2kmod: every IEC source file of the directories
given is checked on its own and, when it checks, run for N cycles in the C
engine and in the interpreter, which must record the same values.

    python3 benchmarks/realcode.py [DIR ...] [--cycles N] [--no-run]
                                   [--json OUT.json] [--smoke]

Without DIR: the vendored corpus, benchmarks/realcode/ (files whose
licence permits it, the licence beside them: see its README.md).  A DIR
may be any checkout (OpenPLC programs, other tools' test suites ...); the
files are found recursively (.st, .il, .iec), identical files counted once.

A file is

* refused: its first error, with the program's own names taken out, is its
  cause; the causes are printed with their counts, most frequent first;
* checked: no CONFIGURATION and no PROGRAM, a library (nothing to run);
* run: its configurations run as they are; a file with PROGRAMs and no
  CONFIGURATION gets one (a resource, a 10 ms task, one instance of each
  PROGRAM).  Every variable ``sim --list`` names is watched; the input
  variables (``%I`` located variables and the programs' inputs) get a
  deterministic pseudo-random trace so the bodies have something to do.
  ``same``: both engines ran and wrote the same CSV (a program stopped by
  a runtime error: the same error, after the same values); ``differ`` or
  ``failed`` (an engine failed: its last lines are printed) otherwise.

``--smoke``: 12 files spread over the corpus, 5 cycles.

Exit status 0 when no run differs or fails (refusals are reported, not
failures: the corpus holds dialect code and files that are invalid on
purpose), 1 otherwise.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import random
import re
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from iec2kmod.parse import frontend  # noqa: E402

VENDORED = Path(__file__).resolve().parent / "realcode"
# a refusal whose message names the dialect the construct belongs to
_DIALECT = re.compile(r"CODESYS|TwinCAT|ed\.3|OpenPLC|vendor|some editors")
SUFFIXES = (".st", ".il", ".iec")


def _env():
    return dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(ROOT)] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]))


def files_of(dirs) -> list[Path]:
    seen = set()
    out = []
    for d in dirs:
        d = Path(d)
        found = [d] if d.is_file() else sorted(p for p in d.rglob("*")
                                                if p.suffix.lower() in SUFFIXES and p.is_file())
        for p in found:
            h = hashlib.sha256(p.read_bytes()).hexdigest()
            if h not in seen:
                seen.add(h)
                out.append(p)
    return out


def cause(message: str) -> str:
    """The message with the program's own names, addresses and places taken
    out (a syntax error keeps its tokens: they are the cause)."""
    if not message.startswith("expected "):
        message = re.sub(r"'[^']*'", "'…'", message)
    m = re.sub(r"\([^()]*:\d+:\d+\)", "(…)", message)
    m = re.sub(r"%[IQM][XBWDL*]?[\d.]*", "%…", m)
    return re.sub(r"\[\d+\]|\b\d+ bits", "[N]", m)


def wrapper(units) -> str | None:
    """A CONFIGURATION for a file with PROGRAMs and none of its own."""
    if any(u.configurations for u in units):
        return ""
    progs = [p.name for u in units for p in u.pous if p.kind == "PROGRAM"]
    if not progs:
        return None
    lines = ["CONFIGURATION RealcodeConf", "  RESOURCE RealcodeRes ON PLC",
             "    TASK RealcodeTask (INTERVAL := T#10ms, PRIORITY := 1);"]
    for i, n in enumerate(progs):
        lines.append(f"    PROGRAM realcode{i} WITH RealcodeTask : {n};")
    lines += ["  END_RESOURCE", "END_CONFIGURATION", ""]
    return "\n".join(lines)


_LIST = re.compile(r"^(\S+)\s+(\S+)\s+(r|rw|w)\b(.*)$")
_VALUES = {"BOOL": lambda r: r.choice(["0", "1"]),
           "SINT": lambda r: str(r.randint(-100, 100)),
           "INT": lambda r: str(r.randint(-1000, 1000)),
           "DINT": lambda r: str(r.randint(-100000, 100000)),
           "USINT": lambda r: str(r.randint(0, 200)),
           "UINT": lambda r: str(r.randint(0, 2000)),
           "UDINT": lambda r: str(r.randint(0, 200000)),
           "BYTE": lambda r: str(r.randint(0, 255)),
           "WORD": lambda r: str(r.randint(0, 65535)),
           "REAL": lambda r: f"{r.uniform(-100, 100):.3f}",
           "LREAL": lambda r: f"{r.uniform(-100, 100):.3f}"}


def listing(files, tmp) -> tuple[list, str]:
    p = subprocess.run([sys.executable, "-m", "iec2kmod", "sim", "--cycles", "1", "--list"]
                       + [str(f) for f in files], capture_output=True, text=True,
                       env=_env(), timeout=600)
    if p.returncode != 0:
        return [], (p.stderr.strip().splitlines() or ["(no output)"])[-1]
    rows = []
    for line in p.stdout.splitlines():
        m = _LIST.match(line)
        if m:
            rows.append((m.group(1), m.group(2), m.group(3), m.group(4)))
    return rows, ""


def trace(rows, cycles, seed) -> str:
    """Pseudo-random values for the inputs: %I located variables and, for
    lack of them, every writable BOOL/number of a program instance."""
    r = random.Random(seed)
    ins = [(n, t) for n, t, acc, rest in rows if "%I" in rest and t in _VALUES]
    if not ins:
        ins = [(n, t) for n, t, acc, rest in rows
               if "w" in acc and t in _VALUES and "%Q" not in rest][:8]
    out = ["time,variable,value"]
    for c in range(0, cycles, 3):
        for n, t in ins:
            if r.random() < 0.4:
                out.append(f"{c * 10}ms,{n},{_VALUES[t](r)}")
    return "\n".join(out) + "\n"


def run_file(f: Path, cycles: int, tmp: Path, do_run: bool) -> dict:
    t0 = time.perf_counter()
    try:
        res = frontend.run([str(f)], use_cache=False, jobs=1)
    except frontend.InputError as e:
        return {"status": "refused", "cause": f"unreadable: {e}"}
    errs = res.diags.errors
    if errs:
        first = sorted(errs, key=lambda d: (d.line, d.col))[0]
        return {"status": "refused", "cause": cause(first.message),
                "error": first.format().splitlines()[0]}
    wrap = wrapper(res.units)
    if wrap is None:
        return {"status": "checked", "seconds": round(time.perf_counter() - t0, 2)}
    if not do_run:
        return {"status": "checked", "seconds": round(time.perf_counter() - t0, 2)}
    files = [f]
    if wrap:
        w = tmp / "realcode_conf.st"
        w.write_text(wrap)
        files.append(w)
    rows, err = listing(files, tmp)
    if err:
        return {"status": "refused", "cause": "with a configuration: " + cause(err),
                "error": err}
    watch = [n for n, t, acc, rest in rows][:400]
    tr = tmp / "inputs.csv"
    tr.write_text(trace(rows, cycles, f.name))
    outs, faults = {}, {}
    for eng in ("c", "interp"):
        out = tmp / f"{eng}.csv"
        if out.exists():
            out.unlink()
        argv = [sys.executable, "-m", "iec2kmod", "sim", "--engine", eng, "--cycles",
                str(cycles), "--inputs", str(tr), "--csv", str(out)]
        if watch:
            argv += ["--watch", ",".join(watch)]
        p = subprocess.run(argv + [str(x) for x in files], capture_output=True, text=True,
                           env=_env(), timeout=900)
        last = (p.stderr.strip().splitlines() or ["(no output)"])[-4:]
        fault = [ln for ln in last if "runtime error:" in ln]
        if p.returncode != 0 and fault:
            # a fault of the program (a stopped task): both engines must
            # report the same one, after the same values
            faults[eng] = re.sub(r"^.*?runtime error:", "runtime error:", fault[0])
        elif p.returncode != 0 or not out.exists():
            return {"status": "failed", "engine": eng, "error": "\n".join(last)}
        outs[eng] = out.read_text() if out.exists() else ""
    same = outs["c"] == outs["interp"] and faults.get("c") == faults.get("interp")
    r = {"status": "same" if same else "differ", "watched": len(watch),
         "rows": outs["c"].count("\n") - 1, "seconds": round(time.perf_counter() - t0, 2)}
    if faults:
        r["fault"] = faults.get("c") or faults.get("interp")
        if not same:
            r["error"] = f"c: {faults.get('c')}; interp: {faults.get('interp')}"
    return r


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dirs", nargs="*", help="directories or files (default: the vendored corpus)")
    ap.add_argument("--cycles", type=int, default=50)
    ap.add_argument("--no-run", action="store_true", help="check only")
    ap.add_argument("--json", help="write every file's result here")
    ap.add_argument("--smoke", action="store_true")
    ap.add_argument("-v", "--verbose", action="store_true", help="print every file's result")
    a = ap.parse_args(argv)
    dirs = a.dirs or [VENDORED]
    fs = files_of(dirs)
    if a.smoke:
        fs, a.cycles = fs[::max(1, len(fs) // 12)][:12], 5
    if not fs:
        print("realcode.py: no source file under " + ", ".join(map(str, dirs)))
        return 2
    results = {}
    with tempfile.TemporaryDirectory(prefix="realcode-") as tmp:
        for f in fs:
            r = run_file(f, a.cycles, Path(tmp), not a.no_run)
            results[str(f)] = r
            if a.verbose or r["status"] in ("differ", "failed"):
                print(f"{r['status']:8} {f}: {r.get('error', r.get('cause', ''))}")
    status = Counter(r["status"] for r in results.values())
    faulted = sum(1 for r in results.values() if r["status"] == "same" and r.get("fault"))
    causes = Counter(r["cause"] for r in results.values() if r["status"] == "refused")
    print(f"{len(fs)} files: " + ", ".join(f"{status[k]} {k}" for k in
                                          ("same", "differ", "failed", "checked", "refused"))
          + (f" ({faulted} of the same stopped by the same runtime error)" if faulted else ""))
    if causes:
        named = sum(n for c, n in causes.items() if _DIALECT.search(c))
        print(f"refusals naming another dialect: {named}; other refusals: "
              f"{sum(causes.values()) - named}")
        print("refusals by cause:")
        for c, n in causes.most_common():
            print(f"  {n:4}  {c}")
    if a.json:
        Path(a.json).write_text(json.dumps(results, indent=1))
    return 1 if status["differ"] or status["failed"] else 0


if __name__ == "__main__":
    sys.exit(main())
