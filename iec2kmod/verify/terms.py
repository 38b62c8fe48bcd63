"""The terms of the z3 encoding, and what works on them without an Encoder.

Value representation (the sort follows the IEC type):
    BOOL                                   Bool
    SINT..ULINT, BYTE..LWORD, TIME, DATE,   BitVec(width), two's complement
    TOD, DT, enumerations, subranges
    REAL / LREAL                           FP(8, 24) / FP(11, 53), RNE
    untyped literal values                 Python int/float (exact), or a
                                           z3 Int when a guarded IL current
                                           result must hold one
    ARRAY / STRUCT / FB instance           list / dict / Instance of terms

Here: the encoding's constants (the unrolling bounds, the timers' automaton
locations, the UNROLL and REFUSED markers), ``Refuse``; connectives that
simplify as they build (``land``, ``lor``, ``lnot``, ``ite``) and
``smt_eq``; an IEC type's sort (``kind``, ``width``, ``signed``,
``sort_of``) and constants to and from the interpreter's Python values
(``const_of``, ``py_value``); where a value lives (``store_into``,
``Cell``, ``Place``) and the running POU (``Frame``); the comparison and
logic operators on terms.

A leaf of verify/: it imports z3, the checker's types and the
interpreter's storage (interp.model, interp.values), and every other module
of verify/ may import it (encode*.py, model.py, engine.py, cex.py, ...)."""

from __future__ import annotations

import math

import z3

from .. import ast
from ..checks.types import BOOL, Elementary, EnumT
from ..interp.model import Instance
from ..interp.values import base_of

TRUE = z3.BoolVal(True)
FALSE = z3.BoolVal(False)
INT64_MAX = (1 << 63) - 1
NS_PER_DAY = 86_400_000_000_000
MAX_UNROLL = 4096          # iterations of one FOR loop
MAX_TOTAL_UNROLL = 100_000  # iterations of all loops of one cycle (below LOOP_BUDGET)
INIT, WORK, TOUT, ON = 0, 1, 2, 3
UNROLL = "unroll: "      # the kind of a fault site that marks an undecided loop


class Refuse(Exception):
    """A construct that cannot be encoded exactly: (source, offset, message)."""

    def __init__(self, src, pos, message):
        super().__init__(message)
        self.src = src
        self.pos = pos
        self.message = message


# ------------------------------------------------------------------ helpers
def land(*xs):
    out = []
    for x in xs:
        if z3.is_false(x):
            return FALSE
        if not z3.is_true(x):
            out.append(x)
    if not out:
        return TRUE
    return out[0] if len(out) == 1 else z3.And(*out)


def lor(*xs):
    out = []
    for x in xs:
        if z3.is_true(x):
            return TRUE
        if not z3.is_false(x):
            out.append(x)
    if not out:
        return FALSE
    return out[0] if len(out) == 1 else z3.Or(*out)


def smt_eq(a, b):
    """Equality of terms as values (for REAL: the same datum, NaN equal to
    NaN, -0.0 different from +0.0), not IEEE comparison."""
    return z3.BoolRef(z3.Z3_mk_eq(a.ctx_ref(), a.as_ast(), b.as_ast()), a.ctx)


def lnot(x):
    if z3.is_true(x):
        return FALSE
    if z3.is_false(x):
        return TRUE
    return z3.Not(x)


def ite(c, a, b):
    if z3.is_true(c):
        return a
    if z3.is_false(c):
        return b
    if isinstance(a, list):
        return [ite(c, x, y) for x, y in zip(a, b)]
    if isinstance(a, dict):
        return {k: ite(c, a[k], b[k]) for k in a}
    if isinstance(a, Instance):
        return a
    if isinstance(a, Opaque) or isinstance(b, Opaque):
        return a if a is b else Opaque("merged", getattr(a, "type", None))
    if a is b or (z3.is_expr(a) and z3.is_expr(b) and a.eq(b)):
        return a
    return z3.If(c, a, b)


