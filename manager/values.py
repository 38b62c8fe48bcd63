# SPDX-License-Identifier: MIT
"""IEC 61131-3 literals for plc-manager: parse what a user writes
(``TRUE``, ``-5``, ``16#FF``, ``INT#7``, ``1.5E3``, ``T#1h2m3s``,
``D#2024-01-31``, ``TOD#12:00:00.5``, ``DT#2024-01-31-12:00:00``,
``'text$N'``, ``"wide"``, an enumeration value), check it against the
variable's type (range, subrange, enumeration, string length), and turn it
into the bytes of the C object the kernel holds -- and back for display.

A variable is described by a :class:`VarType`: the kind and size the
kernel reports, plus what the manifest says (elementary type, subrange,
enumeration values, string length).
"""

from __future__ import annotations

import datetime as _dt
import math
import re
import struct
from dataclasses import dataclass, field
from typing import Any, Dict, Optional, Tuple

from .errors import UsageError

NS = {"d": 86_400 * 10**9, "h": 3_600 * 10**9, "m": 60 * 10**9, "s": 10**9,
      "ms": 10**6, "us": 10**3, "ns": 1}

INT_TYPES = {  # name: (signed, bits)
    "SINT": (True, 8), "INT": (True, 16), "DINT": (True, 32), "LINT": (True, 64),
    "USINT": (False, 8), "UINT": (False, 16), "UDINT": (False, 32), "ULINT": (False, 64),
    "BYTE": (False, 8), "WORD": (False, 16), "DWORD": (False, 32), "LWORD": (False, 64),
}
BIT_TYPES = {"BYTE", "WORD", "DWORD", "LWORD"}
REAL_TYPES = {"REAL": 4, "LREAL": 8}
TIME_TYPES = {"TIME": "time", "LTIME": "time", "DATE": "date", "LDATE": "date",
              "TOD": "tod", "LTOD": "tod", "TIME_OF_DAY": "tod", "DT": "dt", "LDT": "dt",
              "DATE_AND_TIME": "dt"}
# literal prefixes of the time types
TIME_PREFIX = {"T": "time", "TIME": "time", "LT": "time", "LTIME": "time",
               "D": "date", "DATE": "date", "LD": "date", "LDATE": "date",
               "TOD": "tod", "TIME_OF_DAY": "tod", "LTOD": "tod",
               "DT": "dt", "DATE_AND_TIME": "dt", "LDT": "dt"}
REAL_MAX = 3.4028234663852886e38

_KIND_BASE = {"b": "BOOL", "f": None, "t": "TIME", "s": "STRING", "w": "WSTRING"}


@dataclass
class VarType:
    path: str
    kind: str                    # b i u f t e s w
    size: int                    # bytes of the C object (0: unknown)
    type: str = "?"              # IEC type name as declared (INT, Percent, STRING[16])
    base: Optional[str] = None   # elementary type (INT, TOD, STRING ...)
    range: Optional[Tuple[int, int]] = None
    enum: Dict[str, int] = field(default_factory=dict)
    length: Optional[int] = None  # STRING[n]
    writable: bool = True

    @classmethod
    def from_manifest(cls, v: dict, size: int = 0) -> "VarType":
        return cls(path=v["path"], kind=v["kind"], size=size or v.get("size") or 0,
                   type=v.get("type", "?"), base=v.get("base"),
                   range=tuple(v["range"]) if v.get("range") else None,
                   enum=dict(v.get("enum") or {}), length=v.get("length"),
                   writable=bool(v.get("writable", True)))

    def elementary(self) -> str:
        """The elementary type name, guessed from kind and size when the
        manifest does not say."""
        if self.base:
            return self.base.upper()
        k = self.kind
        if k == "i" or k == "e":
            return {1: "SINT", 2: "INT", 4: "DINT", 8: "LINT"}.get(self.size, "DINT")
        if k == "u":
            return {1: "USINT", 2: "UINT", 4: "UDINT", 8: "ULINT"}.get(self.size, "UDINT")
        if k == "f":
            return "LREAL" if self.size == 8 else "REAL"
        return _KIND_BASE.get(k) or "?"

    @property
    def shown(self) -> str:
        return self.type if self.type not in (None, "?") else self.elementary()


# ---------------------------------------------------------------------------
# parsing

_INT_RE = re.compile(r"^([+-]?)(?:(2|8|16)#)?([0-9A-Fa-f_]+)$")
_REAL_RE = re.compile(r"^[+-]?[0-9][0-9_]*(\.[0-9_]+)?([eE][+-]?[0-9]+)?$")
_TIME_PART = re.compile(r"(\d[\d_]*(?:\.\d+)?)(ms|us|ns|d|h|m|s)", re.IGNORECASE)


