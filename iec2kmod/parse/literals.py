"""Classification of literal tokens (the grammar matches every literal as one
token).  Times are integer nanoseconds; dates are nanoseconds since
1970-01-01; strings are decoded Python strings."""

from __future__ import annotations

import re

NS = {"d": 86_400_000_000_000, "h": 3_600_000_000_000, "m": 60_000_000_000,
      "s": 1_000_000_000, "ms": 1_000_000, "us": 1_000, "ns": 1}

TIME_PREFIX = {"T": "TIME", "TIME": "TIME", "LT": "LTIME", "LTIME": "LTIME"}
DATE_PREFIX = {"D": "DATE", "DATE": "DATE", "LD": "LDATE", "LDATE": "LDATE"}
TOD_PREFIX = {"TOD": "TOD", "TIME_OF_DAY": "TOD", "LTOD": "LTOD", "LTIME_OF_DAY": "LTOD"}
DT_PREFIX = {"DT": "DT", "DATE_AND_TIME": "DT", "LDT": "LDT", "LDATE_AND_TIME": "LDT"}

_DUR_PART = re.compile(r"([0-9][0-9_]*(?:\.[0-9_]+)?)(d|h|ms|m|s|us|ns)_?", re.I)
_DATE = re.compile(r"([0-9]+)-([0-9]+)-([0-9]+)$")
_TOD = re.compile(r"([0-9]+):([0-9]+):([0-9]+)(?:\.([0-9]+))?$")
_DT = re.compile(r"([0-9]+)-([0-9]+)-([0-9]+)-([0-9]+):([0-9]+):([0-9]+)(?:\.([0-9]+))?$")

_ESCAPES = {"$": "$", "'": "'", '"': '"', "L": "\n", "N": "\n", "P": "\f",
            "R": "\r", "T": "\t"}


class LiteralError(ValueError):
    """The literal is malformed (the message says why)."""


def days_from_civil(y: int, m: int, d: int) -> int:
    """Days since 1970-01-01 of a proleptic Gregorian date."""
    y -= m <= 2
    era = (y if y >= 0 else y - 399) // 400
    yoe = y - era * 400
    doy = (153 * (m + (-3 if m > 2 else 9)) + 2) // 5 + d - 1
    doe = yoe * 365 + yoe // 4 - yoe // 100 + doy
    return era * 146097 + doe - 719468


def _check_date(y, m, d):
    if not 1 <= m <= 12:
        raise LiteralError(f"month {m} out of range 1..12")
    mdays = [31, 29 if (y % 4 == 0 and y % 100 != 0) or y % 400 == 0 else 28,
             31, 30, 31, 30, 31, 31, 30, 31, 30, 31][m - 1]
    if not 1 <= d <= mdays:
        raise LiteralError(f"day {d} out of range 1..{mdays}")


def _tod_ns(h, mi, s, frac):
    if h > 23 or mi > 59 or s > 59:
        raise LiteralError("time of day out of range 00:00:00..23:59:59")
    ns = ((h * 60 + mi) * 60 + s) * 1_000_000_000
    if frac:
        ns += int((frac + "000000000")[:9])
    return ns


def parse_duration(body: str) -> int:
    sign = 1
    if body[:1] in "+-":
        sign = -1 if body[0] == "-" else 1
        body = body[1:]
    total = 0.0
    exact = 0
    pos = 0
    for m in _DUR_PART.finditer(body):
        if m.start() != pos:
            raise LiteralError(f"malformed duration '{body}'")
        pos = m.end()
        num = m.group(1).replace("_", "")
        unit = NS[m.group(2).lower()]
        if "." in num:
            whole, frac = num.split(".")
            exact += int(whole) * unit
            total += float("0." + (frac or "0")) * unit
        else:
            exact += int(num) * unit
    if pos != len(body):
        raise LiteralError(f"malformed duration '{body}'")
    return sign * (exact + round(total))


def decode_string(body: str, wide: bool) -> str:
    out = []
    i = 0
    n = len(body)
    while i < n:
        c = body[i]
        if c != "$":
            out.append(c)
            i += 1
            continue
        if i + 1 >= n:
            raise LiteralError("'$' at the end of a string")
        e = body[i + 1]
        if e.upper() in _ESCAPES:
            out.append(_ESCAPES[e.upper()])
            i += 2
            continue
        width = 4 if wide else 2
        hexpart = body[i + 1:i + 1 + width]
        if len(hexpart) == width and all(h in "0123456789abcdefABCDEF" for h in hexpart):
            out.append(chr(int(hexpart, 16)))
            i += 1 + width
            continue
        raise LiteralError(f"invalid escape '${e}' in string")
    return "".join(out)


def _number(text: str):
    """(kind, value) of an untyped number: int or real, based or decimal."""
    t = text.replace("_", "")
    if "#" in t:
        base, digits = t.split("#", 1)
        neg = False
        if digits[:1] in "+-":
            neg = digits[0] == "-"
            digits = digits[1:]
        try:
            v = int(digits, int(base))
        except ValueError:
            raise LiteralError(f"invalid digits for base {base} in '{text}'") from None
        return "int", -v if neg else v
    if any(c in t for c in ".eE"):
        return "real", float(t)
    return "int", int(t)


def classify(text: str):
    """Returns (kind, value, type_name)."""
    upper = text.upper()
    if upper in ("TRUE", "FALSE"):
        return "bool", upper == "TRUE", None
    first = text[0]
    if first == "'":
        return "string", decode_string(text[1:-1], False), None
    if first == '"':
        return "wstring", decode_string(text[1:-1], True), None
    if first.isdigit():
        if upper.startswith(("2#", "8#", "16#")):
            return ("int",) + _number(text)[1:] + (None,)
        kind, value = _number(text)
        return kind, value, None
    prefix, body = text.split("#", 1)
    up = prefix.upper()
    if up in TIME_PREFIX:
        return "time", parse_duration(body), TIME_PREFIX[up]
    if up in DATE_PREFIX and _DATE.match(body):
        y, m, d = map(int, _DATE.match(body).groups())
        _check_date(y, m, d)
        return "date", days_from_civil(y, m, d) * 86_400_000_000_000, DATE_PREFIX[up]
    if up in TOD_PREFIX and _TOD.match(body):
        h, mi, s, frac = _TOD.match(body).groups()
        return "tod", _tod_ns(int(h), int(mi), int(s), frac), TOD_PREFIX[up]
    if up in DT_PREFIX and _DT.match(body):
        y, mo, d, h, mi, s, frac = _DT.match(body).groups()
        y, mo, d = int(y), int(mo), int(d)
        _check_date(y, mo, d)
        ns = days_from_civil(y, mo, d) * 86_400_000_000_000 + _tod_ns(int(h), int(mi), int(s), frac)
        return "dt", ns, DT_PREFIX[up]
    # typed literal: TYPE#value
    b0 = body[:1]
    if b0 == "'":
        return "string", decode_string(body[1:-1], False), up
    if b0 == '"':
        return "wstring", decode_string(body[1:-1], True), up
    if b0.isdigit() or b0 in "+-":
        sign = 1
        digits = body
        if b0 in "+-":
            sign = -1 if b0 == "-" else 1
            digits = body[1:]
        kind, value = _number(digits)
        return kind, sign * value, up
    if body.upper() in ("TRUE", "FALSE"):
        return "bool", body.upper() == "TRUE", up
    return "enum", body, prefix
