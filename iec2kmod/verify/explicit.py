"""`iec2kmod verify --engine explicit`: explicit-state exploration of a
configuration over the reference interpreter, the referee of the z3 engine.

It shares nothing with the z3 encoder (encode*.py, terms.py, model.py,
engine.py, ranges.py): the runs are the interpreter's own (iec2kmod.interp),
one scheduler instant at a time (Machine._instant, the code `sim --engine
interp` runs), from states saved and restored canonically.

The time point (the same as the z3 engine's): the configuration advances in
steps of the gcd of the periodic tasks' periods.  At step k (1-based, time
(k-1)*step) the inputs take their values for that step -- every valuation
of every free input --, every task released at that instant runs in
priority order (declaration order on ties; copy-in, body, copy-out; event
tasks as the interpreter's scheduler runs them at the instant), then the
assumptions and properties are evaluated on the resulting state, with the
input values that step read.  A valuation that makes an assumption FALSE at
step k is not a successor (nothing of that step is checked).  "Violated at
cycle K" is step K.  A runtime fault stops only the faulting task (its
cycle publishes none of its writes; the other tasks go on): "no runtime
error" is an implicit property violated at the fault's step, and the other
properties keep being checked after it.

The free inputs (the set the z3 engine documents in verify/__init__.py,
computed here on its own from the checked AST): %-addresses connected to
program inputs, globals no task's program writes (a write anywhere in the
program, the FBs and functions it calls -- VAR_EXTERNAL, a VAR_IN_OUT
connection --, or a connected output), program inputs connected to nothing
that the program does not write, and the variables of READ_WRITE access
paths (written before every step, whatever the cycles wrote).  An input
ranges over every value of its type: BOOL, an enumeration's values, a
subrange, an integer type's whole range; a REAL, TIME, date or string
input has too many values (too large).  The granularity is the declared
variable: an array global any element of which a program writes is state
as a whole.

Breadth-first search from the initial state, with every valuation of the
inputs at every step: a state is everything a later step can read --
globals, addresses, every program and FB instance variable at every depth
(VAR_TEMP excepted: reset at every call), the hidden state of the standard
FBs (a running timer by its elapsed time, not its start time), the edge
memories, the scheduler (which tasks are released next, which have faulted,
the event tasks' last SINGLE values) -- but not the inputs, which every
step overwrites.  Answers per property: proved (every reachable state
explored); violated at cycle K (the shortest run, its input trace written
as a `sim --inputs` CSV and replayed in the interpreter); vacuous (the
assumptions allow no run longer than K cycles: the reachable graph has no
cycle and its longest path is K steps); too large (more states than
--max-states, or more input valuations per step than --max-inputs).

Refused (VerifyError naming it): configurations without a periodic task,
SFC bodies (their steps' times are absolute), properties that fault.

The inputs, their domains and the saved states are explicit_state.py's;
the search, the properties, counterexamples and the command are here."""

from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass, field

from .. import ast
from ..checks.types import BOOL
from ..diagnostics import Diagnostics
from ..interp.compiler import PouCompiler
from .cli import EXIT_BOUNDED as EXIT_UNDECIDED  # the exit statuses are the command's
from .cli import (EXIT_INTERNAL, EXIT_PROVED, EXIT_SOURCE, EXIT_USAGE, EXIT_VACUOUS,
                  EXIT_VIOLATED, _fmt_time, cex_paths)
from ..interp.errors import Fault
from ..interp.machine import Machine
from ..traces import input_literal, write_inputs
from .clockfb import clock_user
from .explicit_state import Snapshots, VerifyError, domain, input_entries

DEFAULT_MAX_STATES = 200_000
DEFAULT_MAX_INPUTS = 4096


@dataclass
class Result:
    name: str
    status: str = "unknown"      # proved | violated | vacuous | too_large
    cycle: int = 0               # violated: K; vacuous: the longest run
    depth: int = 0               # too_large: every run of this many steps explored
    reason: str = ""             # too_large: the bound
    trace: list = field(default_factory=list)   # violated: [{input path: value}] per step
    fault: tuple | None = None   # no runtime error: (task, kind, pou, file, line)


