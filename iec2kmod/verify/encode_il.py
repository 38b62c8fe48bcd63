"""Encoder, instruction lists: the current result (one term per sort, or
an untyped literal value; set on the paths that reach it), forward jumps
and RET as path conditions (a backward jump, a loop, is refused),
deferred operators ``OP(``, S/R, the FB input operators, CAL/CALC/CALCN.

``ILEncoding`` is mixed into encode.Encoder and calls its methods:
``conv``, ``refuse`` (encode.py), ``expr``, ``expr_as``, ``place``,
``store_value``, ``write`` (encode_expr.py), ``call_expr``, ``fb_call``
(encode_calls.py), ``apply_std`` (encode_std.py).  It imports terms.py and
the checker, not encode.py."""

from __future__ import annotations

import z3

from ..checks import stdlib
from ..checks.types import BOOL, FBType, LiteralT, concrete
from .terms import (TRUE, Ref_of, _SlotVal, compare, const_of, ite, kind, land, lnot, logic,
                    lor, sort_of, store_into)


class ILEncoding:
    # ---------------------------------------------------------------- IL
    def cr_get(self, frame, t):
        cr = frame.inst.cr
        if cr is None:
            raise AssertionError("IL current result read before it is set")
        if t is None or isinstance(t, LiteralT):
            for key in ("lit", "int"):
                if key in cr:
                    return cr[key]
        else:
            s = sort_of(t)
            if s is not None and "s:" + s.sexpr() in cr:
                return cr["s:" + s.sexpr()]
        # the most recently set value (a literal loaded into a typed register)
        return list(cr.values())[-1]

    def cr_set(self, frame, rel, val):
        """Sets the current result on the paths of ``rel`` (relative to the
        start of the body: the current result is local to one execution)."""
        inst = frame.inst
        if z3.is_true(rel):
            if isinstance(val, (int, float, bool)) and not isinstance(val, z3.ExprRef):
                inst.cr = {"lit": val}
            elif z3.is_int(val):
                inst.cr = {"int": val}
            else:
                inst.cr = {"s:" + val.sort().sexpr(): val}
            return
        new = {}
        for k, v in (inst.cr or {}).items():
            if k == "lit":
                if isinstance(v, float):
                    self.refuse(frame.pou, None, "an untyped REAL current result on a "
                                                 "conditional path")
                k, v = "int", z3.IntVal(int(v))
            new[k] = v
        if isinstance(val, (int, float, bool)) and not isinstance(val, z3.ExprRef):
            if isinstance(val, float):
                self.refuse(frame.pou, None, "an untyped REAL current result on a conditional "
                                             "path")
            val = z3.IntVal(int(val))
        key = "int" if z3.is_int(val) else "s:" + val.sort().sexpr()
        old = new.pop(key, None)
        new[key] = ite(rel, val, old) if old is not None else val
        inst.cr = new

    def il_body(self, instrs, frame, g):
        labels = {}
        for n, i in enumerate(instrs):
            if i.label:
                labels[i.label.upper()] = n
        incoming = {}
        live = TRUE          # relative to the start of the body
        frame.inst.cr = None
        for n, i in enumerate(instrs):
            if n in incoming:
                live = lor(live, *incoming.pop(n))
            live = land(live, lnot(frame.ret))
            if z3.is_false(live):
                continue
            op = i.op
            if op in ("JMP", "JMPC", "JMPCN"):
                target = labels[i.operand.name.upper()]
                if target <= n:
                    self.refuse(frame.pou, i.pos, "an IL jump backwards (a loop)")
                if op == "JMP":
                    c = TRUE
                else:
                    cr = self.conv(self.cr_get(frame, BOOL), i.cr_in, BOOL)
                    c = cr if op == "JMPC" else lnot(cr)
                incoming.setdefault(target, []).append(land(live, c))
                live = land(live, lnot(c))
                continue
            if op in ("RET", "RETC", "RETCN"):
                if op == "RET":
                    c = TRUE
                else:
                    cr = self.conv(self.cr_get(frame, BOOL), i.cr_in, BOOL)
                    c = cr if op == "RETC" else lnot(cr)
                frame.ret = lor(frame.ret, land(live, c))
                live = land(live, lnot(c))
                continue
            self.il_instr(i, frame, land(g, live), live)

    def il_instr(self, i, frame, g, rel):
        """One IL instruction: variables written under g, the current
        result under rel (g relative to the start of the body)."""
        op = i.op
        cr_in = i.cr_in
        pou = frame.pou
        if op is None:
            self.cr_set(frame, rel, self.call_expr(i.call, frame, g))
            return
        if i.deferred:
            outer = self.cr_get(frame, cr_in) if frame.inst.cr is not None else None
            saved = frame.inst.cr
            inner_t = i.nested[-1].cr_out if i.nested else i.operand.type
            if i.operand is not None:
                frame.inst.cr = None
                self.cr_set(frame, TRUE, self.expr(i.operand, frame, g))
            for j in i.nested:
                if j.op in ("JMP", "JMPC", "JMPCN", "RET", "RETC", "RETCN"):
                    self.refuse(pou, j.pos, "a jump inside a parenthesised IL operation")
                self.il_instr(j, frame, g, TRUE)
            inner = self.cr_get(frame, inner_t)
            frame.inst.cr = saved
            val = self.il_combine(i, op, outer, cr_in, inner, inner_t, frame, g)
            self.cr_set(frame, rel, val)
            return
        if op in ("LD", "LDN"):
            t = i.cr_out
            tt = t if not isinstance(i.operand.type, LiteralT) else concrete(t)
            val = self.expr_as(i.operand, tt, frame, g)
            if isinstance(val, (int, float)) and not isinstance(val, z3.ExprRef) and \
                    not isinstance(tt, LiteralT) and kind(tt):
                val = const_of(val, concrete(tt))
            if op == "LDN":
                val = z3.Not(val) if z3.is_bool(val) else ~val
            self.cr_set(frame, rel, val)
            return
        if op in ("ST", "STN"):
            val = self.cr_get(frame, cr_in)
            st_t = cr_in
            if op == "STN":     # negated in the checker's type (sig)
                st_t = concrete(i.sig[0])
                val = self.conv(val, cr_in, st_t)
                val = z3.Not(val) if z3.is_bool(val) else ~val
            self.write(i.operand, val, st_t, frame, g, i.pos)
            return
        if op in ("S", "R") and not isinstance(getattr(i.operand, "type", None), FBType):
            cr = self.conv(self.cr_get(frame, cr_in), cr_in, BOOL)
            self.write(i.operand, z3.BoolVal(op == "S"), BOOL, frame, land(g, cr), i.pos)
            return
        if op in ("S1", "R1", "CLK", "CU", "CD", "PV", "IN", "PT", "S", "R", "LD"):
            inst_var = i.operand.symbol
            param = inst_var.type.pou.var(op)
            val = self.store_value(self.cr_get(frame, cr_in), cr_in, param.type, frame, g,
                                   i.pos)
            place = self.place(Ref_of(inst_var, i.pos), frame, g)
            for cond, inst in place.instances():
                gi = land(g, cond)
                store_into(inst.v, param.key, gi, val)
            return
        if op == "NOT":         # in the result's type: a bit string for a literal
            val = self.conv(self.cr_get(frame, cr_in), cr_in, concrete(i.cr_out))
            self.cr_set(frame, rel, z3.Not(val) if z3.is_bool(val) else ~val)
            return
        if op in ("AND", "ANDN", "OR", "ORN", "XOR", "XORN", "ADD", "SUB", "MUL", "DIV",
                  "MOD", "GT", "GE", "EQ", "NE", "LE", "LT"):
            b = self.expr(i.operand, frame, g)
            a = self.cr_get(frame, cr_in)
            self.cr_set(frame, rel, self.il_combine(i, op, a, cr_in, b, i.operand.type, frame, g))
            return
        if op in ("CAL", "CALC", "CALCN"):
            if op == "CAL":
                self.fb_call(i.call, frame, g)
            else:
                cr = self.conv(self.cr_get(frame, cr_in), cr_in, BOOL)
                self.fb_call(i.call, frame, land(g, cr if op == "CALC" else lnot(cr)))
            return
        if op == "NOP":
            return
        self.refuse(pou, i.pos, f"the IL operator {op}")

    def il_combine(self, i, op, x, cr_t, y, op_t, frame, g):
        base = op[:-1] if op in ("ANDN", "ORN", "XORN") else op
        neg = op in ("ANDN", "ORN", "XORN")
        if base in ("AND", "OR", "XOR"):
            t = i.sig[1][0]
            x = self.conv(x, cr_t, t)
            y = self.conv(y, op_t, t)
            if neg:
                y = z3.Not(y) if z3.is_bool(y) else ~y
            return logic(base, x, y)
        if base in stdlib.ARITH_FAMILIES:
            return self.apply_std(i.std, [_SlotVal(x, cr_t), _SlotVal(y, op_t)], i.sig, frame,
                                  g, i.pos)
        t = i.sig[1][0]
        x = self.conv(x, cr_t, t)
        y = self.conv(y, op_t, t)
        return compare({"GT": ">", "GE": ">=", "EQ": "=", "NE": "<>", "LE": "<=",
                        "LT": "<"}[base], x, y, t)
