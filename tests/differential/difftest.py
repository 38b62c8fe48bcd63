"""Differential execution of generated projects (progen.py) in several engines.

Engines:
  c         the compiled C simulator (iec2kmod.sim, in process)
  sanitize  the same with -fsanitize=undefined,address: any report is a failure
  selective the compiled C simulator with selective execution (``sim
            --selective``, iec2kmod/codegen/selective.py): blocks whose
            argument set did not change are skipped, which must be invisible
  vm        the reference interpreter (iec2kmod.interp.run, what ``iec2kmod sim
            --engine vm`` runs), in process on the project the front end
            checked once; used when the CLI offers ``--engine vm``

Several generated units share one configuration (one front-end run and one
simulator build per engine for a whole batch); a batch that does not run
(rejected, does not compile, crashes) is split into its units so that each
failure is attributed to one project.

Comparison: every watched variable (the whole variable table of the
simulator: globals, direct addresses, program and FB instance variables)
as the sequence of its changes over time, and every runtime fault as
(time, task, fault, POU, line).  REAL/LREAL values may differ by at most
``ULP_TOLERANCE`` units in the last place of their own width (transcendental
functions come from different libms; the generator keeps such values out of
control flow), NaNs are equal to each other, everything else must be equal.
"""

from __future__ import annotations

import math
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
# this checkout's package first, whatever is installed
for _p in (str(HERE), str(ROOT)):
    if _p in sys.path:
        sys.path.remove(_p)
    sys.path.insert(0, _p)

import progen  # noqa: E402

from iec2kmod import sim  # noqa: E402
from iec2kmod.parse import frontend  # noqa: E402
from iec2kmod.compilation import Compilation  # noqa: E402

ULP_TOLERANCE = 4
# A sink (progen: fz<n>, never read) may hold a chain of transcendental
# functions, EXP(TAN(x)): each libm's last-bit error is amplified along the
# chain (EXP multiplies TAN's absolute error by its result), far beyond 4
# ULPs and harmlessly, since nothing reads a sink.
SINK_ULP_TOLERANCE = 1 << 16
_SINK = re.compile(r"\.FZ[0-9]+$", re.I)
INTERVAL_NS = 10_000_000
SANITIZER_REPORT = re.compile(r"runtime error|Sanitizer|^==\d+==|SUMMARY:", re.M)
ALL_ENGINES = ("c", "sanitize", "selective", "vm")


