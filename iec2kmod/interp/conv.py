"""Type conversion functions: <T>_TO_<U>, <REAL>_TRUNC_<INT>, TRUNC, the BCD
conversions, and the textual forms of values (<T>_TO_STRING, STRING_TO_<T>).

Rules (IEC 61131-3 ed.3, 6.6.2.5.6 and table 22): between integer and bit
string types the bit pattern is kept modulo 2^width of the destination;
REAL to integer rounds to the nearest integer (ties to even) and saturates
at the destination's limits (NaN gives 0); TRUNC truncates toward zero.
Time types count, as integers: TIME milliseconds, LTIME nanoseconds, TOD
milliseconds since midnight, DATE and DT seconds since 1970-01-01, the L
forms nanoseconds."""

from __future__ import annotations

import math
import re

from ..checks.types import Elementary, StringT
from ..parse.literals import LiteralError, classify, days_from_civil
from .values import base_of, f32_safe, wrap, wrap64
from .std import NS_PER_DAY, round_half_even, sat_i64

# (nanoseconds per counted unit, kind: duration | point | date | tod)
TIME_UNITS = {"TIME": (1_000_000, "dur"), "LTIME": (1, "dur"), "TOD": (1_000_000, "tod"),
              "LTOD": (1, "tod"), "DATE": (1_000_000_000, "date"), "LDATE": (1, "date"),
              "DT": (1_000_000_000, "point"), "LDT": (1, "point")}


def int_to_f32(v: int) -> float:
    """An integer rounded once, to nearest even, to binary32."""
    if abs(v) < (1 << 53):
        return f32_safe(float(v))
    neg = v < 0
    a = -v if neg else v
    shift = a.bit_length() - 24
    q, r = divmod(a, 1 << shift)
    half = 1 << (shift - 1)
    if r > half or (r == half and q & 1):
        q += 1
    x = f32_safe(float(q << shift))
    return -x if neg else x


def int_to_f64(v: int) -> float:
    try:
        return float(v)       # Python rounds int -> float to nearest even
    except OverflowError:
        return math.inf if v > 0 else -math.inf


def _sat(r: float, b) -> int:
    lo, hi = b.range
    if r != r:
        return 0
    if r < lo:
        return lo
    if r > hi:
        return hi
    return int(r)


def real_to_int(x: float, b, trunc=False) -> int:
    if x != x:
        return 0
    if x in (math.inf, -math.inf):
        return _sat(x, b)
    r = math.trunc(x) if trunc else round(x)   # round(): ties to even
    lo, hi = b.range
    return lo if r < lo else hi if r > hi else r


def time_to_count(v: int, name: str) -> int:
    unit, kind = TIME_UNITS[name]
    if kind == "dur":
        q = abs(v) // unit
        return q if v >= 0 else -q
    return v // unit


def count_to_time(n: int, name: str) -> int:
    unit, kind = TIME_UNITS[name]
    v = wrap64(n * unit)
    if kind == "date":
        return wrap64(v - v % NS_PER_DAY)
    if kind == "tod":
        return v % NS_PER_DAY
    return v


def real_to_time(x: float, name: str) -> int:
    unit, kind = TIME_UNITS[name]
    v = sat_i64(round_half_even(x * float(unit)))
    if kind == "date":
        return wrap64(v - v % NS_PER_DAY)
    if kind == "tod":
        return v % NS_PER_DAY
    return v


def _tname(t):
    b = base_of(t)
    if isinstance(b, StringT):
        return "WSTRING" if b.wide else "STRING"
    return b.name


def _norm(n):
    return {"TIME_OF_DAY": "TOD", "DATE_AND_TIME": "DT", "LDATE": "LDATE"}.get(n, n)


# ---------------------------------------------------------------- to text
def _digits_shortest(v: float, single: bool):
    """(digit string, decimal exponent of the first digit) of the shortest
    decimal that reads back as v (v > 0)."""
    if not single:
        s = f"{v:.16e}"
        for p in range(1, 18):
            s = f"{v:.{p - 1}e}"
            if float(s) == v:
                break
    else:
        for p in range(1, 10):
            s = f"{v:.{p - 1}e}"
            if f32_safe(float(s)) == v:
                break
    mant, exp = s.split("e")
    digits = mant.replace(".", "").rstrip("0") or "0"
    return digits, int(exp)


