#!/usr/bin/env python3
"""Robustness campaign of `iec2kmod verify` on random projects
(tests/differential/progen.py): every project the front end accepts is either
encoded (a verdict per property) or refused with `file:line:col: error:`
naming the construct; never an internal error or a traceback; and no verdict
is contradicted by the reference interpreter.

    python3 benchmarks/verify_fuzz.py --count 200 --seed 1 --size 0.2 --depth 6
    python3 benchmarks/verify_fuzz.py --unit 1000042 --keep /tmp/found   (one project again)
    python3 benchmarks/verify_fuzz.py --smoke                            (2 projects, CI)

Per project (progen seed difftest.unit_seed(SEED, i), body size --size; SFC
bodies in about one project in ten and strings in three in ten, since the
encoding refuses them and a refusal hides the rest of the project):

  * `iec2kmod verify` (a subprocess, --timeout per project) with the
    properties TRUE, FALSE and one or two over generated configuration
    globals of elementary types (`g <= C`, `NOT b`, `b`, `r = r`, which a
    NaN violates, `r < 1000.0`), besides the implicit "no runtime error";
  * outcome: refused (exit 1 and a located error; counted by construct,
    identifiers and numbers blanked), front-end error (exit 1, no `verify:`
    error: the generator's problem, counted apart), verdicts (exit 0/3/4),
    internal error (exit 70, any other exit status, a traceback, an
    unlocated error), timeout;
  * every violated property: its counterexample CSV re-run with
    `iec2kmod sim --engine interp --inputs` to the violating cycle K, and the
    property evaluated on the simulator's CSV (or the runtime error looked
    for at cycle K) -- independently of the verifier's own replay;
  * random traces (--traces, over the inputs the verifier reports, each a
    new value with probability 0.3 per step) run with `iec2kmod sim --engine
    interp`; the properties evaluated after every step: a violation within N
    steps contradicts "holds up to N", any violation contradicts "proved".

Exit status 1 when there is an internal error or a contradicted verdict.

    python3 benchmarks/verify_fuzz.py --referee explicit --count 500 --seed 7 --depth 45

--referee explicit: the soundness campaign of issue 22 instead
(tests/verify/soundgen.py): projects with planted deep bugs over small
domains, each verified by the z3 engine (to --depth) and by the explicit
referee (`verify --engine explicit`, --max-states); every disagreement
printed with its project's seed (--unit SEED runs it again); exit 1 when
there is one."""

from __future__ import annotations

import argparse
import collections
import csv
import json
import math
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
for _p in (str(ROOT / "tests" / "verify"), str(ROOT / "tests" / "differential"), str(ROOT)):
    if _p not in sys.path:
        sys.path.insert(0, _p)

import progen  # noqa: E402

ENV = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
INT_TYPES = {"SINT": (-128, 127), "INT": (-32768, 32767), "DINT": (-2**31, 2**31 - 1),
             "LINT": (-2**63, 2**63 - 1), "USINT": (0, 255), "UINT": (0, 65535),
             "UDINT": (0, 2**32 - 1), "ULINT": (0, 2**64 - 1), "BYTE": (0, 255),
             "WORD": (0, 65535), "DWORD": (0, 2**32 - 1), "LWORD": (0, 2**64 - 1)}
ERR = re.compile(r"^(.+?):(\d+):(\d+): error: (.*)$", re.M)
FAULT = re.compile(r"runtime error: (.+?) in (\S+) \(task [^,]+, t=([0-9.]+) s\)")


def unit_seed(seed, i):
    return seed * 1_000_003 + i   # difftest.unit_seed (no import: it builds engines)


