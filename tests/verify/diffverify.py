"""Differential check of the verifier's encoding against the reference
interpreter: the same random input trace, cycle by cycle, every state
variable (hidden FB state included) compared after every cycle, and the
runtime faults compared.

The encoding's cycle is evaluated concretely: the pre-state and the inputs
substituted into the transition terms and simplified to constants."""

from __future__ import annotations

import math
import random

import z3

from iec2kmod.checks.types import EnumT, SubrangeT, concrete
from iec2kmod.interp.machine import LOOP_BUDGET, Machine
from iec2kmod.verify import build
from iec2kmod.verify.cex import leaf_value, lookup
from iec2kmod.verify.terms import smt_eq, base_of, const_of, kind, py_value, signed, width
from iec2kmod.diagnostics import Diagnostics


def random_value(rnd, leaf):
    t = concrete(leaf.type)
    if isinstance(t, EnumT):
        return rnd.choice([v for _, v in t.values.values()])
    if isinstance(t, SubrangeT):
        return rnd.randint(t.low, t.high)
    k = kind(t)
    if k == "bool":
        return rnd.random() < 0.5
    if k == "fp":
        x = rnd.choice([0.0, -0.0, 1.0, -1.5, 0.1, 1e30, -3.25e-3, 7.0, 2.0 ** 40,
                        rnd.uniform(-100, 100)])
        if base_of(t).bits == 32:
            from iec2kmod.interp.values import f32
            x = f32(x)
        return x
    w = width(t)
    sg = signed(t)
    lo, hi = (-(1 << (w - 1)), (1 << (w - 1)) - 1) if sg else (0, (1 << w) - 1)
    r = rnd.random()
    if r < 0.15:
        return rnd.choice([lo, hi, 0, 1, -1 if sg else 2])
    if r < 0.7:
        return max(lo, min(hi, rnd.randint(-20, 40)))
    if base_of(t).cat == "time":
        return rnd.randint(0, 3_000_000_000)
    return rnd.randint(lo, hi)


def same(a, b):
    if isinstance(a, float) or isinstance(b, float):
        a, b = float(a), float(b)
        if a != a and b != b:
            return True
        return a == b and math.copysign(1, a) == math.copysign(1, b)
    return a == b


def _model(pairs):
    """A z3 model giving each pre-state and input constant its value."""
    s = z3.Solver()
    for var, val in pairs:
        s.add(smt_eq(var, val))
    assert s.check() == z3.sat
    return s.model()


def run(project, cycles, seed, values=None):
    """Returns a list of differences (empty when the engines agree) and
    the number of cycles compared.  values(rnd, leaf, random_value) draws
    the inputs instead of random_value when given."""
    out = build(project, [], [], None, Diagnostics())
    ts = out.system
    sym = out.sym
    rnd = random.Random(seed)
    m = Machine(project)
    order = sorted(range(len(m.tasks)), key=lambda i: (m.tasks[i].priority, i))
    prev_single = [bool(t.single[0][t.single[1]]) if t.single is not None else False
                   for t in m.tasks]
    P = sym.period
    state = {var: init for _, var, init, _ in ts.state}
    diffs = []
    done = 0
    for k in range(1, cycles + 1):
        now = (k - 1) * P
        ins = {}
        for leaf, var, _ in ts.inputs:
            if leaf is None:
                continue    # the free values of a faulted task (read only after a fault)
            v = values(rnd, leaf, random_value) if values else random_value(rnd, leaf)
            c, key = lookup(m, leaf.keys)
            c[key] = v
            ins[var] = const_of(v, leaf.type)
        fault = None
        # the interpreter's scheduler at one instant (machine._schedule)
        pending = [bool(t.interval) and now % t.interval == 0 for t in m.tasks]
        while fault is None:
            for n, t in enumerate(m.tasks):
                if t.single is None:
                    continue
                c, key = t.single
                cur = bool(c[key])
                if cur and not prev_single[n]:
                    pending[n] = True
                prev_single[n] = cur
            best = next((i for i in order if pending[i]), None)
            if best is None:
                break
            pending[best] = False
            m.rt.now = now
            m.rt.budget = LOOP_BUDGET
            fault = m._run_task(m.tasks[best])
        pairs = list(state.items()) + list(ins.items())
        model = _model(pairs)
        mine = next((kind for c, kind, *_ in ts.faults
                     if z3.is_true(model.eval(c, model_completion=True))), None)
        if (fault is not None) != (mine is not None) or (fault is not None and
                                                         fault.kind != mine):
            diffs.append((k, "fault", fault.kind if fault else None, mine))
            break
        if fault is not None:
            break
        new = {}
        for leaf, var, _, post in ts.state:
            v = model.eval(post, model_completion=True)
            new[var] = v
            mine = py_value(v, leaf.type)
            theirs = leaf_value(m, leaf, now)
            if leaf.name.endswith(".$EL"):
                pass
            if not same(mine, theirs):
                diffs.append((k, leaf.name, theirs, mine))
        state = new
        done = k
        if diffs:
            break
    return diffs, done
