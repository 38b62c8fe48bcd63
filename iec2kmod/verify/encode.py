"""Symbolic execution of one task cycle over z3 terms.

The storage is the reference interpreter's own (iec2kmod.interp.model):
the same dicts, lists and Instance objects, with every scalar replaced by a
z3 term.  Statements are executed once, symbolically; a write happens under
the path condition that reaches it (``If(guard, new, old)``), so one store
represents every path through IF/CASE/EXIT/RETURN/IL jumps at once and the
references the interpreter binds (VAR_EXTERNAL, VAR_IN_OUT) stay valid.
How each IEC type's values are terms, and what works on terms without an
Encoder, is terms.py.

``Encoder`` is one class written in five files, one mixin per part, in the
order a reader meets them:

    encode.py        Encoder: its state (fault sites, unrolling counts, the
                     lazy strings' stand-ins), implicit conversions
                     (``conv``), a POU body (VAR_TEMP, edge inputs),
                     statements, loops unrolled a bounded number of times
    encode_expr.py   ExprEncoding: variable access (indexes, members, bits)
                     and expressions
    encode_calls.py  CallEncoding: calls, EN/ENO, argument binding, user
                     functions and FB instances
    encode_std.py    StdEncoding: the standard functions and function
                     blocks (the timers' automata)
    encode_il.py     ILEncoding: IL, its current result, forward jumps

The mixins reach each other and the Encoder's state through ``self``; they
import terms.py and the checker's and interpreter's modules, never
encode.py (which imports them).  model.py runs the Encoder over a cycle.

Every construct the encoder cannot encode exactly raises Refuse naming it.
"""

from __future__ import annotations

import z3

from .. import ast
from ..checks.symbols import Var
from ..checks.types import ArrayT, BOOL, EnumT, FBType, LiteralT, StringT, concrete
from ..interp.closures import implicit
from ..interp.compiler import PouCompiler
from ..interp.errors import ENUM, LOOP
from ..execmodel import LOOP_BUDGET
from ..interp.model import Instance
from ..interp.values import base_of
from .encode_calls import CallEncoding
from .encode_expr import ExprEncoding
from .encode_il import ILEncoding
from .encode_std import StdEncoding
from .terms import (FALSE, MAX_TOTAL_UNROLL, MAX_UNROLL, REFUSED, TRUE, UNROLL, Cell, Frame,
                    Opaque, Refuse, _representable, bv_lit, const_of, fp_sort, ite, kind, land,
                    lnot, lor, py_value, signed, simplify_if_const, width)


