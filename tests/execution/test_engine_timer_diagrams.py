"""The standard's timer diagrams (tests/reference/timer_diagrams.py) run
as a whole IEC program through `iec2kmod sim`, once per simulation engine:
one TON/TOF/TP instance per table in one periodic task (T#10ms), IN and PT
driven by an input trace, Q and ET read from the CSV output at every row of
every table.  The C timers alone are checked in
tests/runtime/test_rt_timer_diagrams.py."""

from __future__ import annotations

import csv
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests"))

from reference import timer_diagrams as td  # noqa: E402

pytestmark = pytest.mark.execution
MS = 1_000_000

# engine name -> extra arguments of `iec2kmod sim`; a new engine is one line
ENGINES = {
    "c": [],
    "vm": ["--engine", "interp"],
}


def project_text():
    names = sorted(td.TABLES)
    decl = "\n".join(f"    in_{n} : BOOL;\n    pt_{n} : TIME;\n    fb_{n} : {td.TABLES[n][0]};"
                     for n in names)
    calls = "\n".join(f"  fb_{n}(IN := in_{n}, PT := pt_{n});" for n in names)
    return (f"PROGRAM timer_diagrams\n  VAR\n{decl}\n  END_VAR\n{calls}\nEND_PROGRAM\n\n"
            "CONFIGURATION timer_diagrams_cfg\n"
            "  TASK t (INTERVAL := T#10ms, PRIORITY := 1);\n"
            "  PROGRAM p WITH t : timer_diagrams;\n"
            "END_CONFIGURATION\n")


def trace_rows():
    rows = []
    for n, (_, table) in sorted(td.TABLES.items()):
        prev = None
        for r in table:
            if prev is None or r.IN != prev.IN:
                rows.append((r.t * MS, f"p.in_{n}", "TRUE" if r.IN else "FALSE"))
            if prev is None or r.PT != prev.PT:
                rows.append((r.t * MS, f"p.pt_{n}", str(r.PT * MS)))
            prev = r
    return rows


def read_csv(path):
    with open(path, newline="") as fh:
        rd = csv.reader(fh)
        header = next(rd)
        return header[1:], [(int(r[0]), r[1:]) for r in rd]


def value_at(rows, col, t_ns):
    cur = None
    for t, vals in rows:
        if t > t_ns:
            break
        cur = vals[col]
    return cur


@pytest.mark.parametrize("engine", sorted(ENGINES))
def test_engine_follows_the_diagrams(engine, tmp_path):
    src = tmp_path / "timer_diagrams.st"
    src.write_text(project_text())
    trace = tmp_path / "trace.csv"
    trace.write_text("time,variable,value\n" +
                     "".join(f"{t}ns,{p},{v}\n" for t, p, v in trace_rows()))
    out = tmp_path / "out.csv"
    end = max(rows[-1].t for _, rows in td.TABLES.values()) * MS
    watch = ",".join(f"p.fb_{n}.Q,p.fb_{n}.ET" for n in sorted(td.TABLES))
    p = subprocess.run([sys.executable, "-m", "iec2kmod.cli", "sim", str(src),
                        "--duration", f"{end}ns", "--inputs", str(trace), "--csv", str(out),
                        "--watch", watch, *ENGINES[engine]],
                       cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stdout + p.stderr
    header, rows = read_csv(out)
    col = {h.upper(): i for i, h in enumerate(header)}
    bad, checked = [], 0
    for n, (_, table) in sorted(td.TABLES.items()):
        for r in table:
            q = value_at(rows, col[f"P.FB_{n}.Q".upper()], r.t * MS)
            et = value_at(rows, col[f"P.FB_{n}.ET".upper()], r.t * MS)
            checked += 1
            if (q, et) != ("TRUE" if r.Q else "FALSE", str(r.ET * MS)):
                bad.append(f"{n} t={r.t} ms: {engine} gives Q={q} ET={et} ns, "
                           f"expected Q={r.Q} ET={r.ET} ms ({r.why})")
    assert checked == sum(len(rows) for _, rows in td.TABLES.values()) > 100
    assert not bad, "\n".join(bad)
