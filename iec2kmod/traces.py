"""Traces: what a run reads and writes, for both engines of `iec2kmod sim`
(the generated C and the reference interpreter) and the verifier's
counterexamples.

    watch_indexes   the table indexes of ``--watch`` names (default: the globals)
    read_trace      an ``--inputs`` CSV (time,variable,value) into events
    write_inputs    such a CSV (a counterexample's inputs)
    input_literal   a value as such a CSV writes it
    Trace           a run: the watched values' changes, faults, cycles
    write_csv       a Trace as CSV (one row per instant with a change)
    write_vcd       a Trace as VCD (GTKWave)

A trace names variables by their path in the variable table (the
manager's: codegen.plan.TableEntry, or the interpreter's Entry: both have
path, type, kind, size and writable)."""

from __future__ import annotations

import csv
from dataclasses import dataclass, field

from . import __version__
from .checks.types import Elementary, EnumT, SubrangeT, concrete
from .parse.literals import LiteralError, classify, parse_duration
from .located import name_index


class TraceError(Exception):
    """A bad trace or value (the engines report it as a usage error)."""


@dataclass
class Trace:
    """One run of a configuration, as both engines report it."""
    names: list                      # watched IEC paths
    changes: list                    # (t_ns, index into names, value)
    faults: list = field(default_factory=list)   # (t_ns, task, fault, pou, file, line)
    cycles: dict = field(default_factory=dict)   # task -> cycles run
    selective: dict = field(default_factory=dict)  # task -> (blocks evaluated, skipped)
    end_ns: int = 0
    stderr: str = ""                             # the simulator's stderr (sanitizer reports)

    def values_at(self, t_ns=None):
        """Last value of every watched variable at time t (default: the end)."""
        out = {}
        for t, i, v in self.changes:
            if t_ns is not None and t > t_ns:
                break
            out[self.names[i]] = v
        return out


# ------------------------------------------------------------ reading
def parse_time(text: str) -> int:
    """T#1.5s, TIME#100ms, 250ms, 1.5s, or a number of seconds."""
    s = text.strip()
    try:
        if "#" in s:
            kind, value, _ = classify(s)
            if kind != "time":
                raise ValueError
            return value
        for unit in ("ms", "us", "ns", "s", "m", "h", "d"):
            if s.lower().endswith(unit) and s[:-len(unit)].replace(".", "", 1).isdigit():
                return parse_duration(s)
        return round(float(s) * 1e9)
    except (LiteralError, ValueError):
        raise TraceError(f"'{text}' is not a time (write T#100ms, 100ms or 0.1)") from None


def value_for(entry, text: str):
    """(kind, value) of an IEC literal for a variable of the table: kind
    'f' (a float, for a REAL entry) or 'i' (an integer)."""
    s = text.strip()
    try:
        t = concrete(entry.type)
        if isinstance(t, EnumT):
            name = s.split("#")[-1].upper()
            if name not in t.values:
                raise ValueError(f"'{s}' is not a value of {t.name}")
            return "i", t.values[name][1]
        sign = 1
        if s[:1] in "+-" and "#" not in s:
            sign, s = (-1 if s[0] == "-" else 1), s[1:].strip()
        kind, value, _ = classify(s)
        if sign < 0 and kind in ("int", "real"):
            value = -value
    except (LiteralError, ValueError, IndexError) as exc:
        raise TraceError(f"invalid value '{text}' for {entry.path}: {exc}") from None
    if entry.kind == "f":
        if kind not in ("int", "real"):
            raise TraceError(f"{entry.path} is REAL: '{text}' is not a number")
        return "f", float(value)
    if entry.kind in ("s", "w"):
        raise TraceError(f"{entry.path}: string inputs are not supported by the simulator")
    if kind == "bool" or (entry.kind == "b" and kind == "int" and value in (0, 1)):
        return "i", int(value)
    if kind in ("int", "time", "date", "tod", "dt"):
        if entry.kind == "b":
            raise TraceError(f"{entry.path} is BOOL: '{text}' is not TRUE/FALSE")
        rng = _int_range(entry.type) if kind == "int" else None
        if rng is not None and not rng[0] <= int(value) <= rng[1]:
            # as plc-manager write refuses it: never wrapped silently
            raise TraceError(f"invalid value '{text}' for {entry.path}: out of range "
                             f"{rng[0]}..{rng[1]}")
        return "i", int(value)
    raise TraceError(f"invalid value '{text}' for {entry.path}")


def _int_range(t):
    """(low, high) of an integer, bit string or subrange type; None otherwise."""
    t = concrete(t)
    if isinstance(t, SubrangeT):
        return t.low, t.high
    return t.range if isinstance(t, Elementary) else None


def watch_indexes(table, addresses, watch) -> list[int]:
    """Indexes into *table* of the names in *watch* (paths or, for a located
    variable, its address; *addresses* as for read_trace), each once and in
    the order given; every global and directly represented variable when
    *watch* is empty.  An unknown name raises TraceError."""
    if not watch:
        return [i for i, e in enumerate(table) if e.owner in ("global", "direct")]
    index = name_index(table, addresses)
    idx = []
    for w in watch:
        i = index.get(w.strip().upper())
        if i is None:
            raise TraceError(f"unknown variable '{w}' (see `iec2kmod sim --list`)")
        if i not in idx:         # an address and its name are one variable
            idx.append(i)
    return idx