class Encoder(ExprEncoding, CallEncoding, StdEncoding, ILEncoding):
    """Executes POU bodies symbolically.  ``sym`` is the SymbolicMachine
    (storage, initial values, timers' step)."""

    def __init__(self, sym):
        self.sym = sym
        self.m = sym.machine
        self.faults = []          # (cond, kind, pou name, src, pos)
        self.unrolled = 0
        self.max_iter = getattr(sym, "max_iter", 16)
        self._ipc = {}
        self.time_step = 0
        # lazy_strings: a STRING construct is not refused where it is met;
        # a non-string value computed from strings (FIND, LEN, a string
        # comparison) is a stand-in constant named REFUSED..., recorded here
        # with the construct, and a check whose cone of influence reads one
        # is refused naming it (engine.refusal); string values themselves
        # are Opaque and never reach a term.  The string functions cannot
        # fault (the interpreter's), and their other arguments are encoded.
        self.lazy_strings = False
        self.refused = {}         # stand-in name -> (src, pos, message)
        self.stand_ins = []

    # ------------------------------------------------------- utilities
    def ipc(self, pou):
        pc = self._ipc.get(pou.key)
        if pc is None:
            pc = self._ipc[pou.key] = PouCompiler(self.m, pou)
        return pc

    def refuse(self, pou, pos, what):
        raise Refuse(pou.src if pou is not None else None, pos,
                     f"verify: {what} cannot be encoded exactly")

    def stand_in(self, pou, pos, what, t):
        """lazy_strings: the stand-in of a value of type t computed by the
        construct `what` (an Opaque for a string)."""
        if not self.lazy_strings:
            self.refuse(pou, pos, what)
        ct = concrete(t) if t is not None else None
        if ct is None or isinstance(base_of(ct), StringT):
            return Opaque(what, ct)
        name = f"{REFUSED}{len(self.refused)}"
        self.refused[name] = (pou.src if pou is not None else None, pos,
                              f"verify: {what} cannot be encoded exactly")
        c = z3.Const(name, const_of(0, ct).sort())
        self.stand_ins.append(c)
        return c

    def fault(self, g, cond, what, frame, pos):
        if z3.is_expr(cond) and z3.is_false(z3.simplify(cond)):
            return          # cannot happen (a constant index in range...)
        c = land(g, cond)
        if not z3.is_false(c):
            self.faults.append((c, what, frame.pou.name, frame.pou.src, pos))

    def conv(self, v, src, dst, frame=None, pos=None):
        """A value of type src converted implicitly to dst (the
        interpreter's ``implicit``)."""
        if dst is None:
            return v
        if isinstance(v, (list, dict, Instance, Opaque)):
            return v
        if isinstance(v, (int, float, bool)) and not isinstance(v, z3.ExprRef):
            # an exact literal value: convert in Python as the interpreter does
            if isinstance(dst, LiteralT):
                return v
            f = implicit(src if src is not None else LiteralT(
                "real" if isinstance(v, float) else "int", v), dst)
            pv = f(v) if f is not None else v
            if kind(dst) == "bv" and isinstance(pv, float):
                pv = int(pv)
            return const_of(pv, concrete(dst))
        if z3.is_int(v):          # a literal value held as a z3 Int
            if kind(dst) == "bv":
                return z3.Int2BV(v, width(dst))
            if kind(dst) == "bool":
                return v != 0
            if isinstance(dst, LiteralT):
                return v
            self.refuse(frame.pou if frame else None, pos,
                        "an untyped literal value converted to REAL on a conditional path")
        d = base_of(dst)
        s = base_of(src) if src is not None and not isinstance(src, LiteralT) else None
        kd = kind(d)
        if kd is None:
            return v
        if z3.is_bool(v):
            if kd == "bool":
                return v
            if kd == "bv":
                w = width(d)
                return z3.If(v, bv_lit(1, w), bv_lit(0, w))
            if kd == "fp":
                return z3.If(v, const_of(1.0, d), const_of(0.0, d))
        if z3.is_bv(v):
            w0 = v.size()
            sg = signed(s) if s is not None else True
            if kd == "bool":
                return v != bv_lit(0, w0)
            if kd == "bv":
                w = width(d)
                if w == w0:
                    return v
                if w < w0:
                    return z3.Extract(w - 1, 0, v)
                return z3.SignExt(w - w0, v) if sg else z3.ZeroExt(w - w0, v)
            if kd == "fp":
                if sg:
                    return z3.fpSignedToFP(z3.RNE(), v, fp_sort(d))
                return z3.fpUnsignedToFP(z3.RNE(), v, fp_sort(d))
        if z3.is_fp(v):
            if kd == "fp":
                if v.sort() == fp_sort(d):
                    return v
                return z3.fpFPToFP(z3.RNE(), v, fp_sort(d))
            if kd == "bool":
                return z3.Not(z3.fpIsZero(v))
        return v

    # -------------------------------------------------------- statements
    def run_body(self, pou, inst, g):
        frame = Frame(inst, pou)
        for v in pou.vars.values():
            if v.section == "VAR_TEMP":
                t = concrete(v.type)
                if isinstance(t, FBType) or (isinstance(t, ArrayT) and
                                             isinstance(concrete(t.elem), FBType)):
                    inst.v[v.key] = self.sym.fresh_instance_value(v, inst)
                else:
                    inst.v[v.key] = self.sym.fresh_value(v)
        for v in pou.inputs:
            if v.edge:
                cur = inst.v[v.key]
                prev = inst.e["$" + v.key]
                e = z3.And(cur, z3.Not(prev)) if v.edge == "R_EDGE" else z3.And(prev, z3.Not(cur))
                inst.e[v.key] = ite(g, e, inst.e.get(v.key, FALSE))
                inst.e["$" + v.key] = ite(g, cur, prev)
        node = pou.node
        if node.language == "SFC":
            # steps, transitions and action control are not encoded: an
            # empty body here would give verdicts about a different program
            self.refuse(pou, node.pos, "an SFC body (steps, transitions, actions)")
        if node.language == "IL":
            self.il_body(node.body, frame, g)
        else:
            self.block(node.body, frame, g)

    def block(self, stmts, frame, g):
        for s in stmts:
            gs = land(g, lnot(frame.ret), lnot(frame.brk), lnot(frame.cnt))
            if z3.is_false(gs):
                return
            self.stmt(s, frame, gs)

    def stmt(self, s, frame, g):
        if isinstance(s, ast.Assign):
            v = self.expr(s.value, frame, g)
            self.write(s.target, v, s.value.type, frame, g, s.pos)
        elif isinstance(s, ast.CallStmt):
            c = s.call
            if isinstance(c.target, Var):
                self.fb_call(c, frame, g)
            else:
                self.call_expr(c, frame, g)
        elif isinstance(s, ast.If):
            rest = g
            for cnd, body in s.branches:
                c = self.expr_as(cnd, BOOL, frame, rest)
                self.block(body, frame, land(rest, c))
                rest = land(rest, lnot(c))
            if s.else_:
                self.block(s.else_, frame, rest)
        elif isinstance(s, ast.Case):
            self.case(s, frame, g)
        elif isinstance(s, ast.For):
            self.for_(s, frame, g)
        elif isinstance(s, ast.While):
            self.while_(s, frame, g)
        elif isinstance(s, ast.Repeat):
            self.repeat(s, frame, g)
        elif isinstance(s, ast.Exit):
            frame.brk = lor(frame.brk, g)
        elif isinstance(s, ast.Continue):
            frame.cnt = lor(frame.cnt, g)
        elif isinstance(s, ast.Return):
            frame.ret = lor(frame.ret, g)
        elif isinstance(s, ast.Empty):
            pass
        else:
            self.refuse(frame.pou, s.pos, f"the statement {type(s).__name__}")

    def case(self, s, frame, g):
        st = concrete(s.selector.type)
        sel = self.expr(s.selector, frame, g)
        sel = self.conv(sel, s.selector.type, st)
        w = sel.size()
        sg = signed(st)
        if isinstance(st, EnumT):
            valid = lor(*[sel == bv_lit(v, w) for _, v in st.values.values()])
            self.fault(g, lnot(valid), ENUM, frame, s.pos)
        taken = FALSE
        for n, values in enumerate(s.values):
            conds = []
            for lo, hi in values:
                if hi == lo:
                    if _representable(lo, w, sg):
                        conds.append(sel == bv_lit(lo, w))
                else:
                    lo2 = max(lo, -(1 << (w - 1)) if sg else 0)
                    hi2 = min(hi, (1 << (w - 1)) - 1 if sg else (1 << w) - 1)
                    if lo2 > hi2:
                        continue
                    if sg:
                        conds.append(z3.And(sel >= bv_lit(lo2, w), sel <= bv_lit(hi2, w)))
                    else:
                        conds.append(z3.And(z3.UGE(sel, bv_lit(lo2, w)),
                                            z3.ULE(sel, bv_lit(hi2, w))))
            c = lor(*conds)
            self.block(s.elements[n][1], frame, land(g, c, lnot(taken)))
            taken = lor(taken, c)
        if s.else_:
            self.block(s.else_, frame, land(g, lnot(taken)))

    def for_(self, s, frame, g):
        pou = frame.pou
        v = pou.var(s.var)
        vt = concrete(v.type)
        vals = []
        terms = []
        for e in (s.start, s.end, s.step):
            if e is None:
                vals.append(1)
                terms.append(bv_lit(1, width(vt)))
                continue
            x = self.expr_as(e, vt, frame, g)
            x = simplify_if_const(x)
            terms.append(x)
            vals.append(py_value(x, vt) if z3.is_bv_value(x) else None)
        if vals[2] is None:
            self.refuse(pou, s.step.pos, "a FOR loop whose step is not constant")
        if vals[0] is None or vals[1] is None:
            return self.for_bounded(s, frame, g, v, vt, terms, vals[2])
        a, e_, st = vals
        lo_t, hi_t = base_of(vt).range
        seq = []
        i = a
        up = st >= 0
        final = None     # the value stored by the step that ends the loop
        while not ((i > e_) if up else (i < e_)):
            seq.append(i)
            if len(seq) > LOOP_BUDGET:
                break
            i = i + st
            if i < lo_t or i > hi_t:
                break
            if (i > e_) if up else (i < e_):
                final = i
                break
        if len(seq) > LOOP_BUDGET:
            # the loop budget runs out whenever the loop is reached
            self.fault(g, TRUE, LOOP, frame, s.pos)
            return
        if len(seq) > MAX_UNROLL:
            self.refuse(pou, s.pos, f"a FOR loop of {len(seq)} iterations (more than "
                                    f"{MAX_UNROLL})")
        self.unrolled += len(seq)
        if self.unrolled > MAX_TOTAL_UNROLL:
            self.refuse(pou, s.pos, f"more than {MAX_TOTAL_UNROLL} loop iterations in one cycle")
        cell = Cell(frame.inst.v, v.key)
        w = width(vt)
        cell.put(g, bv_lit(a, w))
        saved = frame.brk
        frame.brk = FALSE
        for n, i in enumerate(seq):
            gi = land(g, lnot(frame.brk), lnot(frame.ret))
            if z3.is_false(gi):
                break
            if n > 0:
                cell.put(gi, bv_lit(i, w))
            self.iteration(s.body, frame, gi)
        if final is not None and seq:
            cell.put(land(g, lnot(frame.brk), lnot(frame.ret)), bv_lit(final, w))
        frame.brk = saved

    # --------------------------------------------- loops, unrolled a bounded number of times
    def iteration(self, body, frame, g):
        """One iteration of a loop's body: a CONTINUE in it skips the rest of
        the body, then ends with the iteration (the step or the test runs)."""
        saved = frame.cnt
        frame.cnt = FALSE
        self.block(body, frame, g)
        frame.cnt = saved

    def unroll_exceeded(self, g, cond, frame, pos):
        """The loop may run more iterations than the encoding unrolls: not a
        runtime error, an undecided case (reported as such, never assumed)."""
        self.fault(g, cond, f"{UNROLL}more than {self.max_iter} iterations of a loop "
                            "(the encoding's unrolling bound, --unroll)", frame, pos)

    def _count(self, n, frame, pos):
        self.unrolled += n
        if self.unrolled > MAX_TOTAL_UNROLL:
            self.refuse(frame.pou, pos, f"more than {MAX_TOTAL_UNROLL} loop iterations in one "
                                        "cycle")

    def while_(self, s, frame, g):
        saved = frame.brk
        frame.brk = FALSE
        live = g
        self._count(self.max_iter, frame, s.pos)
        for _ in range(self.max_iter):
            gi = land(live, lnot(frame.brk), lnot(frame.ret))
            c = self.expr_as(s.cond, BOOL, frame, gi)
            run = land(gi, c)
            if z3.is_false(run) or z3.is_false(z3.simplify(run)):
                break
            self.iteration(s.body, frame, run)
            live = run
        else:
            gi = land(live, lnot(frame.brk), lnot(frame.ret))
            self.unroll_exceeded(gi, self.expr_as(s.cond, BOOL, frame, gi), frame, s.pos)
        frame.brk = saved

    def repeat(self, s, frame, g):
        saved = frame.brk
        frame.brk = FALSE
        live = g
        self._count(self.max_iter, frame, s.pos)
        for _ in range(self.max_iter):
            gi = land(live, lnot(frame.brk), lnot(frame.ret))
            if z3.is_false(gi) or z3.is_false(z3.simplify(gi)):
                break
            self.iteration(s.body, frame, gi)
            gi = land(gi, lnot(frame.brk), lnot(frame.ret))
            c = self.expr_as(s.cond, BOOL, frame, gi)
            live = land(gi, lnot(c))
        else:
            gi = land(live, lnot(frame.brk), lnot(frame.ret))
            self.unroll_exceeded(gi, TRUE, frame, s.pos)
        frame.brk = saved

    def for_bounded(self, s, frame, g, v, vt, terms, st):
        """A FOR loop with variable start or end (constant step), unrolled."""
        a, e, _ = terms
        w = width(vt)
        sg = signed(vt)
        lo_t, hi_t = base_of(vt).range
        cell = Cell(frame.inst.v, v.key)
        cell.put(g, a)
        up = st >= 0
        ww = w + 2

        def ext(x):
            return z3.SignExt(2, x) if sg else z3.ZeroExt(2, x)

        def gt(x, y):
            return x > y if sg else z3.UGT(x, y)

        def lt(x, y):
            return x < y if sg else z3.ULT(x, y)
        if st == 0:
            # never ends once started: the loop budget runs out
            self.fault(land(g, lnot(gt(a, e))), TRUE, LOOP, frame, s.pos)
            return
        saved = frame.brk
        frame.brk = FALSE
        live = g
        self._count(self.max_iter, frame, s.pos)
        for _ in range(self.max_iter):
            i = cell.get()
            cont = lnot(gt(i, e)) if up else lnot(lt(i, e))
            run = land(live, lnot(frame.brk), lnot(frame.ret), cont)
            if z3.is_false(run) or z3.is_false(z3.simplify(run)):
                live = FALSE
                break
            self.iteration(s.body, frame, run)
            gi = land(run, lnot(frame.brk), lnot(frame.ret))
            nxt = ext(cell.get()) + bv_lit(st, ww)
            inside = z3.And(nxt >= bv_lit(lo_t, ww), nxt <= bv_lit(hi_t, ww)) if sg else \
                z3.And(z3.UGE(nxt, bv_lit(lo_t, ww)), z3.ULE(nxt, bv_lit(hi_t, ww)))
            cell.put(land(gi, inside), z3.Extract(w - 1, 0, nxt))
            live = land(gi, inside)
        else:
            i = cell.get()
            cont = lnot(gt(i, e)) if up else lnot(lt(i, e))
            self.unroll_exceeded(land(live, lnot(frame.brk), lnot(frame.ret)), cont, frame,
                                 s.pos)
        frame.brk = saved