@dataclass
class Outcome:
    results: list
    inputs: list                 # [(path, [values])]
    period: int
    tasks: list                  # [(name, interval ns or None, single var name or None)]
    states: int = 0
    transitions: int = 0
    depth: int = 0               # steps of the deepest layer explored
    seconds: float = 0.0
    assumptions: list = field(default_factory=list)   # their texts


# ------------------------------------------------------- properties
class _PropCompiler(PouCompiler):
    def expr(self, e):
        if isinstance(e, ast.Direct):
            d = self.m.directs
            key = e.address if e.address in d else e.address.upper()
            return lambda env: d[key]
        return super().expr(e)


def _scopes(m, prop, instance):
    from .props import config_scope, instance_of_path
    from . import UsageError
    ns = _NS(m)
    progs = [pi for r in m.cfg.resources for pi in r.programs]
    if prop.program is not None:
        return [(f"{path}.{prop.name}", pi.pou, inst)
                for (path, inst), pi in zip(m.instances, progs)
                if pi.pou.key == prop.program and pi.task is not None]
    if instance is not None and prop.src.path.startswith("<"):
        hit = instance_of_path(ns, instance)
        if hit is None:
            raise UsageError(f"--instance: no program instance '{instance}' (the instances: "
                             + ", ".join(p for p, _ in m.instances) + ")")
        return [(prop.name, hit[0], hit[1])]
    pou, inst = config_scope(ns)
    return [(prop.name, pou, inst)]


class _NS:
    def __init__(self, m):
        self.machine = m
        self.cfg = m.cfg


def properties(project, m, cli_props, cli_assumes, instance, diags):
    """[(kind, name, fn() -> bool, text)] bound to Machine m; None after
    errors (in diags)."""
    from .props import PropChecker, collect, parse_expr
    props = collect(project, cli_props, cli_assumes, diags)
    directs = dict(m.direct_types)
    out = []
    for p in props:
        for name, pou, inst in _scopes(m, p, instance):
            e = parse_expr(p.text, p.src, p.start, diags)
            if e is None:
                continue
            ck = PropChecker(project, diags, pou, p.src, directs)
            if not ck.check_expr(e):
                continue
            f = _PropCompiler(m, pou).expr_as(e, BOOL)

            def fn(f=f, inst=inst, p=p, e=e):
                try:
                    return bool(f(inst))
                except Fault as x:
                    raise VerifyError(p.src, e.pos, f"verify: the property faults "
                                      f"({x.kind})") from None
            out.append((p.kind, name, fn, p.text))
    if diags.errors:
        return None
    return out