def kind(t):
    """'bool', 'bv' (with signedness), 'fp', or None."""
    b = base_of(t)
    if isinstance(b, EnumT):
        return "bv"
    if isinstance(b, Elementary):
        if b.cat == "bool":
            return "bool"
        if b.cat == "real":
            return "fp"
        return "bv"
    return None


def width(t):
    b = base_of(t)
    if isinstance(b, EnumT):
        return b.elem_base.bits if b.elem_base is not None else 32
    return b.bits


def signed(t):
    b = base_of(t)
    if isinstance(b, EnumT):
        return True
    return not (isinstance(b, Elementary) and b.cat in ("uint", "bit", "bool"))


def fp_sort(t):
    return z3.Float32() if base_of(t).bits == 32 else z3.Float64()


def sort_of(t):
    k = kind(t)
    if k == "bool":
        return z3.BoolSort()
    if k == "fp":
        return fp_sort(t)
    if k == "bv":
        return z3.BitVecSort(width(t))
    return None


def const_of(v, t):
    """The z3 constant of Python value v (the interpreter's representation)
    of scalar type t."""
    k = kind(t)
    if k == "bool":
        return z3.BoolVal(bool(v))
    if k == "bv":
        w = width(t)
        return z3.BitVecVal(int(v) % (1 << w), w)
    if k == "fp":
        s = fp_sort(t)
        x = float(v)
        if x != x:
            return z3.fpNaN(s)
        if x == math.inf:
            return z3.fpPlusInfinity(s)
        if x == -math.inf:
            return z3.fpMinusInfinity(s)
        if x == 0 and math.copysign(1.0, x) < 0:
            return z3.fpMinusZero(s)
        return z3.FPVal(x, None, s)
    raise AssertionError(f"constant of {t}")


def py_value(term, t):
    """A concrete z3 term back as the interpreter's Python value."""
    k = kind(t)
    if k == "bool":
        return z3.is_true(term)
    if k == "bv":
        v = term.as_long()
        if signed(t) and v >> (width(t) - 1):
            v -= 1 << width(t)
        return v
    if k == "fp":
        if z3.is_fp_value(term):
            if term.isNaN():
                return math.nan
            if term.isInf():
                return -math.inf if term.isNegative() else math.inf
            if term.isZero():
                return -0.0 if term.isNegative() else 0.0
            return _fp_float(term)
    raise AssertionError(f"value of {t}")


def _fp_float(term):
    # exact: the significand and exponent of the FP numeral
    sig = term.significand_as_long()
    exp = term.exponent_as_long(biased=False)
    ebits = term.ebits()
    sbits = term.sbits()
    bias = (1 << (ebits - 1)) - 1
    if term.exponent_as_long(biased=True) == 0:   # subnormal
        val = math.ldexp(sig, 1 - bias - (sbits - 1))
    else:
        val = math.ldexp(sig + (1 << (sbits - 1)), exp - (sbits - 1))
    return -val if term.isNegative() else val


def bv_lit(v, w):
    return z3.BitVecVal(v % (1 << w), w)


class Opaque:
    """A value the encoding does not represent (a STRING): reading it refuses."""

    __slots__ = ("name", "type")

    def __init__(self, name, t):
        self.name = name
        self.type = t


REFUSED = "$refused"     # prefix of the stand-ins of values not encoded (lazy_strings)


def copy_tree(v):
    """An independent copy of an array or structure value (its terms shared)."""
    if isinstance(v, list):
        return [copy_tree(x) for x in v]
    if isinstance(v, dict):
        return {k: copy_tree(x) for k, x in v.items()}
    return v


def store_into(c, k, guard, v):
    """c[k] := v on the paths of guard.  An array or structure is updated in
    place, element by element: the containers stay the ones the state
    leaves (and references) point into."""
    old = c[k]
    if isinstance(old, list) and isinstance(v, list):
        for i in range(len(old)):
            store_into(old, i, guard, v[i])
        return
    if isinstance(old, dict) and isinstance(v, dict):
        for key in old:
            store_into(old, key, guard, v[key])
        return
    if isinstance(old, Instance):
        return
    c[k] = ite(guard, v, old)


