#!/usr/bin/env python3
"""OSCAT BASIC (its OpenPLC/Beremiz translation) through iec2kmod: what checks,
what is refused and why, and whether its functions compute what OSCAT's
documentation says, in the C engine and the interpreter.

    python3 benchmarks/oscat.py --oscat PATH [--engines c,vm,kernel] [--plc-st]
                                [--cases NAME,NAME] [--json OUT.json] [--smoke]

PATH is a copy of the translation the user provides (github
wonka929/OSCAT_OpenPLC, "OSCAT BASIC 3.33/<chapter>/build/generated_plc.st");
nothing is fetched, and no OSCAT source is part of this repository (it has
no licence file).  PATH may be the repository, its "OSCAT BASIC 3.33"
directory or any directory above the chapters: every
``<chapter>/build/generated_plc.st`` under it is a chapter (``--plc-st``:
``build/plc.st``, the same with Beremiz's LOGGER and python_eval blocks and
their MatIEC inline C).

1. Each chapter is checked as its own project; every POU is counted
   accepted or refused, a refusal by the cause of its first error.
2. The chapters are concatenated into one library: each chapter's own
   ``program0`` and CONFIGURATION are left out, POUs and types that several
   chapters repeat identically are kept once, and POUs or types of one name
   with different text are reported as conflicts (kept: the copy that
   declares more parameters, the translation lost the VAR_INPUT of some
   copies; else the first).  The
   library is checked as one project, its errors counted by cause; the
   refused POUs, and the POUs that call them, are then left out until the
   rest checks clean, and every POU left out is listed with its cause.
3. The cases of ``oscat_cases.py`` (inputs -> outputs written from OSCAT's
   documentation: the translation's plc.xml texts and the examples of the
   OSCAT BASIC manual, never from our output) run in one program that calls the
   POUs it needs from the library, in every engine given: the simulator's
   C engine and interpreter (default), and ``kernel``: the same program as
   kernel modules in the PREEMPT_RT QEMU guest (booted as the QEMU tier
   does; its prerequisites missing, the run says which).  A case whose
   call does not check is reported with the error and not run.

``--smoke`` (CI, tests/unit/test_oscat_benchmark.py on a stand-in of the
translation): steps 1 and 2 whole, step 3 with the first 3 cases in the C
engine only.

Exit status: 0 when every case agrees with its expectation in every engine
and no POU is refused but those ``oscat_cases.KNOWN_REFUSALS`` names (the
constructs outside ed.2, with the reason), 1 otherwise, 2 when PATH holds no
chapter.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from collections import Counter, OrderedDict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from iec2kmod.parse import frontend  # noqa: E402

import importlib.util  # noqa: E402

# comments, strings and pragmas (MatIEC's {{ }} inline C too) are skipped whole
_SKIP = r"'(?:[^'$\n]|\$.)*'|\"(?:[^\"$\n]|\$.)*\"|\(\*.*?\*\)|//[^\n]*|" \
        r"\{\{(?:[^}]|\}(?!\}))*\}\}|\{[^}]*\}"
_TOP = re.compile(_SKIP + r"|\b(FUNCTION_BLOCK|FUNCTION|PROGRAM|TYPE|CONFIGURATION)\b"
                  r"(?:\s+([A-Za-z_]\w*))?", re.S | re.I)
_TYPE_TOKENS = re.compile(_SKIP + r"|\b(STRUCT|END_STRUCT|END_TYPE)\b|(;)", re.S | re.I)
_IDENT = re.compile(_SKIP + r"|\b([A-Za-z_]\w*)\b", re.S)


# ------------------------------------------------------------------ sources

def chapters(path: Path, plc_st: bool) -> list[Path]:
    name = "plc.st" if plc_st else "generated_plc.st"
    return sorted(p for p in path.rglob(name) if p.parent.name == "build")


def chapter_name(f: Path) -> str:
    return f.parent.parent.name


class Block:
    """A top-level declaration of a file: a POU, one type of a TYPE block,
    or a CONFIGURATION."""

    def __init__(self, kind, name, text, path, line):
        self.kind, self.name, self.text, self.path, self.line = kind, name, text, path, line
        self.end_line = line + text.count("\n")

    @property
    def key(self):
        return self.name.upper()

    def norm(self):
        return re.sub(r"\s+", " ", re.sub(r"\(\*.*?\*\)", " ", self.text, flags=re.S)).strip()


def _end_of(text: str, kind: str, start: int) -> int:
    """The offset after the END_<kind> that closes the block at start."""
    end = re.compile(_SKIP + rf"|\b(END_{kind})\b", re.S | re.I)
    for m in end.finditer(text, start):
        if m.group(1):
            return m.end()
    return len(text)


def split_blocks(path: Path, text: str) -> list[Block]:
    out = []
    pos = 0
    while True:
        m = None
        for m2 in _TOP.finditer(text, pos):
            if m2.group(1):
                m = m2
                break
        if m is None:
            return out
        kind = m.group(1).upper()
        end = _end_of(text, kind, m.end(1))
        line = text.count("\n", 0, m.start()) + 1
        if kind == "TYPE":
            out += _split_types(path, text, m.end(1), end - len("END_TYPE"))
        else:
            out.append(Block(kind, m.group(2) or "?", text[m.start():end], path, line))
        pos = end


def _split_types(path, text, start, end):
    """The declarations of one TYPE block, each as its own TYPE ... END_TYPE."""
    out = []
    depth = 0
    begin = start
    for m in _TYPE_TOKENS.finditer(text, start, end):
        word = (m.group(1) or "").upper()
        if word == "STRUCT":
            depth += 1
        elif word == "END_STRUCT":
            depth -= 1
        elif m.group(2) and depth == 0:
            body = text[begin:m.end()]
            name = re.match(r"\s*([A-Za-z_]\w*)", body)
            if name:
                lead = len(body) - len(body.lstrip())
                line = text.count("\n", 0, begin + lead) + 1
                out.append(Block("TYPE", name.group(1), "TYPE\n" + body.strip() + "\nEND_TYPE\n",
                                 path, line))
            begin = m.end()
    return out


# ------------------------------------------------------------------ checking

def _check(files: list[Path], jobs: int = 1):
    res = frontend.run([str(f) for f in files], use_cache=False, jobs=jobs)
    return res


def _cause(message: str) -> str:
    """The message with the program's own names taken out: the cause."""
    return re.sub(r"'[^']*'", "'…'", message)