def _bad(var: VarType, text: str, why: str) -> UsageError:
    return UsageError(f"{var.path}: {why} (value {text!r}, type {var.shown})")


def _split_prefix(text: str) -> Tuple[Optional[str], str]:
    m = re.match(r"^([A-Za-z_][A-Za-z0-9_]*)#(.*)$", text, re.S)
    if m:
        return m.group(1), m.group(2)
    return None, text


def _parse_int(var: VarType, text: str, body: str) -> int:
    m = _INT_RE.match(body.strip())
    if not m or m.group(3).startswith("_") or m.group(3).endswith("_") or "__" in m.group(3):
        raise _bad(var, text, "not an integer literal")
    sign, base, digits = m.group(1), int(m.group(2) or 10), m.group(3).replace("_", "")
    if base != 10 and sign:
        raise _bad(var, text, "a based literal has no sign")
    try:
        v = int(digits, base)
    except ValueError:
        raise _bad(var, text, "not an integer literal") from None
    return -v if sign == "-" else v


def _parse_time(var: VarType, text: str, body: str) -> int:
    s = body.strip().replace("_", "")
    neg = s.startswith("-")
    if s[:1] in "+-":
        s = s[1:]
    pos, total, units = 0, 0, []
    for m in _TIME_PART.finditer(s):
        if m.start() != pos:
            break
        unit = m.group(2).lower()
        units.append(unit)
        total += int(float(m.group(1)) * NS[unit]) if "." in m.group(1) else \
            int(m.group(1)) * NS[unit]
        pos = m.end()
    if not units or pos != len(s):
        raise _bad(var, text, "not a duration (T#1h2m3s4ms5us6ns)")
    return -total if neg else total


def _parse_date(var: VarType, text: str, body: str) -> int:
    try:
        d = _dt.date.fromisoformat(body.strip())
    except ValueError:
        raise _bad(var, text, "not a date (D#YYYY-MM-DD)") from None
    return (d - _dt.date(1970, 1, 1)).days * NS["d"]


def _parse_tod(var: VarType, text: str, body: str) -> int:
    m = re.match(r"^(\d{1,2}):(\d{2}):(\d{2})(?:\.(\d{1,9}))?$", body.strip())
    if not m or int(m.group(1)) > 23 or int(m.group(2)) > 59 or int(m.group(3)) > 59:
        raise _bad(var, text, "not a time of day (TOD#HH:MM:SS.fff)")
    frac = (m.group(4) or "").ljust(9, "0")
    return ((int(m.group(1)) * 60 + int(m.group(2))) * 60 + int(m.group(3))) * NS["s"] + \
        int(frac or 0)


def _parse_dt(var: VarType, text: str, body: str) -> int:
    m = re.match(r"^(\d{4}-\d{2}-\d{2})-(.*)$", body.strip())
    if not m:
        raise _bad(var, text, "not a date and time (DT#YYYY-MM-DD-HH:MM:SS)")
    return _parse_date(var, text, m.group(1)) + _parse_tod(var, text, m.group(2))


_ESC = {"$": "$", "'": "'", '"': '"', "L": "\n", "N": "\n", "P": "\f", "R": "\r", "T": "\t"}


def _parse_string(var: VarType, text: str, wide: bool) -> str:
    q = '"' if wide else "'"
    t = text
    if not (len(t) >= 2 and t[0] == q and t[-1] == q):
        if t[:1] in "'\"":
            raise _bad(var, text, f"a {'WSTRING' if wide else 'STRING'} literal is quoted "
                                  f"with {q}")
        return t                                   # unquoted: the text itself
    body, out, i = t[1:-1], [], 0
    hexlen = 4 if wide else 2
    while i < len(body):
        c = body[i]
        if c == q:
            raise _bad(var, text, f"a {q} inside the literal must be written ${q}")
        if c != "$":
            out.append(c)
            i += 1
            continue
        nxt = body[i + 1:i + 2]
        if nxt.upper() in _ESC:
            out.append(_ESC[nxt.upper()])
            i += 2
        elif re.match(r"^[0-9A-Fa-f]{%d}$" % hexlen, body[i + 1:i + 1 + hexlen]):
            out.append(chr(int(body[i + 1:i + 1 + hexlen], 16)))
            i += 1 + hexlen
        else:
            raise _bad(var, text, "bad $ escape")
    return "".join(out)


