"""Bounded model checking and k-induction over the transition system.

    state    X: every leaf a cycle may change (z3 constants, one set per step)
    inputs   U: the free leaves, fresh in every cycle, inside their domain
    T(X, U)  the post-cycle value of each state leaf
    F(X, U)  a runtime fault happens in the cycle (a violation)
    P(X, U)  each property, on the state after the cycle
    A(X, U)  the assumptions, on the state at the start of the cycle

BMC unrolls from the initial state; cycle k is checked once every cycle
before it held (so the first violation is the one reported).  k-induction
proves "for every path of k+1 cycles from any state satisfying the proved
invariants, if the first k cycles hold so does the last"; with the base case
to depth k+1 this proves the property for every depth.  Paths in the
induction step are kept simple (pairwise distinct states), which makes the
method complete for finite state.  Invariants about hidden state (timer
locations, enumeration ranges...) are candidates proved first by Houdini
(one-step induction, dropping the ones that fail until the rest is
inductive): only proved ones strengthen the induction."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import z3

from .encode import FALSE, TRUE, UNROLL, land, lnot, lor, smt_eq


@dataclass
class Result:
    name: str
    status: str = "unknown"   # proved | bounded | violated | unknown
    cycle: int = 0            # violated: the cycle; bounded: the depth
    k: int = 0                # proved: the induction depth
    seconds: float = 0.0
    model: object = None      # violated: the z3 model of the path
    fault: tuple | None = None
    invariants: list = field(default_factory=list)


@dataclass
class System:
    state: list               # [(leaf, var, init term, post term)]
    inputs: list              # [(leaf, var, domain term)]
    faults: list              # [(cond, kind, pou, src, pos)]
    props: list               # [(name, term)]
    assume: object            # term
    invariants: list = field(default_factory=list)   # [(name, term over state vars)]


class Unroller:
    def __init__(self, ts: System, tag: str):
        self.ts = ts
        self.tag = tag
        self.X = []     # per step: {var: term}
        self.U = []

    def vars_at(self, k, initial=None):
        if initial is not None:
            m = {var: init for _, var, init, _ in self.ts.state}
        else:
            m = {var: z3.Const(f"{var}@{self.tag}{k}", var.sort())
                 for _, var, _, _ in self.ts.state}
        self.X.append(m)
        return m

    def step(self, k):
        """Adds step k (1-based): inputs U_k, state X_k; returns (constraints,
        subst pairs for evaluating terms of cycle k)."""
        ts = self.ts
        U = {var: z3.Const(f"{var}@{self.tag}{k}", var.sort()) for _, var, _ in ts.inputs}
        self.U.append(U)
        pre = self.X[k - 1]
        pairs = list(pre.items()) + list(U.items())
        X = {}
        cons = []
        for _, var, _, post in ts.state:
            nv = z3.Const(f"{var}@{self.tag}{k}", var.sort())
            X[var] = nv
            cons.append(smt_eq(nv, z3.substitute(post, *pairs) if pairs else post))
        self.X.append(X)
        for _, var, dom in ts.inputs:
            if not z3.is_true(dom):
                cons.append(z3.substitute(dom, (var, U[var])))
        if not z3.is_true(ts.assume):
            cons.append(z3.substitute(ts.assume, *pairs) if pairs else ts.assume)
        return cons, pairs

    @staticmethod
    def sub(term, pairs):
        return z3.substitute(term, *pairs) if pairs else term


def _fault_term(ts, pairs):
    return lor(*[Unroller.sub(c, pairs) for c, *_ in ts.faults])


def houdini(ts: System, timeout_ms: int):
    """The subset of ts.invariants that holds initially and is inductive."""
    cands = []
    init_pairs = [(var, init) for _, var, init, _ in ts.state]
    for name, term in ts.invariants:
        v = z3.simplify(z3.substitute(term, *init_pairs)) if init_pairs else term
        if z3.is_true(v):
            cands.append((name, term))
    if not cands:
        return []
    u = Unroller(ts, "h")
    u.vars_at(0)
    s = z3.Solver()
    s.set("timeout", timeout_ms)
    cons, pairs = u.step(1)
    s.add(*cons)
    s.add(lnot(_fault_term(ts, pairs)))
    pre_pairs = [(var, u.X[0][var]) for _, var, _, _ in ts.state]
    post_pairs = [(var, u.X[1][var]) for _, var, _, _ in ts.state]
    while cands:
        s.push()
        for _, term in cands:
            s.add(Unroller.sub(term, pre_pairs))
        bad = []
        for i, (name, term) in enumerate(cands):
            s.push()
            s.add(lnot(Unroller.sub(term, post_pairs)))
            r = s.check()
            s.pop()
            if r != z3.unsat:
                bad.append(i)
        s.pop()
        if not bad:
            return cands
        cands = [c for i, c in enumerate(cands) if i not in bad]
    return []


def free_consts(terms):
    """The uninterpreted constants the terms read."""
    seen = set()
    out = {}
    stack = [t for t in terms if z3.is_expr(t)]
    while stack:
        t = stack.pop()
        i = t.get_id()
        if i in seen:
            continue
        seen.add(i)
        if z3.is_const(t) and t.decl().kind() == z3.Z3_OP_UNINTERPRETED:
            out[i] = t
            continue
        stack.extend(t.children())
    return out


def restrict(ts: System, roots):
    """The cone of influence of the root terms: the state variables they
    read, the ones those are computed from, and so on; the inputs read."""
    post = {var.get_id(): (leaf, var, init, p) for leaf, var, init, p in ts.state}
    need = {}
    todo = list(free_consts(list(roots) + [ts.assume]).values())
    while todo:
        v = todo.pop()
        i = v.get_id()
        if i in need or i not in post:
            continue
        need[i] = post[i]
        todo.extend(free_consts([post[i][3]]).values())
    state = [x for x in ts.state if x[1].get_id() in need]
    used = free_consts([x[3] for x in state] + list(roots) + [ts.assume])
    inputs = [x for x in ts.inputs if x[1].get_id() in used]
    inv = [(n, t) for n, t in ts.invariants
           if all(i in need for i in free_consts([t]))]
    return System(state, inputs, ts.faults, ts.props, ts.assume, inv)


def check(ts: System, depth: int, timeout_ms: int = 60000, log=None):
    """Results for every property, the first one 'no runtime error'.  Each
    one is decided on its own cone of influence; the properties are checked
    on runs without a runtime error unless none can happen (proved)."""
    fault_roots = [c for c, *_ in ts.faults]
    t0 = time.perf_counter()
    sub = restrict(ts, fault_roots)
    first = check_one(sub, "no runtime error", None, depth, timeout_ms, no_fault=False)
    first.seconds = time.perf_counter() - t0
    results = [first]
    invs = set()
    for name, term in ts.props:
        t0 = time.perf_counter()
        no_fault = first.status != "proved" and bool(ts.faults)
        sub = restrict(ts, [term] + (fault_roots if no_fault else []))
        r = check_one(sub, name, term, depth, timeout_ms, no_fault=no_fault)
        r.seconds = time.perf_counter() - t0
        results.append(r)
        invs.update(n for n, _ in r.invariants)
    return results, sorted(invs)


def check_one(ts: System, name, prop, depth, timeout_ms, no_fault):
    """BMC to ``depth`` cycles and k-induction of one property (prop None:
    no runtime error)."""
    res = Result(name)
    if prop is not None and z3.is_true(z3.simplify(prop)):
        # true after every cycle from every state: no solving needed
        res.status, res.k = "proved", 1
        return res
    inv = houdini(ts, timeout_ms)
    res.invariants = inv

    def viol(pairs):
        if prop is None:
            return _fault_term(ts, pairs)
        return lnot(Unroller.sub(prop, pairs))

    def good(pairs):
        g = [lnot(viol(pairs))]
        if no_fault:
            g.append(lnot(_fault_term(ts, pairs)))
        return g

    base = z3.Solver()
    base.set("timeout", timeout_ms)
    bu = Unroller(ts, "b")
    bu.vars_at(0, initial=True)
    ind = z3.Solver()
    ind.set("timeout", timeout_ms)
    iu = Unroller(ts, "i")
    iu.vars_at(0)
    y0 = [(var, iu.X[0][var]) for _, var, _, _ in ts.state]
    for _, term in inv:
        ind.add(Unroller.sub(term, y0))
    ind_pairs = None
    for k in range(1, depth + 1):
        cons, pairs = bu.step(k)
        base.add(*cons)
        base.push()
        base.add(viol(pairs))
        if no_fault and prop is not None:
            base.add(lnot(_fault_term(ts, pairs)))
        r = base.check()
        if r == z3.sat:
            res.status, res.cycle, res.model = "violated", k, base.model()
            if prop is None:
                res.fault = _which_fault(ts, pairs, res.model)
                if res.fault is not None and res.fault[0].startswith(UNROLL):
                    # a loop longer than the unrolling: undecided, not a runtime error
                    res.status, res.cycle, res.model = "unknown", k - 1, None
            base.pop()
            return res
        base.pop()
        if r == z3.unknown:
            res.status, res.cycle = "unknown", k - 1
            return res
        base.add(*good(pairs))
        # induction: a path of k cycles from any state of the invariants
        cons, pairs = iu.step(k)
        ind.add(*cons)
        for j in range(0, k):
            if ts.state:
                ind.add(lor(*[lnot(smt_eq(iu.X[j][var], iu.X[k][var])) for _, var, _, _ in ts.state]))
        if ind_pairs is not None:
            ind.add(*good(ind_pairs))
        ind_pairs = pairs
        ind.push()
        ind.add(viol(pairs))
        if no_fault and prop is not None:
            ind.add(lnot(_fault_term(ts, pairs)))
        r = ind.check()
        ind.pop()
        if r == z3.unsat:
            res.status, res.k = "proved", k
            return res
    res.status, res.cycle = "bounded", depth
    return res


def _which_fault(ts, pairs, model):
    for c, kind, pou, src, pos in ts.faults:
        if z3.is_true(model.eval(Unroller.sub(c, pairs), model_completion=True)):
            return kind, pou, src, pos
    return None


_ = (FALSE, TRUE, land)
