"""The configuration as a transition system: state, inputs, one cycle.

A SymbolicMachine starts from the reference interpreter's Machine (its
storage, initial values and VAR_EXTERNAL bindings are reused as they are)
and replaces every scalar in it by a z3 constant named after its path
(``crossing.phase``, ``crossing.phase_timer.$S``).  Running the cycle
symbolically (encode.Encoder) leaves in each place the term of its value
after the cycle, as a function of those constants: the transition relation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import z3

from ..checks.types import ArrayT, EnumT, FBType, StringT, StructT, SubrangeT, concrete
from ..checks.types import BOOL as _BOOL, TIME as _TIME, Elementary
from ..interp.machine import Machine
from ..interp.model import Instance
from .encode import Encoder
from .terms import (FALSE, INT64_MAX, TRUE, UNROLL, WORK, Frame, Opaque, Refuse, bv_lit,
                    const_of, ite, kind, land, lnot, lor, signed, sort_of, store_into)


@dataclass
class Leaf:
    name: str
    type: object
    c: object            # container
    k: object            # key
    init: object         # Python value (interpreter representation)
    var: object = None   # the z3 constant of the pre-state
    role: str = "state"  # state | input | const
    candidate: bool = False   # may be an input (global, %I, unconnected program input)
    hidden: bool = False
    keys: tuple = ()     # (root name, keys...) to find it in another Machine
    outside: bool = False     # written between cycles (a READ_WRITE access path)


@dataclass
class Cycle:
    """One task cycle: post-state terms, fault sites, input domains."""

    post: dict = field(default_factory=dict)      # leaf name -> term
    faults: list = field(default_factory=list)    # (cond, kind, pou, src, pos)


class SymbolicMachine:
    def __init__(self, project):
        self.project = project
        self.machine = Machine(project)
        m = self.machine
        self.cfg = m.cfg
        self.leaves: list[Leaf] = []
        self.by_name: dict[str, Leaf] = {}
        self.timers: list[Instance] = []
        self._check_shape()
        for path, v, container in m.global_paths:
            root = self._root_of(container)
            self._slot(container, v.key, v.type, path, candidate=not v.constant,
                       keys=(root, v.key))
        for address in sorted(m.directs):
            t = m.direct_types[address]
            self._slot(m.directs, address, t, address, candidate=True,
                       keys=("%", address))
        self.unconnected = set()
        for (path, inst), pi in zip(m.instances, self.programs):
            connected = {c.name.upper() for c in pi.node.connections}
            # a program's located %I variable is an input of the process
            # image, as a located %I global is: free where no cycle writes it
            self._instance(inst, path, keys=("I", path), unconnected={
                v.key for v in pi.pou.inputs if v.key not in connected} | {
                v.key for v in pi.pou.vars.values() if (v.location or "")[:2] == "%I"})
        self.clock = {"$tick": 0}
        if self.ticks > 1:
            self._hidden(self.clock, "$tick", Elementary("$TICK", "uint",
                                                         max(1, (self.ticks - 1).bit_length()),
                                                         None), "$tick", ("T",))
            leaf = self.by_name["$tick"]
            leaf.period, leaf.ticks = self.period, self.ticks
        # a task stopped by a runtime fault: it never runs again, the
        # other tasks go on (a constant FALSE when no cycle of it can fault)
        self.havoc = []             # [(constant, domain)]: free values (inputs)
        # [(placeholder Bool, the task's fault condition)]: the placeholder
        # stands for "this task faults in this step" in the post terms;
        # build() puts the condition in (or FALSE, for the system used once
        # 'no runtime error' is proved)
        self.fault_flags = []
        for t in self.tasks:
            self.clock["$stop_" + t.name] = False
            self._hidden(self.clock, "$stop_" + t.name, _BOOL, "$stop_" + t.name,
                         ("S", t.name))
        for t in self.events:
            # the SINGLE variable's value at the last edge detection (its initial value)
            c, k = self.machine.cells[id(t.single)]
            init = c[k]
            self.clock["$prev_" + t.name] = bool(init.init) if hasattr(init, "init") else \
                self._initial_of(c, k)
            self._hidden(self.clock, "$prev_" + t.name, _BOOL, "$prev_" + t.name,
                         ("E", t.name))
            single = next((lf for lf in self.leaves if lf.c is c and lf.k == k), None)
            self.by_name["$prev_" + t.name].single_keys = single.keys if single else None

    # ------------------------------------------------------------ shape
    def _check_shape(self):
        cfg = self.cfg
        self.programs = [pi for r in cfg.resources for pi in r.programs]
        tasks = [(r, t) for r in cfg.resources for t in r.tasks.values()]
        src = cfg.src
        if not tasks:
            raise Refuse(src, cfg.node.pos, "verify: the configuration has no TASK")
        periods = [t.interval_ns for _, t in tasks if t.single is None and t.interval_ns]
        if not periods:
            raise Refuse(src, tasks[0][1].pos, "verify: a configuration without a periodic "
                                               "task (the step of time) cannot be encoded")
        self.events = [t for _, t in tasks if t.single is not None]
        base = 0
        for p in periods:
            base = math.gcd(base, p)
        hyper = 1
        for p in periods:
            hyper = hyper * p // math.gcd(hyper, p)
        if hyper // base > 1 << 16:
            raise Refuse(src, tasks[0][1].pos, "verify: task periods whose hyperperiod is more "
                                               f"than 65536 steps of {base} ns")
        self.period = base                 # the step: one instant of the scheduler
        self.ticks = hyper // base
        # tasks as the scheduler runs them at one instant: priority, then declaration
        order = sorted(range(len(tasks)), key=lambda i: (tasks[i][1].priority, i))
        self.tasks = [tasks[i][1] for i in order]
        self.task = self.tasks[0]

    def task_runs(self, tick):
        """[(TaskInfo, guard)] in the order they run at an instant."""
        out = []
        for t in self.tasks:
            if t.single is not None:
                continue
            r = t.interval_ns // self.period
            if r == 1 or tick is None:
                out.append((t, TRUE))
            else:
                w = tick.size()
                out.append((t, z3.URem(tick, z3.BitVecVal(r, w)) == z3.BitVecVal(0, w)))
        return out

    def _initial_of(self, c, k):
        v = c[k]
        for leaf in self.leaves:
            if leaf.c is c and leaf.k == k:
                return bool(leaf.init)
        return bool(v) if isinstance(v, bool) else False

    def _root_of(self, container):
        m = self.machine
        if container is m.globals:
            return "G"
        for name, g in m.res_globals.items():
            if g is container:
                return "R:" + name
        raise AssertionError("global container")

    # --------------------------------------------------------- leaves
    def _leaf(self, c, k, t, name, candidate=False, hidden=False, keys=()):
        init = c[k]
        if isinstance(concrete(t), StringT):
            c[k] = Opaque(name, t)
            return
        s = sort_of(t)
        var = z3.Const(name, s)
        leaf = Leaf(name, t, c, k, init, var, candidate=candidate, hidden=hidden, keys=keys)
        self.leaves.append(leaf)
        self.by_name[name] = leaf
        c[k] = var

    def _slot(self, c, k, t, name, candidate=False, keys=()):
        ct = concrete(t)
        if isinstance(ct, FBType):
            self._instance(c[k], name, keys=keys)
        elif isinstance(ct, ArrayT):
            lst = c[k]
            for i in range(len(lst)):
                self._slot(lst, i, ct.elem, f"{name}[{self._index_text(ct, i)}]", candidate,
                           keys + (i,))
        elif isinstance(ct, StructT):
            for fk, (fname, ft, _) in ct.fields.items():
                self._slot(c[k], fk, ft, f"{name}.{fname}", candidate, keys + (fk,))
        else:
            self._leaf(c, k, t, name, candidate, keys=keys)

    @staticmethod
    def _index_text(t, n):
        cur = t
        rem = n
        parts = []
        for lo, hi in reversed(cur.dims):
            size = hi - lo + 1
            parts.append(lo + rem % size)
            rem //= size
        parts.reverse()
        return ",".join(map(str, parts))

    def _instance(self, inst, path, keys, unconnected=()):
        pou = inst.pou
        if pou.standard:
            self._standard(inst, path, keys)
            return
        for v in pou.vars.values():
            if v.section in ("VAR_EXTERNAL", "VAR_IN_OUT", "VAR_TEMP"):
                if v.section == "VAR_TEMP" and v.key in inst.v:
                    self.constify(inst.v, v.key, v.type)
                continue
            self._slot(inst.v, v.key, v.type, f"{path}.{v.name}",
                       candidate=v.key in unconnected, keys=keys + (v.key,))
        for v in pou.inputs:
            if v.edge:
                inst.e["$" + v.key] = False
                self._leaf(inst.e, "$" + v.key, _BOOL, f"{path}.${v.name}", hidden=True,
                           keys=keys + (("e", "$" + v.key),))
                inst.e[v.key] = FALSE

    def _standard(self, inst, path, keys):
        pou = inst.pou
        name = pou.name.upper()
        for v in pou.vars.values():
            self._leaf(inst.v, v.key, v.type, f"{path}.{v.name}", keys=keys + (v.key,))
        hidden = {"$M": _BOOL, "$CU": _BOOL, "$CD": _BOOL, "$LAST": _BOOL}
        for k, t in hidden.items():
            if k in inst.v:
                if name in ("TON", "TOF") and k == "$LAST":
                    del inst.v[k]
                    continue
                self._leaf(inst.v, k, t, f"{path}.{k}", hidden=True, keys=keys + (k,))
        if "$S" in inst.v:
            # timer: state as 2 bits, the time since its start instead of T0
            self._hidden(inst.v, "$S", STATE2, f"{path}.$S", keys + ("$S",))
            del inst.v["$T0"]
            inst.v["$EL"] = 0
            self._hidden(inst.v, "$EL", _TIME, f"{path}.$EL", keys + ("$EL",))
            self.timers.append(inst)

    def _hidden(self, c, k, t, name, keys):
        init = c[k]
        var = z3.Const(name, sort_of(t))
        leaf = Leaf(name, t, c, k, init, var, hidden=True, keys=keys)
        self.leaves.append(leaf)
        self.by_name[name] = leaf
        c[k] = var

    # ------------------------------------------------ fresh constants
    def constify(self, c, k, t):
        """Python value(s) at c[k] turned into z3 constants (not leaves)."""
        ct = concrete(t)
        v = c[k]
        if isinstance(ct, FBType):
            self.const_instance(v)
        elif isinstance(ct, ArrayT):
            for i in range(len(v)):
                self.constify(v, i, ct.elem)
        elif isinstance(ct, StructT):
            for fk, (_, ft, _) in ct.fields.items():
                self.constify(v, fk, ft)
        elif isinstance(ct, StringT):
            c[k] = Opaque(k, t)
        else:
            c[k] = const_of(v, ct)

    def const_instance(self, inst):
        pou = inst.pou
        for v in pou.vars.values():
            if v.section in ("VAR_EXTERNAL", "VAR_IN_OUT"):
                continue
            if v.key in inst.v:
                self.constify(inst.v, v.key, v.type)
        for k in ("$M", "$CU", "$CD", "$LAST"):
            if k in inst.v:
                inst.v[k] = z3.BoolVal(bool(inst.v[k]))
        if "$S" in inst.v:
            inst.v["$S"] = z3.BitVecVal(inst.v["$S"], 2)
            inst.v.pop("$T0", None)
            inst.v["$EL"] = z3.BitVecVal(0, 64)
        if not pou.standard:
            for v in pou.inputs:
                if v.edge:
                    inst.e["$" + v.key] = FALSE
                    inst.e[v.key] = FALSE

    def fresh_value(self, v):
        holder = {"x": self.machine.init.value(v.type, v.init)}
        self.constify(holder, "x", v.type)
        return holder["x"]

    def fresh_instance_value(self, v, owner):
        t = concrete(v.type)
        m = self.machine
        if isinstance(t, FBType):
            inst = m.new_instance(t.pou, owner.s, v.init)
            self.const_instance(inst)
            return inst
        lst = [m.new_instance(concrete(t.elem).pou, owner.s, None) for _ in range(t.count)]
        for i in lst:
            self.const_instance(i)
        return lst

    def direct_value(self, address):
        return self.machine.directs[address]

    # ------------------------------------------------------------ cycle
    def run_cycle(self, enc: Encoder):
        """Executes one cycle of the task on the storage (in place)."""
        m = self.machine
        P = self.period
        for inst in self.timers:
            el = inst.v["$EL"]
            grown = z3.If(z3.UGT(el, bv_lit(INT64_MAX - P, 64)), bv_lit(INT64_MAX, 64),
                          el + bv_lit(P, 64))
            inst.v["$EL"] = z3.If(inst.v["$S"] == z3.BitVecVal(WORK, 2), grown, bv_lit(0, 64))
        insts = {id(pi): inst for (_, inst), pi in zip(m.instances, self.programs)}
        tick = self.clock["$tick"] if self.ticks > 1 else None

        published = [lf for lf in self.leaves
                     if lf.keys and (lf.keys[0] in ("G", "%") or str(lf.keys[0]).startswith("R:"))]

        def run_task(task, g):
            # a stopped task does not run; a cycle that faults publishes
            # none of its writes to globals and %Q/%M (the kernel does not
            # copy its image out) and stops its task.  The variables of its
            # program instances keep, in the interpreter and the kernel,
            # what the cycle wrote before the statement that faulted: any
            # value here (free: what is proved holds for every one of them)
            stop_key = "$stop_" + task.name
            stop = self.clock[stop_key]
            g = land(g, lnot(stop))
            before = [(lf, lf.c[lf.k]) for lf in published]
            n0 = len(enc.faults)
            mine = [pi for pi in self.programs if pi.task is task]
            for pi in mine:
                self.run_program(enc, pi, insts[id(pi)], g)
            real = [c for c, kind, *_ in enc.faults[n0:] if not kind.startswith(UNROLL)]
            if not real:
                return
            f = z3.Bool(f"$fault_{task.name}#{len(self.fault_flags)}")
            self.fault_flags.append((f, lor(*real)))
            for lf, old in before:
                cur = lf.c[lf.k]
                if not (z3.is_expr(cur) and z3.is_expr(old) and cur.eq(old)):
                    lf.c[lf.k] = ite(f, old, cur)
            for (path, _), pi in zip(m.instances, self.programs):
                if pi.task is not task:
                    continue
                for lf in self.leaves:
                    cur = lf.c[lf.k]
                    if z3.is_expr(cur) and cur.eq(lf.var):
                        continue    # not written by the cycle (an input stays one)
                    if lf.keys[:2] == ("I", path):
                        h = z3.Const(f"$havoc{len(self.havoc)}:{lf.name}", lf.var.sort())
                        self.havoc.append((h, self.domain(lf, h)))
                        lf.c[lf.k] = ite(f, h, lf.c[lf.k])
            self.clock[stop_key] = z3.Or(stop, f)
        if not self.events:
            for task, g in self.task_runs(tick):
                run_task(task, g)
        else:
            self.schedule_with_events(enc, tick, run_task)
        if tick is not None:
            w = tick.size()
            self.clock["$tick"] = z3.If(tick == z3.BitVecVal(self.ticks - 1, w),
                                        z3.BitVecVal(0, w), tick + z3.BitVecVal(1, w))

    def schedule_with_events(self, enc, tick, run_task):
        """The interpreter's scheduler at one instant, unrolled: look for
        rising edges of the SINGLE variables, run the highest-priority
        pending task, again until nothing is pending.  An instant needing
        more task runs than unrolled is reported undecided."""
        pending = {id(t): g for t, g in self.task_runs(tick)}
        for t in self.events:
            pending[id(t)] = FALSE

        def detect():
            for t in self.events:
                c, k = self.machine.cells[id(t.single)]
                cur = c[k]
                prev = self.clock["$prev_" + t.name]
                pending[id(t)] = z3.Or(pending[id(t)], z3.And(cur, z3.Not(prev)))
                self.clock["$prev_" + t.name] = cur
        rounds = len(self.tasks) + len(self.events)
        for _ in range(rounds):
            detect()
            higher = FALSE
            runs = []
            for t in self.tasks:
                run = land(pending[id(t)], lnot(higher))
                higher = z3.Or(higher, pending[id(t)])
                runs.append((t, run))
            if z3.is_false(z3.simplify(higher)):
                return
            for t, run in runs:
                if z3.is_false(run):
                    continue
                run_task(t, run)
                pending[id(t)] = land(pending[id(t)], lnot(run))
        detect()
        left = z3.Or(*[pending[id(t)] for t in self.tasks])
        enc.faults.append((left, f"{UNROLL}more than {rounds} task runs in one instant (the "
                                 "encoding's unrolling of the scheduler)", "scheduler",
                           self.cfg.src, self.tasks[0].pos))

    def run_program(self, enc, pi, inst, g):
        m = self.machine
        frame = Frame(inst, pi.pou)
        iv = inst.v
        for param, value in pi.inputs:
            val, vt = self.connection_value(value, param, enc, frame)
            new = enc.store_value(val, vt, param.type, frame, g, getattr(value, "pos", None))
            store_into(iv, param.key, g, new)
        enc.run_body(pi.pou, inst, g)
        for param, target in pi.outputs:
            val = iv[param.key]
            if hasattr(target, "address"):
                c, k = m._direct(target.address, param.type)
                tt = param.type
            else:
                c, k = m.cells[id(target.symbol)]
                tt = target.symbol.type
            new = enc.store_value(val, param.type, tt, frame, g, getattr(target, "pos", None))
            store_into(c, k, g, new)

    def connection_value(self, value, param, enc, frame):
        m = self.machine
        if hasattr(value, "address"):
            return m.directs[value.address], param.type
        sym = getattr(value, "symbol", None)
        if sym is not None and id(sym) in m.cells:
            c, k = m.cells[id(sym)]
            v = c[k]
            if isinstance(v, Opaque):
                raise Refuse(self.cfg.src, value.pos, "verify: a STRING connection cannot "
                                                      "be encoded exactly")
            return v, sym.type
        if getattr(value, "kind", None) in ("string", "wstring"):
            raise Refuse(self.cfg.src, value.pos, "verify: a STRING connection cannot be "
                                                  "encoded exactly")
        return const_of(m.init.const(value, param.type), concrete(param.type)), param.type

    # ------------------------------------------------------ input domain
    def domain(self, leaf, var):
        """The values an input may take: its type's (an enumeration's values,
        a subrange's range; REAL inputs finite: a trace cannot write NaN)."""
        t = concrete(leaf.type)
        if isinstance(t, EnumT):
            w = var.size()
            return z3.Or(*[var == bv_lit(v, w) for _, v in t.values.values()])
        if isinstance(t, SubrangeT):
            w = var.size()
            if kind(t) == "bv":
                lo, hi = bv_lit(t.low, w), bv_lit(t.high, w)
                if signed(t):
                    return z3.And(var >= lo, var <= hi)
                return z3.And(z3.UGE(var, lo), z3.ULE(var, hi))
        if kind(t) == "fp":
            return z3.Not(z3.Or(z3.fpIsNaN(var), z3.fpIsInf(var)))
        return TRUE

    def invariant_candidates(self, var_of):
        """Facts about hidden and typed state that hold in every reachable
        state; they are only used once proved (Houdini, engine.py)."""
        out = []
        for leaf in self.leaves:
            if leaf.role != "state":
                continue
            v = var_of(leaf)
            if leaf.name == "$tick":
                w = v.size()
                out.append(("$tick < hyperperiod", z3.ULE(v, z3.BitVecVal(self.ticks - 1, w))))
            elif leaf.name.endswith(".$S") and leaf.hidden:
                out.append((f"{leaf.name} valid", z3.ULE(v, z3.BitVecVal(3, 2))))
            elif leaf.name.endswith(".$EL") and leaf.hidden:
                out.append((f"{leaf.name} >= 0", v >= bv_lit(0, 64)))
                base = leaf.name[:-4]
                pt = self.by_name.get(base + ".PT")
                st = self.by_name.get(base + ".$S")
                if pt is not None and st is not None and pt.role != "input":
                    ptv = var_of(pt) if pt.role == "state" else const_of(pt.init, pt.type)
                    stv = var_of(st)
                    out.append((f"{leaf.name} < PT in Work",
                                z3.Implies(stv == z3.BitVecVal(WORK, 2), v < ptv)))
                    out.append((f"{leaf.name} is 0 outside Work",
                                z3.Implies(stv != z3.BitVecVal(WORK, 2), v == bv_lit(0, 64))))
            else:
                t = concrete(leaf.type)
                if isinstance(t, (EnumT, SubrangeT)):
                    out.append((f"{leaf.name} in its type", self.domain(leaf, v)))
        return out



STATE2 = Elementary("$STATE", "uint", 2, None)   # a timer's automaton location