def cli(args, timeout, cwd):
    """(exit status or None on timeout, stdout, stderr, seconds)"""
    t0 = time.perf_counter()
    try:
        p = subprocess.run([sys.executable, "-m", "iec2kmod.cli"] + args, cwd=cwd, env=ENV,
                           capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None, "", "", time.perf_counter() - t0
    return p.returncode, p.stdout, p.stderr, time.perf_counter() - t0


# ------------------------------------------------------------ properties
class P:
    """A property: its ST text and its value on one row of `sim --csv`."""

    def __init__(self, text, var, test):
        self.text, self.var, self.test = text, var, test


def _num(s):
    return float(s) if any(c in s for c in ".eEna") else int(s)


def properties(unit, rnd):
    props = [P("TRUE", None, lambda v: True), P("FALSE", None, lambda v: False)]
    cands = []
    free = {path.upper() for path, _ in unit.inputs}
    for ln in unit.globals_text:
        m = re.match(r"(\w+)(?:\s+AT\s+%\S+)?\s*:\s*(\w+)\s*(?::=.*)?;$", ln)
        # not the generator's trace inputs: a property over an input is
        # violated at cycle 1 whatever the program does
        if m and m.group(1).upper() not in free:
            cands.append((m.group(1), m.group(2).upper()))
    rnd.shuffle(cands)
    # globals a program writes first (a global nothing writes is an input
    # of the verifier: a property over it is violated at cycle 1 too)
    text = unit.decl_text + unit.resources_text
    cands.sort(key=lambda c: not re.search(
        rf"(\b{c[0]}\b(\[[^\]]*\])?(\.\w+)*\s*:=(?!=)|=>\s*{c[0]}\b)", text, re.I))
    for name, ty in cands:
        if len(props) >= 4:
            break
        if ty in INT_TYPES:
            lo = INT_TYPES[ty][0]
            c = rnd.choice([0, 1, 5, 20, 40, 100]) if lo == 0 else rnd.choice([-5, 0, 3, 20, 40])
            props.append(P(f"{name} <= {c}", name, lambda v, c=c: int(v) <= c))
        elif ty == "BOOL":
            if rnd.random() < 0.5:
                props.append(P(f"NOT {name}", name, lambda v: v == "FALSE"))
            else:
                props.append(P(name, name, lambda v: v == "TRUE"))
        elif ty in ("REAL", "LREAL"):
            if rnd.random() < 0.5:
                props.append(P(f"{name} = {name}", name, lambda v: not math.isnan(float(v))))
            else:
                props.append(P(f"{name} < 1000.0", name, lambda v: float(v) < 1000.0))
    # two integers of the same signedness and maybe different widths (an
    # implicit widening inside the property)
    ints = [(n, t) for n, t in cands[:3] if t in INT_TYPES and not t.endswith("WORD")
            and t != "BYTE"]
    if len(ints) >= 2 and rnd.random() < 0.5:
        (a, ta), (b, tb) = ints[:2]
        if (ta[0] == "U") == (tb[0] == "U"):
            props.append(P(f"{a} <= {b}", (a, b), lambda v: int(v[0]) <= int(v[1])))
    return props


# ------------------------------------------------------------ verify's output
LINE = re.compile(r"^  (no runtime error|property \d+)\s+(proved|holds up to (\d+) cycles|"
                  r"violated at cycle (\d+)|unknown \(timeout\)(?:: holds up to (\d+) cycles)?)"
                  r"(.*)$", re.M)


def parse_verdicts(out):
    """{name: (status, cycle)}: status proved / bounded / violated."""
    res = {}
    for m in LINE.finditer(out):
        name, what = m.group(1), m.group(2)
        if what.startswith("proved"):
            res[name] = ("proved", None)
        elif what.startswith("unknown (timeout)"):
            # verify's --timeout: no claim past the cycles it had checked
            res[name] = ("bounded", int(m.group(5) or 0))
        elif m.group(3) is not None:
            res[name] = ("bounded", int(m.group(3)))
        else:
            res[name] = ("violated", int(m.group(4)))
    return res


_TIME = re.compile(r"([0-9.]+) (s|ms|us|ns)")


def parse_step(out):
    """The verifier's step in ns, from its first line."""
    m = re.search(r"a step is ([0-9.]+ (?:s|ms|us|ns))", out) or \
        re.search(r"every ([0-9.]+ (?:s|ms|us|ns))", out)
    if not m:
        return None
    v, u = _TIME.match(m.group(1)).groups()
    return round(float(v) * {"s": 1e9, "ms": 1e6, "us": 1e3, "ns": 1}[u])


def construct(msg):
    """A refusal's message with its identifiers and numbers blanked."""
    msg = re.sub(r"'[^']*'", "'_'", msg)
    return re.sub(r"\b\d+\b", "N", msg)


# ------------------------------------------------------------ the interpreter's runs
def sim_run(path, trace, steps, step_ns, watch, cwd, timeout):
    """Runs `sim --engine interp` over `steps` steps; returns (rows, first fault
    step or None, error text or None).  rows[k-1]: {var: text} after step k."""
    out_csv = Path(cwd) / "sim_out.csv"
    args = ["sim", "--engine", "interp", str(path), "--duration", f"{(steps - 1) * step_ns}ns",
            "--csv", str(out_csv)]
    if trace:
        args += ["--inputs", str(trace)]
    if watch:
        args += ["--watch", ",".join(watch)]
    rc, so, se, _ = cli(args, timeout, cwd)
    if rc is None:
        return None, None, "sim timed out"
    m = FAULT.search(se)
    # exit 1: a runtime error stopped a task (the run went on)
    if not (rc == 0 or rc == 1 and m) or "Traceback" in se:
        return None, None, f"sim exit {rc}: {se.strip().splitlines()[-1:] if se else ''}"
    fault = None
    if m:
        fault = round(float(m.group(3)) * 1e9 / step_ns) + 1
    rows = []
    with open(out_csv) as fh:
        changes = list(csv.DictReader(fh))
    cur, i = {}, 0
    for k in range(1, steps + 1):
        t = (k - 1) * step_ns
        while i < len(changes) and int(changes[i]["time_ns"]) <= t:
            cur.update(changes[i])
            i += 1
        rows.append(dict(cur))
    return rows, fault, None


def first_violation(prop, rows, fault):
    """The first step whose state violates prop (steps before a fault only)."""
    for k, row in enumerate(rows, 1):
        if fault is not None and k >= fault:
            return None
        if prop.var is None:
            if not prop.test(None):
                return k
        elif isinstance(prop.var, tuple):
            if all(v in row for v in prop.var) and not prop.test([row[v] for v in prop.var]):
                return k
        elif prop.var in row and not prop.test(row[prop.var]):
            return k
    return None


def _inputs_main(path, n, seed):
    """--inputs-of: prints JSON [[name, [n random values]]] of the verifier's inputs."""
    from diffverify import random_value
    from iec2kmod.cli import front_end
    from iec2kmod.diagnostics import Diagnostics
    from iec2kmod.verify import build
    from iec2kmod.traces import input_literal
    import contextlib
    import io
    with contextlib.redirect_stderr(io.StringIO()):
        project = front_end([path])
    out = build(project, [], [], None, Diagnostics())
    rnd = random.Random(seed)
    res = []
    for leaf, _, _ in out.system.inputs:
        if leaf is None:
            continue        # a faulted task's free values, a stand-in: not trace inputs
        res.append([leaf.name, [input_literal(leaf.type, random_value(rnd, leaf)) for _ in range(n)]])
    print(json.dumps(res))


def random_trace(inputs, steps, step_ns, rnd, path):
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(("time", "variable", "value"))
        for k in range(steps):
            for name, vals in inputs:
                if k == 0 or rnd.random() < 0.3:
                    w.writerow((f"{k * step_ns}ns", name, rnd.choice(vals)))


# ------------------------------------------------------------ one project
def run_project(seed, size, depth, timeout, traces, workdir):
    """A dict: outcome, and details (verdicts, refusal, problems)."""
    rnd = random.Random(seed)
    sfc, strings = rnd.random() < 0.1, rnd.random() < 0.3
    unit = progen.generate_unit(seed, 0, 100, size, sfc=sfc, strings=strings)
    wd = Path(workdir)
    wd.mkdir(parents=True, exist_ok=True)
    src = wd / f"p{seed}.st"
    src.write_text(unit.standalone())
    props = properties(unit, rnd)
    args = ["verify", str(src), "--depth", str(depth), "--cex-dir", str(wd / "cex"),
            "--timeout", str(max(1, timeout * 2 // 3))]     # the whole run's deadline
    for p in props:
        args += ["-p", p.text]
    rc, out, err, secs = cli(args, timeout, wd)
    r = {"seed": seed, "seconds": secs, "problems": [], "harness": [], "verdicts": {},
         "file": str(src)}
    if rc is None:
        r["outcome"] = "timeout"
        return r
    if "Traceback" in err or "Traceback" in out:
        r["outcome"] = "internal"
        r["problems"].append("traceback: " + err.strip().splitlines()[-1])
        return r
    if rc == 70:
        r["outcome"] = "internal"
        line = next((ln for ln in err.splitlines() if "internal error" in ln), err.strip())
        r["problems"].append(line)
        if "does not replay" in line:
            r["outcome"] = "contradicted"
        return r
    if rc == 1:
        errs = ERR.findall(err)
        verr = [e for e in errs if e[3].startswith("verify: ")]
        if verr:
            r["outcome"] = "refused"
            r["construct"] = construct(verr[0][3][len("verify: "):])
            r["where"] = f"{Path(verr[0][0]).name}:{verr[0][1]}:{verr[0][2]}"
        elif errs:
            r["outcome"] = "frontend"
            r["construct"] = construct(errs[0][3])
            r["where"] = f"{Path(errs[0][0]).name}:{errs[0][1]}:{errs[0][2]}"
        else:
            r["outcome"] = "internal"
            r["problems"].append("exit 1 without a located error: " + err.strip()[-300:])
        return r
    if rc not in (0, 3, 4):
        r["outcome"] = "internal"
        r["problems"].append(f"exit {rc}: {err.strip()[-300:]}")
        return r
    verdicts = parse_verdicts(out)
    r["verdicts"] = verdicts
    names = ["no runtime error"] + [f"property {n}" for n in range(1, len(props) + 1)]
    missing = [n for n in names if n not in verdicts]
    if missing:
        # "holds up to K; undecided ..." lines parse too; anything else is a bug
        r["outcome"] = "internal"
        r["problems"].append(f"no verdict for {missing}: {out[-400:]}")
        return r
    r["outcome"] = "verdicts"
    step = parse_step(out)
    byname = dict(zip(names[1:], props))
    watch = sorted({v for p in props if p.var for v in
                    (p.var if isinstance(p.var, tuple) else (p.var,))})
    # 1. every violation re-run in the simulator, independently of verify's replay
    for name, (status, k) in verdicts.items():
        if status != "violated":
            continue
        stem = "cex_" + re.sub(r"[^A-Za-z0-9_]+", "_", name).strip("_")
        trace = wd / "cex" / f"{stem}.csv"
        rows, fault, e = sim_run(src, trace, k, step, watch, wd, timeout)
        if e:
            r["problems"].append(f"{name}: counterexample does not run: {e}")
            continue
        if name == "no runtime error":
            if fault != k:
                r["problems"].append(f"{name}: violated at cycle {k}, but sim --inputs "
                                     f"{trace.name} faults at {fault}")
            continue
        p = byname[name]
        # a fault stops only its task: a property's counterexample may
        # fault on the way (the other tasks go on); it must break the
        # property at step k
        if first_violation(p, rows[-1:], None) is None:
            r["problems"].append(f"{name} ({p.text}): violated at cycle {k}, but sim --inputs "
                                 f"{trace.name} gives {rows[-1]} there")
    # 2. random traces against proved / holds-up-to-N
    claims = {n: v for n, v in verdicts.items() if v[0] in ("proved", "bounded")}
    if traces and claims and step:
        try:
            pr = subprocess.run([sys.executable, __file__, "--inputs-of", str(src),
                                 "--seed", str(seed)], env=ENV, capture_output=True, text=True,
                                timeout=timeout, cwd=wd)
            inputs = json.loads(pr.stdout) if pr.returncode == 0 else None
            if inputs is None:
                r["harness"].append("inputs-of failed: " + pr.stderr.strip()[-300:])
        except subprocess.TimeoutExpired:
            inputs = None
            r["trace_timeout"] = True
        if inputs is not None:
            steps = depth + 4
            for t in range(traces):
                tp = wd / f"rnd{t}.csv"
                random_trace(inputs, steps, step, rnd, tp)
                rows, fault, e = sim_run(src, tp, steps, step, watch, wd, timeout)
                if e:
                    r["harness"].append(f"random trace {t}: {e}")
                    break
                for name, (status, n) in claims.items():
                    lim = steps if status == "proved" else n
                    if name == "no runtime error":
                        bad = fault if fault is not None and fault <= lim else None
                    else:
                        bad = first_violation(byname[name], rows[:lim], fault)
                    if bad is not None:
                        what = "proved" if status == "proved" else f"holds up to {n}"
                        text = name if name == "no runtime error" else byname[name].text
                        r["problems"].append(f"{name} ({text}) {what}, but random trace "
                                             f"{tp.name} violates it at step {bad}")
                        shutil.copy(tp, wd / f"contra_{t}.csv")
    if r["problems"]:
        r["outcome"] = "contradicted"
    return r


# ------------------------------------------------------------ campaign
def campaign(seeds, size, depth, timeout, traces, workroot, keep=None, log=print):
    results = []
    for seed in seeds:
        wd = Path(workroot) / str(seed)
        r = run_project(seed, size, depth, timeout, traces, wd)
        results.append(r)
        v = r["verdicts"]
        summ = ", ".join(f"{s}" + (f"@{k}" if k else "") for s, k in v.values())
        extra = r.get("construct") or summ
        log(f"{seed}: {r['outcome']} ({r['seconds']:.1f} s) {extra}"
            + "".join(f"\n    PROBLEM: {p}" for p in r["problems"])
            + "".join(f"\n    harness: {p}" for p in r["harness"]))
        if keep and r["outcome"] in ("internal", "contradicted"):
            dst = Path(keep) / str(seed)
            shutil.copytree(wd, dst, dirs_exist_ok=True)
            log(f"    kept in {dst}")
        shutil.rmtree(wd, ignore_errors=True)
    return results


def table(results, wall):
    c = collections.Counter(r["outcome"] for r in results)
    lines = [f"{len(results)} projects in {wall:.0f} s"]
    for k in ("verdicts", "refused", "frontend", "timeout", "internal", "contradicted"):
        lines.append(f"  {k:<13} {c.get(k, 0):>5}")
    h = sum(1 for r in results if r["harness"])
    lines.append(f"  (random-trace check not run on {h} projects: harness errors)")
    vc = collections.Counter()
    for r in results:
        for name, (s, _) in r["verdicts"].items():
            vc[s] += 1
    lines.append("property verdicts (implicit 'no runtime error' included): " +
                 ", ".join(f"{s} {vc.get(s, 0)}" for s in ("proved", "bounded", "violated")))
    rc = collections.Counter(r["construct"] for r in results if r["outcome"] == "refused")
    if rc:
        lines.append("refused, by construct:")
        lines += [f"  {n:>4}  {m}" for m, n in rc.most_common()]
    fc = collections.Counter(r["construct"] for r in results if r["outcome"] == "frontend")
    if fc:
        lines.append("front-end errors (the generator's or the property's):")
        lines += [f"  {n:>4}  {m}" for m, n in fc.most_common()]
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--count", type=int, default=50)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--unit", type=int, action="append", help="this project seed only")
    ap.add_argument("--size", type=float, default=0.2, help="progen body size factor")
    ap.add_argument("--depth", type=int, default=6)
    ap.add_argument("--timeout", type=int, default=60, help="seconds per verify run")
    ap.add_argument("--traces", type=int, default=3, help="random traces per project")
    ap.add_argument("--keep", metavar="DIR", help="copy failing projects here")
    ap.add_argument("--inputs-of", help=argparse.SUPPRESS)
    ap.add_argument("--referee", choices=("traces", "explicit"), default="traces",
                    help="explicit: the soundness campaign against the explicit-state engine")
    ap.add_argument("--max-states", type=int, default=20000,
                    help="--referee explicit: states before the referee says too large")
    ap.add_argument("--jobs", type=int, default=2, help="--referee explicit: worker processes")
    ap.add_argument("--smoke", action="store_true",
                    help="a few seconds' run at a small size (CI: tests/benchmarks): 2 "
                         "projects, depth 3, one trace each (with --referee explicit: 2 "
                         "projects, depth 3, 2,000 states)")
    a = ap.parse_args(argv)
    if a.smoke:
        a.count, a.depth, a.traces, a.timeout, a.max_states = 2, 3, 1, 60, 2000
    if a.referee == "explicit":
        return referee_main(a)
    if a.inputs_of:
        _inputs_main(a.inputs_of, 8, a.seed)
        return 0
    seeds = a.unit or [unit_seed(a.seed, i) for i in range(a.count)]
    work = tempfile.mkdtemp(prefix="verify-fuzz-")
    t0 = time.time()
    try:
        res = campaign(seeds, a.size, a.depth, a.timeout, a.traces, work, a.keep,
                       log=lambda s: print(s, flush=True))
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print(table(res, time.time() - t0))
    return 1 if any(r["outcome"] in ("internal", "contradicted") for r in res) else 0


def referee_main(a):
    import soundgen
    seeds = a.unit or [a.seed * 1000 + i for i in range(a.count)]
    t0 = time.time()

    def log(r):
        x = ", ".join(f"{s}" + (f"@{k}" if s in ("violated", "vacuous") else "")
                      for s, k in r["explicit"].values())
        print(f"{r['seed']}: {'+'.join(r.get('patterns', []))} {r['states']} states "
              f"({r['explicit_s']:.1f} s), z3 {r['z3_s']:.1f} s: {x}"
              + "".join(f"\n    DISAGREEMENT: {p}" for p in r["problems"]), flush=True)
    res = soundgen.campaign(seeds, a.depth, a.timeout * 1000, a.max_states, a.jobs, log=log)
    bad = [(r["seed"], p) for r in res for p in r["problems"]]
    print(f"{len(res)} projects in {time.time() - t0:.0f} s (z3 depth {a.depth}, explicit "
          f"--max-states {a.max_states}); {len(bad)} disagreements")
    print("verdicts: " + soundgen.summary(res))
    for s, p in bad:
        print(f"  project {s}: {p}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