def real_text(v: float, single: bool) -> str:
    if v != v:
        return "NaN"
    out = ""
    if math.copysign(1.0, v) < 0:
        out = "-"
        v = -v
    if v == math.inf:
        return out + "Inf"
    if v == 0:
        return out + "0.0"
    dig, e10 = _digits_shortest(v, single)
    p = len(dig)
    plain_max = 7 if single else 15
    if -5 <= e10 < plain_max:
        if e10 < 0:
            return out + "0." + "0" * (-e10 - 1) + dig
        whole = "".join(dig[i] if i < p else "0" for i in range(e10 + 1))
        frac = dig[e10 + 1:] or "0"
        return out + whole + "." + frac
    frac = dig[1:] or "0"
    return out + dig[0] + "." + frac + "E" + ("-" if e10 < 0 else "+") + str(abs(e10))


_PARTS = ((NS_PER_DAY, "d"), (3_600_000_000_000, "h"), (60_000_000_000, "m"),
          (1_000_000_000, "s"), (1_000_000, "ms"), (1_000, "us"), (1, "ns"))


def duration_text(v: int, prefix: str) -> str:
    out = prefix + ("-" if v < 0 else "")
    mag = abs(v)
    if mag == 0:
        return out + "0s"
    for ns, unit in _PARTS:
        q = mag // ns
        if q:
            out += f"{q}{unit}"
            mag -= q * ns
    return out