def parse(var: VarType, text: str) -> Any:
    """The Python value of literal *text* for *var*, checked against its
    type; raises :class:`UsageError` with one clear line."""
    text = text.strip()
    if not text:
        raise _bad(var, text, "empty value")
    base = var.elementary()
    k = var.kind
    if k in "sw":
        s = _parse_string(var, text, k == "w")
        limit = var.length
        if limit is None and var.size:
            limit = (var.size - 2) // (2 if k == "w" else 1) - 1
        if limit is not None and len(s) > limit:
            raise _bad(var, text, f"string too long: {len(s)} characters, at most {limit}")
        if k == "s" and any(ord(c) > 255 for c in s):
            raise _bad(var, text, "a STRING holds characters 0..255 only")
        if k == "w" and any(ord(c) > 0xFFFF for c in s):
            raise _bad(var, text, "a WSTRING holds characters of the BMP only")
        return s
    prefix, body = _split_prefix(text)
    if k == "e":
        if prefix and prefix.upper() != var.type.upper():
            raise _bad(var, text, f"wrong type: {prefix}# is not {var.type}")
        names = {n.upper(): (n, v) for n, v in var.enum.items()}
        if not names:
            raise _bad(var, text, "the manifest lists no values for this enumeration "
                                  "(regenerate the project)")
        if body.strip().upper() not in names:
            raise _bad(var, text, "not a value of the enumeration: one of " +
                       ", ".join(var.enum))
        return names[body.strip().upper()][1]
    if k == "b":
        if prefix and prefix.upper() != "BOOL":
            raise _bad(var, text, f"wrong type: a {prefix} literal for a BOOL")
        b = body.strip().upper()
        if b in ("TRUE", "1"):
            return True
        if b in ("FALSE", "0"):
            return False
        raise _bad(var, text, "wrong type: a BOOL is TRUE or FALSE")
    if k in "iu":
        if prefix and prefix.upper() not in (base, var.type.upper()):
            raise _bad(var, text, f"wrong type: a {prefix} literal for {var.shown}")
        if body.strip().upper() in ("TRUE", "FALSE"):
            raise _bad(var, text, "wrong type: a BOOL literal for an integer")
        if _REAL_RE.match(body.strip()) and ("." in body or "e" in body.lower()):
            raise _bad(var, text, "wrong type: a REAL literal for an integer")
        v = _parse_int(var, text, body)
        signed, bits = INT_TYPES.get(base, (k == "i", var.size * 8 or 32))
        lo, hi = (-(1 << (bits - 1)), (1 << (bits - 1)) - 1) if signed else (0, (1 << bits) - 1)
        if var.range:
            lo, hi = var.range
        if not lo <= v <= hi:
            raise _bad(var, text, f"out of range {lo}..{hi}")
        return v
    if k == "f":
        if prefix and prefix.upper() not in ("REAL", "LREAL"):
            raise _bad(var, text, f"wrong type: a {prefix} literal for {var.shown}")
        b = body.strip().replace("_", "")
        if b.upper() in ("TRUE", "FALSE") or not _REAL_RE.match(b):
            raise _bad(var, text, "wrong type: not a number")
        v = float(b)
        if base == "REAL" and abs(v) > REAL_MAX:
            raise _bad(var, text, "out of range for REAL")
        if math.isinf(v):
            raise _bad(var, text, "out of range")
        return v
    if k == "t":
        want = TIME_TYPES.get(base, "time")
        got = TIME_PREFIX.get((prefix or "").upper())
        if got is None:
            raise _bad(var, text, {"time": "wrong type: a duration is written T#...",
                                   "date": "wrong type: a date is written D#YYYY-MM-DD",
                                   "tod": "wrong type: a time of day is written TOD#HH:MM:SS",
                                   "dt": "wrong type: a date and time is written "
                                         "DT#YYYY-MM-DD-HH:MM:SS"}[want])
        if got != want:
            raise _bad(var, text, f"wrong type: a {prefix}# literal for {var.shown}")
        v = {"time": _parse_time, "date": _parse_date, "tod": _parse_tod,
             "dt": _parse_dt}[want](var, text, body)
        if not -(1 << 63) <= v < (1 << 63):
            raise _bad(var, text, "out of range")
        return v
    raise _bad(var, text, f"cannot write variables of kind {k!r}")


# ---------------------------------------------------------------------------
# bytes

def _int_fmt(var: VarType) -> Tuple[int, bool]:
    size = var.size or {"b": 1, "t": 8}.get(var.kind, 4)
    signed = var.kind in "ite"
    if var.kind == "e" and var.base:
        signed = INT_TYPES.get(var.base.upper(), (True, 32))[0]
    return size, signed


