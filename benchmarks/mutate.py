#!/usr/bin/env python3
"""Mutation benchmark (issue 29): small plausible bugs put into the code one
at a time -- a comparison flipped, an ``and`` swapped for ``or``, a ``not``
dropped, a constant off by one, a mask dropped, a check loosened -- each run
against the tests of the tier that owns the area; a mutant the tests do not
notice *survived*.

    python3 benchmarks/mutate.py                    # 60 mutants, seed 1
    python3 benchmarks/mutate.py --count 80 --seed 3 --areas checks,verify
    python3 benchmarks/mutate.py --smoke            # 3 mutants (the fast tier runs this)
    python3 benchmarks/mutate.py --list             # the mutation sites, no run

Mutation sites are found mechanically: in the Python of an area (ast: the
operators of comparisons, boolean operators, ``not``, small integer
constants, ``+ 1``/``- 1``), in its C (the operators ``<= < >= > == != &&
|| << >>``, masks ``& 0x..``, ``+ 1``/``- 1``); ``--count`` of them are drawn
at random (seeded), spread over the areas.  Every mutant runs in a copy of
the tree (a temporary directory; the working tree is never touched), with
its own simulator cache.  A mutant whose tests fail (or time out, or whose
code no longer imports or compiles) is *killed*; one whose mutated text is
the same program (the site is dead code for the tests' inputs is not
enough) is *equivalent* only when listed in EQUIVALENT below with the
reason; the others *survived* and are listed with their file, line and
change.  The report ends with the score per area:
killed / (killed + survived)."""

from __future__ import annotations

import argparse
import ast
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

# area -> (files, pytest arguments of the tier that owns it, timeout s)
AREAS = {
    "emitter": (["iec2kmod/codegen/expr.py", "iec2kmod/codegen/body.py"],
                ["tests/execution/test_cases.py", "-k", "plain"], 600),
    "runtime": (["kmod_templates/runtime/iec_int.h", "kmod_templates/runtime/iec_conv.h",
                 "kmod_templates/runtime/iec_time.h", "kmod_templates/runtime/iec_std_fb.c"],
                ["tests/runtime/test_rt_c_drivers.py", "tests/execution/test_cases.py",
                 "-k", "plain or driver"], 600),
    "checks": (["iec2kmod/checks/types.py", "iec2kmod/checks/body.py",
                "iec2kmod/checks/expr.py", "iec2kmod/checks/calls.py"],
               ["tests/unit/test_type_table.py", "tests/unit/test_checker_rules.py",
                "tests/errors", "tests/conformance"], 300),
    "interp": (["iec2kmod/interp/values.py", "iec2kmod/interp/std.py",
                "iec2kmod/interp/conv.py"],
               ["tests/execution/test_cases_vm.py"], 300),
    "selective": (["iec2kmod/codegen/selective.py"],
                  ["tests/differential/test_selective_settle.py",
                   "tests/execution/test_selective.py"], 600),
    "verify": (["iec2kmod/verify/encode.py", "iec2kmod/verify/encode_expr.py",
                "iec2kmod/verify/encode_calls.py", "iec2kmod/verify/encode_std.py",
                "iec2kmod/verify/encode_il.py", "iec2kmod/verify/terms.py"],
               ["tests/verify/test_encode_diff.py", "tests/verify/test_verify.py",
                "-k", "differential or encoding or unsigned"], 600),
}

# (file, the line's text stripped, original, mutated) -> why the mutant
# computes the same thing (the line's text, not its number: other changes to
# the file move it)
EQUIVALENT: dict = {
    ("iec2kmod/checks/expr.py", "if len(hits) > 1:", ">", ">="):
        "len(hits) == 1 returned just before: > 1 and >= 1 agree on what reaches it",
    ("iec2kmod/interp/conv.py", "return lo if v < lo else hi if v > hi else v", ">", ">="):
        "at v == hi both forms return hi, which is v",
}

_PY_CMP = {ast.Lt: ("<", "<="), ast.LtE: ("<=", "<"), ast.Gt: (">", ">="),
           ast.GtE: (">=", ">"), ast.Eq: ("==", "!="), ast.NotEq: ("!=", "=="),
           ast.In: ("in", "not in"), ast.NotIn: ("not in", "in"),
           ast.Is: ("is", "is not"), ast.IsNot: ("is not", "is")}
_C_OPS = [(r"(?<![<>=!&|])<=(?!=)", "<"), (r"(?<![<>=!&|-])<(?![<=])", "<="),
          (r"(?<![<>=!&|-])>=(?!=)", ">"), (r"(?<![<>=!&|-])>(?![>=])", ">="),
          (r"==", "!="), (r"!=", "=="), (r"&&", "||"), (r"\|\|", "&&"),
          (r"<<", ">>"), (r">>", "<<"), (r"\+ 1\b", "+ 0"), (r"- 1\b", "- 0"),
          (r"& 0x[0-9a-fA-F]+[uUlL]*", "")]


@dataclass
class Mutant:
    area: str
    path: str       # relative to the tree
    line: int       # 1-based
    col: int        # 0-based start of the replaced text in the line
    old: str
    new: str
    kind: str

    def label(self):
        return f"{self.path}:{self.line}: {self.old!r} -> {self.new!r} ({self.kind})"