def refusals(blocks: list[Block], diags, path_of) -> dict:
    """{block key: first error message} for the blocks an error falls in."""
    out = {}
    by_path = {}
    for b in blocks:
        by_path.setdefault(str(path_of(b)), []).append(b)
    for d in sorted((d for d in diags.items if d.severity == "error"),
                    key=lambda d: (d.path, d.line, d.col)):
        for b in by_path.get(str(d.path), ()):
            if b.line <= d.line <= b.end_line:
                out.setdefault(b.key, (b, d.message, d.line))
                break
    return out


def check_chapter(f: Path) -> dict:
    text = f.read_text(errors="replace")
    blocks = [b for b in split_blocks(f, text) if b.kind in ("FUNCTION", "FUNCTION_BLOCK",
                                                             "PROGRAM")]
    t0 = time.perf_counter()
    res = _check([f])
    refused = refusals(blocks, res.diags, lambda b: f)
    if res.project is None and res.diags.errors:
        # a syntax error: nothing of the file was checked, every POU is refused
        first = res.diags.errors[0]
        for b in blocks:
            refused.setdefault(b.key, (b, first.message, first.line))
    return {"chapter": chapter_name(f), "pous": len(blocks),
            "accepted": len(blocks) - len(refused),
            "refused": {k: {"kind": b.kind, "error": msg, "line": line}
                        for k, (b, msg, line) in refused.items()},
            "errors": len(res.diags.errors), "warnings": len(res.diags.warnings),
            "seconds": round(time.perf_counter() - t0, 2)}


