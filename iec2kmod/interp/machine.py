"""The configuration at run time: globals, program instances, tasks, the
variable table, and the scheduler on a simulated clock.

Cycle model (IEC 61131-3 ed.3, 6.8.2 and the simulator's contract):
  * every periodic task is released at 0, INTERVAL, 2*INTERVAL, ...; an
    event task (SINGLE) on each rising edge of its BOOL variable, looked
    for after the inputs of an instant are applied and after every task
    cycle;
  * tasks released at the same instant run in priority order (0 first),
    ties in declaration order; a cycle runs to completion and takes no
    simulated time;
  * a task cycle runs its program instances in declaration order, each:
    copy the connected inputs in, run the body, copy the connected outputs
    out;
  * a runtime fault stops the task (the programs after it in that cycle
    do not run, its outputs are not copied, and every global it wrote in
    that cycle is put back: the kernel does not copy a faulting cycle's
    image out); the other tasks go on;
  * every loop iteration (WHILE, REPEAT, FOR, and IL backward jumps)
    costs one unit of a per-cycle budget; a cycle that exceeds it faults
    ("endless loop")."""

from __future__ import annotations

import struct
from dataclasses import dataclass, field

from .. import ast
from ..checks.types import ArrayT, EnumT, FBType, StringT, StructT, SubrangeT, concrete
from ..located import addresses_of
from .compiler import PouCompiler
from ..execmodel import (LOOP_BUDGET, MAX_TABLE_ELEMENTS, SIM_ITERATION_NS, element_path,
                         kind_of)
from ..traces import Trace, TraceError, read_trace, watch_indexes
from .errors import LOOP, OVERRUN, WATCHDOG, Fault, InterpError
from .fbs import body_of
from .model import Initializer, Instance, copier, copy_of
from .values import base_of, f32, wrap, wrap64



class Runtime:
    """What the running code reads from its task: the cycle's start time
    and the loop budget left."""

    __slots__ = ("now", "budget")

    def __init__(self):
        self.now = 0
        self.budget = LOOP_BUDGET


# a run, as the C simulator reports it too
InterpResult = Trace


@dataclass
class Entry:
    """One row of the variable table: an IEC path and where it lives."""

    path: str
    type: object
    kind: str
    size: int
    writable: bool
    owner: str
    root: object       # a dict (or list) the path starts in
    keys: tuple        # keys from the root to the value

    def get(self):
        c = self.root
        for k in self.keys[:-1]:
            c = c[k]
            if isinstance(c, Instance):
                c = c.v
        return c[self.keys[-1]]

    def set(self, v):
        c = self.root
        for k in self.keys[:-1]:
            c = c[k]
            if isinstance(c, Instance):
                c = c.v
        c[self.keys[-1]] = v


