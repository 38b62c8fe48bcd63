"""PouCompiler, variable access and expressions: a variable access as a
reader, a writer (converted, truncated, range-checked, copied: ``storer``)
or a cell (container, key) for VAR_IN_OUT bindings, its accessors checked
(an index out of range is a fault); every expression as ``f(env)`` in its
own type's representation (``expr``) or converted to another's
(``expr_as``; an untyped expression typed by its context), literals,
comparison and logic operators, unary operators.

``ExprCompiler`` is mixed into compiler.PouCompiler, whose state it uses
(``pou``) and whose calls it reaches through ``call_expr``, ``std_call``,
``apply_std`` (compile_calls.py).  It imports closures.py and the
interpreter's value modules, never compiler.py."""

from __future__ import annotations

from .. import ast
from ..checks import stdlib
from ..checks.symbols import EnumValue
from ..checks.symbols import Var
from ..checks.types import (ArrayT, BOOL, Elementary, LiteralT, StringT, StructT, SubrangeT,
                            concrete)
from .closures import REF_SECTIONS, _Slot, _const, _from_sig, conv_fn, implicit
from .conv import int_to_f32
from .errors import INDEX, RANGE, Fault
from .model import BitCell, copier
from .values import base_of, f32_safe, wrap, wrap64


class ExprCompiler:
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
