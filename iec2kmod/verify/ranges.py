"""Interval analysis of the transition system: candidate invariants
``lo <= v`` and ``v <= hi`` for the bit-vector state variables.

The post term of every state variable is evaluated over intervals (the
signed value of the bit pattern; a result that may wrap is the whole type),
from the initial state, joining until nothing grows; a variable still
growing after a few rounds jumps to the next constant of the terms, then
to its whole type.  The results are only candidates: Houdini (engine.py)
keeps the ones that are inductive, so an imprecision here costs a lost
invariant, never a wrong verdict.  They give k-induction the facts a
reachable state has and an arbitrary one lacks, e.g. the index of a ring
buffer ``next := (next + 1) MOD 10`` staying in 0..9 (examples/two_resources)."""

from __future__ import annotations

import z3

_DELAY = 6          # rounds of plain joining before widening
_MAX_ROUNDS = 200


def _top(w):
    return (-(1 << (w - 1)), (1 << (w - 1)) - 1)


def _signed(v, w):
    v &= (1 << w) - 1
    return v - (1 << w) if v >> (w - 1) else v


def _fit(lo, hi, w):
    t = _top(w)
    if lo < t[0] or hi > t[1]:
        return t
    return (lo, hi)


def _unsigned(iv, w):
    """The interval as unsigned values, or None when it straddles the sign."""
    lo, hi = iv
    if lo >= 0:
        return iv
    if hi < 0:
        return (lo + (1 << w), hi + (1 << w))
    return None


def _tdiv(a, b):
    q = abs(a) // abs(b)
    return q if (a >= 0) == (b >= 0) else -q


# three-valued booleans: (can be false, can be true)
_T, _F, _U = (False, True), (True, False), (True, True)


def _b(x):
    return _T if x else _F


class _Node:
    __slots__ = ("kind", "kids", "w", "val", "params", "var")


def _compile(roots):
    """The DAG under the roots in topological order (children first)."""
    order = []
    index = {}
    stack = [(t, False) for t in roots]
    while stack:
        t, done = stack.pop()
        i = t.get_id()
        if done:
            if i not in index:
                index[i] = len(order)
                order.append(t)
            continue
        if i in index:
            continue
        stack.append((t, True))
        for c in t.children():
            if c.get_id() not in index:
                stack.append((c, False))
    nodes = []
    for t in order:
        n = _Node()
        n.kids = [index[c.get_id()] for c in t.children()]
        n.var = None
        n.val = None
        n.params = None
        s = t.sort()
        n.w = s.size() if z3.is_bv_sort(s) else (0 if s == z3.BoolSort() else -1)
        if z3.is_bv_value(t):
            n.kind = "num"
            n.val = _signed(t.as_long(), n.w)
        elif z3.is_true(t) or z3.is_false(t):
            n.kind = "bool"
            n.val = _b(z3.is_true(t))
        elif z3.is_const(t) and t.decl().kind() == z3.Z3_OP_UNINTERPRETED:
            n.kind = "var"
            n.var = t.get_id()
        elif z3.is_app(t):
            n.kind = t.decl().kind()
            if n.kind == z3.Z3_OP_EXTRACT:
                n.params = t.params()
        else:
            n.kind = None
        nodes.append(n)
    return nodes, index


def _eval(nodes, env):
    out = [None] * len(nodes)
    for k, n in enumerate(nodes):
        a = [out[c] for c in n.kids]
        if n.kind == z3.Z3_OP_ITE and n.w > 0 and a[0] == _U:
            # the guard narrows the branch that is its own operand:
            # If(x + 1 <= 9, x + 1, 0) is in [lo, 9] u {0}
            a = [a[0], _narrow(nodes, out, n.kids[0], n.kids[1], a[1], True),
                 _narrow(nodes, out, n.kids[0], n.kids[2], a[2], False)]
        out[k] = _op(n, a, env)
    return out


# the comparison as "left OP right" read the other way round
_FLIP = {z3.Z3_OP_SLEQ: z3.Z3_OP_SGEQ, z3.Z3_OP_SGEQ: z3.Z3_OP_SLEQ,
         z3.Z3_OP_SLT: z3.Z3_OP_SGT, z3.Z3_OP_SGT: z3.Z3_OP_SLT, z3.Z3_OP_EQ: z3.Z3_OP_EQ}
_NEGATE = {z3.Z3_OP_SLEQ: z3.Z3_OP_SGT, z3.Z3_OP_SGT: z3.Z3_OP_SLEQ,
           z3.Z3_OP_SLT: z3.Z3_OP_SGEQ, z3.Z3_OP_SGEQ: z3.Z3_OP_SLT}


