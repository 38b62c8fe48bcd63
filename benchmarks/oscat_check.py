#!/usr/bin/env python3
"""OSCAT BASIC (its OpenPLC translation, github.com/wonka929/OSCAT_OpenPLC)
checked as one project; prints the refusals counted by cause.

Fetches nothing: give it a copy of the repository (or of its
``OSCAT BASIC 3.33/*/build/plc.st`` files).  The library's files are not
kept in this repository (its licence is not stated with it).

    python3 benchmarks/oscat_check.py PATH [--keep DIR] [--strict]

Each module's plc.st is OpenPLC Editor's whole project: the module's POUs,
copies of the POUs it uses from other modules, Beremiz's runtime blocks
(LOGGER, python_eval, ...) and a CONFIGURATION.  They are merged: every
TYPE and POU once (the first text; a later different text of the same name
is counted), no CONFIGURATION.  The merged project is written to --keep (or
a temporary directory) and checked like `iec2kmod check`."""

from __future__ import annotations

import argparse
import collections
import re
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from iec2kmod import frontend  # noqa: E402

_BLOCK = re.compile(r"^(TYPE|FUNCTION_BLOCK|FUNCTION|PROGRAM|CONFIGURATION)\b(.*)$", re.M)
_END = {"TYPE": "END_TYPE", "FUNCTION_BLOCK": "END_FUNCTION_BLOCK", "FUNCTION": "END_FUNCTION",
        "PROGRAM": "END_PROGRAM", "CONFIGURATION": "END_CONFIGURATION"}


def blocks(text: str):
    """(kind, name, text) of the top-level declarations of a plc.st."""
    pos = 0
    while True:
        m = _BLOCK.search(text, pos)
        if m is None:
            return
        kind = m.group(1)
        end = re.compile(rf"^\s*{_END[kind]}\b.*$", re.M).search(text, m.end())
        if end is None:
            return
        body = text[m.start():end.end()]
        name = (m.group(2).split() or ["?"])[0].rstrip(":") if kind != "TYPE" else None
        if kind == "TYPE":
            for t in re.findall(r"^\s*(\w+)\s*:", body[4:], re.M):
                name = name or t
        yield kind, (name or "?").upper(), body
        pos = end.end()


def merge(files):
    seen, order, differ = {}, [], collections.Counter()
    for f in files:
        for kind, name, body in blocks(f.read_text(errors="replace")):
            if kind == "CONFIGURATION":
                continue
            key = (kind, name)
            if key in seen:
                if re.sub(r"\s+", " ", seen[key]) != re.sub(r"\s+", " ", body):
                    differ[f"{kind} {name}"] += 1
                continue
            seen[key] = body
            order.append(key)
    return "\n\n".join(seen[k] for k in order) + "\n", len(order), differ


def cause(message: str) -> str:
    """A refusal's cause: the message without its names and numbers."""
    m = re.sub(r"'[^']*'", "'_'", message)
    m = re.sub(r"\b\d+\b", "N", m)
    return m[:140]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("path", help="a copy of wonka929/OSCAT_OpenPLC (or of its plc.st files)")
    ap.add_argument("--keep", metavar="DIR", help="write the merged project here")
    ap.add_argument("--strict", action="store_true", help="check with --strict")
    a = ap.parse_args(argv)
    root = Path(a.path)
    files = sorted(p for p in root.rglob("plc.st") if "OSCAT BASIC" in str(p)) or \
        sorted(root.rglob("*.st"))
    if not files:
        print(f"no plc.st under {root}", file=sys.stderr)
        return 2
    text, n, differ = merge(files)
    out = Path(a.keep) if a.keep else Path(tempfile.mkdtemp(prefix="oscat_"))
    out.mkdir(parents=True, exist_ok=True)
    (out / "oscat_basic.st").write_text(text)
    res = frontend.run([str(out / "oscat_basic.st")], use_cache=False, strict=a.strict)
    errors = [d for d in res.diags.items if d.severity == "error"]
    warnings = [d for d in res.diags.items if d.severity == "warning"]
    print(f"{len(files)} files, {n} declarations merged ({sum(differ.values())} later copies "
          f"differ from the first); {len(text.splitlines())} lines -> {out / 'oscat_basic.st'}")
    print(f"{len(errors)} errors, {len(warnings)} warnings")
    for title, items in (("errors", errors), ("warnings", warnings)):
        tally = collections.Counter(cause(d.message) for d in items)
        if tally:
            print(f"{title} by cause:")
            for c, k in tally.most_common():
                print(f"  {k:5}  {c}")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