def civil_from_days(z: int):
    z += 719468
    era = z // 146097
    doe = z - era * 146097
    yoe = (doe - doe // 1460 + doe // 36524 - doe // 146096) // 365
    doy = doe - (365 * yoe + yoe // 4 - yoe // 100)
    mp = (5 * doy + 2) // 153
    d = doy - (153 * mp + 2) // 5 + 1
    m = mp + 3 if mp < 10 else mp - 9
    y = yoe + era * 400 + (m <= 2)
    return y, m, d


def ymd_text(v: int) -> str:
    y, m, d = civil_from_days(v // NS_PER_DAY)
    sign = "-" if y < 0 else ""
    return f"{sign}{abs(y):04d}-{m:02d}-{d:02d}"


def hms_text(v: int) -> str:
    ns = v % NS_PER_DAY
    frac, secs = ns % 1_000_000_000, ns // 1_000_000_000
    out = f"{secs // 3600:02d}:{secs // 60 % 60:02d}:{secs % 60:02d}"
    if frac:
        out += "." + f"{frac:09d}".rstrip("0")
    return out


def to_text(v, t) -> str:
    b = base_of(t)
    n = _tname(b)
    if isinstance(b, StringT):
        return v
    if b.cat == "bool":
        return "TRUE" if v else "FALSE"
    if b.cat in ("sint", "uint", "bit"):
        return str(v)
    if b.cat == "real":
        return real_text(v, b.bits == 32)
    if n in ("TIME", "LTIME"):
        return duration_text(v, "T#" if n == "TIME" else "LTIME#")
    if n in ("DATE", "LDATE"):
        return ("D#" if n == "DATE" else "LDATE#") + ymd_text(v)
    if n in ("TOD", "LTOD"):
        return ("TOD#" if n == "TOD" else "LTOD#") + hms_text(v)
    if n in ("DT", "LDT"):
        return ("DT#" if n == "DT" else "LDT#") + ymd_text(v) + "-" + hms_text(v)
    raise AssertionError(n)


# -------------------------------------------------------------- from text
_INT_RE = re.compile(r"^([+-]?)(?:(2|8|16)#)?([0-9A-Fa-f_]+)$")
_TYPE_PREFIX = re.compile(r"^(?:[A-Za-z_]+)#(?=.)")


def _parse_int(s: str):
    """(value) of an integer literal text, or None."""
    s = s.strip(" \t\r\n\f\v")
    m = re.match(r"^(SINT|INT|DINT|LINT|USINT|UINT|UDINT|ULINT|BYTE|WORD|DWORD|LWORD)#",
                 s, re.I)
    if m:
        s = s[m.end():]
    sign = 1
    if s and s[0] in "+-":
        sign = -1 if s[0] == "-" else 1
        s = s[1:]
    base = 10
    m = re.match(r"^(2|8|16)#", s)
    if m:
        base = int(m.group(1))
        s = s[m.end():]
    if not s or s[0] == "_" or s[-1] == "_" or "__" in s:
        return None
    try:
        return sign * int(s.replace("_", ""), base)
    except ValueError:
        return None


def text_to(s: str, t):
    b = base_of(t)
    n = _tname(b)
    if isinstance(b, StringT):
        return s[:b.length]
    if b.cat == "bool":
        x = s.strip(" \t\r\n\f\v")
        if x.upper() == "TRUE":
            return True
        if x.upper() == "FALSE":
            return False
        v = _parse_int(x)
        return bool(v) if v is not None else False
    if b.cat in ("sint", "uint", "bit"):
        v = _parse_int(s)
        if v is None:
            return 0
        lo, hi = b.range
        return lo if v < lo else hi if v > hi else v
    if b.cat == "real":
        x = s.strip(" \t\r\n\f\v")
        x = re.sub(r"^(REAL|LREAL)#", "", x, flags=re.I)
        low = x.lower().lstrip("+-")
        sign = -1.0 if x.startswith("-") else 1.0
        if low == "nan":
            v = math.nan
        elif low in ("inf", "infinity"):
            v = sign * math.inf
        elif re.fullmatch(r"[+-]?[0-9](_?[0-9])*(\.[0-9](_?[0-9])*)?([eE][+-]?[0-9]+)?", x):
            v = float(x.replace("_", ""))
        else:
            v = 0.0
        return f32_safe(v) if b.bits == 32 else v
    # time types: through the literal syntax of the front end
    x = s.strip(" \t\r\n\f\v")
    try:
        if "#" not in x:
            x = {"TIME": "T#", "LTIME": "LTIME#", "DATE": "D#", "LDATE": "LDATE#",
                 "TOD": "TOD#", "LTOD": "LTOD#", "DT": "DT#", "LDT": "LDT#"}[n] + x
        kind, value, _ = classify(x)
    except (LiteralError, ValueError, KeyError, IndexError):
        return 0
    want = {"TIME": "time", "LTIME": "time", "DATE": "date", "LDATE": "date", "TOD": "tod",
            "LTOD": "tod", "DT": "dt", "LDT": "dt"}[n]
    if kind != want:
        return 0
    return wrap64(int(value))


# ------------------------------------------------------------ conversions
def _bcd_decode(v: int, digits: int) -> int:
    r, scale = 0, 1
    for i in range(digits):
        nib = (v >> (4 * i)) & 0xF
        if nib > 9:
            return 0
        r += nib * scale
        scale *= 10
    return r


def _bcd_encode(v: int, digits: int) -> int:
    if v < 0:
        return 0
    r = 0
    for i in range(digits):
        r |= (v % 10) << (4 * i)
        v //= 10
    return 0 if v else r


def converter(family: str, src, dst):
    """A Python function converting one value of type src into dst."""
    sb, db = base_of(src), base_of(dst)
    sn, dn = _norm(_tname(sb)), _norm(_tname(db))
    if family == "TRUNC":
        return lambda x: real_to_int(x, db, trunc=True)
    if family == "BCD_TO":
        digits = sb.bits // 4
        return lambda v: wrap(_bcd_decode(v, digits), db)
    if family == "TO_BCD":
        digits = db.bits // 4
        return lambda v: _bcd_encode(v, digits)
    # strings
    if isinstance(db, StringT):
        if isinstance(sb, StringT):
            if db.wide:
                return lambda s: s[:db.length]
            return lambda s: "".join(c if ord(c) < 256 else "?" for c in s)[:db.length]
        return lambda v: to_text(v, sb)[:db.length]
    if isinstance(sb, StringT):
        return lambda s: text_to(s, db)
    sc, dc = sb.cat, db.cat
    ints = ("sint", "uint", "bit")
    times = ("time", "date", "tod", "dt")
    if dc == "bool":
        return lambda v: v != 0
    if sc == "bool":
        if dc in times:
            return lambda v: count_to_time(1 if v else 0, dn)
        if dc == "real":
            return lambda v: 1.0 if v else 0.0
        return lambda v: 1 if v else 0
    if sc in ints and dc in ints:
        return lambda v: wrap(v, db)
    if sc in ints and dc == "real":
        return int_to_f32 if db.bits == 32 else int_to_f64
    if sc == "real" and dc in ints:
        return lambda x: real_to_int(x, db)
    if sc == "real" and dc == "real":
        return (lambda x: f32_safe(x)) if db.bits == 32 else (lambda x: x)
    if sc in times and dc in ints:
        return lambda v: wrap(time_to_count(v, sn), db)
    if sc in ints and dc in times:
        return lambda v: count_to_time(v, dn)
    if sc in times and dc == "real":
        unit = float(TIME_UNITS[sn][0])
        if db.bits == 32:
            return lambda v: f32_safe(float(v) / unit)
        return lambda v: float(v) / unit
    if sc == "real" and dc in times:
        return lambda x: real_to_time(x, dn)
    if sc in times and dc in times:
        kind = TIME_UNITS[dn][1]
        if kind == "date":
            return lambda v: wrap64(v - v % NS_PER_DAY)
        if kind == "tod":
            return lambda v: v % NS_PER_DAY
        return lambda v: v
    raise AssertionError(f"conversion {sn} -> {dn}")


def is_elementary_type(t):
    return isinstance(base_of(t), (Elementary, StringT))


__all__ = ["converter", "to_text", "text_to", "int_to_f32", "days_from_civil"]
