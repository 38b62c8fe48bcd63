#!/usr/bin/env python3
"""OSCAT BASIC functions against the outputs OSCAT's own documentation gives
(the examples of the OSCAT BASIC manual, as in github.com/
franz-hoepfinger-oscat/oscat-basic-docs, docs/en/...), run in the C
simulator and the reference interpreter.

Fetches nothing and keeps no OSCAT code: give it a copy of the OpenPLC
translation (github.com/wonka929/OSCAT_OpenPLC, or its plc.st files).

    python3 benchmarks/oscat_expected.py PATH [--engines c,vm] [--keep DIR]

The functions under test and every declaration they use are taken from the
merged library (benchmarks/oscat_check.py), with a PROGRAM that calls each
example once; after one cycle every result is compared with the manual's.
The translation keeps OSCAT's CODESYS representation of dates: DATE and DT
as UDINT seconds since 1970-01-01, TOD as UDINT milliseconds (the manual's
dates are converted to it here, not taken from our output).  MINUTE_OF_DT,
SINH and SQRTN are left out: the translation declares their parameters in
VAR, so no call can pass them (benchmarks/oscat_check.py reports it)."""

from __future__ import annotations

import argparse
import datetime as _dt
import math
import re
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from oscat_check import blocks, merge  # noqa: E402

from iec2kmod import frontend  # noqa: E402


def d(y, m, day, h=0, mi=0, s=0) -> str:
    """A date (time) as the translation holds it: UDINT seconds since 1970."""
    t = _dt.datetime(y, m, day, h, mi, s, tzinfo=_dt.timezone.utc)
    return str(int(t.timestamp()))


def tod(h, m, s=0.0) -> str:
    return str(int(round((h * 3600 + m * 60 + s) * 1000)))


