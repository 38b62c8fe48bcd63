"""Encoder, the standard library: every standard function family on its
arguments' terms in the call's types (arithmetic with its division faults,
time and date arithmetic, shifts, bitwise, selection, comparison,
conversions; exact integer arithmetic on untyped literals), the string
functions as stand-ins (lazy strings), and the standard function blocks:
SR, RS, R_TRIG, F_TRIG, the counters and the timers TON, TOF, TP as
seed 002's automata (the elapsed time advances in model.py, by the task's
period).  EXPT, the transcendental functions and the conversions the
encoding cannot make exactly are refused.

``StdEncoding`` is mixed into encode.Encoder, whose state it uses
(``lazy_strings``) and whose methods it calls: ``conv``, ``fault``,
``refuse``, ``stand_in`` (encode.py), ``expr``, ``expr_as``
(encode_expr.py).  It imports terms.py, the checker and the interpreter
(interp.std for exact literal arithmetic), not encode.py."""

from __future__ import annotations

import z3

from ..checks import stdlib
from ..checks.types import BOOL, EnumT, LiteralT, StringT, concrete
from ..checks.types import ELEMENTARY as _E
from ..interp.errors import DIV_ZERO, MUX
from ..interp.values import base_of
from .terms import (INIT, NS_PER_DAY, ON, TOUT, TRUE, WORK, _representable, bv_lit, compare,
                    const_of, ite, kind, land, lnot, lor, signed, width)

ELEM_LINT = _E["LINT"]