def _py_sites(area, rel, text):
    lines = text.splitlines()
    out = []
    tree = ast.parse(text)
    skip_lines = set()
    for node in ast.walk(tree):
        # docstrings and messages are not behaviour
        if isinstance(node, ast.Expr) and isinstance(getattr(node, "value", None), ast.Constant):
            skip_lines.update(range(node.lineno, (node.end_lineno or node.lineno) + 1))
    for node in ast.walk(tree):
        ln = getattr(node, "lineno", None)
        if ln is None or ln in skip_lines or getattr(node, "end_lineno", ln) != ln:
            continue
        src = lines[ln - 1]
        if isinstance(node, ast.Compare) and len(node.ops) == 1:
            a, b = node.left, node.comparators[0]
            if a.end_lineno != ln or b.lineno != ln:
                continue
            gap = src[a.end_col_offset:b.col_offset]
            op, rep = _PY_CMP.get(type(node.ops[0]), (None, None))
            if op is None:
                continue
            k = gap.find(op)
            if k < 0:
                continue
            out.append(Mutant(area, rel, ln, a.end_col_offset + k, op, rep, "compare"))
        elif isinstance(node, ast.BoolOp) and len(node.values) == 2:
            a, b = node.values
            if a.end_lineno != ln or b.lineno != ln:
                continue
            gap = src[a.end_col_offset:b.col_offset]
            op = "and" if isinstance(node.op, ast.And) else "or"
            k = gap.find(op)
            if k >= 0:
                out.append(Mutant(area, rel, ln, a.end_col_offset + k, op,
                                  "or" if op == "and" else "and", "and/or"))
        elif isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.Not):
            if src[node.col_offset:node.col_offset + 4] == "not ":
                out.append(Mutant(area, rel, ln, node.col_offset, "not ", "", "drop not"))
        elif isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Sub)) and \
                isinstance(node.right, ast.Constant) and node.right.value == 1 and \
                node.right.lineno == ln:
            out.append(Mutant(area, rel, ln, node.right.col_offset, "1", "0", "off by one"))
        elif isinstance(node, ast.BinOp) and isinstance(node.op, ast.BitAnd) and \
                isinstance(node.right, ast.Constant) and isinstance(node.right.value, int) \
                and node.left.end_lineno == ln and node.right.end_lineno == ln:
            s, e = node.left.end_col_offset, node.right.end_col_offset
            out.append(Mutant(area, rel, ln, s, src[s:e], "", "drop mask"))
    return out


def _c_sites(area, rel, text):
    out = []
    in_comment = False
    for ln, src in enumerate(text.splitlines(), 1):
        s = src.strip()
        if in_comment:
            if "*/" in s:
                in_comment = False
            continue
        if s.startswith("/*") and "*/" not in s:
            in_comment = True
            continue
        if s.startswith(("#include", "//", "/*", "*")) or not s:
            continue
        code = src.split("//")[0].split("/*")[0]
        for pat, rep in _C_OPS:
            for m in re.finditer(pat, code):
                kind = "drop mask" if pat.startswith("& 0x") else \
                    "off by one" if "1" in pat else "operator"
                out.append(Mutant(area, rel, ln, m.start(), m.group(0), rep, kind))
    return out


def sites(tree, areas):
    out = []
    for area in areas:
        for rel in AREAS[area][0]:
            p = tree / rel
            if not p.exists():
                continue
            text = p.read_text()
            out += _py_sites(area, rel, text) if rel.endswith(".py") else \
                _c_sites(area, rel, text)
    return out


def choose(all_sites, areas, count, seed):
    """count mutants spread evenly over the areas (seeded)."""
    rnd = random.Random(seed)
    by = {a: [m for m in all_sites if m.area == a] for a in areas}
    for a in by:
        rnd.shuffle(by[a])
    chosen = []
    while len(chosen) < count and any(by.values()):
        for a in areas:
            if by[a] and len(chosen) < count:
                chosen.append(by[a].pop())
    return chosen


def apply(tree, m):
    p = tree / m.path
    lines = p.read_text().splitlines(keepends=True)
    src = lines[m.line - 1]
    assert src[m.col:m.col + len(m.old)] == m.old, (m.label(), src)
    lines[m.line - 1] = src[:m.col] + m.new + src[m.col + len(m.old):]
    p.write_text("".join(lines))
    return src


def copy_tree(dst):
    files = subprocess.run(["git", "ls-files", "-z", "--cached", "--others",
                            "--exclude-standard"], cwd=ROOT, capture_output=True,
                           check=True).stdout.decode().split("\0")
    for f in files:
        if not f or not (ROOT / f).is_file():
            continue
        (dst / f).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(ROOT / f, dst / f)
    pypath = dst / ".pypath"
    pypath.mkdir(exist_ok=True)
    link = pypath / "plc_manager"
    if not link.exists():
        link.symlink_to("../manager")


