# SPDX-License-Identifier: MIT
"""Reference model of the IEC 61131-3 string functions as the runtime
documents them (1-based positions, results truncated to the destination
capacity).  Works on any Python sequence (bytes for STRING, tuples of code
units for WSTRING).  Written from the standard's definitions, not from the
C code."""


def _clamp(v, lo, hi):
    return max(lo, min(v, hi))


def left(s, n):
    return s[:_clamp(n, 0, len(s))]


def right(s, n):
    k = _clamp(n, 0, len(s))
    return s[len(s) - k:]


def mid(s, n, p):
    if p < 1 or p > len(s):
        return s[:0]
    return s[p - 1:p - 1 + max(n, 0)]


def concat(a, b):
    return a + b


def insert(a, b, p):
    k = _clamp(p, 0, len(a))
    return a[:k] + b + a[k:]


def delete(s, n, p):
    if p < 1 or p > len(s):
        return s
    return s[:p - 1] + s[p - 1 + max(n, 0):]


def replace(a, b, n, p):
    start = _clamp(p - 1, 0, len(a))
    k = _clamp(n, 0, len(a) - start)
    return a[:start] + b + a[start + k:]


def find(a, b):
    if len(b) == 0 or len(b) > len(a):
        return 0
    for i in range(len(a) - len(b) + 1):
        if a[i:i + len(b)] == b:
            return i + 1
    return 0


def cmp(a, b):
    return (a > b) - (a < b)


def truncate(s, cap):
    return s[:cap]


# TIME/DATE formatting as the runtime documents it.
_DAY = 86400 * 10**9
_UNITS = [(_DAY, "d"), (3600 * 10**9, "h"), (60 * 10**9, "m"), (10**9, "s"),
          (10**6, "ms"), (10**3, "us"), (1, "ns")]


def time_to_string(ns, prefix="T#"):
    out = prefix + ("-" if ns < 0 else "")
    mag = abs(ns)
    if mag == 0:
        return out + "0s"
    for unit, name in _UNITS:
        q, mag = divmod(mag, unit)
        if q:
            out += f"{q}{name}"
    return out


def _civil(days):
    import datetime
    d = datetime.date(1970, 1, 1) + datetime.timedelta(days=days)
    return d.year, d.month, d.day


def _hms(ns):
    ns %= _DAY
    secs, frac = divmod(ns, 10**9)
    s = f"{secs // 3600:02d}:{secs // 60 % 60:02d}:{secs % 60:02d}"
    if frac:
        s += "." + f"{frac:09d}".rstrip("0")
    return s


def date_to_string(ns, prefix="D#"):
    y, m, d = _civil(ns // _DAY)
    return f"{prefix}{y:04d}-{m:02d}-{d:02d}"


def tod_to_string(ns, prefix="TOD#"):
    return prefix + _hms(ns)


def dt_to_string(ns, prefix="DT#"):
    return date_to_string(ns, prefix) + "-" + _hms(ns)