class StdEncoding:
    # ------------------------------------------------ standard functions
    def apply_std(self, fres, args, sig, frame, g, pos):
        fam = fres.family
        pou = frame.pou
        res, ptypes = sig
        if isinstance(res, LiteralT):
            vals = [literal_int(self.expr(a, frame, g), a) for a in args]
            return self.literal_arith(fam, vals, res, frame, g, pos)
        if isinstance(base_of(res), StringT) or any(
                isinstance(base_of(concrete(pt)), StringT) for pt in ptypes):
            if self.lazy_strings:
                for a in args:      # their faults are the call's
                    self.expr(a, frame, g)
            return self.stand_in(pou, pos, f"the string function {fres.name}", res)

        def vals():
            return [self.expr_as(a, concrete(pt), frame, g) for a, pt in zip(args, ptypes)]

        if fam in stdlib.ARITH_FAMILIES:
            fs = [self.expr_as(a, res, frame, g) for a in args]
            acc = fs[0]
            for b in fs[1:]:
                acc = self.arith(fam, acc, b, res, frame, g, pos)
            return acc
        if fam in ("ADD_TIME", "SUB_TIME"):
            a, b = vals()
            return a + b if fam == "ADD_TIME" else a - b
        if fam in ("MUL_TIME", "DIV_TIME"):
            t2 = concrete(ptypes[1])
            a = self.expr_as(args[0], concrete(ptypes[0]), frame, g)
            if kind(t2) == "fp":
                # the time as a binary64, times (or divided by) the factor, rounded
                # to nearest even and saturated into 64 bits (std.mul_time_real)
                f = self.expr_as(args[1], t2, frame, g)
                d = z3.Float64()
                x = z3.fpSignedToFP(z3.RNE(), a, d)
                y = z3.fpFPToFP(z3.RNE(), f, d) if f.sort() != d else f
                if fam == "MUL_TIME":
                    r = z3.fpMul(z3.RNE(), x, y)
                else:
                    self.fault(g, z3.fpIsZero(y), DIV_ZERO, frame, pos)
                    r = z3.fpDiv(z3.RNE(), x, y)
                return real_to_int(r, ELEM_LINT, z3.RNE())
            b = self.conv(self.expr_as(args[1], t2, frame, g), t2, concrete(ptypes[0]))
            if fam == "MUL_TIME":
                return a * b
            self.fault(g, b == bv_lit(0, 64), DIV_ZERO, frame, pos)
            return z3.If(b == bv_lit(0, 64), bv_lit(0, 64), a / b)
        if fam in stdlib.TIME_FAMILIES:
            a = self.expr_as(args[0], concrete(ptypes[0]), frame, g)
            b = self.expr_as(args[1], concrete(ptypes[1]), frame, g)
            if fam in ("ADD_TOD_TIME", "SUB_TOD_TIME"):
                day = bv_lit(NS_PER_DAY, 64)
                x, y = a % day, b % day      # bvsmod, Python's %: the sign of the divisor
                return (x + y if fam == "ADD_TOD_TIME" else x - y) % day
            if fam in ("ADD_DT_TIME", "CONCAT_DATE_TOD"):
                return a + b
            return a - b          # SUB_DT_TIME SUB_DATE_DATE SUB_TOD_TOD SUB_DT_DT
        if fam == "EXPT":
            self.refuse(pou, pos, "EXPT (**)")
        if fam == "MOVE":
            return self.expr_as(args[0], res, frame, g)
        if fam == "ABS":
            a = self.expr_as(args[0], res, frame, g)
            if z3.is_fp(a):
                return z3.fpAbs(a)
            if signed(res):
                return z3.If(a < bv_lit(0, a.size()), -a, a)
            return a
        if fam == "SQRT":
            a = self.expr_as(args[0], res, frame, g)
            return z3.fpSqrt(z3.RNE(), a)
        if fam in ("LN", "LOG", "EXP", "SIN", "COS", "TAN", "ASIN", "ACOS", "ATAN", "ATAN2"):
            self.refuse(pou, pos, f"the transcendental function {fam}")
        if fam in ("SHL", "SHR", "ROL", "ROR"):
            a, n = vals()
            w = a.size()
            nt = concrete(ptypes[1])
            n = self.conv(n, nt, nt)
            nw = n.size()
            ww = max(w, nw) + 1
            nn = z3.SignExt(ww - nw, n) if signed(nt) else z3.ZeroExt(ww - nw, n)
            if fam in ("SHL", "SHR"):
                outside = z3.Or(nn < bv_lit(0, ww), nn >= bv_lit(w, ww))
                amount = z3.Extract(w - 1, 0, nn) if ww > w else nn
                sh = a << amount if fam == "SHL" else z3.LShR(a, amount)
                return z3.If(outside, bv_lit(0, w), sh)
            r = _py_mod(nn, w, ww)
            amount = z3.Extract(w - 1, 0, r) if ww > w else r
            if w == 1:
                return a
            return z3.RotateLeft(a, amount) if fam == "ROL" else z3.RotateRight(a, amount)
        if fam in ("AND", "OR", "XOR"):
            fs = [self.expr_as(a, res, frame, g) for a in args]
            if kind(res) == "bool":
                if fam == "AND":
                    return land(*fs) if len(fs) > 1 else fs[0]
                if fam == "OR":
                    return lor(*fs) if len(fs) > 1 else fs[0]
                acc = fs[0]
                for f in fs[1:]:
                    acc = z3.Xor(acc, f)
                return acc
            acc = fs[0]
            for f in fs[1:]:
                acc = acc & f if fam == "AND" else acc | f if fam == "OR" else acc ^ f
            return acc
        if fam == "NOT":
            a = self.expr_as(args[0], res, frame, g)
            return z3.Not(a) if z3.is_bool(a) else ~a
        if fam == "SEL":
            gv = self.expr_as(args[0], BOOL, frame, g)
            a0 = self.expr_as(args[1], res, frame, g)
            a1 = self.expr_as(args[2], res, frame, g)
            return ite(gv, a1, a0)
        if fam in ("MAX", "MIN", "LIMIT"):
            fs = [self.expr_as(a, res, frame, g) for a in args]
            if fam == "LIMIT":
                mn, v, mx = fs
                return self.minmax("MIN", [self.minmax("MAX", [v, mn], res), mx], res)
            return self.minmax(fam, fs, res)
        if fam == "MUX":
            kt = concrete(ptypes[0])
            k = self.expr_as(args[0], kt, frame, g)
            fs = [self.expr_as(a, res, frame, g) for a in args[1:]]
            w = k.size()
            sg = signed(kt)
            out = fs[-1]
            conds = []
            for i in range(len(fs) - 1, -1, -1):
                if not _representable(i, w, sg):
                    continue
                c = k == bv_lit(i, w)
                conds.append(c)
                out = ite(c, fs[i], out)
            self.fault(g, lnot(lor(*conds)), MUX, frame, pos)
            return out
        if fam in stdlib.COMPARE_FAMILIES:
            ct = concrete(ptypes[0])
            fs = [self.expr_as(a, ct, frame, g) for a in args]
            if fam == "NE":
                return compare("<>", fs[0], fs[1], ct)
            op = {"GT": ">", "GE": ">=", "EQ": "=", "LE": "<=", "LT": "<"}[fam]
            return land(*[compare(op, fs[i], fs[i + 1], ct) for i in range(len(fs) - 1)])
        if fam in ("CONVERT", "TRUNC"):
            src = concrete(ptypes[0])
            a = self.expr_as(args[0], src, frame, g)
            return self.convert(fam, a, src, res, pou, pos)
        self.refuse(pou, pos, f"the standard function {fres.name}")

    def literal_arith(self, fam, vals, res, frame, g, pos):
        if all(not isinstance(v, z3.ExprRef) for v in vals):
            from ..interp import std
            acc = vals[0]
            for y in vals[1:]:
                if fam == "ADD":
                    acc = acc + y
                elif fam == "SUB":
                    acc = acc - y
                elif fam == "MUL":
                    acc = acc * y
                elif fam == "DIV":
                    if res.cat == "real":
                        acc = std.real_div(float(acc), float(y))
                    else:
                        if y == 0:
                            self.fault(g, TRUE, DIV_ZERO, frame, pos)
                            return 0
                        acc = std.int_div(acc, y)
                elif fam == "MOD":
                    if y == 0:
                        self.fault(g, TRUE, DIV_ZERO, frame, pos)
                        return 0
                    acc = std.int_mod(acc, y)
                else:
                    self.refuse(frame.pou, pos, "EXPT (**)")
            return acc
        if res.cat == "real":
            self.refuse(frame.pou, pos, "untyped REAL literal arithmetic on a conditional path")
        xs = [z3.IntVal(v) if not isinstance(v, z3.ExprRef) else v for v in vals]
        acc = xs[0]
        for y in xs[1:]:
            if fam == "ADD":
                acc = acc + y
            elif fam == "SUB":
                acc = acc - y
            elif fam == "MUL":
                acc = acc * y
            else:
                self.fault(g, y == 0, DIV_ZERO, frame, pos)
                qa = z3.If(acc >= 0, acc, -acc)
                qb = z3.If(y >= 0, y, -y)
                q = qa / z3.If(qb == 0, 1, qb)
                if fam == "DIV":
                    acc = z3.If((acc >= 0) == (y >= 0), q, -q)
                else:
                    r = qa % z3.If(qb == 0, 1, qb)
                    acc = z3.If(acc >= 0, r, -r)
        return acc

    def arith(self, fam, a, b, t, frame, g, pos):
        if z3.is_fp(a):
            op = {"ADD": z3.fpAdd, "SUB": z3.fpSub, "MUL": z3.fpMul, "DIV": z3.fpDiv}.get(fam)
            if op is None:
                self.refuse(frame.pou, pos, "MOD on REAL")
            return op(z3.RNE(), a, b)
        if fam == "ADD":
            return a + b
        if fam == "SUB":
            return a - b
        if fam == "MUL":
            return a * b
        w = a.size()
        zero = bv_lit(0, w)
        self.fault(g, b == zero, DIV_ZERO, frame, pos)
        if signed(t):
            q = a / b if fam == "DIV" else z3.SRem(a, b)
        else:
            q = z3.UDiv(a, b) if fam == "DIV" else z3.URem(a, b)
        return z3.If(b == zero, zero, q)

    def minmax(self, fam, fs, t):
        acc = fs[0]
        for x in fs[1:]:
            if z3.is_fp(acc):
                keep = z3.fpGEQ(acc, x) if fam == "MAX" else z3.fpLEQ(acc, x)
                acc = z3.If(z3.fpIsNaN(acc), acc, z3.If(z3.fpIsNaN(x), x,
                                                      z3.If(keep, acc, x)))
            elif z3.is_bool(acc):
                acc = z3.Or(acc, x) if fam == "MAX" else z3.And(acc, x)
            else:
                keep = compare(">=" if fam == "MAX" else "<=", acc, x, t)
                acc = ite(keep, acc, x)
        return acc

    def convert(self, fam, a, src, dst, pou, pos):
        sb, db = base_of(src), base_of(dst)
        if isinstance(sb, EnumT) or isinstance(db, EnumT):
            self.refuse(pou, pos, "a conversion of an enumeration")
        sc, dc = sb.cat, db.cat
        ints = ("sint", "uint", "bit")
        if fam == "TRUNC":
            return real_to_int(a, db, z3.RTZ())
        if dc == "bool":
            if sc == "bool":
                return a
            if sc == "real":
                return z3.Not(z3.fpIsZero(a))
            return a != bv_lit(0, a.size())
        if sc == "bool":
            if dc in ints:
                return z3.If(a, bv_lit(1, db.bits), bv_lit(0, db.bits))
            if dc == "real":
                return z3.If(a, const_of(1.0, db), const_of(0.0, db))
            if dc == "time" and db.name == "LTIME":
                return z3.If(a, bv_lit(1, 64), bv_lit(0, 64))
            if dc == "time":
                return z3.If(a, bv_lit(1_000_000, 64), bv_lit(0, 64))
        if sc in ints and dc in ints:
            return self.conv(a, sb, db) if db.bits != sb.bits else a
        if sc in ints and dc == "real":
            return self.conv(a, sb, db)
        if sc == "real" and dc in ints:
            return real_to_int(a, db, z3.RNE())
        if sc == "real" and dc == "real":
            return self.conv(a, sb, db)
        if sc == "time" and dc in ints:
            unit = 1 if sb.name == "LTIME" else 1_000_000
            q = a if unit == 1 else a / bv_lit(unit, 64)   # truncation toward zero
            return self.conv(q, ELEM_LINT, db)
        if sc in ints and dc == "time":
            unit = 1 if db.name == "LTIME" else 1_000_000
            v = self.conv(a, sb, ELEM_LINT)
            return v * bv_lit(unit, 64)
        if sc == "time" and dc == "time":
            return a
        self.refuse(pou, pos, f"the conversion {sb.name} to {db.name}")

    # -------------------------------------------------- standard FBs
    def std_fb(self, pou, inst, g, frame, pos):
        v = inst.v
        name = pou.name.upper()

        def put(k, val):
            v[k] = ite(g, val, v[k])
        if name == "SR":
            put("Q1", z3.Or(v["S1"], z3.And(z3.Not(v["R"]), v["Q1"])))
        elif name == "RS":
            put("Q1", z3.And(z3.Not(v["R1"]), z3.Or(v["S"], v["Q1"])))
        elif name == "R_TRIG":
            clk = v["CLK"]
            put("Q", z3.And(clk, z3.Not(v["$M"])))
            put("$M", clk)
        elif name == "F_TRIG":
            clk = v["CLK"]
            put("Q", z3.And(z3.Not(clk), z3.Not(v["$M"])))
            put("$M", z3.Not(clk))
        elif name in ("TON", "TOF", "TP"):
            self.timer(name, v, put)
        else:
            for k in ("CTUD", "CTU", "CTD"):
                if name.startswith(k):
                    self.counter(k, pou, v, put)
                    return
            raise AssertionError(name)

    def counter(self, kind_, pou, v, put):
        t = pou.vars["CV"].type
        lo, hi = base_of(t).range
        w = width(t)
        cv = v["CV"]
        pv = v["PV"]
        lo_, hi_ = bv_lit(lo, w), bv_lit(hi, w)
        one = bv_lit(1, w)

        def edge(name):
            x = v[name]
            e = z3.And(x, z3.Not(v["$" + name]))
            put("$" + name, x)
            return e
        lt = (lambda a, b: a < b) if signed(t) else z3.ULT
        ge = (lambda a, b: a >= b) if signed(t) else z3.UGE
        le = (lambda a, b: a <= b) if signed(t) else z3.ULE
        zero = bv_lit(0, w)
        if kind_ == "CTU":
            cu = edge("CU")
            new = z3.If(v["R"], zero, z3.If(z3.And(cu, lt(cv, hi_)), cv + one, cv))
            put("CV", new)
            put("Q", ge(new, pv))
        elif kind_ == "CTD":
            cd = edge("CD")
            new = z3.If(v["LD"], pv, z3.If(z3.And(cd, lt(lo_, cv)), cv - one, cv))
            put("CV", new)
            put("Q", le(new, zero) if signed(t) else new == zero)
        else:
            cu = edge("CU")
            cd = edge("CD")
            new = z3.If(v["R"], zero, z3.If(v["LD"], pv, z3.If(
                z3.And(cu, cd), cv, z3.If(z3.And(cu, lt(cv, hi_)), cv + one,
                                          z3.If(z3.And(cd, lt(lo_, cv)), cv - one, cv)))))
            put("CV", new)
            put("QU", ge(new, pv))
            put("QD", le(new, zero) if signed(t) else new == zero)

    def timer(self, name, v, put):
        zero = bv_lit(0, 64)
        pt = z3.If(v["PT"] < zero, zero, v["PT"])
        st = v["$S"]
        el = v["$EL"]
        inp = v["IN"]
        S = lambda n: z3.BitVecVal(n, 2)  # noqa: E731
        if name == "TON":
            enter = z3.And(inp, st == S(INIT))
            st1 = z3.If(z3.Not(inp), S(INIT), z3.If(st == S(INIT), S(WORK), st))
            el1 = z3.If(enter, zero, el)
            st2 = z3.If(z3.And(st1 == S(WORK), el1 >= pt), S(TOUT), st1)
            q = st2 == S(TOUT)
        elif name == "TOF":
            enter = z3.And(z3.Not(inp), st == S(ON))
            st1 = z3.If(inp, S(ON), z3.If(st == S(ON), S(WORK), st))
            el1 = z3.If(enter, zero, el)
            st2 = z3.If(z3.And(z3.Not(inp), st1 == S(WORK), el1 >= pt), S(TOUT), st1)
            q = z3.Or(st2 == S(ON), st2 == S(WORK))
        else:
            rising = z3.And(inp, z3.Not(v["$LAST"]))
            enter = z3.And(z3.Or(st == S(INIT), st == S(TOUT)), rising)
            st1 = z3.If(enter, S(WORK), st)
            el1 = z3.If(enter, zero, el)
            st2 = z3.If(st1 == S(WORK),
                        z3.If(el1 >= pt, z3.If(inp, S(TOUT), S(INIT)), st1),
                        z3.If(z3.And(st1 == S(TOUT), z3.Not(inp)), S(INIT), st1))
            put("$LAST", inp)
            q = st2 == S(WORK)
        put("$S", st2)
        put("$EL", z3.If(st2 == S(WORK), el1, zero))
        put("Q", q)
        put("ET", z3.If(st2 == S(WORK), el1, z3.If(st2 == S(TOUT), pt, zero)))