class Cell:
    """One place a value lives: container[key], or bit n of it."""

    __slots__ = ("c", "k", "bit")

    def __init__(self, c, k, bit=None):
        self.c, self.k, self.bit = c, k, bit

    def get(self):
        v = self.c[self.k]
        if self.bit is not None:
            return z3.Extract(self.bit, self.bit, v) == 1
        return v

    def put(self, guard, v):
        if z3.is_false(guard):
            return
        if self.bit is not None:
            old = self.c[self.k]
            w = old.size()
            m = bv_lit(1 << self.bit, w)
            v = z3.If(v, old | m, old & ~m)
            self.c[self.k] = ite(guard, v, old)
            return
        store_into(self.c, self.k, guard, v)


class Place:
    """A variable access: alternative cells under exclusive conditions
    (a symbolic array index), the last one taken by default."""

    __slots__ = ("alts",)

    def __init__(self, alts):
        self.alts = alts   # [(cond, Cell)]

    def get(self):
        out = self.alts[-1][1].get()
        for cond, cell in reversed(self.alts[:-1]):
            out = ite(cond, cell.get(), out)
        return out

    def put(self, guard, v):
        for cond, cell in self.alts:
            cell.put(land(guard, cond), v)

    def instances(self):
        return [(cond, cell.c[cell.k]) for cond, cell in self.alts]


class Frame:
    """The running POU: its instance and the accumulated EXIT/RETURN, and
    CONTINUE within the current iteration of the innermost loop."""

    __slots__ = ("inst", "pou", "ret", "brk", "cnt")

    def __init__(self, inst, pou):
        self.inst = inst
        self.pou = pou
        self.ret = FALSE
        self.brk = FALSE
        self.cnt = FALSE


class _SlotVal(ast.Expr):
    """An already computed value standing in an argument list."""

    __slots__ = ("value",)

    def __init__(self, value, t):
        super().__init__(None)
        self.value = value
        self.type = t


def Ref_of(var, pos):
    r = ast.Ref(pos, var.name, [])
    r.symbol = var
    r.type = var.type
    return r


def simplify_if_const(x):
    if z3.is_bv_value(x) or not z3.is_expr(x):
        return x
    y = z3.simplify(x)
    return y


def _representable(i, w, sg):
    if sg:
        return -(1 << (w - 1)) <= i < (1 << (w - 1))
    return 0 <= i < (1 << w)


def compare(op, a, b, t):
    if z3.is_fp(a):
        f = {"=": z3.fpEQ, "<>": lambda x, y: z3.Not(z3.fpEQ(x, y)), "<": z3.fpLT,
             ">": z3.fpGT, "<=": z3.fpLEQ, ">=": z3.fpGEQ}[op]
        return f(a, b)
    if z3.is_bool(a):
        if op == "=":
            return a == b
        if op == "<>":
            return a != b
        a = z3.If(a, bv_lit(1, 1), bv_lit(0, 1))
        b = z3.If(b, bv_lit(1, 1), bv_lit(0, 1))
        t = BOOL
    if op == "=":
        return a == b
    if op == "<>":
        return a != b
    if signed(t):
        return {"<": a < b, ">": a > b, "<=": a <= b, ">=": a >= b}[op]
    return {"<": z3.ULT(a, b), ">": z3.UGT(a, b), "<=": z3.ULE(a, b),
            ">=": z3.UGE(a, b)}[op]


def logic(op, a, b):
    if z3.is_bool(a):
        if op == "AND":
            return land(a, b)
        if op == "OR":
            return lor(a, b)
        return z3.Xor(a, b)
    if op == "AND":
        return a & b
    if op == "OR":
        return a | b
    return a ^ b
