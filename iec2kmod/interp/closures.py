"""What every part of the interpreter's compiler (compiler.py and its
mixins compile_*.py) builds its closures from: the results of a statement
closure (``EXIT``, ``RETURN``, ``CONTINUE``), the sections reached by
reference, the constant closure, the implicit conversions between types
(``implicit``: the widenings of the standard and of untyped literals, also
the z3 encoder's, verify/encode.py), a standard call's value in its
context's type (``_from_sig``), and ``_Slot``, an argument standing for a
value handed over at run time.

A leaf of the compiler: it imports the checker's types and the
interpreter's value modules (conv.py, values.py), never compiler.py or a
compile_*.py."""

from __future__ import annotations

from ..checks.types import Elementary, LiteralT
from .conv import int_to_f32, int_to_f64
from .values import base_of, f32_safe, wrap

EXIT = 1
RETURN = 2
CONTINUE = 3        # the rest of the loop's iteration is skipped (ed.3)
REF_SECTIONS = ("VAR_EXTERNAL", "VAR_IN_OUT")


def _const(v):
    return lambda env: v


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


class _Slot:
    """An argument expression standing for a value handed over at run time
    (IL: the current result and the operand, combined by a standard
    function)."""

    def __init__(self, n, t):
        self.n = n
        self.type = t
