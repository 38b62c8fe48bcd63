"""Encoder, variable access and expressions: the Place of a variable
access (constant or symbolic indexes, each index out of range a fault;
structure and FB members; bits), reading it and writing it
(``store_value``: converted, subrange-checked, copied), and the term of
every expression: literals, references, operators (an untyped expression
typed by its context, as the interpreter types it).

``ExprEncoding`` is mixed into encode.Encoder, whose state it uses
(``sym``, ``lazy_strings``) and whose methods it calls: ``conv``, ``fault``,
``refuse``, ``stand_in``, ``ipc`` (encode.py), ``call_expr``, ``std_call``
(encode_calls.py), ``apply_std`` (encode_std.py), ``cr_get``
(encode_il.py).  It imports terms.py, the checker and the interpreter, not
encode.py."""

from __future__ import annotations

import z3

from .. import ast
from ..checks import stdlib
from ..checks.symbols import EnumValue
from ..checks.types import (BOOL, Elementary, LiteralT, StringT, StructT, SubrangeT,
                            concrete)
from ..interp.errors import INDEX, RANGE
from ..interp.model import Instance
from ..interp.values import base_of
from .terms import (FALSE, TRUE, Cell, Opaque, Place, _representable, _SlotVal, bv_lit,
                    compare, const_of, copy_tree, land, lnot, logic, lor, py_value, signed,
                    simplify_if_const, width)