def cache_root() -> Path:
    base = os.environ.get("IEC2KMOD_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "iec2kmod")
    return Path(base)


def vm_available() -> bool:
    """Does `iec2kmod sim` offer --engine vm?"""
    from iec2kmod.cli import build_parser
    p = build_parser()
    sub = next(a for a in p._actions if a.__class__.__name__ == "_SubParsersAction")
    simp = sub.choices["sim"]
    for a in simp._actions:
        if "--engine" in a.option_strings:
            return a.choices is None or "vm" in a.choices
    return False


def available_engines() -> list:
    return ["c", "sanitize", "selective"] + (["vm"] if vm_available() else [])


# ----------------------------------------------------------------- runs
@dataclass
class EngineRun:
    engine: str
    status: str                      # ok reject compile crash sanitizer error
    detail: str = ""
    changes: dict = field(default_factory=dict)    # NAME -> [(t, text)]
    faults: list = field(default_factory=list)     # (t, task, fault, pou, line)
    floats: set = field(default_factory=set)       # NAMEs of REAL/LREAL (kind f)
    widths: dict = field(default_factory=dict)     # NAME -> 32|64 for floats
    selective: dict = field(default_factory=dict)  # task -> (blocks evaluated, skipped)

    @property
    def ok(self):
        return self.status == "ok"


def _text(v):
    return sim.format_value(None, v)


def _compress(seq):
    out = []
    for t, v in seq:
        if out and out[-1][1] == v:
            continue
        out.append((t, v))
    return out


def project_of(paths):
    """(project, None) or (None, first error message)."""
    try:
        res = frontend.run([str(p) for p in paths], use_cache=False)
    except Exception as exc:  # noqa: BLE001 - a front-end crash is a finding
        return None, f"front end crashed: {type(exc).__name__}: {exc}"
    if not res.ok:
        errs = [d.format() for d in res.diags.sorted() if d.severity == "error"]
        return None, "\n".join(errs[:3])
    return res.project, None


def write_trace(events, table, path, addresses=None):
    """The trace rows whose variable exists and is writable (a minimised
    project may have lost some); a located variable may be named by its
    address (``addresses``: ConfigInfo.addresses)."""
    ok = {e.path.upper() for e in table if e.writable}
    ok |= {a.upper() for a, p in (addresses or {}).items() if p.upper() in ok}
    rows = [f"{t}ns,{p},{v}\n" for t, p, v in events if p.upper() in ok]
    Path(path).write_text("".join(rows))
    return len(rows)


def run_c(project, plan, end_ns, trace, sanitize, selective=False):
    eng = "selective" if selective else "sanitize" if sanitize else "c"
    watch = [e.path for e in plan.table]
    try:
        res = sim.run(project, end_ns, watch=watch, inputs=str(trace), sanitize=sanitize,
                      build_dir=cache_root() / "sim", timeout=300,
                      selective="all" if selective else None)
    except sim.InternalError as exc:
        msg = str(exc)
        if "did not compile" in msg:
            return EngineRun(eng, "compile", msg[:1500])
        if sanitize and SANITIZER_REPORT.search(msg):
            return EngineRun(eng, "sanitizer", msg[:3000])
        return EngineRun(eng, "crash", msg[:1500])
    except subprocess.TimeoutExpired:
        return EngineRun(eng, "crash", "the simulator did not finish in 300 s")
    except sim.SimError as exc:
        return EngineRun(eng, "error", str(exc))
    if sanitize and SANITIZER_REPORT.search(res.stderr or ""):
        return EngineRun(eng, "sanitizer", res.stderr[:3000])
    run = EngineRun(eng, "ok")
    for t, i, v in res.changes:
        run.changes.setdefault(res.names[i].upper(), []).append((t, _text(v)))
    run.faults = [(t, task, fault, pou, line) for t, task, fault, pou, _f, line in res.faults]
    run.selective = dict(res.selective)
    return run


def run_vm_inproc(project, plan, end_ns, trace):
    """The interpreter in this process (iec2kmod.interp.run, the function
    behind `sim --engine vm`), on the project the front end already checked."""
    from iec2kmod import interp
    watch = [e.path for e in plan.table]
    try:
        machine = interp.Machine(project)
        have = {e.path.upper() for e in machine.table()}
        missing = [w for w in watch if w.upper() not in have]
        if missing:
            return EngineRun("vm", "error", f"the interpreter's variable table lacks "
                             f"{len(missing)} of the simulator's: {missing[:5]}")
        res = interp.run(project, end_ns, watch=watch, inputs=str(trace), machine=machine)
    except interp.InterpError as exc:
        return EngineRun("vm", "error", f"InterpError: {exc}")
    except RecursionError as exc:
        return EngineRun("vm", "crash", f"RecursionError: {exc}")
    except Exception as exc:  # noqa: BLE001 - an interpreter crash is a finding
        import traceback
        tb = traceback.extract_tb(exc.__traceback__)[-1]
        return EngineRun("vm", "crash", f"{type(exc).__name__}: {exc} at "
                         f"{Path(tb.filename).name}:{tb.lineno}")
    run = EngineRun("vm", "ok")
    for t, i, v in res.changes:
        run.changes.setdefault(res.names[i].upper(), []).append((t, _text(v)))
    run.faults = [(t, task, fault, pou, line) for t, task, fault, pou, _f, line in res.faults]
    return run


def _ulps(a: float, b: float, width: int) -> float:
    if width == 32:
        ia = struct.unpack("<i", struct.pack("<f", a))[0]
        ib = struct.unpack("<i", struct.pack("<f", b))[0]
        big = 1 << 31
    else:
        ia = struct.unpack("<q", struct.pack("<d", a))[0]
        ib = struct.unpack("<q", struct.pack("<d", b))[0]
        big = 1 << 63
    # sign-magnitude to a monotonic integer line
    ia = -(ia & (big - 1)) if ia < 0 else ia
    ib = -(ib & (big - 1)) if ib < 0 else ib
    return abs(ia - ib)


def values_equal(a: str, b: str, width, tolerance=ULP_TOLERANCE) -> bool:
    if a == b:
        return True
    if not width:
        return False
    try:
        x, y = float(a), float(b)
    except ValueError:
        return False
    if math.isnan(x) and math.isnan(y):
        return True
    if math.isinf(x) or math.isinf(y):
        return x == y
    if x == y:
        return True
    try:
        return _ulps(x, y, width) <= tolerance
    except (OverflowError, struct.error):
        return False


def compare(a: EngineRun, b: EngineRun, names, widths) -> str | None:
    """None if the runs agree on names; else the first difference."""
    fa = sorted(a.faults)
    fb = sorted(b.faults)
    if fa != fb:
        return f"faults differ: {a.engine} {fa[:2]} / {b.engine} {fb[:2]}"
    first = None
    for n in names:
        w = widths.get(n)
        tol = SINK_ULP_TOLERANCE if _SINK.search(n) else ULP_TOLERANCE
        sa = _compress_tol(a.changes.get(n, []), w, tol)
        sb = _compress_tol(b.changes.get(n, []), w, tol)
        for k in range(max(len(sa), len(sb))):
            x = sa[k] if k < len(sa) else None
            y = sb[k] if k < len(sb) else None
            if x is None or y is None or x[0] != y[0] or not values_equal(x[1], y[1], w, tol):
                t = min(z[0] for z in (x, y) if z is not None)
                if first is None or t < first[0]:
                    first = (t, f"t={t}ns {n}: {a.engine} {x} / {b.engine} {y}")
                break
    return first[1] if first else None


def _compress_tol(seq, width, tolerance=ULP_TOLERANCE):
    out = []
    for t, v in seq:
        if out and values_equal(out[-1][1], v, width, tolerance):
            continue
        out.append((t, v))
    return out


# ---------------------------------------------------------------- units
@dataclass
class UnitResult:
    seed: int
    features: set
    problems: list = field(default_factory=list)   # (kind, engine(s), text)
    statuses: dict = field(default_factory=dict)   # engine -> status
    selective: tuple = (0, 0)     # blocks evaluated, skipped by the selective engine

    @property
    def ok(self):
        return not self.problems


def unit_names(unit, table):
    pre = unit.prefix.upper()
    addrs = {a.upper() for a in unit.addresses}
    return [e.path.upper() for e in table if e.path.upper().startswith(pre)
            or e.path.upper() in addrs]


def _widths(table):
    return {e.path.upper(): (32 if e.size == 4 else 64) for e in table if e.kind == "f"}


def end_ns(cycles):
    return (cycles - 1) * INTERVAL_NS


def run_units(units, engines, workdir, split_on_failure=True):
    """Runs units as one batch; {unit seed: UnitResult}."""
    workdir = Path(workdir)
    workdir.mkdir(parents=True, exist_ok=True)
    results = {u.seed: UnitResult(u.seed, u.features) for u in units}
    files = []
    for u in units:
        f = workdir / f"{u.prefix}prog.st"
        f.write_text(u.decl_text)
        files.append(f)
    cfg = workdir / "batch_config.st"
    cfg.write_text(progen.config_text("fuzz_batch", units))
    paths = files + [cfg]
    project, err = project_of(paths)
    if project is None:
        if len(units) == 1 or not split_on_failure:
            for u in units:
                results[u.seed].problems.append(("reject", "front end", err))
            return results
        m = re.search(r"u(\d+)_prog\.st", err or "")
        return _split(units, engines, workdir, f"pou_u{m.group(1)}_" if m else "")
    plan = Compilation(project).plan
    trace = workdir / "trace.csv"
    events = sorted((ev for u in units for ev in u.trace), key=lambda e: e[0])
    write_trace(events, plan.table, trace, project.configurations[0].addresses)
    end = end_ns(max(u.cycles for u in units))
    runs = {}
    for eng in engines:
        if eng == "c":
            runs[eng] = run_c(project, plan, end, trace, False)
        elif eng == "sanitize":
            runs[eng] = run_c(project, plan, end, trace, True)
        elif eng == "selective":
            runs[eng] = run_c(project, plan, end, trace, False, selective=True)
        elif eng == "vm":
            runs[eng] = run_vm_inproc(project, plan, end, trace)
    bad = [e for e, r in runs.items() if not r.ok]
    if bad and len(units) > 1 and split_on_failure:
        return _split(units, engines, workdir, runs[bad[0]].detail)
    widths = _widths(plan.table)
    for u in units:
        res = results[u.seed]
        res.statuses = {e: r.status for e, r in runs.items()}
        if "selective" in runs:
            mine = [v for task, v in runs["selective"].selective.items()
                    if task.upper().startswith(u.prefix.upper())]
            res.selective = (sum(v[0] for v in mine), sum(v[1] for v in mine))
        for e in bad:
            r = runs[e]
            res.problems.append((r.status, e, r.detail))
        okr = [runs[e] for e in engines if runs[e].ok]
        if len(okr) < 2:
            continue
        names = unit_names(u, plan.table)
        pre = u.prefix.upper()
        base = okr[0]
        for other in okr[1:]:
            ra = _restrict(base, pre)
            rb = _restrict(other, pre)
            d = compare(ra, rb, names, widths)
            if d:
                res.problems.append(("diff", f"{base.engine}/{other.engine}", d))
    return results


def _restrict(run, pre):
    r = EngineRun(run.engine, run.status, run.detail, run.changes,
                  [f for f in run.faults if f[1].upper().startswith(pre)])
    return r


def _split(units, engines, workdir, detail=""):
    """A batch failed: the unit a compile error names runs alone, the others
    as a batch; otherwise the batch is halved until the failures are single
    units."""
    out = {}
    workdir = Path(workdir)
    m = re.search(r"pou_u(\d+)_", detail or "")
    culprit = [u for u in units if m and u.prefix == f"u{m.group(1)}_"]
    if culprit:
        rest = [u for u in units if u is not culprit[0]]
        parts = [culprit, rest]
    else:
        half = len(units) // 2
        parts = [units[:half], units[half:]]
    for n, part in enumerate(parts):
        if not part:
            continue
        sub = workdir / f"part{n}"
        out.update(run_units(part, engines, sub, split_on_failure=True))
        shutil.rmtree(sub, ignore_errors=True)
    return out


# ---------------------------------------------------------- standalone
def run_text(text, events, engines, cycles, workdir):
    """Runs one standalone project text: (EngineRuns by engine, error) where
    error is the front end's message if it rejects the text."""
    workdir = Path(workdir)
    workdir.mkdir(parents=True, exist_ok=True)
    f = workdir / "case.st"
    f.write_text(text)
    project, err = project_of([f])
    if project is not None and not project.configurations:
        project, err = None, "error: no configuration"
    if project is None:
        return None, err
    plan = Compilation(project).plan
    trace = workdir / "trace.csv"
    write_trace(events, plan.table, trace, project.configurations[0].addresses)
    end = end_ns(cycles)
    runs = {}
    for eng in engines:
        if eng in ("c", "sanitize", "selective"):
            runs[eng] = run_c(project, plan, end, trace, eng == "sanitize",
                              selective=eng == "selective")
        else:
            runs[eng] = run_vm_inproc(project, plan, end, trace)
    runs["_names"] = [e.path.upper() for e in plan.table]
    runs["_widths"] = _widths(plan.table)
    return runs, None


def signature(runs, err, engines):
    """What kind of failure a standalone run shows (None: none)."""
    if runs is None:
        return ("reject", _first_error(err))
    for e in engines:
        if not runs[e].ok:
            return (runs[e].status, e, failure_class(runs[e].detail))
    okr = [runs[e] for e in engines]
    for other in okr[1:]:
        if compare(okr[0], other, runs["_names"], runs["_widths"]):
            return ("diff", f"{okr[0].engine}/{other.engine}")
    return None


def failure_class(detail):
    """What stays the same while a failure is minimised: gcc's warning
    option, the sanitizer's message kind, the exit status of a crash."""
    m = re.search(r"\[-Werror=([\w-]+)\]", detail or "")
    if m:
        return m.group(1)
    m = re.search(r"error: ([^\n\[]*)", detail or "")
    if m and "did not compile" in detail:
        return re.sub(r"[‘'][^’']*[’']|[0-9]+", "_", m.group(1))[:80]
    m = re.search(r"runtime error: ([^\n]*)", detail or "")
    if m:
        return re.sub(r"'[^']*'|0x[0-9a-f]+|-?[0-9]+", "_", m.group(1))[:80]
    m = re.search(r"failed \((-?\d+)\)", detail or "")
    return m.group(1) if m else ""


def _first_error(err):
    line = (err or "").splitlines()[0] if err else ""
    msg = line.split("error: ", 1)[-1]
    return re.sub(r"'[^']*'|[0-9]+", "_", msg)


def first_difference(runs, engines):
    okr = [runs[e] for e in engines if runs[e].ok]
    for other in okr[1:]:
        d = compare(okr[0], other, runs["_names"], runs["_widths"])
        if d:
            return d
    bad = [runs[e] for e in engines if not runs[e].ok]
    return bad[0].detail.splitlines()[0] if bad else None


# ------------------------------------------------------------ minimiser
_OPEN = re.compile(r"\s*(IF|CASE|FOR|WHILE|REPEAT|VAR\w*|FUNCTION_BLOCK|FUNCTION|PROGRAM|"
                   r"RESOURCE|CONFIGURATION|TYPE)\b", re.I)
_CLOSE = {"IF": "END_IF", "CASE": "END_CASE", "FOR": "END_FOR", "WHILE": "END_WHILE",
          "REPEAT": "END_REPEAT", "FUNCTION_BLOCK": "END_FUNCTION_BLOCK",
          "FUNCTION": "END_FUNCTION", "PROGRAM": "END_PROGRAM", "RESOURCE": "END_RESOURCE",
          "CONFIGURATION": "END_CONFIGURATION", "TYPE": "END_TYPE"}


def _spans(lines):
    """(start, end) of every construct the generator writes over several
    lines (IF ... END_IF, VAR ... END_VAR, a POU, a resource), innermost
    included; the generator puts one construct per line."""
    out = []
    for i, s in enumerate(lines):
        m = _OPEN.match(s)
        if not m or re.search(r"\bEND_\w+\s*;?\s*$", s):
            continue
        kw = m.group(1).upper()
        if kw.startswith("VAR"):
            close = "END_VAR"
            opener = re.compile(r"\s*VAR", re.I)
        else:
            close = _CLOSE[kw]
            opener = re.compile(rf"\s*{kw}\b", re.I)
        depth = 0
        for j in range(i, len(lines)):
            t = lines[j]
            if opener.match(t) and not re.search(r"\bEND_\w+\s*;?\s*$", t):
                depth += 1
            if re.match(rf"\s*{close}\b", t, re.I):
                depth -= 1
                if depth == 0:
                    out.append((i, j + 1))
                    break
    return out


def minimise(text, events, cycles, engines, sig, workdir, budget=400, log=None):
    """Delta debugging over lines and blocks of a standalone project while the
    failure signature stays the same and the front end accepts the text
    (except when the signature is a rejection)."""
    calls = [0]

    def still(lines):
        if calls[0] >= budget:
            return False
        calls[0] += 1
        runs, err = run_text("\n".join(lines) + "\n", events, engines, cycles, workdir)
        return signature(runs, err, engines) == sig

    lines = text.splitlines()
    changed = True
    while changed and calls[0] < budget:
        changed = False
        # constructs, biggest first (a POU, a resource, a loop ...)
        tried = set()
        while calls[0] < budget:
            spans = sorted(_spans(lines), key=lambda ab: ab[0] - ab[1])
            todo = [sp for sp in spans if tuple(lines[sp[0]:sp[1]]) not in tried]
            if not todo:
                break
            a, b = todo[0]
            tried.add(tuple(lines[a:b]))
            cand = lines[:a] + lines[b:]
            if cand and still(cand):
                lines = cand
                changed = True
                if log:
                    log(f"  minimise: {len(lines)} lines ({calls[0]} runs)")
        # then single lines, bottom up
        k = len(lines) - 1
        while k >= 0 and calls[0] < budget:
            if not re.match(r"\s*(END_|ELSE|ELSIF|UNTIL)", lines[k]):
                cand = lines[:k] + lines[k + 1:]
                if still(cand):
                    lines = cand
                    changed = True
            k -= 1
        if log:
            log(f"  minimise: {len(lines)} lines ({calls[0]} runs)")
    return "\n".join(lines) + "\n", calls[0]


# ------------------------------------------------------------- campaign
def unit_seed(seed: int, i: int) -> int:
    """The seed of the i-th project of a campaign (printed; --unit reruns it)."""
    return seed * 1_000_003 + i


def _batch_job(args):
    seeds, engines, workdir, cycles, size = args
    units = [progen.generate_unit(s, k, cycles, size) for k, s in enumerate(seeds)]
    try:
        return run_units(units, engines, workdir)
    finally:
        shutil.rmtree(workdir, ignore_errors=True)


def campaign(seeds, engines, jobs=2, batch=10, cycles=100, workroot=None, progress=None,
             size=1.0):
    """Runs the projects of the given seeds in batches on `jobs` processes;
    returns [UnitResult] in seed order."""
    import multiprocessing
    workroot = Path(workroot or tempfile.mkdtemp(prefix="fuzzdiff-"))
    chunks = [seeds[i:i + batch] for i in range(0, len(seeds), batch)]
    args = [(c, engines, str(workroot / f"b{n}"), cycles, size) for n, c in enumerate(chunks)]
    out = {}
    if jobs <= 1:
        for a in args:
            r = _batch_job(a)
            out.update(r)
            if progress:
                progress(r)
    else:
        ctx = multiprocessing.get_context("fork")
        with ctx.Pool(jobs) as pool:
            for r in pool.imap_unordered(_batch_job, args):
                out.update(r)
                if progress:
                    progress(r)
    shutil.rmtree(workroot, ignore_errors=True)
    return [out[s] for s in seeds]


def minimise_unit(seed, engines, cycles, workdir, budget=300, log=None, size=1.0):
    """(minimal text, signature, first difference, runs) for a failing project."""
    u = progen.generate_unit(seed, 0, cycles, size)
    text = u.standalone()
    runs, err = run_text(text, u.trace, engines, cycles, workdir)
    sig = signature(runs, err, engines)
    if sig is None:
        return None
    small, _ = minimise(text, u.trace, cycles, engines, sig, workdir, budget=budget, log=log)
    runs, err = run_text(small, u.trace, engines, cycles, workdir)
    first = err.splitlines()[0] if runs is None else first_difference(runs, engines)
    return small, sig, first, u