def read_trace(path: str, table, addresses=None):
    """Input events of a CSV trace (time,variable,value; header and
    ``#`` comment lines optional; a located variable may be named by its
    address, *addresses* mapping address -> path), sorted by time then line:
    [(t_ns, line, table index, kind, value)]."""
    index = name_index(table, addresses)
    events = []
    try:
        with open(path, newline="") as fh:
            for n, row in enumerate(csv.reader(fh), 1):
                if not row or row[0].strip().startswith("#"):
                    continue
                if n == 1 and row[0].strip().lower() == "time":
                    continue
                if len(row) != 3:
                    raise TraceError(f"{path}:{n}: expected time,variable,value")
                i = index.get(row[1].strip().upper())
                if i is None:
                    raise TraceError(f"{path}:{n}: unknown variable '{row[1].strip()}'")
                e = table[i]
                if not e.writable:
                    raise TraceError(f"{path}:{n}: '{e.path}' cannot be written")
                try:
                    kind, value = value_for(e, row[2])
                    t = parse_time(row[0])
                except TraceError as exc:
                    raise TraceError(f"{path}:{n}: {exc}") from None
                events.append((t, n, i, kind, value))
    except OSError as exc:
        raise TraceError(f"{path}: {exc.strerror}") from None
    events.sort(key=lambda ev: (ev[0], ev[1]))
    return events


# ------------------------------------------------------------ writing
def write_inputs(path, rows) -> int:
    """An ``--inputs`` CSV of *rows* (time, variable, value text); the
    number of rows.  csv quoting: an element of a multi-dimensional array
    is 'a[0,5]'."""
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(("time", "variable", "value"))
        w.writerows(rows)
    return len(rows)


def input_literal(t, v) -> str:
    """Value *v* of a variable of type *t* as an ``--inputs`` CSV reads it
    back (a counterexample's inputs, both verify engines): an enumeration's
    ``T#NAME``, ``TRUE``/``FALSE``, a REAL with its exponent as ``1.0E-05``."""
    t = concrete(t)
    if isinstance(t, EnumT):
        for name, val in t.values.values():
            if val == v:
                return f"{t.name}#{name}"
        return str(v)
    if isinstance(v, bool) or (isinstance(t, Elementary) and t.cat == "bool"):
        return "TRUE" if v else "FALSE"
    if isinstance(v, float) or (isinstance(t, Elementary) and t.cat == "real"):
        v = float(v)
        r = repr(v)
        if "e" in r:
            mant, exp = r.split("e")
            if "." not in mant:
                mant += ".0"
            r = f"{mant}E{exp}"
        return r
    return str(v)


def format_value(entry_type, v):
    if isinstance(v, bool):
        return "TRUE" if v else "FALSE"
    return str(v)


def write_csv(res: Trace, path):
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["time_ns"] + res.names)
        cur = [""] * len(res.names)
        i = 0
        ch = res.changes
        while i < len(ch):
            t = ch[i][0]
            while i < len(ch) and ch[i][0] == t:
                cur[ch[i][1]] = format_value(None, ch[i][2])
                i += 1
            w.writerow([t] + cur)


def write_vcd(res: Trace, path, table=None):
    """*table*: the variable table the names are paths of (their kinds and
    sizes give the VCD types), or None (every value a 64-bit integer)."""
    ids = [_vcd_id(k) for k in range(len(res.names))]
    kinds = {}
    if table is not None:
        by_path = {e.path: e for e in table}
        kinds = {n: by_path[n] for n in res.names if n in by_path}
    with open(path, "w") as fh:
        fh.write(f"$date iec2kmod sim $end\n$version iec2kmod {__version__} $end\n"
                 "$timescale 1ns $end\n$scope module plc $end\n")
        for n, vid in zip(res.names, ids):
            e = kinds.get(n)
            if e is not None and e.kind == "b":
                fh.write(f"$var wire 1 {vid} {_vcd_name(n)} $end\n")
            elif e is not None and e.kind == "f":
                fh.write(f"$var real 64 {vid} {_vcd_name(n)} $end\n")
            elif e is not None and e.kind in ("s", "w"):
                fh.write(f"$var string 1 {vid} {_vcd_name(n)} $end\n")
            else:
                bits = e.size * 8 if e is not None else 64
                fh.write(f"$var integer {bits} {vid} {_vcd_name(n)} $end\n")
        fh.write("$upscope $end\n$enddefinitions $end\n")
        last_t = None
        for t, i, v in res.changes:
            if t != last_t:
                fh.write(f"#{t}\n")
                last_t = t
            e = kinds.get(res.names[i])
            if isinstance(v, bool):
                fh.write(f"{int(v)}{ids[i]}\n")
            elif isinstance(v, float):
                fh.write(f"r{v!r} {ids[i]}\n")
            elif isinstance(v, str) and (e is None or e.kind != "e"):
                fh.write(f"s{v.replace(' ', '_') or '_'} {ids[i]}\n")
            elif isinstance(v, str):
                fh.write(f"s{v} {ids[i]}\n")
            else:
                bits = e.size * 8 if e is not None else 64
                fh.write(f"b{v & ((1 << bits) - 1):b} {ids[i]}\n")
        fh.write(f"#{res.end_ns}\n")


def _vcd_id(k):
    chars = [chr(c) for c in range(33, 127)]
    out = ""
    k += 1
    while k:
        k, r = divmod(k - 1, len(chars))
        out = chars[r] + out
    return out


def _vcd_name(n):
    return n.replace("[", "(").replace("]", ")").replace(",", "_").replace("%", "")