# ------------------------------------------------------------ search
class Explorer:
    def __init__(self, project, cli_props=(), cli_assumes=(), instance=None, diags=None,
                 max_states=DEFAULT_MAX_STATES, max_inputs=DEFAULT_MAX_INPUTS):
        self.project = project
        self.diags = diags if diags is not None else Diagnostics()
        self.max_states, self.max_inputs = max_states, max_inputs
        m = self.m = Machine(project)
        cfg = m.cfg
        periods = [t.interval for t in m.tasks if t.single is None and t.interval]
        if not m.tasks:
            raise VerifyError(cfg.src, cfg.node.pos, "verify: the configuration has no TASK")
        if not periods:
            raise VerifyError(cfg.src, cfg.node.pos, "verify: a configuration without a "
                              "periodic task (the step of time) cannot be explored")
        if (clock := clock_user(project)) is not None:
            raise VerifyError(*clock)
        for pou in project.pous.values():
            if getattr(pou, "sfc", None) is not None and pou.node is not None and \
                    getattr(pou.node, "language", "") == "SFC":
                raise VerifyError(pou.src, pou.node.pos, "verify --engine explicit: an SFC "
                                  f"body ({pou.name}) is not explored")
        base = 0
        hyper = 1
        for p in periods:
            base = math.gcd(base, p)
            hyper = hyper * p // math.gcd(hyper, p)
        self.period, self.ticks = base, hyper // base
        self.props = properties(project, m, list(cli_props), list(cli_assumes), instance,
                                self.diags)
        self.inputs = input_entries(m)
        self.domains = []
        self.too_many = None
        count = 1
        for e, _ in self.inputs:
            d, why = domain(e)
            if d is None:
                self.too_many = f"the input {e.path} takes {why} values"
                d = [e.get()]
            count *= len(d)
            self.domains.append(d)
            e.canon = d[0]
        self.valuations = count
        if self.too_many is None and count > max_inputs:
            self.too_many = (f"{count} input valuations per step (more than --max-inputs "
                             f"{max_inputs})")

    def _released(self, tick):
        t = tick * self.period
        return [bool(tk.interval) and t % tk.interval == 0 for tk in self.m.tasks]

    def run(self):
        t0 = time.perf_counter()
        m = self.m
        props = [p for p in self.props if p[0] == "property"]
        assumes = [p[2] for p in self.props if p[0] == "assume"]
        results = [Result("no runtime error")] + [Result(name) for _, name, _, _ in props]
        out = Outcome(results, [(e.path, d) for (e, _), d in zip(self.inputs, self.domains)],
                      self.period,
                      [(t.name, t.interval or None,
                        None if t.single is None else t.single[1]) for t in m.tasks],
                      assumptions=[p[3].strip() for p in self.props if p[0] == "assume"])
        if self.too_many is not None:
            for r in results:
                r.status, r.reason = "too_large", self.too_many
            out.seconds = time.perf_counter() - t0
            return out
        snaps = Snapshots(m, self.inputs, self.period)
        ntasks = len(m.tasks)
        prev0 = [bool(t.single[0][t.single[1]]) if t.single is not None else False
                 for t in m.tasks]
        s0 = snaps.save(([False] * ntasks, prev0, [0] * ntasks), -self.period, 0)
        ids = {s0: 0}
        parent = [None]              # id -> (parent id, valuation index)
        succ = [set()]
        frontier = [0]
        states = [s0]
        open_ = list(range(len(results)))
        valuations = list(itertools.product(*self.domains))
        entries = [e for e, _ in self.inputs]
        k = 0
        cycles = [0] * ntasks
        transitions = 0
        too_large = None
        while frontier and open_:
            k += 1
            nxt = []
            for sid in frontier:
                snap = states[sid]
                tick = snap[0]
                now = tick * self.period
                released = self._released(tick)
                for vi, val in enumerate(valuations):
                    faulted, prev, late = snaps.restore(snap, now)
                    for e, x in zip(entries, val):
                        e.set(x)
                    faults = []
                    m._instant(now, list(released), faulted, prev, late, cycles, faults)
                    if not all(a() for a in assumes):
                        continue
                    transitions += 1
                    for i in list(open_):
                        r = results[i]
                        if i == 0:
                            bad = bool(faults)
                        else:
                            bad = not props[i - 1][2]()
                        if bad:
                            r.status, r.cycle = "violated", k
                            r.trace = self._trace(parent, sid, valuations) + \
                                [self._valuation(val)]
                            if i == 0:
                                r.fault = faults[0][1:]
                            open_.remove(i)
                    s = snaps.save((faulted, prev, late), now, (tick + 1) % self.ticks)
                    nid = ids.get(s)
                    if nid is None:
                        nid = len(states)
                        ids[s] = nid
                        states.append(s)
                        parent.append((sid, vi))
                        succ.append(set())
                        nxt.append(nid)
                    succ[sid].add(nid)
                if len(states) > self.max_states:
                    too_large = (f"more than {self.max_states} states (--max-states); every "
                                 f"run of {k - 1} cycles explored")
                    break
            if too_large:
                break
            frontier = nxt
        out.states, out.transitions, out.depth = len(states), transitions, k
        if too_large:
            for i in open_:
                results[i].status, results[i].reason = "too_large", too_large
                results[i].depth = k - 1
        elif open_:
            longest = _longest_run(succ)
            for i in open_:
                if longest is None:
                    results[i].status = "proved"
                else:
                    results[i].status, results[i].cycle = "vacuous", longest
        out.seconds = time.perf_counter() - t0
        return out

    def _valuation(self, val):
        return {e.path: x for (e, _), x in zip(self.inputs, val)}

    def _trace(self, parent, sid, valuations):
        steps = []
        while parent[sid] is not None:
            sid, vi = parent[sid]
            steps.append(self._valuation(valuations[vi]))
        steps.reverse()
        return steps


