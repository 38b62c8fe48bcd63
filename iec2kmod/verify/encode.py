"""Symbolic execution of one task cycle over z3 terms.

The storage is the reference interpreter's own (iec2kmod.interp.model):
the same dicts, lists and Instance objects, with every scalar replaced by a
z3 term.  Statements are executed once, symbolically; a write happens under
the path condition that reaches it (``If(guard, new, old)``), so one store
represents every path through IF/CASE/EXIT/RETURN/IL jumps at once and the
references the interpreter binds (VAR_EXTERNAL, VAR_IN_OUT) stay valid.

Value representation (the sort follows the IEC type):
    BOOL                                   Bool
    SINT..ULINT, BYTE..LWORD, TIME, DATE,   BitVec(width), two's complement
    TOD, DT, enumerations, subranges
    REAL / LREAL                           FP(8, 24) / FP(11, 53), RNE
    untyped literal values                 Python int/float (exact), or a
                                           z3 Int when a guarded IL current
                                           result must hold one
    ARRAY / STRUCT / FB instance           list / dict / Instance of terms

Every construct this module cannot encode exactly raises Refuse naming it.
"""

from __future__ import annotations

import math

import z3

from .. import ast
from ..checks import stdlib
from ..checks.symbols import EnumValue
from ..checks.symbols import Var
from ..checks.types import (ArrayT, BOOL, Elementary, EnumT, FBType, LiteralT, StringT,
                            StructT, SubrangeT, concrete)
from ..checks.types import ELEMENTARY as _E
from ..interp.compiler import PouCompiler, implicit
from ..interp.errors import DIV_ZERO, ENUM, INDEX, LOOP, MUX, RANGE
from ..execmodel import LOOP_BUDGET
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


def to_bv(x, w):
    if isinstance(x, int):
        return bv_lit(x, w)
    if z3.is_int(x):
        return z3.Int2BV(x, w)
    return x


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


class Encoder:
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

    # ------------------------------------------------ standard functions
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


class _SlotVal(ast.Expr):
    """An already computed value standing in an argument list."""

    __slots__ = ("value",)

    def __init__(self, value, t):
        super().__init__(None)
        self.value = value
        self.type = t


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


def _py_mod(nn, w, ww):
    """n mod w as Python's % does (a non-negative result)."""
    m = bv_lit(w, ww)
    r = z3.SRem(nn, m)
    return z3.If(r < bv_lit(0, ww), r + m, r)


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




ELEM_LINT = _E["LINT"]