def size_of(t):
    t = concrete(t)
    if isinstance(t, SubrangeT):
        t = t.elem
    if isinstance(t, EnumT):
        return (t.elem_base.bits if t.elem_base is not None else 32) // 8
    if isinstance(t, StringT):
        return 0
    return max(1, t.bits // 8)


@dataclass
class ProgramRun:
    path: str
    inst: Instance
    body: object
    inputs: list        # (param key, fn() -> value)
    outputs: list       # (param key, (container, key), store)


@dataclass
class TaskRun:
    name: str
    interval: int
    priority: int
    single: tuple | None     # (container, key) of the SINGLE variable
    programs: list = field(default_factory=list)
    watchdog_ns: int = 0     # 0: no limit (checks/tasks.py)
    watchdog_overruns: int = 0


class Machine:
    def __init__(self, project):
        if not project.configurations:
            raise InterpError("the project has no CONFIGURATION to run")
        self.p = project
        self.rt = Runtime()
        self.init = Initializer(project)
        self.bodies = {}
        self._frame_makers = {}
        for pou in project.pous.values():
            self.bodies[pou.key] = PouCompiler(self, pou).body()
        self.cfg = project.configurations[0]
        self._build_configuration()

    # --------------------------------------------------------- storage
    def maker(self, v):
        """A function returning a fresh initial value of variable v."""
        t = concrete(v.type)
        if isinstance(t, FBType):
            return lambda: self.new_instance(t.pou, {}, v.init)
        val = self.init.value(v.type, v.init)
        cp = copier(t)
        if cp is None:
            return lambda: val
        return lambda: cp(val)

    def new_frame(self, key):
        """The activation of a FUNCTION: every variable at its initial value."""
        makers = self._frame_makers.get(key)
        if makers is None:
            pou = self.p.pous[key]
            makers = [(v.key, self.maker(v)) for v in pou.vars.values()
                      if v.section != "VAR_IN_OUT"]
            self._frame_makers[key] = makers
        f = Instance(self.p.pous[key])
        f.v = {k: mk() for k, mk in makers}
        return f

    def new_instance(self, pou, scope, init=None):
        """A program or FB instance; its externals (and those of every FB
        inside it, at every depth) bound by name to the globals of
        ``scope`` (upper name -> (container, key))."""
        inst = Instance(pou)
        given = {}
        if isinstance(init, ast.StructInit):
            given = {name.upper(): val for name, val, _ in init.fields}
        if pou.standard:
            # (v.init: the ENO of a block that keeps it, stdlib.keeping_eno)
            for v in pou.vars.values():
                inst.v[v.key] = self.init.value(v.type, given.get(v.key, v.init))
            inst.v.update(body_of(pou)[1])
            return inst
        inner = dict(scope)
        for v in pou.vars.values():
            if v.section == "VAR_GLOBAL":
                inner[v.key] = (inst.v, v.key)
        inst.s = inner
        for v in pou.vars.values():
            if v.section == "VAR_EXTERNAL":
                if v.key not in scope:
                    raise InterpError(f"VAR_EXTERNAL '{v.name}' of {pou.name} has no global")
                inst.r[v.key] = scope[v.key]
                continue
            if v.section == "VAR_IN_OUT":
                continue
            t = concrete(v.type)
            vinit = given.get(v.key, v.init)
            if isinstance(t, FBType):
                inst.v[v.key] = self.new_instance(t.pou, inner, vinit)
            elif isinstance(t, ArrayT) and isinstance(concrete(t.elem), FBType):
                inst.v[v.key] = [self.new_instance(concrete(t.elem).pou, inner, None)
                                 for _ in range(t.count)]
            else:
                inst.v[v.key] = self.init.value(v.type, vinit)
        return inst

    # --------------------------------------------------- configuration
    def _build_configuration(self):
        cfg = self.cfg
        self.implicit = cfg.resources[0].node.name is None if cfg.resources else True
        self.globals = {}
        self.cells = {}              # id(global Var) -> (container, key)
        self.global_paths = []       # (path, Var, container)
        for v in cfg.globals.values():
            self.globals[v.key] = self.init.value(v.type, v.init)
            self.cells[id(v)] = (self.globals, v.key)
            self.global_paths.append((v.name, v, self.globals))
        self.res_globals = {}
        for r in cfg.resources:
            g = {}
            self.res_globals[r.name] = g
            for v in r.globals.values():
                g[v.key] = self.init.value(v.type, v.init)
                self.cells[id(v)] = (g, v.key)
                self.global_paths.append((r.path(v.name), v, g))
        self.directs = {}            # address -> value
        self.direct_types = {}
        self.tasks = []
        self.instances = []          # (path, Instance)
        for r in cfg.resources:
            scope = {k: (self.globals, k) for k in cfg.globals}
            scope.update({k: (self.res_globals[r.name], k) for k in r.globals})
            rtasks = {}
            for t in r.tasks.values():
                tr = TaskRun(t.name if self.implicit else f"{r.name}.{t.name}",
                             t.interval_ns or 0, t.priority,
                             self.cells[id(t.single)] if t.single is not None else None,
                             watchdog_ns=t.watchdog_ns, watchdog_overruns=t.watchdog_overruns)
                self.tasks.append(tr)
                rtasks[t.name.upper()] = tr
            for pi in r.programs:
                path = r.path(pi.name)
                inst = self.new_instance(pi.pou, scope)
                for _, target, chain, init in cfg.config_inits:
                    if target is pi:        # VAR_CONFIG: an instance-specific initial value
                        holder = inst
                        for v in chain[:-1]:
                            holder = holder.v[v.key]
                        holder.v[chain[-1].key] = self.init.value(chain[-1].type, init)
                self.instances.append((path, inst))
                pc = PouCompiler(self, pi.pou)
                inputs = []
                for conn in pi.node.connections:
                    param = pi.pou.var(conn.name)
                    if param is not None and param.section == "VAR_IN_OUT":
                        # a program's in-out stands for the connected global itself
                        inst.r[param.key] = self.cells[id(conn.value.symbol)]
                for param, value in pi.inputs:
                    inputs.append((param.key, self._connection_in(pc, param, value)))
                outputs = []
                for param, target in pi.outputs:
                    if isinstance(target, ast.Direct):
                        cell = self._direct(target.address, param.type)
                        store = pc.storer(param.type, param.type)
                    else:
                        cell = self.cells[id(target.symbol)]
                        store = pc.storer(target.symbol.type, param.type)
                    outputs.append((param.key, cell, store))
                run = ProgramRun(path, inst, self.bodies[pi.pou.key], inputs, outputs)
                if pi.task is not None:
                    rtasks[pi.task.name.upper()].programs.append(run)

    def _direct(self, address, t):
        if address not in self.directs:
            self.directs[address] = self.init.default(t)
            self.direct_types[address] = t
        return (self.directs, address)

    def _connection_in(self, pc, param, value):
        store = pc.storer(param.type, getattr(value, "type", None) or param.type)
        if isinstance(value, ast.Direct):
            c, k = self._direct(value.address, param.type)
            return lambda: store(c[k])
        if isinstance(value, ast.Ref) and id(value.symbol) in self.cells:
            c, k = self.cells[id(value.symbol)]
            return lambda: store(c[k])
        if isinstance(value, ast.Lit) and value.kind in ("string", "wstring"):
            s = value.value
            return lambda: store(s)
        v = self.init.const(value, param.type)
        return lambda: v

    # ---------------------------------------------------- variable table
    def table(self):
        out = []
        for path, v, container in self.global_paths:
            self._expand(path, v.type, not v.constant, "global", container, (v.key,), out,
                         len(out) + 4096)
        for path, inst in self.instances:
            for v in inst.pou.vars.values():
                if v.section in ("VAR_EXTERNAL", "VAR_IN_OUT", "VAR_TEMP"):
                    continue
                self._expand(f"{path}.{v.name}", v.type, not v.constant and v.step is None,
                             path, inst.v,
                             (v.key,), out, len(out) + 4096)
        for address in sorted(self.directs):
            t = self.direct_types[address]
            out.append(Entry(address, t, kind_of(t), size_of(t), address[1] != "Q", "direct",
                             self.directs, (address,)))
        return out

    def _expand(self, path, t, writable, owner, root, keys, out, budget):
        if len(out) >= budget:
            return
        k = kind_of(t)
        if k is not None:
            out.append(Entry(path, t, k, size_of(t), writable, owner, root, keys))
            return
        t = concrete(t)
        if isinstance(t, ArrayT):
            dims, levels = [], []
            cur = t
            while isinstance(cur, ArrayT):
                dims += cur.dims
                levels.append(cur)
                cur = cur.elem
            count = 1
            for lo, hi in dims:
                count *= hi - lo + 1
            for n in range(min(count, MAX_TABLE_ELEMENTS)):
                # the element's keys through nested lists: one flat index per level
                ekeys = []
                rest = n
                inner_counts = [lv.count for lv in levels]
                for i in range(len(levels)):
                    below = 1
                    for c in inner_counts[i + 1:]:
                        below *= c
                    ekeys.append(rest // below)
                    rest %= below
                self._expand(element_path(path, dims, n), cur, writable, owner, root,
                             keys + tuple(ekeys), out, budget)
            return
        if isinstance(t, StructT):
            for fkey, (fname, ft, _) in t.fields.items():
                self._expand(f"{path}.{fname}", ft, writable, owner, root, keys + (fkey,), out,
                             budget)
            return
        if isinstance(t, FBType):
            pou = t.pou
            for v in pou.vars.values():
                if v.section in ("VAR_INPUT", "VAR_OUTPUT") or (not pou.standard and
                                                             v.section == "VAR"):
                    self._expand(f"{path}.{v.name}", v.type,
                                 writable and v.section != "VAR_OUTPUT" and v.step is None,
                                 owner, root,
                                 keys + (v.key,), out, budget)

    # ------------------------------------------------------------ the scheduler
    def schedule(self, table, idx, events, end):
        tasks = self.tasks
        ntasks = len(tasks)
        res = InterpResult([table[i].path for i in idx], [], end_ns=end)
        next_release = [0] * ntasks
        cycles = [0] * ntasks
        late = [0] * ntasks                # overrunning cycles in a row
        faulted = [False] * ntasks
        pending = [False] * ntasks
        prev_single = [False] * ntasks
        for n, tk in enumerate(tasks):
            if tk.single is not None:
                c, k = tk.single
                prev_single[n] = bool(c[k])
        last = {}
        watched = [(k, i, table[i]) for k, i in enumerate(idx)]
        nev = len(events)
        ev = 0
        t = 0
        while True:
            while ev < nev and events[ev][0] <= t:
                _, i, v = events[ev]
                e = table[i]
                e.set(_store_as(e, None, v))
                ev += 1
            for n, tk in enumerate(tasks):
                if tk.interval and next_release[n] == t:
                    pending[n] = True
            self._instant(t, pending, faulted, prev_single, late, cycles, res.faults)
            for k, i, e in watched:
                v = e.get()
                if i in last and _same(e.kind, v, last[i]):
                    continue
                last[i] = v
                res.changes.append((t, k, present(e, v)))
            for n, tk in enumerate(tasks):
                if tk.interval and next_release[n] == t:
                    next_release[n] += tk.interval
            nt = end + 1
            for n, tk in enumerate(tasks):
                if tk.interval and next_release[n] < nt:
                    nt = next_release[n]
            if ev < nev and events[ev][0] < nt:
                nt = events[ev][0]
            if nt > end:
                break
            t = nt
        for n, tk in enumerate(tasks):
            res.cycles[tk.name] = cycles[n]
        return res


    def _instant(self, t, pending, faulted, prev_single, late, cycles, faults):
        """One instant t of the scheduler, after the inputs of t are applied and
        the periodic tasks released at t are marked pending: the event tasks'
        edges looked for before every task run, the pending task of highest
        priority run (declaration order on ties), until none is pending.  The
        lists (one entry per task) are the scheduler's state, updated in place;
        a fault appends (t, task, kind, pou, file, line) to faults and stops
        its task (faulted).  The explicit-state verifier
        (iec2kmod.verify.explicit) runs one instant at a time through this."""
        tasks = self.tasks
        ntasks = len(tasks)
        rt = self.rt
        while True:
            for n, tk in enumerate(tasks):
                if tk.single is None:
                    continue
                c, k = tk.single
                s = bool(c[k])
                if s and not prev_single[n]:
                    pending[n] = True
                prev_single[n] = s
            best = -1
            for n in range(ntasks):
                if pending[n] and (best < 0 or tasks[n].priority < tasks[best].priority):
                    best = n
            if best < 0:
                break
            pending[best] = False
            if faulted[best]:
                continue
            rt.now = t
            tk = tasks[best]
            # the watchdog in simulated time: iterations of SIM_ITERATION_NS
            wd = tk.watchdog_ns // SIM_ITERATION_NS if tk.watchdog_ns else LOOP_BUDGET
            granted = rt.budget = min(wd, LOOP_BUDGET)
            fault = self._run_task(tk)
            cycles[best] += 1
            if fault is not None and fault.kind == LOOP and wd < LOOP_BUDGET:
                fault.kind = WATCHDOG
            if fault is None and tk.interval and tk.watchdog_overruns:
                if (granted - rt.budget) * SIM_ITERATION_NS > tk.interval:
                    late[best] += 1
                    if late[best] >= tk.watchdog_overruns:
                        self._restore_globals(self._cycle_saved)
                        fault = Fault(OVERRUN)
                else:
                    late[best] = 0
            if fault is not None:
                faulted[best] = True
                faults.append((t, tasks[best].name, fault.kind, fault.pou or "?",
                                   getattr(fault, "file", None) or "?", fault.line or 0))


    def _run_task(self, task):
        """One cycle of *task*.  The kernel publishes a task's results at the end
        of its cycle, and not at all when the cycle faults (the task's image is
        not copied out): a faulting cycle leaves every global as it was."""
        saved = self._save_globals()
        self._cycle_saved = saved
        for pr in task.programs:
            iv = pr.inst.v
            try:
                for k, f in pr.inputs:
                    iv[k] = f()
                pr.body(pr.inst)
            except Fault as f:
                self._restore_globals(saved)
                return f
            for k, (c, ck), store in pr.outputs:
                c[ck] = store(iv[k])
        return None


    def _save_globals(self):
        out = []
        for _path, v, container in self.global_paths:
            out.append((container, v.key, copy_of(v.type)(container[v.key])))
        # directly represented variables (%Q written through a connection) are
        # part of the task's image too: not published from a faulting cycle
        for address, value in self.directs.items():
            out.append((self.directs, address, list(value) if isinstance(value, list) else value))
        return out


    def _restore_globals(self, saved):
        for container, key, value in saved:
            cur = container[key]
            if isinstance(cur, list):
                cur[:] = value          # in place: references to the array stay valid
            elif isinstance(cur, dict):
                cur.clear()
                cur.update(value)
            else:
                container[key] = value


def _store_as(entry, kind, value):
    """An input value stored the way a write through the table stores it."""
    t = base_of(entry.type)
    if entry.kind == "f":
        x = float(value)
        return f32(x) if t.bits == 32 else x
    if entry.kind == "b":
        return bool(int(value) & 0xFF)
    if entry.kind == "e":
        bits = size_of(entry.type) * 8
        v = int(value) & ((1 << bits) - 1)
        return v - (1 << bits) if v >> (bits - 1) else v
    if entry.kind == "t":
        return wrap64(int(value))
    return wrap(int(value), t)


def present(entry, v):
    """A value as the simulator reports it (sim.SimResult.changes)."""
    if entry.kind == "e":
        t = concrete(entry.type)
        for name, val in t.values.values():
            if val == v:
                return name
        return v
    if entry.kind == "b":
        return bool(v)
    return v


_D = struct.Struct("<d")


def run(project, end_ns: int, watch=None, inputs=None, machine=None) -> InterpResult:
    """Runs the configuration from 0 to end_ns (inclusive) of simulated time
    (on ``machine``, a fresh Machine of the project, when given)."""
    m = machine if machine is not None else Machine(project)
    table = m.table()
    addresses = addresses_of(project)
    try:
        idx = watch_indexes(table, addresses, watch)
    except TraceError as exc:
        raise InterpError(str(exc)) from None
    try:
        events = read_trace(inputs, table, addresses) if inputs else []
    except TraceError as exc:
        raise InterpError(str(exc)) from None
    return m.schedule(table, idx, [(t, i, v) for t, _, i, _, v in events], end_ns)


def _same(kind, a, b):
    if kind == "f":
        return _D.pack(a) == _D.pack(b)
    return a == b and type(a) is type(b)

