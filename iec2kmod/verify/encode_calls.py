"""Encoder, calls: a call expression to a standard function (EN/ENO,
its value in the type settle gave it) or a user FUNCTION (a fresh frame);
an FB call statement, of an instance or of an element of an array of
instances picked by a symbolic index; the binding of arguments
(VAR_INPUT, VAR_IN_OUT places, outputs, negated outputs).

``CallEncoding`` is mixed into encode.Encoder, whose state it uses (``m``:
initial values, ``sym``: fresh values) and whose methods it calls:
``conv``, ``refuse``, ``run_body`` (encode.py), ``expr``, ``expr_as``,
``from_sig``, ``place``, ``store_value``, ``write`` (encode_expr.py),
``apply_std``, ``std_fb`` (encode_std.py).  It imports terms.py, the
checker and the interpreter, not encode.py."""

from __future__ import annotations

import z3

from ..checks import stdlib
from ..checks.types import BOOL, LiteralT, concrete
from ..interp.model import Instance
from .terms import (FALSE, TRUE, Ref_of, const_of, ite, kind, land, lnot, store_into)


class CallEncoding:
    # ------------------------------------------------------------ calls
    def call_expr(self, c, frame, g):
        if isinstance(c.target, stdlib.StdFunc):
            return self.std_call(c, frame, g)
        return self.user_call(c, frame, g)

    def en_eno(self, c, frame, g):
        en = eno = None
        for a in c.args:
            if a.kind == "in" and a.name and a.name.upper() == "EN" and a.value is not None:
                en = self.expr_as(a.value, BOOL, frame, g)
            elif a.kind == "out" and a.name and a.name.upper() == "ENO" and a.value is not None:
                eno = a.value
        return en, eno

    def std_call(self, c, frame, g):
        fres = c.target
        rt = c.sig[0]       # the type the call is computed in (checks/settle.py)
        if isinstance(rt, LiteralT) and c.type is not None and not isinstance(c.type, LiteralT):
            rt = c.type     # computed exactly, then converted to it (from_sig)
        args = [a.value for a in c.args
                if a.kind == "pos" or (a.name or "").upper() not in ("EN", "ENO")]
        en, eno = self.en_eno(c, frame, g)
        g2 = land(g, en) if en is not None else g
        v = self.from_sig(self.apply_std(fres, args, c.sig, frame, g2, c.pos), c.sig, c.type,
                          frame, c.pos)
        if eno is not None:
            self.write(eno, en if en is not None else TRUE, BOOL, frame, g, c.pos)
        if en is not None:
            if isinstance(rt, LiteralT):
                self.refuse(frame.pou, c.pos, "EN on a function of untyped literals")
            dflt = const_of(self.m.init.default(concrete(rt)), concrete(rt))
            return ite(en, self.conv(v, rt, rt), dflt)
        return v

    # ------------------------------------------------------- user calls
    def bind_args(self, c, pou, frame, g):
        ins, inouts, outs = [], [], []
        for key, a in (c.bound or {}).items():
            param = pou.vars[key]
            if a.kind == "out":
                if a.value is None:
                    continue
                outs.append((key, a, param))
            elif param.section == "VAR_IN_OUT":
                inouts.append((key, self.place(a.value, frame, g)))
            elif a.value is not None:
                v = self.expr(a.value, frame, g)
                ins.append((key, self.store_value(v, a.value.type, param.type, frame, g,
                                                  a.value.pos)))
        return ins, inouts, outs

    def write_outs(self, outs, values, frame, g):
        for key, a, param in outs:
            v = values[key]
            if a.negate:
                v = lnot(v)
            self.write(a.value, v, param.type, frame, g, a.pos)

    def user_call(self, c, frame, g):
        pou = c.target
        en, eno = self.en_eno(c, frame, g)
        g2 = land(g, en) if en is not None else g
        ins, inouts, outs = self.bind_args(c, pou, frame, g2)
        fr = Instance(pou)
        for v in pou.vars.values():
            if v.section == "VAR_IN_OUT":
                continue
            fr.v[v.key] = self.sym.fresh_value(v)
        for k, val in ins:
            fr.v[k] = val
        for k, pl in inouts:
            fr.r[k] = pl
        self.run_body(pou, fr, g2)
        self.write_outs(outs, fr.v, frame, g2)
        if eno is not None:
            self.write(eno, en if en is not None else TRUE, BOOL, frame, g, c.pos)
        res = fr.v.get(pou.key)
        if en is not None and res is not None:
            dflt = const_of(self.m.init.default(pou.result), concrete(pou.result)) \
                if kind(pou.result) else res
            return ite(en, res, dflt)
        return res

    def fb_call(self, c, frame, g):
        inst_var = c.target
        # an element of an array of instances (t[i](...)): c.ref is the
        # indexed reference, c.target the array variable
        pou = (c.ref.type if c.ref is not None else inst_var.type).pou
        # the index is computed (and checked) before EN and the arguments,
        # as the interpreter does
        ref = c.ref if c.ref is not None else Ref_of(inst_var, c.pos)
        place = self.place(ref, frame, g)
        en, eno = self.en_eno(c, frame, g)
        g2 = land(g, en) if en is not None else g
        ins, inouts, outs = self.bind_args(c, pou, frame, g2)
        v_en = pou.var("EN")
        en_key = v_en.key if v_en is not None and v_en.section == "VAR_INPUT" and \
            en is not None else None
        v_eno = pou.var("ENO")
        eno_key = v_eno.key if v_eno is not None and v_eno.section == "VAR_OUTPUT" else None
        eno_val = None
        for cond, inst in place.instances():
            iv = inst.v
            if en is not None and eno_key is not None:
                # an instance that keeps its ENO (checks/eno.fb_eno)
                # gets FALSE from a call with EN = FALSE
                off = land(land(g, cond), z3.Not(en))
                if not z3.is_false(off):
                    iv[eno_key] = ite(off, FALSE, iv[eno_key])
            gi = land(g2, cond)
            if z3.is_false(gi):
                continue
            for k, val in ins:
                store_into(iv, k, gi, val)
            for k, pl in inouts:
                inst.r[k] = pl
            if en_key is not None:
                iv[en_key] = ite(gi, TRUE, iv[en_key])
            if eno_key is not None:
                iv[eno_key] = ite(gi, TRUE, iv[eno_key])
            if pou.standard:
                self.std_fb(pou, inst, gi, frame, c.pos)
            else:
                self.run_body(pou, inst, gi)
            self.write_outs(outs, iv, frame, gi)
            if eno is not None:
                e = iv[eno_key] if eno_key is not None else TRUE
                eno_val = e if eno_val is None else ite(cond, e, eno_val)
        if eno is not None:
            self.write(eno, ite(en, eno_val, FALSE) if en is not None else eno_val,
                       BOOL, frame, g, c.pos)