def library(files: list[Path]):
    """(blocks kept in order, duplicates dropped, conflicts) over every
    chapter, without each chapter's program0 and CONFIGURATION."""
    kept = OrderedDict()
    dups = 0
    conflicts = []
    for f in files:
        for b in split_blocks(f, f.read_text(errors="replace")):
            if b.kind == "CONFIGURATION" or (b.kind == "PROGRAM" and b.key == "PROGRAM0"):
                continue
            key = (b.kind == "TYPE", b.key)
            if key in kept:
                if kept[key].norm() == b.norm():
                    dups += 1
                    continue
                # the translation lost the VAR_INPUT of some copies (SINH and
                # SQRTN of the Mathematics chapter declare their inputs as
                # VAR): keep the copy with the larger interface
                old = kept[key]
                if _interface_size(b) > _interface_size(old):
                    kept[key] = b
                    conflicts.append((old, b))
                else:
                    conflicts.append((b, old))
                continue
            kept[key] = b
    return list(kept.values()), dups, conflicts


def _interface_size(b: Block) -> int:
    """How many inputs, outputs and in-outs a POU declares."""
    sections = re.findall(r"\bVAR_(?:INPUT|OUTPUT|IN_OUT)\b(.*?)\bEND_VAR\b", b.text, re.S | re.I)
    return sum(sec.count(";") for sec in sections)


def _callees(blocks: list[Block]) -> dict:
    names = {b.key for b in blocks}
    out = {}
    for b in blocks:
        body = b.text.split("\n", 1)[1] if "\n" in b.text else ""
        ids = {m.group(1).upper() for m in _IDENT.finditer(body) if m.group(1)}
        out[b.key] = (ids & names) - {b.key}
    return out


def closure(blocks: list[Block], roots: set) -> list[Block]:
    calls = _callees(blocks)
    want = set()
    todo = [r for r in roots]
    while todo:
        k = todo.pop()
        if k in want or k not in calls:
            continue
        want.add(k)
        todo += calls[k]
    return [b for b in blocks if b.key in want]


def write_library(blocks: list[Block], path: Path):
    """One file; every block's source line is recorded for mapping errors."""
    lines = []
    where = {}
    n = 1
    for b in blocks:
        where[b.key, b.kind == "TYPE"] = n
        lines.append(b.text.rstrip("\n") + "\n\n")
        n += b.text.rstrip("\n").count("\n") + 2
    path.write_text("".join(lines))
    return where


def check_library(blocks: list[Block], tmp: Path) -> dict:
    """Checks the library as one project; leaves out the refused POUs and
    their callers until the rest checks clean."""
    rounds = []
    left_out = OrderedDict()
    current = list(blocks)
    calls = _callees(current)
    f = tmp / "oscat_library.st"
    while True:
        where = write_library(current, f)
        for b in current:
            b.lib_line = where[b.key, b.kind == "TYPE"]
            b.lib_end = b.lib_line + b.text.rstrip("\n").count("\n")
        res = _check([f], jobs=os.cpu_count() or 1)
        errs = res.diags.errors
        rounds.append({"pous": sum(b.kind != "TYPE" for b in current), "errors": len(errs),
                       "warnings": len(res.diags.warnings),
                       "causes": Counter(_cause(d.message) for d in errs)})
        if not errs:
            return {"rounds": rounds, "left_out": left_out, "blocks": current,
                    "warnings": Counter(_cause(d.message) for d in res.diags.warnings)}
        bad = {}
        for d in sorted(errs, key=lambda d: (d.line, d.col)):
            for b in current:
                if b.lib_line <= d.line <= b.lib_end:
                    bad.setdefault(b.key, (b, d.message))
                    break
        if not bad:
            raise SystemExit("oscat.py: an error outside every block of the library: " +
                             "; ".join(d.format() for d in errs[:3]))
        for k, (b, msg) in bad.items():
            left_out[k] = {"kind": b.kind, "error": msg, "chapter": chapter_name(b.path)}
        # the callers of a refused POU cannot be checked without it
        changed = True
        while changed:
            changed = False
            for b in current:
                if b.key not in left_out and calls.get(b.key, set()) & set(left_out):
                    dep = sorted(calls[b.key] & set(left_out))[0]
                    left_out[b.key] = {"kind": b.kind, "error": f"calls {dep}, left out",
                                       "chapter": chapter_name(b.path)}
                    changed = True
        current = [b for b in current if b.key not in left_out]