def _longest_run(succ):
    """None when the graph (from node 0) has a cycle (runs of every
    length); else the number of steps of its longest path."""
    n = len(succ)
    indeg = [0] * n
    for s in succ:
        for t in s:
            indeg[t] += 1
    order = [i for i in range(n) if indeg[i] == 0]
    seen = 0
    longest = [0] * n
    while order:
        i = order.pop()
        seen += 1
        for t in succ[i]:
            if longest[i] + 1 > longest[t]:
                longest[t] = longest[i] + 1
            indeg[t] -= 1
            if indeg[t] == 0:
                order.append(t)
    if seen < n:
        return None
    return max(longest)


def explore(project, cli_props=(), cli_assumes=(), instance=None, diags=None,
            max_states=DEFAULT_MAX_STATES, max_inputs=DEFAULT_MAX_INPUTS):
    """An Outcome; None after source errors (in diags).  Raises VerifyError
    for what is not explored, verify.UsageError for a bad --instance."""
    ex = Explorer(project, cli_props, cli_assumes, instance, diags, max_states, max_inputs)
    if ex.props is None:
        return None
    out = ex.run()
    out.explorer = ex
    return out


# ------------------------------------------------------ counterexamples
def write_trace(out, result, path):
    """The input trace of a violation as `sim --inputs` CSV: step k's values
    at (k-1)*step, a value written when it changes (always, for a READ_WRITE
    access path: over what the cycles wrote)."""
    ex = out.explorer
    kinds = {e.path: (e, outside) for e, outside in ex.inputs}
    last = {}
    rows = []
    for k, vals in enumerate(result.trace, 1):
        t = (k - 1) * out.period
        for name in sorted(vals):
            v = vals[name]
            e, outside = kinds[name]
            if name in last and last[name] == v and not outside:
                continue
            last[name] = v
            rows.append((f"{t}ns", name, input_literal(e.type, v)))
    return write_inputs(path, rows)


def replay(out, result, trace_path, vcd_path=None, cli_props=(), instance=None):
    """Runs the trace with `sim --engine interp`'s interpreter to (K-1)*step;
    (confirmed, message)."""
    from .. import interp
    from ..traces import write_vcd
    ex = out.explorer
    end = (result.cycle - 1) * out.period
    m = Machine(ex.project)
    table = m.table()
    res = interp.run(ex.project, end, watch=[e.path for e in table], inputs=trace_path,
                     machine=m)
    if vcd_path:
        write_vcd(res, vcd_path, table)
    if result.name == "no runtime error":
        hits = [f for f in res.faults if f[0] == end]
        if hits:
            return True, f"{hits[0][4]}:{hits[0][5]}: runtime error: {hits[0][2]}"
        return False, "the interpreter ran the trace without a runtime error at its end"
    props = properties(ex.project, m, list(cli_props), [], instance, Diagnostics())
    fn = next((p[2] for p in props or () if p[1] == result.name), None)
    if fn is None:
        return False, "the property cannot be evaluated on the replay"
    if not fn():
        return True, "the property is FALSE after that cycle"
    return False, "the interpreter's state satisfies the property"


# ------------------------------------------------------------ the command


def _duration(ns):
    if ns % 1_000_000 == 0:
        return f"{ns // 1_000_000}ms"
    return f"{ns}ns"


