"""Values and types of the reference interpreter.

How an IEC value is held in Python (one representation per type family):

    BOOL                      bool
    SINT .. ULINT, BYTE ..    int, always inside the type's range (wrapped)
    REAL                      float holding a value exactly representable as
                              IEEE binary32 (every REAL result is rounded to
                              binary32, round to nearest even)
    LREAL                     float (IEEE binary64)
    TIME, LTIME, DATE, TOD,   int: signed 64-bit count of nanoseconds (since
    DT and the L forms        midnight for TOD, since 1970-01-01 for DATE/DT)
    STRING, WSTRING           str, never longer than the declared length
    enumerations              int (the value's number)
    subranges                 int of the base type, inside the subrange
    ARRAY                     list, one entry per element, row-major over all
                              dimensions of that ARRAY declaration
    STRUCT                    dict: upper-case member name -> value
    FB instance               Instance (see machine.py)

Nothing here knows about C: the rules are the standard's (two's complement
wrap-around of ANY_INT, IEEE 754 for ANY_REAL, TIME as a signed 64-bit
duration)."""

from __future__ import annotations

import struct

from ..checks.types import (Elementary, EnumT, StringT, SubrangeT, concrete)

_F32 = struct.Struct("<f")
F32_MAX_ROUND = 3.4028235677973366e38   # (2 - 2^-24) * 2^127: the rounding boundary


def f32(x: float) -> float:
    """x rounded to the nearest IEEE binary32 value (ties to even); beyond the
    largest finite REAL it becomes an infinity, as IEEE rounding does."""
    try:
        return _F32.unpack(_F32.pack(x))[0]
    except OverflowError:
        return float("inf") if x > 0 else float("-inf")


def f32_safe(x: float) -> float:
    if x != x or x in (float("inf"), float("-inf")):
        return x
    if abs(x) >= F32_MAX_ROUND:
        return float("inf") if x > 0 else float("-inf")
    return f32(x)


def base_of(t):
    """The elementary (or string/enum/...) type behind aliases and subranges."""
    t = concrete(t)
    if isinstance(t, SubrangeT):
        return t.elem
    return t


def int_range(t):
    t = base_of(t)
    if isinstance(t, EnumT):
        return None
    return t.range if isinstance(t, Elementary) else None


def wrap(v: int, t) -> int:
    """v taken modulo 2^bits into the range of integer/bit type t."""
    t = base_of(t)
    bits = t.bits
    m = (1 << bits) - 1
    v &= m
    if t.cat == "sint" and v >> (bits - 1):
        v -= 1 << bits
    return v


def wrap64(v: int) -> int:
    v &= (1 << 64) - 1
    return v - (1 << 64) if v >> 63 else v


def is_real_t(t) -> bool:
    t = base_of(t)
    return isinstance(t, Elementary) and t.cat == "real"


def is_int_t(t) -> bool:
    t = base_of(t)
    return isinstance(t, Elementary) and t.cat in ("sint", "uint", "bit")


def is_time_t(t) -> bool:
    t = base_of(t)
    return isinstance(t, Elementary) and t.cat in ("time", "date", "tod", "dt")


def convert_implicit(v, t):
    """A value of any type converted implicitly to t (the widenings the
    standard allows, and untyped literals taking the type of their
    context)."""
    t0 = concrete(t)
    b = base_of(t0)
    if isinstance(b, Elementary):
        c = b.cat
        if c == "bool":
            return bool(v)
        if c == "real":
            x = float(v)
            return f32_safe(x) if b.bits == 32 else x
        if c in ("sint", "uint", "bit"):
            return wrap(int(v), b)
        return wrap64(int(v))
    if isinstance(b, StringT):
        return v[:b.length]
    return v