# ------------------------------------------------------------------ cases

def _literal(v, typ):
    if typ == "BOOL":
        return "TRUE" if v else "FALSE"
    if typ in ("REAL", "LREAL"):
        return repr(float(v))
    return str(v)


def case_program(cases) -> str:
    """One PROGRAM: a result variable per case; FB cases run a call a cycle."""
    decls, body = [], []
    decls.append("    cyc : INT;")
    for i, c in enumerate(cases):
        decls += [f"    {v} (* var of case {i} *)" for v in getattr(c, "vars", ())]
        for j, (out, typ, _v) in enumerate(c.outputs):
            decls.append(f"    r{i}_{j} : {typ};")
        if c.kind == "FB":
            decls.append(f"    f{i} : {c.pou};")
            body.append(f"  (* case {i}: {c.name} *)")
            body.append("  CASE cyc OF")
            for k, args in enumerate(c.calls):
                body.append(f"    {k}: f{i}({args});")
            body.append("  END_CASE;")
            for j, (out, typ, _v) in enumerate(c.outputs):
                body.append(f"  r{i}_{j} := f{i}.{out};")
        else:
            body.append(f"  (* case {i}: {c.name} *)")
            for j, (out, typ, _v) in enumerate(c.outputs):
                body.append(f"  r{i}_{j} := {out};")
    body.append("  cyc := cyc + 1;")
    return ("PROGRAM OscatCases\n  VAR\n" + "\n".join(decls) + "\n  END_VAR\n" +
            "\n".join(body) + "\nEND_PROGRAM\n\n"
            "CONFIGURATION OscatCasesConf\n"
            "  TASK t (INTERVAL := T#10ms, PRIORITY := 1);\n"
            "  PROGRAM m WITH t : OscatCases;\n"
            "END_CONFIGURATION\n")


def _case_lines(text: str):
    """{case index: (first line, last line)} in the case program."""
    out = {}
    lines = text.split("\n")
    cur = None
    for n, line in enumerate(lines, 1):
        m = re.match(r"\s*\(\* case (\d+):", line)
        if m:
            cur = int(m.group(1))
            out[cur] = [n, n]
        elif cur is not None and re.match(r"\s*(cyc := cyc|r\d+_\d+ :=|CASE|END_CASE|\d+:)",
                                          line):
            out[cur][1] = n
        m = re.match(r"\s*(?:r|f)(\d+)(?:_\d+)?\s*:\s*\w+;", line) or \
            re.search(r"\(\* var of case (\d+) \*\)$", line)
        if m:
            out.setdefault(("decl", int(m.group(1))), []).append(n)
    return out


def engine_names() -> list[str]:
    """The interpreter's name for --engine (vm, or interp after a rename)."""
    p = subprocess.run([sys.executable, "-m", "iec2kmod", "sim", "--help"],
                       capture_output=True, text=True, env=_env())
    m = re.search(r"--engine \{([^}]*)\}", p.stdout)
    return m.group(1).split(",") if m else ["c", "vm"]


def _env():
    return dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(ROOT)] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]))