def _narrow(nodes, out, ci, bi, iv, truth):
    """The interval iv of branch node bi where the guard node ci has the
    truth value `truth`: when the guard compares bi itself (the same node)
    with a constant, signed, the interval is cut to the values where the
    comparison has that outcome (an empty cut leaves iv as it is: sound,
    only less precise)."""
    if iv is None or isinstance(iv[0], bool):
        return iv
    c = nodes[ci]
    while c.kind == z3.Z3_OP_NOT and len(c.kids) == 1:
        truth = not truth
        c = nodes[c.kids[0]]
    if c.kind not in _FLIP or len(c.kids) != 2:
        return iv
    p, q = c.kids
    op = c.kind
    if q == bi and nodes[p].kind == "num":
        p, q, op = q, p, _FLIP[op]
    if p != bi or nodes[q].kind != "num":
        return iv
    k = nodes[q].val
    if not truth:
        if op == z3.Z3_OP_EQ:
            return iv           # x <> k: no interval cut (but at its ends)
        op = _NEGATE[op]
    lo, hi = iv
    if op == z3.Z3_OP_SLEQ:
        hi = min(hi, k)
    elif op == z3.Z3_OP_SLT:
        hi = min(hi, k - 1)
    elif op == z3.Z3_OP_SGEQ:
        lo = max(lo, k)
    elif op == z3.Z3_OP_SGT:
        lo = max(lo, k + 1)
    else:
        lo, hi = max(lo, k), min(hi, k)
    return (lo, hi) if lo <= hi else iv


