"""PouCompiler, calls: a standard function call (EN/ENO; its value in
the types settle gave it, ``apply_std`` over std.py and conv.py; exact
arithmetic on untyped literals), a user FUNCTION (a new frame, every
variable at its initial value), an FB instance (a standard one runs
fbs.py's body), the binding of their arguments.

``CallCompiler`` is mixed into compiler.PouCompiler, whose state it uses
(``m``: the machine's bodies, frames and initial values; ``rt``) and whose
variable access and expressions it calls: ``cell``, ``expr``, ``expr_as``,
``storer``, ``writer`` (compile_expr.py).  It imports closures.py and the
interpreter's library modules, never compiler.py."""

from __future__ import annotations

from ..checks import stdlib
from ..checks.types import BOOL, LiteralT, concrete
from ..checks.types import LREAL as LREAL_T
from . import std
from .closures import REF_SECTIONS, _from_sig
from .conv import converter
from .fbs import body_of
from .model import copier
from .values import base_of, wrap, wrap64


class CallCompiler:
    # ----------------------------------------------------- standard functions
    def call_expr(self, c):
        if isinstance(c.target, stdlib.StdFunc):
            return self.std_call(c)
        return self.user_call(c, want_result=True)

    def en_eno(self, c):
        en = eno = None
        for a in c.args:
            if a.kind == "in" and a.name and a.name.upper() == "EN":
                en = self.expr_as(a.value, BOOL) if a.value is not None else None
            elif a.kind == "out" and a.name and a.name.upper() == "ENO" and a.value is not None:
                eno = self.writer(a.value, BOOL)
        return en, eno

    def std_call(self, c):
        fres = c.target
        args = [a.value for a in c.args
                if a.kind == "pos" or (a.name or "").upper() not in ("EN", "ENO")]
        f = _from_sig(self.apply_std(fres, args, c.sig), c.sig, c.type)
        en, eno = self.en_eno(c)
        if en is None and eno is None:
            return f
        # EN = FALSE: the default of the type the call is computed in (its
        # sig, checks/settle.py; an exact computation on literals: the
        # literal's own type, DINT, LINT or LREAL), as codegen's guarded_call,
        # in the type f gives it (_from_sig)
        dflt = self.m.init.default(concrete(c.sig[0]))
        conv = _from_sig(lambda env: dflt, c.sig, c.type)
        dflt = conv(None)

        def guarded(env):
            if en is not None and not en(env):
                if eno is not None:
                    eno(env, False)
                return dflt
            v = f(env)
            if eno is not None:
                eno(env, True)
            return v
        return guarded

    def apply_std(self, fres, args, sig):
        """f(env) computing standard function ``fres`` on argument exprs, in
        the types ``sig`` (the call's, checks/settle.py)."""
        fam = fres.family
        res, ptypes = sig
        if isinstance(res, LiteralT):
            # a computation on untyped literals: exact, in Python
            return self._literal_std(fam, args, res)

        def vals():
            return [self.expr_as(a, concrete(pt)) for a, pt in zip(args, ptypes)]

        if fam in stdlib.ARITH_FAMILIES:
            fs = [self.expr_as(a, res) for a in args]
            op = std.arith(fam, res)
            return _fold(op, fs)
        if fam in stdlib.TIME_FAMILIES:
            return self._time_fn(fam, args, ptypes, res)
        if fam == "EXPT":
            base_t, exp_t = concrete(ptypes[0]), concrete(ptypes[1])
            a = self.expr_as(args[0], base_t)
            b = self.expr_as(args[1], exp_t)
            fn = std.expt(base_t, exp_t, res)
            return lambda env: fn(a(env), b(env))
        if fam == "MOVE":
            a = self.expr_as(args[0], res)
            cp = copier(res)
            if cp is None:
                return a
            return lambda env: cp(a(env))
        if fam == "ABS":
            a = self.expr_as(args[0], res)
            fn = std.abs_fn(res)
            return lambda env: fn(a(env))
        if fam in std.REALFN:
            a = self.expr_as(args[0], res)
            fn = std.realfn(fam, res)
            return lambda env: fn(a(env))
        if fam == "ATAN2":
            y, x = [self.expr_as(a, res) for a in args]
            fn = std.atan2(res)
            return lambda env: fn(y(env), x(env))
        if fam in ("SHL", "SHR", "ROL", "ROR"):
            a, n = vals()
            fn = std.shift(fam, res)
            return lambda env: fn(a(env), n(env))
        if fam in ("AND", "OR", "XOR"):
            fs = [self.expr_as(a, res) for a in args]
            fn = std.bitwise(fam, res)
            return lambda env: fn(*[f(env) for f in fs])
        if fam == "NOT":
            a = self.expr_as(args[0], res)
            fn = std.not_fn(res)
            return lambda env: fn(a(env))
        if fam == "SEL":
            g = self.expr_as(args[0], BOOL)
            a0 = self.expr_as(args[1], res)
            a1 = self.expr_as(args[2], res)

            def sel(env):
                gv = g(env)
                x0 = a0(env)
                x1 = a1(env)
                return x1 if gv else x0
            return sel
        if fam in ("MAX", "MIN", "LIMIT"):
            fs = [self.expr_as(a, res) for a in args]
            fn = {"MAX": std.max_fn, "MIN": std.min_fn, "LIMIT": std.limit_fn}[fam]
            return lambda env: fn(*[f(env) for f in fs])
        if fam == "MUX":
            k = self.expr_as(args[0], concrete(ptypes[0]))
            fs = [self.expr_as(a, res) for a in args[1:]]
            return lambda env: std.mux_fn(k(env), *[f(env) for f in fs])
        if fam in std.COMPARE:
            ct = concrete(ptypes[0])
            fs = [self.expr_as(a, ct) for a in args]
            fn = std.compare(fam)
            return lambda env: fn(*[f(env) for f in fs])
        if fam in ("LEN", "FIND"):
            fs = vals()
            if fam == "LEN":
                a = fs[0]
                return lambda env: wrap(len(a(env)), res)
            a, b = fs
            return lambda env: wrap(std.s_find(a(env), b(env)), res)
        if fam in ("LEFT", "RIGHT", "MID", "INSERT", "DELETE", "REPLACE", "CONCAT"):
            fs = vals()
            n = res.length
            fn = {"LEFT": std.s_left, "RIGHT": std.s_right, "MID": std.s_mid,
                  "INSERT": std.s_insert, "DELETE": std.s_delete, "REPLACE": std.s_replace,
                  "CONCAT": lambda *a: "".join(a)}[fam]
            return lambda env: fn(*[f(env) for f in fs])[:n]
        if fam in ("CONVERT", "TRUNC", "BCD_TO", "TO_BCD"):
            src = concrete(ptypes[0])
            a = self.expr_as(args[0], src)
            fn = converter(fam, src, res)
            return lambda env: fn(a(env))
        raise AssertionError(f"standard function family {fam}")

    def _literal_std(self, fam, args, res):
        fs = [self.expr(a) for a in args]
        if fam in ("ADD", "SUB", "MUL", "DIV", "MOD", "EXPT"):
            real = res.cat == "real"

            def op(x, y):
                if fam == "ADD":
                    return x + y
                if fam == "SUB":
                    return x - y
                if fam == "MUL":
                    return x * y
                if fam == "DIV":
                    return std.real_div(float(x), float(y)) if real else std.int_div(x, y)
                if fam == "MOD":
                    return std.int_mod(x, y)
                return std.expt(None, None, LREAL_T)(float(x), float(y))
            return _fold(op, fs)
        raise AssertionError(f"{fam} on literals")

    def _time_fn(self, fam, args, ptypes, res):
        a = self.expr_as(args[0], concrete(ptypes[0]))
        if fam in ("MUL_TIME", "DIV_TIME"):
            t2 = ptypes[1]
            if isinstance(t2, LiteralT):
                t2 = concrete(t2)
            b = self.expr_as(args[1], t2)
            if base_of(t2).cat == "real":
                fn = std.mul_time_real if fam == "MUL_TIME" else std.div_time_real
            else:
                fn = std.mul_time_int if fam == "MUL_TIME" else std.div_time_int
            return lambda env: fn(a(env), b(env))
        b = self.expr_as(args[1], concrete(ptypes[1]))
        if fam == "ADD_TOD_TIME":
            fn = std.add_tod_time
        elif fam == "SUB_TOD_TIME":
            fn = std.sub_tod_time
        elif fam in ("ADD_TIME", "ADD_DT_TIME", "CONCAT_DATE_TOD"):
            def fn(x, y):
                return wrap64(x + y)
        else:
            def fn(x, y):
                return wrap64(x - y)
        return lambda env: fn(a(env), b(env))

    # ------------------------------------------------------- user POU calls
    def bind_args(self, c, pou):
        """[(kind, param key, fn)] in call order: ('in', K, value fn),
        ('inout', K, cell fn), ('out', K, writer fn)."""
        out = []
        for key, a in (c.bound or {}).items():
            param = pou.vars[key]
            if a.kind == "out":
                if a.value is None:
                    continue
                w = self.writer(a.value, param.type)
                if a.negate:
                    out.append(("out", key, (lambda w: lambda env, v: w(env, not v))(w)))
                else:
                    out.append(("out", key, w))
            elif param.section == "VAR_IN_OUT":
                out.append(("inout", key, self.cell(a.value)))
            elif a.value is not None:
                f = self.expr(a.value)
                st = self.storer(param.type, a.value.type)
                out.append(("in", key, (lambda f, st: lambda env: st(f(env)))(f, st)))
        return out

    def user_call(self, c, want_result):
        pou = c.target
        binds = self.bind_args(c, pou)
        ins = [(k, f) for kind, k, f in binds if kind == "in"]
        inouts = [(k, f) for kind, k, f in binds if kind == "inout"]
        outs = [(k, f) for kind, k, f in binds if kind == "out"]
        en, eno = self.en_eno(c)
        m = self.m
        key = pou.key
        rkey = pou.key
        dflt = m.init.default(pou.result) if pou.result is not None else None
        # a function that declares ENO (or uses it: the implicit output)
        # starts with ENO = TRUE, may set it FALSE, and hands it on
        v_eno = pou.var("ENO")
        eno_key = v_eno.key if v_eno is not None and v_eno.section == "VAR_OUTPUT" else None

        def call(env):
            if en is not None and not en(env):
                if eno is not None:
                    eno(env, False)
                return dflt
            frame = m.new_frame(key)
            fv = frame.v
            for k, f in ins:
                fv[k] = f(env)
            for k, f in inouts:
                frame.r[k] = f(env)
            if eno_key is not None:
                fv[eno_key] = True
            m.bodies[key](frame)
            for k, w in outs:
                w(env, fv[k])
            if eno is not None:
                eno(env, fv[eno_key] if eno_key is not None else True)
            return fv[rkey]
        return call

    def fb_call(self, c):
        """A statement: calls the FB instance c.target."""
        inst_var = c.target
        pou = (c.ref.type if c.ref is not None else inst_var.type).pou
        binds = self.bind_args(c, pou)
        ins = [(k, f) for kind, k, f in binds if kind == "in"]
        inouts = [(k, f) for kind, k, f in binds if kind == "inout"]
        outs = [(k, f) for kind, k, f in binds if kind == "out"]
        en, eno = self.en_eno(c)
        k_inst = inst_var.key
        m = self.m
        if pou.standard:
            body, _ = body_of(pou)
            rt = self.rt

            def run(inst):
                body(inst.v, rt)
        else:
            key = pou.key

            def run(inst):
                m.bodies[key](inst)
        if c.ref is not None:
            # an element of an array of instances (t[i](...)): its index is
            # computed, and checked, before the arguments
            cell = self.cell(c.ref)

            def get_inst(env):
                cc, kk = cell(env)
                return cc[kk]
        elif inst_var.section in REF_SECTIONS:
            def get_inst(env):
                cc, kk = env.r[k_inst]
                return cc[kk]
        else:
            def get_inst(env):
                return env.v[k_inst]

        # a block that declares EN sees it TRUE whenever it runs; one that
        # declares ENO starts each call with ENO = TRUE and hands its ENO on
        v_en = pou.var("EN")
        en_key = v_en.key if v_en is not None and v_en.section == "VAR_INPUT" and \
            en is not None else None
        v_eno = pou.var("ENO")
        eno_key = v_eno.key if v_eno is not None and v_eno.section == "VAR_OUTPUT" else None

        def call(env):
            inst = get_inst(env)
            if en is not None and not en(env):
                if eno_key is not None:
                    # an instance keeps its ENO (checks/eno.fb_eno)
                    inst.v[eno_key] = False
                if eno is not None:
                    eno(env, False)
                return None
            iv = inst.v
            for k, f in ins:
                iv[k] = f(env)
            for k, f in inouts:
                inst.r[k] = f(env)
            if en_key is not None:
                iv[en_key] = True
            if eno_key is not None:
                iv[eno_key] = True
            run(inst)
            for k, w in outs:
                w(env, iv[k])
            if eno is not None:
                eno(env, iv[eno_key] if eno_key is not None else True)
            return None
        return call


def _fold(op, fs):
    if len(fs) == 2:
        a, b = fs
        return lambda env: op(a(env), b(env))

    def fold(env):
        acc = fs[0](env)
        for f in fs[1:]:
            acc = op(acc, f(env))
        return acc
    return fold