def run_cases(cases, lib_blocks, engines, tmp: Path, log) -> dict:
    """Runs the cases; {case name: {engine: [(output, got, ok)]}} plus the
    cases that did not check."""
    # the POUs the cases need, with every type (types are cheap)
    roots = {c.pou.upper() for c in cases} | {n.upper() for c in cases for n in c.needs}
    need = closure([b for b in lib_blocks], roots)
    types = [b for b in lib_blocks if b.kind == "TYPE"]
    need = types + [b for b in need if b.kind != "TYPE"]
    known = {b.key for b in need}
    not_run = {}
    active = []
    for c in cases:
        missing = [p for p in [c.pou] + list(c.needs) if p.upper() not in known]
        if missing:
            not_run[c.name] = f"not in the checked library: {', '.join(missing)}"
        else:
            active.append(c)
    lib = tmp / "lib.st"
    write_library(need, lib)
    prog = tmp / "cases.st"
    while True:
        text = case_program(active)
        prog.write_text(text)
        res = _check([lib, prog])
        errs = [d for d in res.diags.errors]
        if not errs:
            break
        spans = _case_lines(text)
        bad = set()
        for d in errs:
            if Path(d.path) != prog:
                raise SystemExit("oscat.py: the library needed by the cases does not check: "
                                 + d.format())
            for k, v in spans.items():
                if isinstance(k, int) and v[0] <= d.line <= v[1]:
                    bad.add(k)
                    not_run.setdefault(active[k].name, d.message)
                elif isinstance(k, tuple) and d.line in v:
                    bad.add(k[1])
                    not_run.setdefault(active[k[1]].name, d.message)
        if not bad:
            raise SystemExit("oscat.py: the case program does not check: " + errs[0].format())
        active = [c for i, c in enumerate(active) if i not in bad]
    cycles = max([len(c.calls) for c in active if c.kind == "FB"] + [1])
    watch = [f"m.r{i}_{j}" for i, c in enumerate(active) for j in range(len(c.outputs))]
    results = {c.name: {} for c in active}
    for eng in engines:
        if eng == "kernel":
            last = kernel_values(lib, prog, watch, cycles, log)
            for i, c in enumerate(active):
                results[c.name][eng] = [
                    (o, last.get(f"m.r{i}_{j}"), agrees(last.get(f"m.r{i}_{j}"), typ, want, c.tol))
                    for j, (o, typ, want) in enumerate(c.outputs)]
            continue
        out = tmp / f"out_{eng}.csv"
        t0 = time.perf_counter()
        p = subprocess.run([sys.executable, "-m", "iec2kmod", "sim", "--engine", eng,
                            "--cycles", str(cycles), "--watch", ",".join(watch),
                            "--csv", str(out), str(lib), str(prog)],
                           capture_output=True, text=True, env=_env(), timeout=1800)
        log(f"  sim --engine {eng}: {p.returncode}, {time.perf_counter() - t0:.1f} s")
        if p.returncode != 0 or not out.exists():
            for c in active:
                results[c.name][eng] = [(o, None, False) for o, _t, _v in c.outputs]
            for line in (p.stderr.strip().splitlines() or ["(no output)"])[-6:]:
                log("    " + line)
            continue
        last = {}
        with out.open() as fh:
            for row in csv.DictReader(fh):
                for k, v in row.items():
                    if v not in ("", None):
                        last[k] = v
        for i, c in enumerate(active):
            rows = []
            for j, (o, typ, want) in enumerate(c.outputs):
                got = last.get(f"m.r{i}_{j}")
                rows.append((o, got, agrees(got, typ, want, c.tol)))
            results[c.name][eng] = rows
    return {"results": results, "not_run": not_run, "cycles": cycles}