def encode(var: VarType, value: Any) -> bytes:
    """The bytes the kernel stores for *value* (host order)."""
    k = var.kind
    if k == "b":
        return b"\x01" if value else b"\x00"
    if k == "f":
        return struct.pack("<d" if var.size == 8 else "<f", value)
    if k == "s":
        data = value.encode("latin-1")
        return struct.pack("<H", len(data)) + data + b"\x00"
    if k == "w":
        data = value.encode("utf-16-le")
        return struct.pack("<H", len(data) // 2) + data + b"\x00\x00"
    size, signed = _int_fmt(var)
    return int(value).to_bytes(size, "little", signed=signed)


def decode(var: VarType, data: bytes) -> Any:
    """The Python value of the kernel's bytes."""
    k = var.kind
    if data is None:
        return None
    if k == "b":
        return data[:1] != b"\x00"
    if k == "f":
        return struct.unpack("<d" if len(data) == 8 else "<f", data[:8 if len(data) == 8 else 4])[0]
    if k in "sw":
        if len(data) < 2:
            return ""
        n = int.from_bytes(data[:2], "little")
        if k == "s":
            return data[2:2 + n].decode("latin-1")
        return data[2:2 + 2 * n].decode("utf-16-le", "replace")
    size, signed = _int_fmt(var)
    return int.from_bytes(data[:size], "little", signed=signed)


# ---------------------------------------------------------------------------
# display

def _fmt_duration(ns: int, prefix: str = "T#") -> str:
    if ns == 0:
        return prefix + "0s"
    out = "-" if ns < 0 else ""
    ns = abs(ns)
    for unit in ("d", "h", "m", "s", "ms", "us", "ns"):
        q, ns = divmod(ns, NS[unit])
        if q:
            out += f"{q}{unit}"
    return prefix + out


def _fmt_tod(ns: int) -> str:
    s, frac = divmod(ns % NS["d"], NS["s"])
    h, rem = divmod(s, 3600)
    m, s = divmod(rem, 60)
    text = f"{h:02d}:{m:02d}:{s:02d}"
    if frac:
        text += "." + f"{frac:09d}".rstrip("0")
    return text


def _fmt_date(ns: int) -> str:
    return (_dt.date(1970, 1, 1) + _dt.timedelta(days=ns // NS["d"])).isoformat()


def _quote(s: str, wide: bool) -> str:
    q = '"' if wide else "'"
    out = []
    for c in s:
        if c == "$":
            out.append("$$")
        elif c == q:
            out.append("$" + q)
        elif c == "\n":
            out.append("$N")
        elif c == "\t":
            out.append("$T")
        elif c == "\r":
            out.append("$R")
        elif c == "\f":
            out.append("$P")
        elif ord(c) < 32 or (not wide and ord(c) > 126):
            out.append("$%02X" % ord(c) if not wide else "$%04X" % ord(c))
        else:
            out.append(c)
    return q + "".join(out) + q


def text(var: VarType, value: Any) -> str:
    """*value* as an IEC literal (what ``read`` prints)."""
    if value is None:
        return "?"
    k = var.kind
    base = var.elementary()
    if k == "b":
        return "TRUE" if value else "FALSE"
    if k == "e":
        for n, v in var.enum.items():
            if v == value:
                return n
        return f"{var.shown}#{value}?"
    if k == "f":
        if math.isnan(value) or math.isinf(value):
            return repr(value)
        r = "%.7g" % value if var.size != 8 else repr(value)
        if not re.search(r"[.eEn]", r):
            r += ".0"
        return r
    if k == "s":
        return _quote(value, False)
    if k == "w":
        return _quote(value, True)
    if k == "t":
        kind = TIME_TYPES.get(base, "time")
        if kind == "date":
            return "D#" + _fmt_date(value)
        if kind == "tod":
            return "TOD#" + _fmt_tod(value)
        if kind == "dt":
            return "DT#" + _fmt_date(value) + "-" + _fmt_tod(value)
        return _fmt_duration(value, "LTIME#" if base == "LTIME" else "T#")
    if base in BIT_TYPES:
        return "16#%X" % value
    return str(value)


def json_value(var: VarType, value: Any) -> Any:
    """*value* for JSON: numbers and booleans as such, time types in ns,
    enumerations by name, strings as text."""
    if var.kind == "e":
        for n, v in var.enum.items():
            if v == value:
                return n
    return value
