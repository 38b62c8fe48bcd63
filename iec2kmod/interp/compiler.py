"""From the checked AST to Python closures.

Each expression becomes a function ``f(env) -> value`` and each statement a
function ``s(env) -> None | EXIT | RETURN | CONTINUE``, ``env`` being the Instance of
the running POU.  This is still an interpreter of the AST -- one closure per
node, built once, run every cycle -- only without re-dispatching on node
types at every evaluation.

Sections, in the order a reader meets them: conversions between types,
variable access (read, write, cell), expressions, standard function calls,
user POU calls, statements, IL, POU bodies."""

from __future__ import annotations

from .. import ast
from ..checks import stdlib
from ..checks.symbols import EnumValue
from ..checks.symbols import Var
from ..checks.types import (ArrayT, BOOL, Elementary, EnumT, FBType, LiteralT, StringT,
                            StructT, SubrangeT, concrete)
from ..checks.types import LREAL as LREAL_T
from . import std
from .conv import converter, int_to_f32, int_to_f64
from .errors import ENUM, INDEX, LOOP, RANGE, Fault
from .fbs import body_of
from .model import BitCell, copier
from .values import base_of, f32_safe, wrap, wrap64

EXIT = 1
RETURN = 2
CONTINUE = 3        # the rest of the loop's iteration is skipped (ed.3)
REF_SECTIONS = ("VAR_EXTERNAL", "VAR_IN_OUT")
ARITH = {"+": "ADD", "-": "SUB", "*": "MUL", "/": "DIV", "MOD": "MOD"}


def _const(v):
    return lambda env: v


def _type_of(e):
    t = getattr(e, "type", None)
    return t


# ------------------------------------------------------------ conversions
def implicit(src, dst):
    """A function converting a value of type src to dst implicitly (the
    widenings of the standard and untyped literals), or None when the
    representation is the same."""
    if dst is None or src is None:
        return None
    d = base_of(dst)
    s = base_of(src) if not isinstance(src, LiteralT) else src
    if isinstance(d, Elementary):
        if isinstance(s, LiteralT):
            if d.cat == "real":
                if s.cat == "int":
                    return int_to_f32 if d.bits == 32 else int_to_f64
                return f32_safe if d.bits == 32 else None
            if d.cat == "bool":
                return bool
            if d.cat in ("sint", "uint", "bit") and s.cat == "int":
                # a value computed from untyped literals (IL: LD 38 SUB 40)
                # is stored as every store is: into the variable's type
                return lambda v: wrap(v, d)
            return None
        if not isinstance(s, Elementary):
            return None
        if s is d:
            return None
        if d.cat == "real":
            if s.cat == "real":
                return f32_safe if d.bits == 32 and s.bits != 32 else None
            if s.cat == "bool":
                return float
            return int_to_f32 if d.bits == 32 else int_to_f64
        if d.cat in ("sint", "uint", "bit"):
            if s.cat == "bool":
                return int
            if s.cat in ("sint", "uint", "bit"):
                lo, hi = d.range
                slo, shi = s.range
                if lo <= slo and shi <= hi:
                    return None
                return lambda v: wrap(v, d)
            return None
        if d.cat == "bool":
            return bool if s.cat != "bool" else None
        return None
    return None


def conv_fn(f, src, dst):
    c = implicit(src, dst)
    if c is None:
        return f
    return lambda env: c(f(env))


def _from_sig(f, sig, t):
    """f(env) of a standard call computed in its sig, as type t: a call the
    checker computes exactly on untyped literals where t cannot take it (1 +
    2 into a BYTE, stdlib.call_types) is converted as a literal would be."""
    if isinstance(sig[0], LiteralT) and t is not None and not isinstance(t, LiteralT):
        return conv_fn(f, sig[0], t)
    return f