def kernel_values(lib: Path, prog: Path, watch, cycles, log) -> dict:
    """The case program as kernel modules (iec2kmod gen + build) in the
    PREEMPT_RT QEMU guest (iec2kmod.testing.vm, as the QEMU tier boots it): loaded
    with plc-manager, read with `plc-manager read --json` once the task has
    run its cycles, stopped; the kernel log must stay clean.  {path: value
    as text} like the simulator's CSV; {} when anything fails (logged)."""
    from iec2kmod.testing.vm import Guest
    work = Path(tempfile.mkdtemp(prefix="oscat-kernel-", dir=os.environ.get("TMPDIR")))
    tree = work / "tree"
    t0 = time.perf_counter()
    for cmd in (["gen", str(lib), str(prog), "-o", str(tree)], ["build", str(tree)]):
        p = subprocess.run([sys.executable, "-m", "iec2kmod", *cmd], capture_output=True,
                           text=True, env=_env(), timeout=1800)
        if p.returncode != 0:
            log(f"  kernel: iec2kmod {cmd[0]} failed: {(p.stderr or p.stdout).strip()[-800:]}")
            return {}
    log(f"  kernel: modules built in {time.perf_counter() - t0:.1f} s; booting the guest")
    g = Guest(str(work), console_log=str(work / "console.log"))
    values = {}
    try:
        g.start()
        g.start_pyserver()

        def manager(*argv, timeout=300):
            return g.pyrun(script="plc-manager", argv=[str(a) for a in argv], timeout=timeout)
        r = manager("load", str(tree))
        if r.exit_code != 0:
            log(f"  kernel: plc-manager load failed: {r.output[-800:]}")
            return {}
        try:
            deadline = time.monotonic() + 120
            while time.monotonic() < deadline:
                r = manager("status", "--json")
                tasks = [t for res in json.loads(r.output)["resources"] for t in res["tasks"]] \
                    if r.exit_code == 0 else []
                if tasks and all(int(t["cycles"]) > cycles + 2 for t in tasks):
                    break
                time.sleep(1)
            r = manager("read", "--json", *watch)
            if r.exit_code != 0:
                log(f"  kernel: plc-manager read failed: {r.output[-800:]}")
                return {}
            for v in json.loads(r.output):
                val = v["value"]
                values[v["path"]] = ("TRUE" if val else "FALSE") if isinstance(val, bool) \
                    else str(val)
        finally:
            manager("stop")
        g.check_kernel_log()
        log(f"  kernel: {len(values)} values read, kernel log clean, "
            f"{time.perf_counter() - t0:.1f} s")
    except Exception as exc:  # the guest's own errors name what is missing
        log(f"  kernel: {type(exc).__name__}: {str(exc)[-800:]} (console: {work}/console.log)")
        return {}
    finally:
        g.close()
    shutil.rmtree(work, ignore_errors=True)   # kept above when something failed
    return values


def agrees(got, typ, want, tol) -> bool:
    if got is None:
        return False
    if typ == "BOOL":
        return got.upper() in ("TRUE", "1") if want else got.upper() in ("FALSE", "0")
    if typ in ("REAL", "LREAL"):
        try:
            g = float(got)
        except ValueError:
            return False
        return math.isclose(g, float(want), rel_tol=tol, abs_tol=tol)
    if typ == "TIME":
        return int(got) == int(want)  # nanoseconds
    if typ.startswith("STRING"):
        return got == want
    try:
        return int(got) == int(want)
    except ValueError:
        return False


# ------------------------------------------------------------------ report