def _op(n, a, env):
    w = n.w
    kd = n.kind
    if kd == "num":
        return (n.val, n.val)
    if kd == "bool":
        return n.val
    if kd == "var":
        v = env.get(n.var)
        if v is not None:
            return v
        return _top(w) if w > 0 else (_U if w == 0 else None)
    if w == 0:
        return _bool_op(kd, a, n)
    if w < 0:
        return None
    if any(x is None for x in a) and kd != z3.Z3_OP_ITE:
        return _top(w)
    Z = z3
    if kd == Z.Z3_OP_ITE:
        c, x, y = a
        if c == _T:
            return x if x is not None else _top(w)
        if c == _F:
            return y if y is not None else _top(w)
        if x is None or y is None:
            return _top(w)
        return (min(x[0], y[0]), max(x[1], y[1]))
    if kd == Z.Z3_OP_BADD:
        return _fit(sum(x[0] for x in a), sum(x[1] for x in a), w)
    if kd == Z.Z3_OP_BSUB and len(a) == 2:
        return _fit(a[0][0] - a[1][1], a[0][1] - a[1][0], w)
    if kd == Z.Z3_OP_BNEG:
        return _fit(-a[0][1], -a[0][0], w)
    if kd == Z.Z3_OP_BMUL and len(a) == 2:
        ps = [x * y for x in a[0] for y in a[1]]
        return _fit(min(ps), max(ps), w)
    if kd in (Z.Z3_OP_BSREM, Z.Z3_OP_BSREM_I) and a[1][0] > 0:
        m = a[1][1] - 1
        x = a[0]
        if x[0] >= 0:
            return (0, min(x[1], m))
        if x[1] <= 0:
            return (max(x[0], -m), 0)
        return (max(x[0], -m), min(x[1], m))
    if kd in (Z.Z3_OP_BSMOD, Z.Z3_OP_BSMOD_I) and a[1][0] > 0:
        x = a[0]
        if x[0] >= 0:
            return (0, min(x[1], a[1][1] - 1))
        return (0, a[1][1] - 1)
    if kd in (Z.Z3_OP_BSDIV, Z.Z3_OP_BSDIV_I) and a[1][0] > 0:
        qs = [_tdiv(x, y) for x in a[0] for y in a[1]]
        return _fit(min(qs), max(qs), w)
    if kd in (Z.Z3_OP_BUREM, Z.Z3_OP_BUREM_I, Z.Z3_OP_BUDIV, Z.Z3_OP_BUDIV_I):
        x, y = _unsigned(a[0], w), _unsigned(a[1], w)
        if x is not None and y is not None and y[0] > 0:
            if kd in (Z.Z3_OP_BUREM, Z.Z3_OP_BUREM_I):
                return _fit(0, min(x[1], y[1] - 1), w)
            return _fit(x[0] // y[1], x[1] // y[0], w)
        return _top(w)
    if kd == Z.Z3_OP_BAND:
        nonneg = [x for x in a if x[0] >= 0]
        if nonneg:
            return (0, min(x[1] for x in nonneg))
        return _top(w)
    if kd == Z.Z3_OP_SIGN_EXT:
        return a[0]
    if kd == Z.Z3_OP_ZERO_EXT:
        x = a[0]
        wi = w - (n.params[0] if n.params else 0)
        if x[0] >= 0:
            return x
        u = _unsigned(x, wi) if wi > 0 else None
        return u if u is not None else _fit(0, (1 << wi) - 1, w)
    if kd == Z.Z3_OP_EXTRACT and n.params and n.params[1] == 0:
        lo, hi = a[0]
        t = _top(w)
        if t[0] <= lo and hi <= t[1]:
            return (lo, hi)
        return t
    return _top(w)


def _bool_op(kd, a, n):
    Z = z3
    if kd == Z.Z3_OP_NOT:
        x = a[0] or _U
        return (x[1], x[0])
    if kd == Z.Z3_OP_AND:
        xs = [x or _U for x in a]
        return (any(x[0] for x in xs), all(x[1] for x in xs))
    if kd == Z.Z3_OP_OR:
        xs = [x or _U for x in a]
        return (all(x[0] for x in xs), any(x[1] for x in xs))
    if kd == Z.Z3_OP_ITE:
        c, x, y = a
        x, y = x or _U, y or _U
        if c == _T:
            return x
        if c == _F:
            return y
        return (x[0] or y[0], x[1] or y[1])
    if any(x is None for x in a) or len(a) != 2:
        return _U
    x, y = a
    if kd in (Z.Z3_OP_EQ, Z.Z3_OP_DISTINCT):
        if isinstance(x[0], bool):
            r = _U if (x == _U or y == _U) else _b(x == y)
        elif x[0] == x[1] == y[0] == y[1]:
            r = _T
        elif x[1] < y[0] or y[1] < x[0]:
            r = _F
        else:
            r = _U
        return (r[1], r[0]) if kd == Z.Z3_OP_DISTINCT else r
    if kd in (Z.Z3_OP_ULEQ, Z.Z3_OP_ULT, Z.Z3_OP_UGEQ, Z.Z3_OP_UGT):
        w = None
        # the operands' width is not at hand: an interval straddling the
        # sign cannot be compared unsigned
        if x[0] < 0 or y[0] < 0:
            if not (x[1] < 0 and y[1] < 0):
                return _U
        kd = {Z.Z3_OP_ULEQ: Z.Z3_OP_SLEQ, Z.Z3_OP_ULT: Z.Z3_OP_SLT,
              Z.Z3_OP_UGEQ: Z.Z3_OP_SGEQ, Z.Z3_OP_UGT: Z.Z3_OP_SGT}[kd]
        del w
    if kd == Z.Z3_OP_SLEQ:
        return _T if x[1] <= y[0] else _F if x[0] > y[1] else _U
    if kd == Z.Z3_OP_SLT:
        return _T if x[1] < y[0] else _F if x[0] >= y[1] else _U
    if kd == Z.Z3_OP_SGEQ:
        return _T if x[0] >= y[1] else _F if x[1] < y[0] else _U
    if kd == Z.Z3_OP_SGT:
        return _T if x[0] > y[1] else _F if x[1] <= y[0] else _U
    return _U


def range_candidates(state):
    """[(name, term)] candidate invariants for state [(leaf, var, init,
    post)]: the interval each bit-vector variable stays in, as two bounds."""
    bvs = [(leaf, var, init, post) for leaf, var, init, post in state
           if z3.is_bv_sort(var.sort())]
    if not bvs:
        return []
    nodes, index = _compile([post for *_, post in state])
    env = {}
    for leaf, var, init, post in state:
        if z3.is_bv_value(init):
            v = _signed(init.as_long(), init.size())
            env[var.get_id()] = (v, v)
        elif z3.is_true(init) or z3.is_false(init):
            env[var.get_id()] = _b(z3.is_true(init))
    known = env
    thresholds = sorted({n.val for n in nodes if n.kind == "num"})
    grew = {}
    for _ in range(_MAX_ROUNDS):
        vals = _eval(nodes, known)
        changed = False
        for leaf, var, init, post in state:
            i = var.get_id()
            cur = known.get(i)
            new = vals[index[post.get_id()]]
            if cur is None or new is None:
                continue
            if isinstance(cur[0], bool):
                j = (cur[0] or new[0], cur[1] or new[1])
            else:
                j = (min(cur[0], new[0]), max(cur[1], new[1]))
                if j != cur:
                    grew[i] = grew.get(i, 0) + 1
                    if grew[i] > _DELAY:
                        w = var.sort().size()
                        t = _top(w)
                        lo = j[0] if j[0] == cur[0] else max(
                            [c for c in thresholds if c <= j[0]] + [t[0]])
                        hi = j[1] if j[1] == cur[1] else min(
                            [c for c in thresholds if c >= j[1]] + [t[1]])
                        if grew[i] > _DELAY + 4:
                            lo = t[0] if j[0] != cur[0] else lo
                            hi = t[1] if j[1] != cur[1] else hi
                        j = (max(lo, t[0]), min(hi, t[1]))
            if j != cur:
                known[i] = j
                changed = True
        if not changed:
            break
    else:
        return []
    out = []
    for leaf, var, init, post in bvs:
        iv = known.get(var.get_id())
        if iv is None:
            continue
        w = var.sort().size()
        t = _top(w)
        if iv[0] > t[0]:
            out.append((f"{leaf.name} >= {iv[0]}", var >= z3.BitVecVal(iv[0], w)))
        if iv[1] < t[1]:
            out.append((f"{leaf.name} <= {iv[1]}", var <= z3.BitVecVal(iv[1], w)))
    return out


def _constants(term, w, limit=20000):
    """The signed values of the bit-vector numerals of width w in the term
    (a DAG walk, at most `limit` nodes)."""
    seen, out = set(), set()
    todo = [term]
    while todo and len(seen) < limit:
        t = todo.pop()
        i = t.get_id()
        if i in seen:
            continue
        seen.add(i)
        if z3.is_bv_value(t):
            if t.size() == w:
                out.add(_signed(t.as_long(), w))
            continue
        todo.extend(t.children())
    return out


def _assigned(term):
    """The numerals a post term can take as a whole: the leaves of its
    if-then-else tree (a state machine's post term assigns its steps)."""
    out, seen, todo = set(), set(), [term]
    while todo:
        t = todo.pop()
        if t.get_id() in seen:
            continue
        seen.add(t.get_id())
        if z3.is_bv_value(t):
            out.add(t.as_long())
        elif z3.is_app_of(t, z3.Z3_OP_ITE):
            todo.extend(t.children()[1:])
    return out


def _reads(term, limit=20000):
    """{id} of the uninterpreted constants the term reads."""
    seen, out = set(), set()
    todo = [term]
    while todo and len(seen) < limit:
        t = todo.pop()
        i = t.get_id()
        if i in seen:
            continue
        seen.add(i)
        if z3.is_const(t) and t.decl().kind() == z3.Z3_OP_UNINTERPRETED:
            out.add(i)
            continue
        todo.extend(t.children())
    return out


def partition_candidates(state, max_values=16, max_consts=8):
    """Candidate invariants of a state machine: ``E = e -> v >= c`` and
    ``E = e -> v <= c`` for every enumeration E of the state (at most
    max_values values), every other bit-vector state variable v, and the
    constants c of v's own post term (what it is assigned, compared with,
    stepped by).  They give k-induction what holds in one step of a
    sequence and not in another, e.g. a step number that is 1..8 while a
    recipe runs and anything while idle (examples/batch_mixer).  Only
    candidates: Houdini keeps the inductive ones."""
    from ..checks.types import EnumT, concrete
    enums = []
    for leaf, var, init, post in state:
        t = concrete(leaf.type)
        if isinstance(t, EnumT) and z3.is_bv_sort(var.sort()) and \
                len(t.values) <= max_values and len(_assigned(post)) >= 2:
            enums.append((leaf, var, sorted(t.values.values(), key=lambda nv: nv[1])))
    if not enums:
        return []
    out = []
    for leaf, var, init, post in state:
        if not z3.is_bv_sort(var.sort()) or isinstance(concrete(leaf.type), EnumT):
            continue
        w = var.sort().size()
        if w > 32:
            continue
        reads = _reads(post)
        consts = sorted(_constants(post, w), key=lambda c: (abs(c), c))[:max_consts]
        for eleaf, evar, values in enums:
            if evar.get_id() not in reads:
                continue        # v's update does not depend on the machine's step
            ew = evar.sort().size()
            for name, val in values:
                cond = evar == z3.BitVecVal(val, ew)
                for c in sorted(consts):
                    out.append((f"{eleaf.name} = {name} -> {leaf.name} >= {c}",
                                z3.Implies(cond, var >= z3.BitVecVal(c, w))))
                    out.append((f"{eleaf.name} = {name} -> {leaf.name} <= {c}",
                                z3.Implies(cond, var <= z3.BitVecVal(c, w))))
    return out
