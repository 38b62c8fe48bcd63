"""Bounded model checking and k-induction over the transition system.

    state    X: every leaf a cycle may change (z3 constants, one set per step)
    inputs   U: the free leaves, fresh in every cycle, inside their domain
    T(X, U)  the post-cycle value of each state leaf
    F(X, U)  a runtime fault happens in the cycle (a violation)
    P(X, U)  each property, on the state after the cycle (with the inputs
             the cycle read)
    A(X, U)  the assumptions, at the same point as the properties

BMC unrolls from the initial state; cycle k is checked once every cycle
before it held (so the first violation is the one reported).  k-induction
proves "for every path of k+1 cycles from any state satisfying the proved
invariants, if the first k cycles hold so does the last"; with the base case
to depth k+1 this proves the property for every depth.  Paths in the
induction step are kept simple (the states before each of its cycles
pairwise distinct; the state after the violating cycle may repeat one of
them), which makes the method complete for finite state.  Invariants about hidden state (timer
locations, enumeration ranges...) are candidates proved first by Houdini
(one-step induction, dropping the ones that fail until the rest is
inductive): only proved ones strengthen the induction."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import z3

from .terms import FALSE, REFUSED, TRUE, UNROLL, Refuse, land, lnot, lor, smt_eq


@dataclass
class Runs:
    """What the assumptions allow: runs of `longest` cycles at most
    (None: of every length checked, to `depth`); `total`: proved that every
    reachable state has a successor (runs of every length exist)."""
    longest: int | None = None
    depth: int = 0
    total: bool = False
    assumed: bool = False     # are there assumptions at all


@dataclass
class Result:
    name: str
    status: str = "unknown"   # proved | bounded | violated | unknown | vacuous
    cycle: int = 0            # violated: the cycle; bounded: the depth
    k: int = 0                # proved: the induction depth
    seconds: float = 0.0
    model: object = None      # violated: the z3 model of the path
    fault: tuple | None = None
    invariants: list = field(default_factory=list)
    abstract: bool = False    # proved on the floating-point abstraction
    free: list = field(default_factory=list)   # constructs free in its verdict (stand-ins)
    timeout: bool = False     # unknown: the --timeout deadline stopped it
    havoc: list = field(default_factory=list)  # the faulted tasks' variables it reads
    runs_to: int = 0          # proved: the assumptions' runs were found to exist
                              # only up to this depth (0: of every length)


@dataclass
class System:
    state: list               # [(leaf, var, init term, post term)]
    inputs: list              # [(leaf, var, domain term)]
    faults: list              # [(cond, kind, pou, src, pos)]
    props: list               # [(name, term)]
    assume: object            # term
    invariants: list = field(default_factory=list)   # [(name, term over state vars)]
    # stand-ins of values not encoded (strings; free inputs here): name ->
    # (src, pos, message); a check whose cone reads one is refused
    refused: dict = field(default_factory=dict)
    stand_ins: list = field(default_factory=list)     # their constants


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


# the wall-clock deadline of the whole verification (time.monotonic()),
# None: none.  Every query is cut to what is left of it; a check the
# deadline stops is "unknown (timeout)".
_deadline = [None]


def solve(s):
    """s.check() within the deadline (each solver also has its own
    per-query limit, set where it is made); unknown when none is left."""
    d = _deadline[0]
    if d is not None:
        left = int((d - time.monotonic()) * 1000)
        if left <= 0:
            return z3.unknown
        s.set("timeout", left if left < s._per_query else s._per_query)
    return s.check()


def new_solver(timeout_ms):
    s = z3.Solver()
    s.set("timeout", timeout_ms)
    s._per_query = timeout_ms
    return s


def timed_out():
    return _deadline[0] is not None and time.monotonic() >= _deadline[0]


def _fault_term(ts, pairs):
    return lor(*[Unroller.sub(c, pairs) for c, *_ in ts.faults])


def houdini(ts: System, timeout_ms: int):
    """The subset of ts.invariants that holds initially and is inductive
    (all candidates assumed in the pre-state; every solver answer "sat"
    drops the candidates its post-state falsifies, until "unsat")."""
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
    s = new_solver(timeout_ms)
    cons, pairs = u.step(1)
    s.add(*cons)
    # a runtime fault stops its task and the run goes on: the invariants
    # must survive faulting steps too.  Only the encoding's own limit (a
    # loop longer than --unroll) ends the runs the checks look at
    s.add(lnot(lor(*[Unroller.sub(c, pairs) for c, kind, *_ in ts.faults
                     if kind.startswith(UNROLL)])))
    pre_pairs = [(var, u.X[0][var]) for _, var, _, _ in ts.state]
    post_pairs = [(var, u.X[1][var]) for _, var, _, _ in ts.state]
    while cands:
        s.push()
        for _, term in cands:
            s.add(Unroller.sub(term, pre_pairs))
        posts = [Unroller.sub(term, post_pairs) for _, term in cands]
        s.add(lor(*[lnot(p) for p in posts]))
        r = solve(s)
        if r == z3.unsat:
            s.pop()
            return cands
        if r != z3.sat:
            s.pop()
            return []
        m = s.model()
        keep = [c for c, p in zip(cands, posts)
                if not z3.is_false(m.eval(p, model_completion=True))]
        s.pop()
        if len(keep) == len(cands):     # cannot happen with an exact model
            return []
        cands = keep
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


# FP operations whose bit-level encoding is what makes REAL slow
_FP_ARITH = {z3.Z3_OP_FPA_ADD, z3.Z3_OP_FPA_SUB, z3.Z3_OP_FPA_MUL, z3.Z3_OP_FPA_DIV,
             z3.Z3_OP_FPA_REM, z3.Z3_OP_FPA_FMA, z3.Z3_OP_FPA_SQRT,
             z3.Z3_OP_FPA_ROUND_TO_INTEGRAL, z3.Z3_OP_FPA_TO_FP,
             z3.Z3_OP_FPA_TO_FP_UNSIGNED, z3.Z3_OP_FPA_TO_SBV, z3.Z3_OP_FPA_TO_UBV}


def _fp_ops(roots, control_only=False):
    """The outermost floating-point operations of the terms; control_only:
    those the terms reach only through the conditions of if-then-else (a
    value that only decides a branch, like a timer preset compared with a
    clock), the others being read as data and kept."""
    seen = set()
    found = {}
    stack = [(t, False) for t in roots if z3.is_expr(t)]
    if control_only:
        # the nodes reached as data, first
        data = set()
        todo = [t for t in roots if z3.is_expr(t)]
        while todo:
            t = todo.pop()
            i = t.get_id()
            if i in data:
                continue
            data.add(i)
            ch = t.children()
            if z3.is_app(t) and t.decl().kind() == z3.Z3_OP_ITE:
                ch = ch[1:]
            todo.extend(ch)
    while stack:
        t, _ = stack.pop()
        i = t.get_id()
        if i in seen:
            continue
        seen.add(i)
        if z3.is_app(t) and t.decl().kind() in _FP_ARITH and (not control_only or i not in data):
            found[i] = t
            continue
        stack.extend((c, False) for c in t.children())
    return list(found.values())


def abstract_fp(ts: System, control_only=False):
    """An over-approximation of ts: every floating-point arithmetic
    operation or conversion replaced by a fresh input, any value of its
    sort in every cycle; comparisons, selections and everything else exact.
    Every path of ts is a path of the result (its inputs taking the values
    the operations computed), so what k-induction proves on it holds for
    ts; a violation of it proves nothing and is never reported (the exact
    system decides then).  None when ts has no such operation."""
    inputs = list(ts.inputs)
    state = list(ts.state)
    faults, props, assume, invs = list(ts.faults), list(ts.props), ts.assume, list(ts.invariants)
    n = 0
    while True:
        ops = _fp_ops([p for *_, p in state] + [c for c, *_ in faults]
                      + [t for _, t in props] + [assume] + [t for _, t in invs], control_only)
        if not ops:
            break
        pairs = []
        for t in ops:
            c = z3.simplify(t)
            if z3.is_fp_value(c) or z3.is_bv_value(c):
                pairs.append((t, c))        # constant operands: its value, exactly
                continue
            v = z3.Const(f"$abs{n}", t.sort())
            n += 1
            pairs.append((t, v))
            inputs.append((None, v, TRUE))

        def sub(t):
            return z3.substitute(t, *pairs)
        state = [(leaf, var, init, sub(post)) for leaf, var, init, post in state]
        faults = [(sub(c), *rest) for c, *rest in faults]
        props = [(nm, sub(t)) for nm, t in props]
        assume = sub(assume)
        invs = [(nm, sub(t)) for nm, t in invs]
    if n == 0:
        return None
    return System(state, inputs, faults, props, assume, invs)


# the first try of a check, before the stronger candidates are proved
WEAK_DEPTH = 4
WEAK_TIMEOUT_MS = 10000


def check(ts: System, depth: int, timeout_ms: int = 60000, log=None, info=None,
          on_result=None, deadline=None):
    """Results for every property, the first one 'no runtime error'.  Each
    one is decided on its own cone of influence; the properties are checked
    on runs without a runtime error unless none can happen (proved).  The
    candidate invariants are proved once, by Houdini on the whole system
    (on its floating-point abstraction when it has floating-point
    operations: a sound over-approximation, so what is inductive there holds
    in every reachable state); each property uses those of its cone.  A
    check that k-induction does not close with them is decided again with
    the stronger candidates of ts.extra (the state machines' per-step
    ranges, ranges.partition_candidates), proved by Houdini once, only when
    some check needs them: they are many, and most programs do not.

    Every verdict is passed to on_result as soon as it is decided; the
    assumptions' runs (runs_allowed) turn the verdicts about runs they do
    not allow into "vacuous"; past `deadline` (time.monotonic()) the checks
    left are "unknown" with .timeout set.  info["runs"]: the Runs."""
    _deadline[0] = deadline
    # ts.nofault: the system without the stopping of a faulted task (build):
    # 'no runtime error' is decided there -- its runs end at the first
    # fault, and until then both systems take the same steps (the first
    # task that faults in a step sees what it sees in ts) --, and the
    # properties too once it is proved (no task ever stops then)
    nofault = getattr(ts, "nofault", None)
    whole, ts = ts, (nofault if nofault is not None else ts)
    fault_roots = [c for c, *_ in ts.faults]
    refused = ts.refused
    extra = list(getattr(ts, "extra", []))
    # the stand-ins (values computed from strings) free in every cycle and
    # at every evaluation: each stand-in constant is one evaluation site of
    # the one cycle the encoding unrolls, an input here, so fresh in every
    # cycle -- an over-approximation of what the strings compute
    def with_stand_ins(s):
        return System(s.state, s.inputs + [(None, c, TRUE) for c in ts.stand_ins], s.faults,
                      s.props, s.assume, s.invariants)
    full = with_stand_ins(ts)

    def proved_system(cands):
        free = System(full.state, full.inputs, full.faults, full.props, full.assume, cands)
        a = abstract_fp(free)
        proved = {n for n, _ in houdini(a if a is not None else free, timeout_ms)}
        return System(full.state, full.inputs, full.faults, full.props, full.assume,
                      [(n, t) for n, t in cands if n in proved and not _fp_ops([t])])

    cur = {"ts": proved_system(full.invariants), "strong": not extra}

    def decide(roots, name, term, no_fault):
        while True:
            sub = restrict(cur["ts"], roots)
            sub.props = [(name, term)] if term is not None else []
            if term is not None:
                # a runtime fault stops its task and the run goes on: the
                # property is checked after it too.  Only the encoding's
                # own limit (a loop longer than --unroll) ends the runs a
                # property is checked on
                sub.faults = [f for f in sub.faults if f[1].startswith(UNROLL)] \
                    if no_fault else []
            # before the stronger invariants, only the cheap abstractions,
            # and not far (induction without them gets slow as k grows)
            if cur["strong"]:
                r = _decide(sub, name, term, depth, timeout_ms, no_fault=no_fault)
            else:
                r = _decide(sub, name, term, min(depth, WEAK_DEPTH),
                            min(timeout_ms, WEAK_TIMEOUT_MS), no_fault=no_fault, exact=False)
            if r is None:
                undecided = True
            else:
                undecided = r.status == "unknown" or r.status == "bounded" or \
                    (r.status == "violated" and _stand_ins_read(sub, refused))
            if not undecided or cur["strong"]:
                _sound_or_refuse(r, sub, refused)
                r.havoc = sorted({str(v).split(":", 1)[1] for leaf, v, _ in sub.inputs
                                  if leaf is None and str(v).startswith("$havoc")})
                return r
            cur["ts"] = proved_system(full.invariants + extra)
            cur["strong"] = True

    # the runs the assumptions allow, faults and all (no invariants proved
    # for that system yet: the totality query goes without)
    runs = runs_allowed(cur["ts"] if nofault is None else
                        with_stand_ins(System(whole.state, whole.inputs, whole.faults,
                                              whole.props, whole.assume, [])),
                        depth, timeout_ms)

    def vacuous(r):
        # no run longer than runs.longest cycles: a verdict about longer
        # runs (proved, holds up to N >= longest, undecided after it) is
        # about no run at all
        if runs.longest is None or r.status == "violated":
            if r.status == "proved" and not runs.total:
                r.runs_to = runs.depth
            return r
        if r.status in ("proved", "bounded") or r.cycle >= runs.longest:
            r.status, r.cycle, r.k = "vacuous", runs.longest, 0
        return r

    if info is not None:
        info["runs"] = runs

    def run(roots, name, term, no_fault):
        t0 = time.perf_counter()
        if timed_out():
            r = Result(name, status="unknown", timeout=True)
        else:
            r = vacuous(decide(roots, name, term, no_fault))
            if r.status == "unknown" and timed_out():
                r.timeout = True
        r.seconds = time.perf_counter() - t0
        if on_result is not None:
            on_result(r)        # each verdict as soon as it is decided
        return r

    first = run(fault_roots, "no runtime error", None, no_fault=False)
    results = [first]
    invs = set()
    if first.status != "proved" and nofault is not None:
        # a task may fault: the properties on the runs where it stops and
        # the others go on
        ts = whole
        full = with_stand_ins(whole)
        extra = list(getattr(whole, "extra", []))
        cur["ts"], cur["strong"] = proved_system(full.invariants), not extra
    unroll_roots = [c for c, kind, *_ in ts.faults if kind.startswith(UNROLL)]
    for name, term in full.props:
        no_fault = first.status != "proved" and bool(unroll_roots)
        r = run([term] + (unroll_roots if no_fault else []), name, term, no_fault)
        results.append(r)
        invs.update(n for n, _ in r.invariants)
    return results, sorted(invs)


def runs_allowed(ts: System, depth: int, timeout_ms: int) -> Runs:
    """How long the runs the assumptions admit are.  Bounded model
    checking of the assumptions alone (on their cone of influence, with
    the input domains): the first k with no run of k cycles makes every
    verdict after cycle k-1 vacuous.  When runs of `depth` cycles exist,
    totality is tried: no state satisfying the proved invariants lacks a
    successor step satisfying the assumptions (for all inputs ... a
    quantified query): then runs of every length exist."""
    res = Runs(depth=depth, assumed=not z3.is_true(z3.simplify(ts.assume)))
    if not res.assumed:
        res.total = True
        return res
    sub = restrict(ts, [])
    s = new_solver(timeout_ms)
    u = Unroller(sub, "r")
    u.vars_at(0, initial=True)
    for k in range(1, depth + 1):
        cons, _ = u.step(k)
        s.add(*cons)
        r = solve(s)
        if r == z3.unsat:
            res.longest = k - 1
            return res
        if r != z3.sat:
            return res      # undecided: no claim either way
    # totality: exists X (invariants) such that for all inputs U the step
    # breaks the assumptions (or the input domains)?  unsat: total
    t = new_solver(min(timeout_ms, 10000))
    v = Unroller(sub, "t")
    v.vars_at(0)
    cons, pairs = v.step(1)
    y0 = [(var, v.X[0][var]) for _, var, _, _ in sub.state]
    for _, term in sub.invariants:
        t.add(Unroller.sub(term, y0))
    # the post-state equalities define X_1; the step is possible when the
    # domains and the assumption hold for some inputs
    step_ok = land(*[c for c in cons])
    xs = list(v.X[1].values())
    us = list(v.U[0].values())
    if us or xs:
        t.add(z3.ForAll(us + xs, lnot(step_ok)) if (us or xs) else lnot(step_ok))
    else:
        t.add(lnot(step_ok))
    res.total = solve(t) == z3.unsat
    return res


def _stand_ins_read(sub, refused):
    return sorted((str(v) for leaf, v, _ in sub.inputs
                   if leaf is None and str(v) in refused),
                  key=lambda n: int(n[len(REFUSED):]))


def _sound_or_refuse(r, sub, refused):
    """A check whose cone of influence reads stand-ins was decided with
    them free: 'proved' and 'holds up to N cycles' hold for the exact
    system too (every run of it is a run there); a violation or an
    undecided cycle may come from a value the strings cannot produce, so
    the check is refused naming the construct (never reported as a
    verdict).  r.free: the constructs, for the report."""
    names = _stand_ins_read(sub, refused)
    if not names:
        return
    if r.status in ("proved", "bounded") and r.fault is None:
        r.free = sorted({refused[n][2].split("verify: ", 1)[-1]
                         .replace(" cannot be encoded exactly", "") for n in names})
        return
    src, pos, msg = refused[names[0]]
    raise Refuse(src, pos, f"{msg} (the check '{r.name}' reads it and is not proved with "
                           "its value free)")


def _decide(ts, name, prop, depth, timeout_ms, no_fault, exact=True):
    """check_one, first on over-approximations of ts when it has
    floating-point operations (abstract_fp: all of them free; then only
    those that only decide branches), each cut to its own cone of
    influence: a proof there is a proof; otherwise the exact system
    decides (not exact: None then -- the exact floating-point queries are
    the slow ones).  ts.invariants are already proved."""
    for control_only in (False, True):
        a = abstract_fp(ts, control_only)
        if a is None:
            break
        exact = exact or None
        ap = None
        if prop is not None:
            ap = dict(a.props).get(name)
            if ap is None:
                break
        fault_roots = [c for c, *_ in a.faults]
        a = restrict(a, ([ap] if ap is not None else [])
                     + (fault_roots if no_fault or prop is None else []))
        r = check_one(a, name, ap, depth, timeout_ms, no_fault, stop_early=True,
                      proved_inv=a.invariants)
        if r.status == "proved":
            r.abstract = True
            return r
    if exact is None:
        return None
    return check_one(ts, name, prop, depth, timeout_ms, no_fault, proved_inv=ts.invariants)


def check_one(ts: System, name, prop, depth, timeout_ms, no_fault, stop_early=False,
              proved_inv=None):
    """BMC to ``depth`` cycles and k-induction of one property (prop None:
    no runtime error).  stop_early: give up at the first violation found
    (on an abstraction, that is not a verdict).  proved_inv: the invariants
    to use, already proved (else Houdini proves ts.invariants' subset)."""
    res = Result(name)
    if prop is not None and z3.is_true(z3.simplify(prop)):
        # true after every cycle from every state: no solving needed
        res.status, res.k = "proved", 1
        return res
    inv = houdini(ts, timeout_ms) if proved_inv is None else proved_inv
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

    base = new_solver(timeout_ms)
    bu = Unroller(ts, "b")
    bu.vars_at(0, initial=True)
    ind = new_solver(timeout_ms)
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
        r = solve(base)
        if r == z3.sat and stop_early:
            res.status, res.cycle = "violated", k
            return res
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
        # simple paths: the PRE-states of the k cycles pairwise distinct
        # (X_0..X_{k-1}), never the post-state X_k of the violating cycle.
        # The violation is a fact of the last cycle (its inputs, the state
        # before it), not of X_k alone: a shortest counterexample may end
        # in a state it passed before (a latch holding while an input
        # drops), and cutting that loop removes the violating cycle.  A loop
        # between two pre-states can be cut: the path from the second one
        # repeats after the first.
        for j in range(0, k - 1):
            if ts.state:
                ind.add(lor(*[lnot(smt_eq(iu.X[j][var], iu.X[k - 1][var]))
                              for _, var, _, _ in ts.state]))
        if ind_pairs is not None:
            ind.add(*good(ind_pairs))
        ind_pairs = pairs
        ind.push()
        ind.add(viol(pairs))
        if no_fault and prop is not None:
            ind.add(lnot(_fault_term(ts, pairs)))
        r = solve(ind)
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