def load_cases(path: Path):
    spec = importlib.util.spec_from_file_location("oscat_cases", path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules["oscat_cases"] = mod   # dataclasses resolve their module
    spec.loader.exec_module(mod)
    return mod


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--oscat", required=True, type=Path,
                    help="a copy of wonka929/OSCAT_OpenPLC (or its 'OSCAT BASIC 3.33')")
    ap.add_argument("--engines", default=None,
                    help="comma-separated engines of `iec2kmod sim --engine`, and kernel "
                         "(the QEMU guest) (default: the sim engines)")
    ap.add_argument("--plc-st", action="store_true",
                    help="check build/plc.st (with Beremiz's inline C) instead of "
                         "build/generated_plc.st")
    ap.add_argument("--cases", default=None, help="only these cases (comma-separated names)")
    ap.add_argument("--cases-file", type=Path, default=Path(__file__).with_name("oscat_cases.py"),
                    help="the module with CASES and KNOWN_REFUSALS (default: oscat_cases.py)")
    ap.add_argument("--no-run", action="store_true", help="check only, run no case")
    ap.add_argument("--json", type=Path, default=None, help="write every figure as JSON")
    ap.add_argument("--smoke", action="store_true",
                    help="CI size: the first 3 cases, in the C engine only (the chapters and "
                         "the library are checked whole)")
    args = ap.parse_args(argv)

    oscat_cases = load_cases(args.cases_file)
    if not args.oscat.is_dir():
        print(f"oscat.py: {args.oscat}: not a directory (give a copy of "
              "github.com/wonka929/OSCAT_OpenPLC)", file=sys.stderr)
        return 2
    files = chapters(args.oscat, args.plc_st)
    if not files:
        print(f"oscat.py: no <chapter>/build/{'plc.st' if args.plc_st else 'generated_plc.st'}"
              f" under {args.oscat}", file=sys.stderr)
        return 2
    log = print
    report = {"chapters": [], "source": "plc.st" if args.plc_st else "generated_plc.st"}

    # 1. chapters
    log(f"== chapters ({len(files)}, {report['source']})")
    causes = Counter()
    total = acc = 0
    for f in files:
        r = check_chapter(f)
        report["chapters"].append(r)
        total += r["pous"]
        acc += r["accepted"]
        for v in r["refused"].values():
            causes[_cause(v["error"])] += 1
        log(f"  {r['chapter']:<55} {r['accepted']:>3}/{r['pous']:<3} POUs accepted"
            f"  ({r['errors']} errors, {r['warnings']} warnings, {r['seconds']} s)")
        for k, v in r["refused"].items():
            log(f"      refused {v['kind']} {k}: line {v['line']}: {v['error']}")
    log(f"  total: {acc}/{total} POUs accepted, {total - acc} refused")
    for cause, n in causes.most_common():
        log(f"    {n:>4}  {cause}")

    # 2. the library as one project
    blocks, dups, conflicts = library(files)
    npou = sum(b.kind != "TYPE" for b in blocks)
    log(f"== library: {npou} POUs and {len(blocks) - npou} types after removing {dups} "
        f"identical repetitions; {len(conflicts)} conflicting definitions")
    for b, first in conflicts:
        nb, nf = _interface_size(b), _interface_size(first)
        why = (f"kept: the copy declaring {nf} parameters; this one declares {nb}"
               if nf != nb else "kept: the first")
        log(f"    conflict: {b.kind} {b.name} of {chapter_name(b.path)} differs from the one of "
            f"{chapter_name(first.path)} ({why})")
    report["library"] = {"pous": npou, "types": len(blocks) - npou, "duplicates": dups,
                         "conflicts": [[b.kind, b.name, chapter_name(b.path),
                                        chapter_name(first.path)] for b, first in conflicts]}
    with tempfile.TemporaryDirectory(prefix="oscat_") as td:
        tmp = Path(td)
        t0 = time.perf_counter()
        lib = check_library(blocks, tmp)
        left = lib["left_out"]
        log(f"  checked as one project in {len(lib['rounds'])} round(s), "
            f"{time.perf_counter() - t0:.1f} s: " +
            ", ".join(f"{r['pous']} POUs -> {r['errors']} errors" for r in lib["rounds"]))
        if lib["rounds"][0]["errors"]:
            log(f"  errors of the whole library by cause ({lib['rounds'][0]['errors']}):")
            for cause, n in lib["rounds"][0]["causes"].most_common():
                log(f"    {n:>4}  {cause[:150]}")
        clean = sum(b.kind != "TYPE" for b in lib["blocks"])
        log(f"  {clean}/{npou} POUs check clean together; left out {len(left)}:")
        known = {k.upper(): v for k, v in oscat_cases.KNOWN_REFUSALS.items()}
        unexplained = []
        for k, v in left.items():
            why = known.get(k)
            log(f"    {v['kind']} {k} ({v['chapter']}): {v['error']}" +
                (f"\n        outside ed.2: {why}" if why else ""))
            if why is None and not v["error"].startswith("calls "):
                unexplained.append(k)
        for cause, n in lib["warnings"].most_common():
            log(f"    warning x{n}: {cause[:150]}")
        report["library"].update({"clean": clean, "left_out": left, "rounds": lib["rounds"],
                                  "unexplained": unexplained})

        # 3. cases
        ok = not unexplained
        if not args.no_run:
            cases = oscat_cases.CASES
            if args.cases:
                want = {n.strip() for n in args.cases.split(",")}
                cases = [c for c in cases if c.name in want]
            avail = engine_names() + ["kernel"]
            engines = args.engines.split(",") if args.engines else [e for e in avail
                                                                    if e != "kernel"]
            if args.smoke:
                cases, engines = cases[:3], engines[:1]
            for e in engines:
                if e not in avail:
                    print(f"oscat.py: engine {e} is not one of {', '.join(avail)}",
                          file=sys.stderr)
                    return 2
            log(f"== {len(cases)} cases ({sum(len(c.outputs) for c in cases)} values) from "
                f"OSCAT's documentation, engines {', '.join(engines)}")
            run = run_cases(cases, lib["blocks"], engines, tmp, log)
            agree = Counter()
            differs = {}
            for c in cases:
                if c.name in run["not_run"]:
                    log(f"  NOT RUN {c.name}: {run['not_run'][c.name]}")
                    ok = False
                    continue
                per = run["results"][c.name]
                for eng in engines:
                    rows = per.get(eng, [])
                    good = rows and all(r[2] for r in rows)
                    agree[eng] += bool(good)
                    if not good:
                        known = getattr(c, "known", "")
                        if not known:
                            ok = False
                        differs[c.name] = known
                        got = ", ".join(f"{o}={g}" for o, g, _ in rows)
                        exp = ", ".join(f"{o}={v}" for o, _t, v in c.outputs)
                        log(f"  DIFFERS {c.name} [{eng}]: got {got}; documented {exp}"
                            f"\n      doc: {c.doc}" + (f"\n      note: {c.note}" if c.note else "")
                            + (f"\n      why (known): {known}" if known else
                               "\n      why: not yet explained"))
                    elif getattr(c, "known", ""):
                        # a known disagreement that went away: the table is stale
                        ok = False
                        log(f"  AGREES NOW {c.name} [{eng}]: remove its 'known' reason")
                same = len({tuple(r[1] for r in per.get(e, [])) for e in engines}) == 1
                if not same:
                    log(f"  ENGINES DISAGREE {c.name}: " +
                        "; ".join(f"{e}: {[r[1] for r in per.get(e, [])]}" for e in engines))
                    ok = False
            ran = len(cases) - len(run["not_run"])
            for eng in engines:
                log(f"  {eng}: {agree[eng]}/{ran} cases agree with the documentation "
                    f"({len(run['not_run'])} not run)")
            log(f"  differ: {len(differs)} case(s), {sum(1 for v in differs.values() if v)} "
                f"explained (not iec2kmod's defects), "
                f"{sum(1 for v in differs.values() if not v)} unexplained")
            report["cases"] = {"total": len(cases), "not_run": run["not_run"], "differ": differs,
                               "agree": dict(agree),
                               "results": {k: {e: [[o, g, a] for o, g, a in rows]
                                               for e, rows in v.items()}
                                           for k, v in run["results"].items()}}
    if args.json:
        args.json.write_text(json.dumps(report, indent=1, default=str))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