class PouCompiler:
    """Compiles the body of one POU."""

    def __init__(self, machine, pou):
        self.m = machine
        self.rt = machine.rt
        self.pou = pou
        self.src = pou.src
        self.name = pou.name
        self.is_function = pou.kind == "FUNCTION"

    def line(self, pos):
        return self.src.linecol(pos)[0] if pos is not None else 0

    # ------------------------------------------------------ variable access
    def _base(self, v: Var, write: bool, edge_read: bool):
        """(kind, K): how the variable itself is reached."""
        return ("ref" if v.section in REF_SECTIONS else "local"), v.key

    def reader(self, r: ast.Ref):
        """f(env) -> the value of a variable access."""
        sym = r.symbol
        if isinstance(sym, EnumValue):
            return _const(sym.value)
        k = sym.key
        ref = sym.section in REF_SECTIONS
        if not r.accessors:
            if sym.section == "VAR_INPUT" and sym.edge and sym.owner is self.pou:
                return lambda env: env.e[k]
            if ref:
                def rd(env):
                    c, kk = env.r[k]
                    return c[kk]
                return rd
            return lambda env: env.v[k]
        cell = self.cell(r)

        def rd_cell(env):
            c, kk = cell(env)
            return c[kk]
        return rd_cell

    def cell(self, r: ast.Ref):
        """f(env) -> (container, key) of a variable access (for writing and
        for binding VAR_IN_OUT)."""
        sym = r.symbol
        k = sym.key
        if sym.section in REF_SECTIONS:
            f = lambda env: env.r[k]
        else:
            f = lambda env: (env.v, k)
        t = sym.type
        for kind, val, pos in r.accessors:
            f, t = self._accessor(f, t, kind, val)
        return f

    def _accessor(self, f, t, kind, val):
        t = concrete(t)
        if kind == "index":
            dims = t.dims
            idx = [self.expr(e) for e in val]
            if len(dims) == 1:
                (lo, hi), = dims
                ix = idx[0]

                def index1(env):
                    c, k = f(env)
                    i = ix(env)
                    if i < lo or i > hi:
                        raise Fault(INDEX)
                    return c[k], i - lo
                return index1, t.elem
            strides = []
            n = 1
            for lo, hi in reversed(dims):
                strides.append(n)
                n *= hi - lo + 1
            strides.reverse()
            parts = list(zip(idx, dims, strides))

            def index_n(env):
                c, k = f(env)
                off = 0
                for ixf, (lo, hi), st in parts:
                    i = ixf(env)
                    if i < lo or i > hi:
                        raise Fault(INDEX)
                    off += (i - lo) * st
                return c[k], off
            return index_n, t.elem
        if kind == "member":
            key = val.upper()
            if isinstance(t, StructT):
                def member(env):
                    c, k = f(env)
                    return c[k], key
                return member, t.fields[key][1]
            # a function block instance's input, output or in-out
            mv = t.pou.var(val)
            if mv.section == "VAR_IN_OUT":
                def fb_ref(env):
                    c, k = f(env)
                    return c[k].r[key]
                return fb_ref, mv.type

            def fb_member(env):
                c, k = f(env)
                return c[k].v, key
            return fb_member, mv.type
        # a bit of an integer
        n = val

        def bit(env):
            c, k = f(env)
            return BitCell(c, k, n), 0
        return bit, BOOL

    def writer(self, r: ast.Ref, src_t, check=True):
        """f(env, value): stores a value of type src_t into a variable access,
        converted, truncated (strings), checked (subranges), copied
        (arrays, structures)."""
        t = r.type
        store = self.storer(t, src_t)
        sym = r.symbol
        k = sym.key
        if not r.accessors and sym.section not in REF_SECTIONS:
            def w_local(env, v):
                env.v[k] = store(v)
            return w_local
        cell = self.cell(r)

        def w_cell(env, v):
            c, kk = cell(env)
            c[kk] = store(v)
        return w_cell

    def storer(self, t, src_t):
        """A function preparing a value of type src_t for storage in type t."""
        ct = concrete(t)
        conv = implicit(src_t, t)
        if isinstance(ct, SubrangeT):
            lo, hi = ct.low, ct.high

            def sub(v):
                if conv is not None:
                    v = conv(v)
                if v < lo or v > hi:
                    raise Fault(RANGE)
                return v
            return sub
        if isinstance(ct, StringT):
            n = ct.length
            return lambda v: v[:n] if len(v) > n else v
        if isinstance(ct, (ArrayT, StructT)):
            c = copier(ct)
            return c
        if conv is not None:
            return conv
        return lambda v: v

    # ------------------------------------------------------------ expressions
    def expr(self, e):
        """f(env) -> value of e in the representation of its own type."""
        if isinstance(e, ast.Lit):
            return _const(self.lit_value(e))
        if isinstance(e, ast.Ref):
            return self.reader(e)
        if isinstance(e, ast.BinOp):
            return self.binop(e)
        if isinstance(e, ast.UnOp):
            return self.unop(e)
        if isinstance(e, ast.Call):
            return self.call_expr(e)
        if isinstance(e, ast.CR):
            return lambda env: env.cr
        if isinstance(e, _Slot):
            n = e.n
            return lambda env: env.vals[n]
        raise AssertionError(f"expression {e!r}")

    def expr_as(self, e, t):
        """f(env) -> value of e converted to type t."""
        if (t is not None and not isinstance(t, LiteralT) and isinstance(e.type, LiteralT)
                and isinstance(e, (ast.BinOp, ast.Call))):
            # an untyped expression with a generic call in it (TRUNC(1.0E10)
            # + 1 into a LINT): the context gives the type, down to the call
            # (computed as a DINT, TRUNC saturated where C computes a LINT)
            f = self.in_context(e, t)
            if f is not None:
                return f
        return conv_fn(self.expr(e), e.type, t)

    def in_context(self, e, t):
        """f(env) of untyped expression e computed in type t, or None."""
        if isinstance(e, ast.BinOp) and e.fn is not None:
            return _from_sig(self.apply_std(e.fn, [e.left, e.right], e.sig), e.sig, t)
        if isinstance(e, ast.Call) and isinstance(e.target, stdlib.StdFunc) \
                and isinstance(e.target.result, LiteralT):
            return _from_sig(self.std_call(e), e.sig, t)     # in e.sig: settle gave it t
        return None

    def lit_value(self, e):
        t = e.type
        k = e.kind
        if k == "enum":
            return concrete(t).values[e.value.upper()][1]
        if k == "bool":
            v = bool(e.value)
        elif k in ("string", "wstring"):
            return e.value
        else:
            v = e.value
        # an untyped literal is its exact value (16#FFFFFFFFFFFFFFFF is no
        # LINT): its context converts it (expr_as)
        c = implicit(LiteralT("real" if isinstance(v, float) else "int", v)
                     if k in ("int", "real") else t, t) \
            if t is not None and not isinstance(t, LiteralT) else None
        if k in ("int", "real") and t is not None and not isinstance(t, LiteralT):
            b = base_of(t)
            if isinstance(b, Elementary) and b.cat == "real":
                return (f32_safe(float(v)) if not isinstance(v, int) else int_to_f32(v)) \
                    if b.bits == 32 else float(v)
            if isinstance(b, Elementary) and b.cat == "bool":
                return bool(v)
            return v
        return c(v) if c is not None else v

    def binop(self, e):
        op = e.op
        if e.fn is not None:
            return _from_sig(self.apply_std(e.fn, [e.left, e.right], e.sig), e.sig, e.type)
        if op in ("=", "<>", "<", ">", "<=", ">="):
            c = e.sig[1][0]
            a = self.expr_as(e.left, c)
            b = self.expr_as(e.right, c)
            if op == "=":
                return lambda env: a(env) == b(env)
            if op == "<>":
                return lambda env: a(env) != b(env)
            if op == "<":
                return lambda env: a(env) < b(env)
            if op == ">":
                return lambda env: a(env) > b(env)
            if op == "<=":
                return lambda env: a(env) <= b(env)
            return lambda env: a(env) >= b(env)
        # AND OR XOR: both operands are evaluated (no short circuit)
        t = concrete(e.type)
        a = self.expr_as(e.left, t)
        b = self.expr_as(e.right, t)
        if base_of(t) is BOOL:
            if op == "AND":
                def land(env):
                    x = a(env)
                    y = b(env)
                    return x and y
                return land
            if op == "OR":
                def lor(env):
                    x = a(env)
                    y = b(env)
                    return x or y
                return lor
            return lambda env: a(env) != b(env)
        if op == "AND":
            return lambda env: a(env) & b(env)
        if op == "OR":
            return lambda env: a(env) | b(env)
        return lambda env: a(env) ^ b(env)

    def unop(self, e):
        t = concrete(e.type)
        if isinstance(t, LiteralT) or (e.op == "-" and isinstance(e.operand, ast.Lit)):
            v = self._literal_unop(e)
            if v is not None:
                return _const(v)
        b = base_of(t)
        if e.op == "-" and isinstance(b, Elementary) and b.cat in ("bit", "bool") \
                and e.const is not None:
            # an untyped -(-3) stored into a bit string or a BOOL: its folded
            # value, as codegen's unop
            return _const(bool(e.const) if b.cat == "bool" else wrap(int(e.const), b))
        a = self.expr_as(e.operand, t)
        if e.op == "+":
            return a
        if e.op == "NOT":
            if b is BOOL:
                return lambda env: not a(env)
            mask = (1 << b.bits) - 1
            return lambda env: ~a(env) & mask
        if b.cat == "real":
            return lambda env: -a(env)
        if b.cat in ("sint", "uint", "bit"):
            return lambda env: wrap(-a(env), b)
        return lambda env: wrap64(-a(env))

    def _literal_unop(self, e):
        if isinstance(e.operand, ast.Lit) and e.operand.kind in ("int", "real") and \
                e.const is not None:
            v = e.const          # the checker's fold
            t = e.type
            if isinstance(t, LiteralT) or t is None:
                return v
            b = base_of(t)
            if isinstance(b, Elementary) and b.cat == "real":
                return (int_to_f32(v) if isinstance(v, int) else f32_safe(v)) if b.bits == 32 \
                    else float(v)
            if isinstance(b, Elementary) and b.cat in ("sint", "uint", "bit"):
                return wrap(v, b)
            if isinstance(b, Elementary) and b.cat in ("time", "date", "tod", "dt"):
                return wrap64(v)
            return v
        return None

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

    # ------------------------------------------------------------ statements
    def block(self, stmts):
        fns = [self.stmt(s) for s in stmts]
        lines = [self.line(s.pos) for s in stmts]
        name = self.name
        if not fns:
            return lambda env: None
        if len(fns) == 1:
            f0, l0 = fns[0], lines[0]

            def one(env):
                try:
                    return f0(env)
                except Fault as x:
                    if x.pou is None:
                        x.pou, x.line, x.file = name, l0, self.src.path
                    raise
            return one

        def run(env):
            i = 0
            try:
                for i, f in enumerate(fns):
                    r = f(env)
                    if r is not None:
                        return r
            except Fault as x:
                if x.pou is None:
                    x.pou, x.line, x.file = name, lines[i], self.src.path
                raise
            return None
        return run

    def located(self, f, pos):
        """f, with a fault in it located at the line of pos (conditions of
        IF/ELSIF/WHILE/UNTIL: the line of the condition itself)."""
        line = self.line(pos)
        name = self.name
        path = self.src.path

        def at(env):
            try:
                return f(env)
            except Fault as x:
                if x.pou is None:
                    x.pou, x.line, x.file = name, line, path
                raise
        return at

    def cond(self, e):
        return self.located(self.expr(e), e.pos)

    def stmt(self, s):
        if isinstance(s, ast.Assign):
            val = self.expr(s.value)
            w = self.writer(s.target, s.value.type)

            def assign(env):
                w(env, val(env))
            return assign
        if isinstance(s, ast.CallStmt):
            c = s.call
            if isinstance(c.target, Var):
                return self.fb_call(c)
            f = self.call_expr(c)

            def call(env):
                f(env)
            return call
        if isinstance(s, ast.If):
            branches = [(self.cond(cnd), self.block(body)) for cnd, body in s.branches]
            els = self.block(s.else_) if s.else_ else None
            if len(branches) == 1:
                (c0, b0), = branches

                def if1(env):
                    if c0(env):
                        return b0(env)
                    if els is not None:
                        return els(env)
                    return None
                return if1

            def if_(env):
                for cnd, body in branches:
                    if cnd(env):
                        return body(env)
                if els is not None:
                    return els(env)
                return None
            return if_
        if isinstance(s, ast.Case):
            return self.case(s)
        if isinstance(s, ast.For):
            return self.for_(s)
        if isinstance(s, ast.While):
            return self.while_(s)
        if isinstance(s, ast.Repeat):
            return self.repeat(s)
        if isinstance(s, ast.Exit):
            return lambda env: EXIT
        if isinstance(s, ast.Continue):
            return lambda env: CONTINUE
        if isinstance(s, ast.Return):
            return lambda env: RETURN
        if isinstance(s, ast.Empty):
            return lambda env: None
        raise AssertionError(f"statement {s!r}")

    def case(self, s):
        sel = self.expr(s.selector)
        st = concrete(s.selector.type)
        bodies = [self.block(body) for _, body in s.elements]
        els = self.block(s.else_) if s.else_ else None
        table = {}
        ranges = []
        for n, values in enumerate(s.values):
            for lo, hi in values:
                if hi - lo < 64:
                    for v in range(lo, hi + 1):
                        table.setdefault(v, n)
                else:
                    ranges.append((lo, hi, n))
        enum_values = set(v for _, v in st.values.values()) if isinstance(st, EnumT) else None

        def case(env):
            v = sel(env)
            if enum_values is not None and v not in enum_values:
                raise Fault(ENUM)
            n = table.get(v)
            if n is None:
                for lo, hi, k in ranges:
                    if lo <= v <= hi:
                        n = k
                        break
            if n is not None:
                return bodies[n](env)
            if els is not None:
                return els(env)
            return None
        return case

    def _tick(self):
        rt = self.rt

        def tick():
            rt.budget -= 1
            if rt.budget < 0:
                raise Fault(LOOP)
        return tick

    def for_(self, s):
        v = self.pou.var(s.var)
        vt = concrete(v.type)
        k = v.key
        start = self.expr_as(s.start, vt)
        end = self.expr_as(s.end, vt)
        step = self.expr_as(s.step, vt) if s.step is not None else _const(1)
        body = self.block(s.body)
        lo_t, hi_t = base_of(vt).range
        rt = self.rt

        def for_(env):
            a = start(env)
            e = end(env)
            st = step(env)
            vv = env.v
            vv[k] = a
            i = a
            up = st >= 0
            while True:
                if (i > e) if up else (i < e):
                    break
                rt.budget -= 1
                if rt.budget < 0:
                    raise Fault(LOOP)
                r = body(env)
                if r is not None and r != CONTINUE:
                    if r == EXIT:
                        break
                    return r
                i = vv[k] + st
                if i < lo_t or i > hi_t:
                    break
                vv[k] = i
            return None
        return for_

    def while_(self, s):
        cond = self.cond(s.cond)
        body = self.block(s.body)
        rt = self.rt

        def while_(env):
            while cond(env):
                rt.budget -= 1
                if rt.budget < 0:
                    raise Fault(LOOP)
                r = body(env)
                if r is not None and r != CONTINUE:
                    if r == EXIT:
                        break
                    return r
            return None
        return while_

    def repeat(self, s):
        cond = self.cond(s.cond)
        body = self.block(s.body)
        rt = self.rt

        def repeat(env):
            while True:
                rt.budget -= 1
                if rt.budget < 0:
                    raise Fault(LOOP)
                r = body(env)
                if r is not None and r != CONTINUE:
                    if r == EXIT:
                        break
                    return r
                if cond(env):
                    break
            return None
        return repeat

    # -------------------------------------------------------------------- IL
    def il_body(self, instrs):
        """The instruction list as a program of closures run by a
        program counter; each returns None (next), an index (jump) or
        RET_PC (return)."""
        labels = {}
        for n, i in enumerate(instrs):
            if i.label:
                labels[i.label.upper()] = n
        ops = [self.il_instr(i, labels, n) for n, i in enumerate(instrs)]
        lines = [self.line(i.pos) for i in instrs]
        name = self.name
        src = self.src
        count = len(ops)

        def run(env):
            pc = 0
            try:
                while pc < count:
                    r = ops[pc](env)
                    if r is None:
                        pc += 1
                    elif r < 0:
                        return RETURN
                    else:
                        pc = r
            except Fault as x:
                if x.pou is None:
                    x.pou, x.line, x.file = name, lines[pc], src.path
                raise
            return None
        return run

    def il_seq(self, instrs):
        """Nested instructions of a deferred operation (no labels, no jumps
        out): run in order."""
        ops = [self.il_instr(i, {}, n) for n, i in enumerate(instrs)]

        def run(env):
            for f in ops:
                f(env)
        return run

    def il_instr(self, i, labels, n):
        op = i.op
        cr_in = i.cr_in
        if op is None:
            f = self.call_expr(i.call)

            def fn_call(env):
                env.cr = f(env)
            return fn_call
        if i.deferred:
            inner_t = i.nested[-1].cr_out if i.nested else i.operand.type
            first = self.expr(i.operand) if i.operand is not None else None
            seq = self.il_seq(i.nested)
            comb = self.il_combine(i, op, cr_in, inner_t)

            def deferred(env):
                outer = env.cr
                env.cr = first(env) if first is not None else None
                seq(env)
                inner = env.cr
                env.cr = comb(outer, inner)
            return deferred
        if op in ("LD", "LDN"):
            t = i.cr_out
            f = self.expr_as(i.operand, t) if not isinstance(i.operand.type, LiteralT) else \
                self.expr_as(i.operand, concrete(t))
            if op == "LDN":
                nf = std.not_fn(concrete(t))

                def ldn(env):
                    env.cr = nf(f(env))
                return ldn

            def ld(env):
                env.cr = f(env)
            return ld
        if op in ("ST", "STN"):
            if op == "STN":     # negated in the checker's type (sig)
                st_t = concrete(i.sig[0])
                w = self.writer(i.operand, st_t)
                nf = std.not_fn(st_t)
                cv = implicit(cr_in, st_t) or (lambda v: v)

                def stn(env):
                    w(env, nf(cv(env.cr)))
                return stn
            w = self.writer(i.operand, cr_in)

            def st(env):
                w(env, env.cr)
            return st
        if op in ("S", "R") and not isinstance(getattr(i.operand, "type", None), FBType):
            w = self.writer(i.operand, BOOL)
            val = op == "S"

            def set_reset(env):
                if env.cr:
                    w(env, val)
            return set_reset
        if op in ("S1", "R1", "CLK", "CU", "CD", "PV", "IN", "PT", "S", "R", "LD"):
            inst_var = i.operand.symbol
            param = inst_var.type.pou.var(op)
            pk = param.key
            st_ = self.storer(param.type, cr_in)
            kv = inst_var.key

            def fb_input(env):
                env.v[kv].v[pk] = st_(env.cr)
            return fb_input
        if op == "NOT":         # in the result's type: a bit string for a literal
            res = concrete(i.cr_out)
            nf = std.not_fn(res)
            cv = implicit(cr_in, res) or (lambda v: v)

            def not_(env):
                env.cr = nf(cv(env.cr))
            return not_
        if op in ("AND", "ANDN", "OR", "ORN", "XOR", "XORN", "ADD", "SUB", "MUL", "DIV",
                  "MOD", "GT", "GE", "EQ", "NE", "LE", "LT"):
            f = self.expr(i.operand)
            comb = self.il_combine(i, op, cr_in, i.operand.type)

            def apply(env):
                env.cr = comb(env.cr, f(env))
            return apply
        if op in ("JMP", "JMPC", "JMPCN"):
            target = labels[i.operand.name.upper()]
            backward = target <= n
            tick = self._tick() if backward else None
            if op == "JMP":
                if tick:
                    def jmp_back(env):
                        tick()
                        return target
                    return jmp_back
                return lambda env: target
            want = op == "JMPC"

            def jmpc(env):
                if bool(env.cr) == want:
                    if tick:
                        tick()
                    return target
                return None
            return jmpc
        if op in ("RET", "RETC", "RETCN"):
            if op == "RET":
                return lambda env: -1
            want = op == "RETC"
            return lambda env: -1 if bool(env.cr) == want else None
        if op in ("CAL", "CALC", "CALCN"):
            f = self.fb_call(i.call)
            if op == "CAL":
                return f
            want = op == "CALC"

            def calc(env):
                if bool(env.cr) == want:
                    f(env)
                return None
            return calc
        if op == "NOP":
            return lambda env: None
        raise AssertionError(f"IL operator {op}")

    def il_combine(self, i, op, cr_t, op_t):
        """g(cr, operand) -> new current result for a binary IL operator."""
        base = op[:-1] if op in ("ANDN", "ORN", "XORN") else op
        neg = op in ("ANDN", "ORN", "XORN")
        if base in ("AND", "OR", "XOR"):
            t = i.sig[1][0]
            ca, cb = implicit(cr_t, t), implicit(op_t, t)
            b = base_of(t)
            if b is BOOL:
                fn = {"AND": lambda x, y: bool(x and y), "OR": lambda x, y: bool(x or y),
                      "XOR": lambda x, y: bool(x) != bool(y)}[base]
                nf = (lambda y: not y)
            else:
                mask = (1 << b.bits) - 1
                fn = {"AND": lambda x, y: x & y, "OR": lambda x, y: x | y,
                      "XOR": lambda x, y: x ^ y}[base]
                nf = (lambda y: ~y & mask)

            def logic(x, y):
                if ca:
                    x = ca(x)
                if cb:
                    y = cb(y)
                if neg:
                    y = nf(y)
                return fn(x, y)
            return logic
        if base in stdlib.ARITH_FAMILIES:
            holder = _Holder()
            fargs = [_Slot(0, cr_t), _Slot(1, op_t)]
            f = self.apply_std(i.std, fargs, i.sig)

            def arith(x, y):
                holder.vals = (x, y)
                return f(holder)
            return arith
        t = i.sig[1][0]
        ca, cb = implicit(cr_t, t), implicit(op_t, t)
        fn = std.COMPARE[base]

        def cmp(x, y):
            if ca:
                x = ca(x)
            if cb:
                y = cb(y)
            return fn(x, y)
        return cmp

    # ----------------------------------------------------------- POU bodies
    def body(self):
        node = self.pou.node
        if node.language == "SFC":
            from .sfc import compile_sfc
            run = compile_sfc(self)
        elif node.language == "IL":
            run = self.il_body(node.body)
        else:
            run = self.block(node.body)
        pou = self.pou
        edges = [(v.key, v.edge) for v in pou.inputs if v.edge]
        temps = []
        if not self.is_function:
            m = self.m
            for v in pou.vars.values():
                if v.section != "VAR_TEMP":
                    continue
                t = concrete(v.type)
                if isinstance(t, FBType):
                    # a fresh instance per call, its externals bound in the caller's scope
                    temps.append((v.key, None, (t.pou, v.init, None)))
                elif isinstance(t, ArrayT) and isinstance(concrete(t.elem), FBType):
                    temps.append((v.key, None, (concrete(t.elem).pou, None, t.count)))
                else:
                    temps.append((v.key, m.maker(v), None))
        if not edges and not temps:
            return run
        m = self.m

        def body(env):
            iv = env.v
            for k, mk, fb in temps:
                if mk is not None:
                    iv[k] = mk()
                elif fb[2] is None:
                    iv[k] = m.new_instance(fb[0], env.s, fb[1])
                else:
                    iv[k] = [m.new_instance(fb[0], env.s, None) for _ in range(fb[2])]
            e = env.e
            for k, kind in edges:
                cur = bool(iv[k])
                prev = e.get("$" + k, False)
                e[k] = (cur and not prev) if kind == "R_EDGE" else (prev and not cur)
                e["$" + k] = cur
            return run(env)
        return body


class _Holder:
    __slots__ = ("vals",)


class _Slot:
    """An argument expression standing for a value handed over at run time
    (IL: the current result and the operand, combined by a standard
    function)."""

    def __init__(self, n, t):
        self.n = n
        self.type = t


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