def literal_int(v, a):
    """An operand of untyped literal arithmetic as an unbounded integer: a
    typed operand (TRUNC(1.5), a DINT the encoding holds as a bit-vector)
    by its value in its own type's signedness (as the interpreter takes a
    typed value into literal arithmetic)."""
    if not isinstance(v, z3.BitVecRef):
        return v
    t = getattr(a, "type", None)
    sg = True if t is None or isinstance(t, LiteralT) else signed(concrete(t))
    v = z3.simplify(v)
    if z3.is_bv_value(v):
        x = v.as_long()
        return x - (1 << v.size()) if sg and x >> (v.size() - 1) else x
    return z3.BV2Int(v, is_signed=sg)


def _py_mod(nn, w, ww):
    """n mod w as Python's % does (a non-negative result)."""
    m = bv_lit(w, ww)
    r = z3.SRem(nn, m)
    return z3.If(r < bv_lit(0, ww), r + m, r)


def real_to_int(a, db, mode):
    """REAL to integer: rounded (RNE) or truncated (RTZ), saturated, NaN -> 0."""
    w = db.bits
    s = a.sort()
    r = z3.fpRoundToIntegral(mode, a)
    if db.cat == "sint":
        lo = z3.fpSignedToFP(z3.RNE(), bv_lit(-(1 << (w - 1)), w + 1), s)
        top = z3.fpUnsignedToFP(z3.RNE(), bv_lit(1 << (w - 1), w + 1), s)
        return z3.If(z3.fpIsNaN(a), bv_lit(0, w),
                     z3.If(z3.fpLT(r, lo), bv_lit(-(1 << (w - 1)), w),
                           z3.If(z3.fpGEQ(r, top), bv_lit((1 << (w - 1)) - 1, w),
                                 z3.fpToSBV(z3.RTZ(), r, z3.BitVecSort(w)))))
    top = z3.fpUnsignedToFP(z3.RNE(), bv_lit(1 << w, w + 1), s)
    zero = z3.fpPlusZero(s)
    return z3.If(z3.fpIsNaN(a), bv_lit(0, w),
                 z3.If(z3.fpLT(r, zero), bv_lit(0, w),
                       z3.If(z3.fpGEQ(r, top), bv_lit((1 << w) - 1, w),
                             z3.fpToUBV(z3.RTZ(), r, z3.BitVecSort(w)))))