def run_tests(tree, area, cache):
    _, args, timeout = AREAS[area]
    # a test file the tree does not have (an older tree) is left out
    args = [x for x in args if not x.startswith("tests/") or (tree / x).exists()]
    env = dict(os.environ, PYTHONPATH=f"{tree / '.pypath'}:{tree}", IEC2KMOD_CACHE=str(cache),
               PYTHONDONTWRITEBYTECODE="1")
    t0 = time.time()
    try:
        p = subprocess.run([sys.executable, "-m", "pytest", "-q", "-x", "-p", "no:cacheprovider",
                            "-p", "no:randomly", *args], cwd=tree, env=env,
                           capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return "timeout", time.time() - t0, ""
    lines = (p.stdout + p.stderr).strip().splitlines()
    first = next((ln for ln in lines if ln.startswith(("FAILED ", "ERROR "))),
                 lines[-1] if lines else "")
    return ("pass" if p.returncode == 0 else "fail"), time.time() - t0, first[:160]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--count", type=int, default=60)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--areas", default=",".join(AREAS))
    ap.add_argument("--smoke", action="store_true",
                    help="2 mutants of the checks against one table of their tests")
    ap.add_argument("--list", action="store_true", help="print the sites and exit")
    ap.add_argument("--only", default="",
                    help="comma list of FILE:LINE:OLD>NEW: run these mutants only")
    ap.add_argument("--baseline", action="store_true",
                    help="first run each area's tests unmutated (they must pass)")
    a = ap.parse_args(argv)
    areas = [x for x in a.areas.split(",") if x]
    for x in areas:
        if x not in AREAS:
            ap.error(f"unknown area {x!r} (the areas: {', '.join(AREAS)})")
    if a.smoke:
        areas, a.count = ["checks"], 2
        AREAS["checks"] = (["iec2kmod/checks/types.py"],
                           ["tests/unit/test_type_table.py", "-k", "assignment_table"], 300)
    all_sites = sites(ROOT, areas)
    if a.list:
        for m in all_sites:
            print(m.area, m.label())
        print(f"{len(all_sites)} sites")
        return 0
    chosen = choose(all_sites, areas, a.count, a.seed)
    if a.only:
        # the first site of each key (a line may hold the same operator twice)
        first = {}
        for m in all_sites:
            first.setdefault(f"{m.path}:{m.line}:{m.old}>{m.new}", m)
        chosen = [first[k] for k in a.only.split(",") if k in first]
    print(f"{len(all_sites)} sites in {', '.join(areas)}; {len(chosen)} mutants (seed {a.seed})",
          flush=True)
    res = {x: {"killed": 0, "survived": 0, "equivalent": 0} for x in areas}
    survivors = []
    t_all = time.time()
    with tempfile.TemporaryDirectory(prefix="iec2kmod-mutate.") as tmp:
        tree = Path(tmp) / "tree"
        cache = Path(tmp) / "cache"
        copy_tree(tree)
        if a.baseline:
            for x in areas:
                st, dt, tail = run_tests(tree, x, cache)
                print(f"baseline {x}: {st} in {dt:.0f} s  {tail}", flush=True)
                if st != "pass":
                    print("the unmutated tree fails its tests: no score", file=sys.stderr)
                    return 2
        for i, m in enumerate(chosen, 1):
            orig = (tree / m.path).read_text()
            key = (m.path, orig.splitlines()[m.line - 1].strip(), m.old, m.new)
            apply(tree, m)
            try:
                if key in EQUIVALENT:
                    res[m.area]["equivalent"] += 1
                    print(f"[{i}/{len(chosen)}] equivalent {m.label()}: {EQUIVALENT[key]}",
                          flush=True)
                    continue
                st, dt, tail = run_tests(tree, m.area, cache)
            finally:
                (tree / m.path).write_text(orig)
            verdict = "survived" if st == "pass" else "killed"
            res[m.area][verdict] += 1
            if verdict == "survived":
                survivors.append(m)
            print(f"[{i}/{len(chosen)}] {verdict:8s} {dt:5.0f} s  {m.area:9s} {m.label()}"
                  + (f"  [{st}]" if st == "timeout" else f"  [{tail}]" if st == "fail" else ""),
                  flush=True)
    print(f"\n{'area':10s} {'killed':>7s} {'survived':>9s} {'equiv.':>7s} {'score':>7s}")
    tk = ts = te = 0
    for x in areas:
        k, s, e = res[x]["killed"], res[x]["survived"], res[x]["equivalent"]
        tk, ts, te = tk + k, ts + s, te + e
        score = f"{100 * k / (k + s):.0f} %" if k + s else "-"
        print(f"{x:10s} {k:7d} {s:9d} {e:7d} {score:>7s}")
    score = f"{100 * tk / (tk + ts):.1f} %" if tk + ts else "-"
    print(f"{'total':10s} {tk:7d} {ts:9d} {te:7d} {score:>7s}   ({time.time() - t_all:.0f} s)")
    if survivors:
        print("\nsurvivors:")
        for m in survivors:
            print(f"  {m.area:9s} {m.label()}   --only '{m.path}:{m.line}:{m.old}>{m.new}'")
    return 0


if __name__ == "__main__":
    sys.exit(main())