PI = "3.14159265"
# (result type, call, expected value as the simulator prints it, page of the manual)
CASES = [
    ("WORD", "SWAP_BYTE(16#33DF)", str(0xDF33), "Logic/swap_byte"),
    ("DWORD", "SWAP_BYTE2(16#33DF1122)", str(0x2211DF33), "Logic/swap_byte2"),
    ("BYTE", "REVERSE(2#10011110)", str(0b01111001), "Logic/reverse"),
    ("WORD", "BIT_TOGGLE_W(2#0000_1111, 2)", str(0b1011), "Logic/bit_toggle_w"),
    ("DWORD", "BIT_TOGGLE_DW(2#0000_1111, 7)", str(0b10001111), "Logic/bit_toggle_dw"),
    ("BYTE", "BIT_LOAD_B2(2#1111_0000, TRUE, 1, 2)", str(0b11110110), "Logic/bit_load_b2"),
    ("BYTE", "BIT_LOAD_B2(2#1111_1111, FALSE, 7, 2)", str(0b01111110), "Logic/bit_load_b2"),
    ("INT", "CEIL(3.14)", "4", "Mathematical/ceil"),
    ("INT", "CEIL(-3.14)", "-3", "Mathematical/ceil"),
    ("INT", "FLOOR(3.14)", "3", "Mathematical/floor"),
    ("INT", "FLOOR(-3.14)", "-4", "Mathematical/floor"),
    ("DINT", "FLOOR2(-3.14)", "-4", "Mathematical/floor2"),
    ("DINT", "CEIL2(-3.14)", "-3", "Mathematical/ceil2"),
    ("REAL", "MAX3(1.0, 3.0, 2.0)", "3.0", "Mathematical/max3"),
    ("REAL", "MIN3(1.0, 3.0, 2.0)", "1.0", "Mathematical/min3"),
    ("REAL", "MID3(1.0, 5.0, 2.0)", "2.0", "Mathematical/mid3"),
    ("REAL", "RND(355.55, 2)", "360.0", "Mathematical/rnd"),
    ("REAL", "RND(3.555, 2)", "3.6", "Mathematical/rnd"),
    ("REAL", "ROUND(3.555, 2)", "3.56", "Mathematical/round"),
    ("BOOL", "CMP(3.140, 3.149, 3)", "TRUE", "Mathematical/cmp"),
    ("BOOL", "CMP(3.140, 3.149, 4)", "FALSE", "Mathematical/cmp"),
    ("DINT", "FIB(5)", "5", "Mathematical/fib"),
    ("DINT", "FIB(4)", "3", "Mathematical/fib"),
    ("REAL", "EXPN(1.5, 2)", "2.25", "Mathematical/expn"),
    ("REAL", "EXPN(10.0, -2)", "0.01", "Mathematical/expn"),
    ("REAL", "EXP10(0.0)", "1.0", "Mathematical/exp10"),
    ("DINT", "D_TRUNC(-1.6)", "-1", "Mathematical/d_trunc"),
    ("REAL", f"DEG({PI})", "180.0", "Mathematical/deg"),
    ("REAL", "RAD(180.0)", PI, "Mathematical/rad"),
    ("REAL", "SINC(0.0)", "1.0", "Mathematical/sinc"),
    ("REAL", "TANC(0.0)", "1.0", "Mathematical/tanc"),
    ("REAL", "OVERRIDE(10.0, -12.0, 11.0, TRUE, TRUE, TRUE)", "-12.0", "Mathematical/override"),
    ("REAL", "OVERRIDE(10.0, -12.0, 11.0, TRUE, FALSE, TRUE)", "11.0", "Mathematical/override"),
    ("INT", f"DAY_OF_WEEK({d(2007, 1, 8)})", "1", "Time&Date/day_of_week"),
    ("INT", f"DAY_OF_YEAR({d(2007, 12, 31)})", "365", "Time&Date/day_of_year"),
    ("INT", f"DAY_OF_YEAR({d(2008, 12, 31)})", "366", "Time&Date/day_of_year"),
    ("DINT", f"DAYS_DELTA({d(2007, 1, 10)}, {d(2007, 1, 1)})", "-9", "Time&Date/days_delta"),
    ("BOOL", f"LEAP_DAY({d(2004, 2, 29)})", "TRUE", "Time&Date/leap_day"),
    ("UDINT", f"MONTH_BEGIN({d(2008, 2, 13)})", d(2008, 2, 1), "Time&Date/month_begin"),
    ("UDINT", f"MONTH_END({d(2008, 2, 13)})", d(2008, 2, 29), "Time&Date/month_end"),
    ("INT", f"MONTH_OF_DATE({d(2007, 12, 31)})", "12", "Time&Date/month_of_date"),
    ("INT", f"YEAR_OF_DATE({d(2007, 12, 31)})", "2007", "Time&Date/year_of_date"),
    ("INT", f"HOUR({tod(22, 55, 13)})", "22", "Time&Date/hour"),
    ("UDINT", "SET_DATE(2007, 1, 22)", d(2007, 1, 22), "Time&Date/set_date"),
    ("UDINT", "SET_DATE(2007, 1, 365)", d(2007, 12, 31), "Time&Date/set_date"),
    ("UDINT", "SET_DT(2007, 1, 22, 13, 10, 22)", d(2007, 1, 22, 13, 10, 22),
     "Time&Date/set_dt"),
    ("UDINT", "SET_TOD(13, 10, 22.33)", tod(13, 10, 22.33), "Time&Date/set_tod"),
    ("TIME", "SECOND_TO_TIME(63.123)", "T#1m3s123ms", "Time&Date/second_to_time"),
    ("TIME", "MINUTE_TO_TIME(122.5)", "T#2h2m30s", "Time&Date/minute_to_time"),
    ("TIME", "HOUR_TO_TIME(1.1)", "T#1h6m", "Time&Date/hour_to_time"),
    ("TIME", "DAY_TO_TIME(1.1)", "T#1d2h24m", "Time&Date/day_to_time"),
    ("UDINT", "HOUR_TO_TOD(12.1)", tod(12, 6), "Time&Date/hour_to_tod"),
    ("INT", f"HOUR_OF_DT({d(2008, 6, 6, 10, 22, 20)})", "10", "Time&Date/hour_of_dt"),
    ("INT", f"SECOND_OF_DT({d(2008, 6, 6, 10, 22, 20)})", "20", "Time&Date/second_of_dt"),
]