def run_cli(args) -> int:
    """`iec2kmod verify --engine explicit`.  Exit status: 0 every property
    proved, 1 source errors or a construct not explored, 2 usage or I/O, 3 a
    property violated, 5 vacuous (no violation), 4 too large (no violation,
    none vacuous), 70 internal error -- the z3 engine's order."""
    import shlex
    import sys
    from pathlib import Path
    from ..cli import front_end, print_diagnostics
    from . import UsageError
    if args.max_states < 1 or args.max_inputs < 1:
        print("iec2kmod: error: --max-states and --max-inputs must be at least 1",
              file=sys.stderr)
        return EXIT_USAGE
    project = front_end(args.files)
    if project is None:
        return EXIT_SOURCE
    diags = Diagnostics()
    try:
        out = explore(project, args.property, args.assume, args.instance, diags,
                      args.max_states, args.max_inputs)
    except VerifyError as exc:
        if exc.src is not None:
            diags.error(exc.src, exc.pos if exc.pos is not None else 0, exc.message)
        else:
            print(f"iec2kmod: error: {exc.message}", file=sys.stderr)
        out = None
    except UsageError as exc:
        print(f"iec2kmod: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    print_diagnostics(diags, sys.stderr)
    if out is None:
        return EXIT_SOURCE
    tasks = ", ".join(f"{n} every {_fmt_time(iv)}" if iv else f"{n} on {s}"
                      for n, iv, s in out.tasks)
    step = f"; a step is {_fmt_time(out.period)}" if len(out.tasks) > 1 else ""
    print(f"configuration {out.explorer.m.cfg.name}: task{'s' if len(out.tasks) > 1 else ''} "
          f"{tasks}{step}; {len(out.inputs)} inputs ({out.explorer.valuations} valuations a "
          f"step); {len(out.results) - 1} properties")
    print(f"explicit: {out.states} states, {out.transitions} transitions, {out.depth} "
          f"cycles deep, {out.seconds:.2f} s")
    if out.assumptions:
        print("assuming: " + "; ".join(out.assumptions))
    cex_dir = Path(args.cex_dir)
    width = max(len(r.name) for r in out.results)
    worst = EXIT_PROVED
    rank = {EXIT_PROVED: 0, EXIT_UNDECIDED: 1, EXIT_VACUOUS: 2, EXIT_VIOLATED: 3}   # as z3's
    for r in out.results:
        code = EXIT_PROVED
        if r.status == "proved":
            text = f"proved (every reachable state explored: {out.states})"
        elif r.status == "vacuous":
            code = EXIT_VACUOUS
            text = f"vacuous: the assumptions allow no run longer than {r.cycle} cycle" + \
                ("s" if r.cycle != 1 else "")
        elif r.status == "too_large":
            code = EXIT_UNDECIDED
            text = f"too large: {r.reason}"
        else:
            code = EXIT_VIOLATED
            text = f"violated at cycle {r.cycle}"
            if r.fault is not None:
                _task, kind, pou, file, line = r.fault
                text += f": {kind} in {pou} at {file}:{line}"
            try:
                cex_dir.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                print(f"iec2kmod: error: {cex_dir}: {exc.strerror}", file=sys.stderr)
                return EXIT_USAGE
            csv_path, vcd_path = cex_paths(cex_dir, r.name)
            write_trace(out, r, csv_path)
            ok, why = replay(out, r, str(csv_path), str(vcd_path), args.property,
                             args.instance)
            if not ok:
                print(f"iec2kmod: internal error: the counterexample of '{r.name}' does not "
                      f"replay in the interpreter: {why}", file=sys.stderr)
                return EXIT_INTERNAL
            files = " ".join(shlex.quote(f) for f in args.files)
            text += (f"\n{'':{width + 4}}counterexample: {csv_path} (sim --inputs), {vcd_path}"
                     f"\n{'':{width + 4}}replay: iec2kmod sim {files} --inputs "
                     f"{shlex.quote(str(csv_path))} --duration "
                     f"{_duration((r.cycle - 1) * out.period)}")
        if rank[code] > rank[worst]:
            worst = code
        print(f"  {r.name:<{width}}  {text}", flush=True)
    return worst
