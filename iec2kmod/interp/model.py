"""Storage: instances of programs and function blocks, activation frames of
functions, initial values, deep copies.

A variable lives in a Python container under a key: a POU's own variables
in ``inst.v`` (a dict, upper-case name -> value), array elements in a list,
structure members in a dict.  A VAR_EXTERNAL or VAR_IN_OUT is a reference:
``inst.r[name]`` holds the (container, key) cell of the variable it stands
for, bound when the instance is created (externals, by name to the global
in scope -- at every depth of FB nesting) or at every call (in-outs)."""

from __future__ import annotations

from .. import ast
from ..checks import fold
from ..checks.types import (ArrayT, Elementary, EnumT, LiteralT, StringT, StructT,
                            SubrangeT, concrete)
from .values import base_of, convert_implicit, f32_safe


class Instance:
    """A program or FB instance, or a function's activation."""

    __slots__ = ("pou", "v", "r", "e", "cr", "s")

    def __init__(self, pou):
        self.pou = pou
        self.s = {}      # the globals in scope of the FBs inside (for VAR_TEMP instances)
        self.v = {}
        self.r = {}
        self.e = {}      # R_EDGE/F_EDGE inputs: the edge seen by this call, and memory
        self.cr = None   # IL current result

    def __repr__(self):
        return f"<{self.pou.name} instance>"


class BitCell:
    """A single bit of an integer variable, usable as a container:
    ``cell[0]`` reads the bit, ``cell[0] = b`` writes it."""

    __slots__ = ("c", "k", "n")

    def __init__(self, c, k, n):
        self.c, self.k, self.n = c, k, n

    def __getitem__(self, _):
        return bool((self.c[self.k] >> self.n) & 1)

    def __setitem__(self, _, b):
        x = self.c[self.k]
        self.c[self.k] = (x | (1 << self.n)) if b else (x & ~(1 << self.n))


def copier(t):
    """A function returning an independent copy of a value of type t."""
    t = concrete(t)
    if isinstance(t, ArrayT):
        inner = copier(t.elem)
        if inner is None:
            return list.copy
        return lambda a: [inner(x) for x in a]
    if isinstance(t, StructT):
        fields = [(k, copier(ft)) for k, (_, ft, _) in t.fields.items()]
        if all(c is None for _, c in fields):
            return dict.copy
        return lambda d: {k: (c(d[k]) if c else d[k]) for k, c in fields}
    return None


def copy_of(t):
    c = copier(t)
    return c if c is not None else (lambda x: x)


class Initializer:
    """Initial values of declared variables (the type's default where no
    initial value is given: 0, FALSE, '', T#0s, D#1970-01-01, an
    enumeration's first value, a subrange's lower limit)."""

    def __init__(self, project):
        self.project = project
        self.type_inits = project.types.get("__init__", {}) if isinstance(
            project.types.get("__init__"), dict) else {}
        self.constants = {}
        for cfg in project.configurations:
            for g in cfg.globals.values():
                if g.constant and isinstance(g.init, ast.Expr):
                    try:
                        self.constants[g.key] = self.const(g.init, g.type)
                    except ValueError:
                        pass
        self.enum_by_value = {}
        for t in project.types.values():
            if isinstance(t, EnumT):
                for k in t.values:
                    self.enum_by_value.setdefault(k, []).append(t)

    # ---------------------------------------------------- constants
    def const(self, e, t=None):
        """Value of a constant expression (declarations' initial values)."""
        v = self._const(e, t)
        if t is not None and not isinstance(concrete(t), EnumT):
            return convert_implicit(v, t)
        return v

    def _const(self, e, t):
        if isinstance(e, ast.Lit):
            if e.kind == "enum":
                et = self.project.types.get(e.type_name.upper())
                return et.values[e.value.upper()][1]
            if e.kind == "bool":
                return bool(e.value)
            if e.kind == "real" and e.type_name and e.type_name.upper() == "REAL":
                return f32_safe(e.value)
            return e.value
        if isinstance(e, ast.UnOp):
            v = fold.unary(e.op, self._const(e.operand, t))
            if e.op == "NOT" and not isinstance(v, bool):
                b = base_of(t) if t is not None else None
                return v & ((1 << b.bits) - 1) if isinstance(b, Elementary) else v
            return v
        if isinstance(e, ast.BinOp) and (e.op in fold.ARITH_OPS or e.op in fold.LOGIC_OPS):
            # the checker's folder's operators, on values in the variable's type
            return fold.binary(e.op, self._const(e.left, t), self._const(e.right, t))
        if isinstance(e, ast.Ref) and not e.accessors:
            key = e.name.upper()
            ct = concrete(t) if t is not None else None
            if isinstance(ct, EnumT) and key in ct.values:
                return ct.values[key][1]
            hits = self.enum_by_value.get(key, [])
            if len(hits) == 1:
                return hits[0].values[key][1]
            if key in self.constants:
                return self.constants[key]
        raise ValueError(f"not a constant: {e!r}")

    # ------------------------------------------------------ defaults
    def default(self, t):
        t0 = t
        t = concrete(t)
        if isinstance(t, SubrangeT):
            init = self.type_inits.get(t.name.upper())
            return self.const(init, t) if isinstance(init, ast.Expr) else t.low
        if isinstance(t, EnumT):
            init = self.type_inits.get(t.name.upper())
            if init is not None:
                return self.const(init, t)
            return next(iter(t.values.values()))[1] if t.values else 0
        if isinstance(t, StringT):
            return ""
        if isinstance(t, Elementary):
            if t.cat == "bool":
                return False
            if t.cat == "real":
                return 0.0
            return 0
        if isinstance(t, ArrayT):
            return self.value(t, None)
        if isinstance(t, StructT):
            init = self.type_inits.get(t.name.upper())
            return self.value(t, init if isinstance(init, ast.StructInit) else None)
        if isinstance(t, LiteralT):
            return 0
        raise AssertionError(f"default of {t0}")

    def value(self, t, init):
        """A fresh value of type t with initializer ``init`` (or None)."""
        t = concrete(t)
        if isinstance(t, ArrayT):
            n = t.count
            if init is None and isinstance(t.elem, (ArrayT, StructT)):
                return [self.value(t.elem, None) for _ in range(n)]
            if init is None:
                d = self.default(t.elem)
                return [d] * n
            out = []
            for count, item in init.items:
                for _ in range(count if count is not None else 1):
                    if len(out) < n:
                        out.append(self.value(t.elem, item) if item is not None
                                   else self.value(t.elem, None))
            while len(out) < n:
                out.append(self.value(t.elem, None))
            return out
        if isinstance(t, StructT):
            given = {}
            if init is None:
                init = self.type_inits.get(t.name.upper())
            if isinstance(init, ast.StructInit):
                given = {name.upper(): val for name, val, _ in init.fields}
            return {k: self.value(ft, given.get(k, finit))
                    for k, (_, ft, finit) in t.fields.items()}
        if init is None:
            return self.default(t)
        if isinstance(t, StringT):
            return init.value[:t.length]
        v = self.const(init, t)
        return v