class ExprEncoding:
    # -------------------------------------------------- variable access
    def place(self, r, frame, g):
        """The Place of a variable access (faults of its indexes recorded
        under g)."""
        sym = r.symbol
        inst = frame.inst
        k = sym.key
        if sym.section in ("VAR_EXTERNAL", "VAR_IN_OUT"):
            base = inst.r[k]
            if isinstance(base, Place):
                place = base
            else:
                place = Place([(TRUE, Cell(base[0], base[1]))])
        else:
            place = Place([(TRUE, Cell(inst.v, k))])
        t = sym.type
        for kind_, val, pos in r.accessors:
            place, t = self.accessor(place, t, kind_, val, pos, frame, g)
        return place

    def accessor(self, place, t, kind_, val, pos, frame, g):
        t = concrete(t)
        if kind_ == "index":
            dims = t.dims
            strides = []
            n = 1
            for lo, hi in reversed(dims):
                strides.append(n)
                n *= hi - lo + 1
            strides.reverse()
            # every index value: constant or symbolic
            offs = [(TRUE, 0)]
            bad = FALSE
            for e, (lo, hi), st in zip(val, dims, strides):
                iv = self.expr(e, frame, g)
                it = e.type
                if not isinstance(iv, z3.ExprRef):
                    i = int(iv)
                    if i < lo or i > hi:
                        bad = TRUE
                        choices = [(TRUE, lo)]
                    else:
                        choices = [(TRUE, i)]
                else:
                    iv = simplify_if_const(iv)
                    if z3.is_bv_value(iv):
                        i = py_value(iv, it)
                        if i < lo or i > hi:
                            bad = TRUE
                            choices = [(TRUE, lo)]
                        else:
                            choices = [(TRUE, i)]
                    else:
                        w = iv.size()
                        sg = signed(it)
                        # the index compared in a width that holds lo..hi and the index
                        ww = max(w, 66)
                        ext = z3.SignExt(ww - w, iv) if sg else z3.ZeroExt(ww - w, iv)
                        inside = []
                        choices = []
                        for i in range(lo, hi + 1):
                            if not _representable(i, w, sg):
                                continue
                            c = ext == bv_lit(i, ww)
                            choices.append((c, i))
                            inside.append(c)
                        bad = lor(bad, lnot(lor(*inside)))
                        if not choices:
                            choices = [(TRUE, lo)]
                new = []
                for c0, o in offs:
                    for c1, i in choices:
                        new.append((land(c0, c1), o + (i - lo) * st))
                offs = new
            self.fault(g, bad, INDEX, frame, pos)
            alts = []
            for pc, cell in place.alts:
                for c, o in offs:
                    alts.append((land(pc, c), Cell(cell.c[cell.k], o)))
            return Place(alts), t.elem
        if kind_ == "member":
            key = val.upper()
            if isinstance(t, StructT):
                return Place([(c, Cell(cell.c[cell.k], key)) for c, cell in place.alts]), \
                    t.fields[key][1]
            mv = t.pou.var(val)
            alts = []
            for c, cell in place.alts:
                inst = cell.c[cell.k]
                if mv.section in ("VAR_IN_OUT", "VAR_EXTERNAL"):
                    ref = inst.r.get(key)
                    if ref is None:
                        alts.append((c, Cell(inst.v, key)))
                    elif isinstance(ref, Place):
                        for c2, cell2 in ref.alts:
                            alts.append((land(c, c2), cell2))
                    else:
                        alts.append((c, Cell(ref[0], ref[1])))
                else:
                    alts.append((c, Cell(inst.v, key)))
            return Place(alts), mv.type
        # bit access
        return Place([(c, Cell(cell.c, cell.k, val)) for c, cell in place.alts]), BOOL

    def read(self, r, frame, g):
        sym = r.symbol
        if isinstance(sym, EnumValue):
            return const_of(sym.value, sym.enum)
        if not r.accessors and sym.section == "VAR_INPUT" and sym.edge and \
                sym.owner is frame.pou:
            return frame.inst.e[sym.key]
        v = self.place(r, frame, g).get()
        if not z3.is_expr(v) and not isinstance(v, (list, dict, Instance)):
            if self.lazy_strings and isinstance(v, Opaque):
                return v
            self.refuse(frame.pou, r.pos, f"reading '{r.name}' (a STRING)")
        return v

    def store_value(self, v, src_t, dst_t, frame, g, pos):
        """v prepared for storage in dst_t: converted, range-checked."""
        ct = concrete(dst_t)
        if isinstance(ct, StringT):
            if self.lazy_strings and isinstance(v, Opaque):
                return v
            self.refuse(frame.pou, pos, "a STRING value")
        v = self.conv(v, src_t, dst_t, frame, pos)
        if isinstance(ct, SubrangeT):
            w = width(ct)
            sg = signed(ct)
            lo, hi = bv_lit(ct.low, w), bv_lit(ct.high, w)
            if sg:
                out = z3.Or(v < lo, v > hi)
            else:
                out = z3.Or(z3.ULT(v, lo), z3.UGT(v, hi))
            self.fault(g, out, RANGE, frame, pos)
        return copy_tree(v)

    def write(self, r, v, src_t, frame, g, pos):
        val = self.store_value(v, src_t, r.type, frame, g, pos)
        self.place(r, frame, g).put(g, val)

    # ------------------------------------------------------ expressions
    def expr_as(self, e, t, frame, g):
        if (t is not None and not isinstance(t, LiteralT) and isinstance(e.type, LiteralT)
                and isinstance(e, (ast.BinOp, ast.Call))):
            # as the interpreter: the context types an untyped expression
            # down to its generic calls (TRUNC(1.0E10) + 1 into a LINT)
            v = self.in_context(e, t, frame, g)
            if v is not None:
                return v
        return self.conv(self.expr(e, frame, g), e.type, t, frame, e.pos)

    def in_context(self, e, t, frame, g):
        if isinstance(e, ast.BinOp) and e.fn is not None:
            return self.from_sig(self.apply_std(e.fn, [e.left, e.right], e.sig, frame, g, e.pos),
                                 e.sig, t, frame, e.pos)
        if isinstance(e, ast.Call) and isinstance(e.target, stdlib.StdFunc) \
                and isinstance(e.target.result, LiteralT):
            # in e.sig: settle gave it t
            return self.from_sig(self.std_call(e, frame, g), e.sig, t, frame, e.pos)
        return None

    def expr(self, e, frame, g):
        if isinstance(e, ast.Lit):
            if e.kind in ("string", "wstring"):
                return self.stand_in(frame.pou, e.pos, "a STRING literal", None)
            v = self.ipc(frame.pou).lit_value(e)
            if isinstance(e.type, LiteralT) or e.type is None:
                return v
            return const_of(v, concrete(e.type))
        if isinstance(e, ast.Ref):
            return self.read(e, frame, g)
        if isinstance(e, ast.Direct):
            return self.sym.direct_value(e.address)
        if isinstance(e, ast.CR):
            return self.cr_get(frame, e.type)
        if isinstance(e, _SlotVal):
            return e.value
        if isinstance(e.type, LiteralT) and isinstance(e, (ast.BinOp, ast.UnOp)):
            try:
                return self.ipc(frame.pou).expr(e)(None)
            except Exception:  # noqa: BLE001 - not a pure constant
                pass
        if isinstance(e, ast.BinOp):
            return self.binop(e, frame, g)
        if isinstance(e, ast.UnOp):
            return self.unop(e, frame, g)
        if isinstance(e, ast.Call):
            return self.call_expr(e, frame, g)
        raise AssertionError(f"expression {e!r}")

    def from_sig(self, v, sig, t, frame, pos):
        """A standard call's value computed in its sig, as type t: one the
        checker computes exactly on untyped literals where t cannot take it
        (1 + 2 into a BYTE, stdlib.call_types) is converted as a literal is
        (the interpreter's _from_sig)."""
        if isinstance(sig[0], LiteralT) and t is not None and not isinstance(t, LiteralT):
            return self.conv(v, sig[0], t, frame, pos)
        return v

    def binop(self, e, frame, g):
        op = e.op
        if e.fn is not None:
            return self.from_sig(self.apply_std(e.fn, [e.left, e.right], e.sig, frame, g, e.pos),
                                 e.sig, e.type, frame, e.pos)
        if op in ("=", "<>", "<", ">", "<=", ">="):
            c = e.sig[1][0]
            a = self.expr_as(e.left, c, frame, g)
            b = self.expr_as(e.right, c, frame, g)
            if isinstance(a, Opaque) or isinstance(b, Opaque):
                return self.stand_in(frame.pou, e.pos, f"a STRING comparison '{op}'", BOOL)
            return compare(op, a, b, c)
        t = concrete(e.type)
        a = self.expr_as(e.left, t, frame, g)
        b = self.expr_as(e.right, t, frame, g)
        return logic(op, a, b)

    def unop(self, e, frame, g):
        t = concrete(e.type)
        if isinstance(t, LiteralT) or (e.op == "-" and isinstance(e.operand, ast.Lit)):
            v = self.ipc(frame.pou)._literal_unop(e)
            if v is not None:
                return v if isinstance(t, LiteralT) else const_of(v, t)
        if e.op == "-" and isinstance(base_of(t), Elementary) and base_of(t).cat in ("bit", "bool") \
                and e.const is not None:
            # an untyped -(-3) stored into a bit string or a BOOL: its folded
            # value (codegen's unop)
            return self.conv(int(e.const), LiteralT("int", int(e.const)), t, frame, e.pos)
        a = self.expr_as(e.operand, t, frame, g)
        if e.op == "+":
            return a
        if e.op == "NOT":
            return z3.Not(a) if z3.is_bool(a) else ~a
        if z3.is_fp(a):
            return z3.fpNeg(a)
        return -a