def closure(decls: dict, roots) -> list:
    """The declarations roots use, transitively (by name), in library order."""
    words = {k: set(re.findall(r"[A-Za-z_][A-Za-z0-9_]*", body.upper()))
             for k, body in decls.items()}
    need, todo = set(), [r.upper() for r in roots]
    while todo:
        k = todo.pop()
        if k in need or k not in decls:
            continue
        need.add(k)
        todo += [w for w in words[k] if w in decls and w not in need]
    return [k for k in decls if k in need]


def project_text(path: Path) -> str:
    files = sorted(p for p in path.rglob("plc.st") if "OSCAT BASIC" in str(p)) or \
        sorted(path.rglob("*.st"))
    text, _, _ = merge(files)
    decls = {name: body for _kind, name, body in blocks(text)}
    roots = {re.match(r"\w+", call).group(0) for _t, call, _v, _p in CASES}
    body = "\n\n".join(decls[k] for k in closure(decls, roots))
    lines = ["PROGRAM oscat_examples", "VAR"]
    lines += [f"    r{i} : {t};" for i, (t, _c, _v, _p) in enumerate(CASES)]
    lines += ["END_VAR"]
    lines += [f"    r{i} := {call};" for i, (_t, call, _v, _p) in enumerate(CASES)]
    lines += ["END_PROGRAM", "CONFIGURATION oscat_cfg",
              "    TASK t (INTERVAL := T#10ms, PRIORITY := 1);",
              "    PROGRAM main WITH t : oscat_examples;", "END_CONFIGURATION"]
    return body + "\n\n" + "\n".join(lines) + "\n"


def _same(want: str, got: str, t: str) -> bool:
    if t == "REAL":
        try:
            w, g = float(want), float(got)
        except ValueError:
            return False
        return math.isclose(w, g, rel_tol=1e-5, abs_tol=1e-6)
    return want == got


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("path")
    ap.add_argument("--engines", default="c,vm")
    ap.add_argument("--keep", metavar="DIR")
    a = ap.parse_args(argv)
    out = Path(a.keep) if a.keep else Path(tempfile.mkdtemp(prefix="oscat_ex_"))
    out.mkdir(parents=True, exist_ok=True)
    f = out / "oscat_examples.st"
    f.write_text(project_text(Path(a.path)))
    res = frontend.run([str(f)], use_cache=False)
    if not res.ok:
        for dg in res.diags.errors[:10]:
            print(dg.format())
        return 1
    from iec2kmod import interp, sim
    names = [f"main.r{i}" for i in range(len(CASES))]
    failed = 0
    for engine in a.engines.split(","):
        if engine == "vm":
            r = interp.run(res.project, 0, watch=names)
        else:
            r = sim.run(res.project, 0, watch=names)
        final = r.values_at()
        bad = []
        for i, (t, call, want, page) in enumerate(CASES):
            got = sim.format_value(None, final.get(names[i], ""))
            if t == "TIME":
                got = _time_text(final.get(names[i], 0))
            if not _same(want, got, t):
                bad.append(f"  {call} = {got}, the manual ({page}) says {want}")
        print(f"{engine}: {len(CASES) - len(bad)} of {len(CASES)} examples as the manual "
              f"says ({len({c.split('(')[0] for _t, c, _v, _p in CASES})} functions)")
        print("\n".join(bad)) if bad else None
        failed += len(bad)
    return 1 if failed else 0


def _time_text(ns) -> str:
    ns = int(ns)
    parts = []
    for unit, size in (("d", 86400 * 10**9), ("h", 3600 * 10**9), ("m", 60 * 10**9),
                       ("s", 10**9), ("ms", 10**6)):
        q, ns = divmod(ns, size)
        if q:
            parts.append(f"{q}{unit}")
    return "T#" + ("".join(parts) or "0s")


if __name__ == "__main__":
    sys.exit(main())
