# SPDX-License-Identifier: MIT
"""What `plc-manager serve` publishes, built from the running build's
manifest alone (its variables, tasks, access paths and the addresses of
named located variables): no kernel and no network here, so the
address and type mappings are unit-tested on the host.

Modbus (OpenPLC's mapping, so its HMIs work unchanged; OpenPLC
webserver/core/modbus.cpp, MIN_16B_RANGE 1024, MIN_32B_RANGE 2048,
MIN_64B_RANGE 4096):

  =================  =====================  ================================
  located variable   Modbus table           address
  =================  =====================  ================================
  %IXa.b             discrete inputs (FC2)  8*a + b
  %QXa.b             coils (FC1/5/15)       8*a + b
  %IWn               input registers (FC4)  n
  %QWn               holding registers      n            (0..1023)
  %MWn               holding registers      1024 + n     (1024..2047)
  %MDn               holding registers      2048 + 2n    (2 registers)
  %MLn               holding registers      4096 + 4n    (4 registers)
  access path k      holding registers      8192 + ...   (declaration order,
                                                          1/2/4 registers, a string more)
  BOOL access path   coils                  8192 + k-th BOOL path
  =================  =====================  ================================

Multi-register values are big-endian, most significant word first (as
OpenPLC stores %MD/%ML); REAL/LREAL are IEEE 754 in 2/4 registers; a
16-bit register holds the two's complement of INT/SINT.  A STRING[n]
access path takes 1 + ceil(n/2) registers: its current length, then two
characters (Latin-1) a register, the first in the high byte, zeros after
the end; a WSTRING[n] 1 + n: its length, then one UTF-16 unit a register.
A write of a length over the capacity is exception 03.
"""

from __future__ import annotations

import datetime as _dt
import math
import re
import struct
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Sequence, Tuple

from .. import values
from ..errors import UsageError
from ..values import VarType

MW_BASE, MD_BASE, ML_BASE, ACCESS_BASE = 1024, 2048, 4096, 8192
MAX_ADDRESS = 65535

_ADDR = re.compile(r"^%([IQM])([XBWDL]?)(\d+)(?:\.(\d+))?$", re.IGNORECASE)


class Refused(Exception):
    """A value a client may not write.  *why*: "range" (out of the type's
    range, a subrange, an enumeration, a string's capacity), "type" (a
    value of another type), "access" (read-only), "address" (nothing
    there)."""

    def __init__(self, why: str, text: str) -> None:
        super().__init__(text)
        self.why = why


# ---------------------------------------------------------------------------
# registers

def registers_of(var: VarType) -> int:
    """How many 16-bit registers *var* takes on Modbus (0: not on Modbus).
    STRING[n]: 1 + ceil(n/2) (its length, then two characters a register);
    WSTRING[n]: 1 + n (its length, then one UTF-16 unit a register)."""
    if var.kind in "sw":
        if var.length is None:
            return 0
        return 1 + (var.length if var.kind == "w" else (var.length + 1) // 2)
    if var.kind == "b":
        return 1
    size = var.size or (8 if var.kind == "t" else 4)
    return max(1, size // 2)


def to_registers(var: VarType, value) -> List[int]:
    """The registers of *value* (most significant word first)."""
    n = registers_of(var)
    if var.kind == "b":
        return [1 if value else 0]
    if var.kind == "s":
        raw = value.encode("latin-1", "replace")
        raw += b"\0" * (2 * (n - 1) - len(raw))
        return [len(value)] + [raw[i] << 8 | raw[i + 1] for i in range(0, 2 * (n - 1), 2)]
    if var.kind == "w":
        units = value.encode("utf-16-be")
        regs = [int.from_bytes(units[i:i + 2], "big") for i in range(0, len(units), 2)]
        return [len(regs)] + regs + [0] * (n - 1 - len(regs))
    if var.kind == "f":
        raw = struct.pack(">d" if n == 4 else ">f", value)
        return [int.from_bytes(raw[i:i + 2], "big") for i in range(0, len(raw), 2)]
    bits = 16 * n
    v = int(value) & ((1 << bits) - 1)
    if var.size == 1:                       # SINT/USINT/BYTE: one register, sign-extended
        v = int(value) & 0xFFFF
    return [(v >> (16 * (n - 1 - i))) & 0xFFFF for i in range(n)]


def from_registers(var: VarType, regs: Sequence[int]):
    """The value of registers written by a client, checked against the
    variable's type (raises :class:`Refused`)."""
    n = registers_of(var)
    if len(regs) != n or any(not 0 <= r <= 0xFFFF for r in regs):
        raise Refused("range", f"{var.path}: {n} register(s) expected")
    if var.kind == "b":
        if regs[0] not in (0, 1):
            raise Refused("range", f"{var.path}: a BOOL register is 0 or 1")
        return bool(regs[0])
    if var.kind in "sw":
        length = regs[0]
        if length > var.length:
            raise Refused("range", f"{var.path}: length {length} is over the capacity "
                                   f"{var.length}")
        if var.kind == "s":
            raw = b"".join(r.to_bytes(2, "big") for r in regs[1:])[:length]
            return check(var, raw.decode("latin-1"))
        raw = b"".join(r.to_bytes(2, "big") for r in regs[1:1 + length])
        try:
            return check(var, raw.decode("utf-16-be"))
        except UnicodeDecodeError:
            raise Refused("range", f"{var.path}: not UTF-16") from None
    raw = b"".join(r.to_bytes(2, "big") for r in regs)
    if var.kind == "f":
        v = struct.unpack(">d" if n == 4 else ">f", raw)[0]
        if math.isnan(v) or math.isinf(v):
            raise Refused("range", f"{var.path}: not a finite number")
        return v
    u = int.from_bytes(raw, "big")
    size, signed = values._int_fmt(var)
    bits = 8 * size
    if size == 1:
        # one register for an 8-bit value: the 16-bit two's complement
        # (signed) or the plain number (unsigned) must fit the type
        s = u - 0x10000 if (signed and u & 0x8000) else u
    else:
        s = u - (1 << bits) if (signed and u >> (bits - 1)) else u
    return s


# ---------------------------------------------------------------------------
# value checks (the manager's literal checks: the same rules as `write`)

def check(var: VarType, value):
    """*value* (a Python value from a client) checked for *var* with the
    rules of ``plc-manager write`` (range, subrange, enumeration, string
    capacity); returns the value the kernel gets, raises :class:`Refused`."""
    k = var.kind
    if k == "b":
        if not isinstance(value, (bool, int)) or (not isinstance(value, bool) and
                                                  value not in (0, 1)):
            raise Refused("type", f"{var.path}: a BOOL is TRUE or FALSE")
        return bool(value)
    if k in "iue":
        if isinstance(value, bool) or not isinstance(value, int):
            raise Refused("type", f"{var.path}: an integer is expected for {var.shown}")
        text = str(value)
        if k == "e":
            names = [n for n, v in var.enum.items() if v == value]
            if not names:
                raise Refused("range", f"{var.path}: {value} is not a value of {var.shown}")
            text = names[0]
    elif k == "f":
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise Refused("type", f"{var.path}: a number is expected for {var.shown}")
        if math.isnan(value) or math.isinf(value):
            raise Refused("range", f"{var.path}: not a finite number")
        text = repr(float(value))
    elif k == "t":
        if isinstance(value, bool) or not isinstance(value, int):
            raise Refused("type", f"{var.path}: a time in ns is expected for {var.shown}")
        text = values.text(var, value)
    elif k in "sw":
        if not isinstance(value, str):
            raise Refused("type", f"{var.path}: a string is expected for {var.shown}")
        text = values._quote(value, k == "w")
    else:
        raise Refused("type", f"{var.path}: variables of kind {k!r} are not written")
    try:
        return values.parse(var, text)
    except values.UsageError as e:
        raise Refused("range", str(e)) from None


# ---------------------------------------------------------------------------
# OPC UA types

UA_INT = {("i", 1): "SByte", ("i", 2): "Int16", ("i", 4): "Int32", ("i", 8): "Int64",
          ("u", 1): "Byte", ("u", 2): "UInt16", ("u", 4): "UInt32", ("u", 8): "UInt64"}
EPOCH = _dt.datetime(1970, 1, 1)


def ua_type(var: VarType) -> str:
    """The OPC UA built-in type (asyncua VariantType name) of *var*:
    BOOL Boolean; SINT..LINT SByte..Int64; USINT..ULINT, BYTE..LWORD
    Byte..UInt64; REAL Float; LREAL Double; TIME/LTIME/TOD Duration (ms,
    a Double); DATE/DT DateTime; STRING/WSTRING String; an enumeration
    Int32 (its variables' DataType is an enumeration type: opcua.py)."""
    k = var.kind
    if k == "b":
        return "Boolean"
    if k == "e":
        return "Int32"
    if k in "iu":
        return UA_INT.get((k, var.size or 4), "Int64" if k == "i" else "UInt64")
    if k == "f":
        return "Double" if var.size == 8 else "Float"
    if k == "t":
        kind = values.TIME_TYPES.get(var.elementary(), "time")
        return "DateTime" if kind in ("date", "dt") else "Duration"
    if k in "sw":
        return "String"
    return "ByteString"


def to_ua(var: VarType, value):
    """The kernel's value as the OPC UA type's Python value."""
    if var.kind == "t":
        if ua_type(var) == "DateTime":
            return EPOCH + _dt.timedelta(microseconds=value // 1000)
        return value / 1e6
    if var.kind == "f" and var.size != 8:
        return float(value)
    return value


def from_ua(var: VarType, value):
    """A value an OPC UA client wrote, as the kernel's value, checked
    (raises :class:`Refused`)."""
    if var.kind == "t":
        if ua_type(var) == "DateTime":
            if not isinstance(value, _dt.datetime):
                raise Refused("type", f"{var.path}: a DateTime is expected")
            if value.tzinfo is not None:
                value = value.astimezone(_dt.timezone.utc).replace(tzinfo=None)
            d = value - EPOCH
            ns = (d.days * 86400 + d.seconds) * 10**9 + d.microseconds * 1000
        else:
            if isinstance(value, bool) or not isinstance(value, (int, float)) or \
                    math.isnan(value) or math.isinf(value):
                raise Refused("type", f"{var.path}: a Duration (ms) is expected")
            ns = round(value * 1e6)
        return check(var, ns)
    if var.kind == "f" and isinstance(value, int) and not isinstance(value, bool):
        value = float(value)
    return check(var, value)


# ---------------------------------------------------------------------------
# the model

@dataclass
class AccessPath:
    name: str
    path: str            # the variable's path in the manifest
    read_write: bool


@dataclass
class Task:
    resource: str
    name: str
    interval_ns: Optional[int]
    programs: List[str]


@dataclass
class Model:
    configuration: str
    interface_hash: str
    source_hash: str
    variables: Dict[str, VarType]           # lower path -> type
    order: List[str]                        # paths in manifest order
    resources: List[str]
    tasks: List[Task]
    instances: Dict[str, dict]              # lower path -> manifest instance
    access: List[AccessPath] = field(default_factory=list)
    located: Dict[str, str] = field(default_factory=dict)   # %MW100 -> path
    generator: str = ""
    programs: List[str] = field(default_factory=list)      # "TYPE build-id", loaded

    @classmethod
    def from_manifest(cls, m: dict) -> "Model":
        """The model of a manifest: its variables, tasks, the access paths
        ("access": VAR_ACCESS, an aggregate's path gives one access path
        per member, NAME.member) and the addresses of named located
        variables ("addresses")."""
        if "access" not in m:
            raise UsageError("the build's manifest has no access paths (made by an iec2kmod "
                             "older than plc-manager serve): build the project again")
        vs: Dict[str, VarType] = {}
        order = []
        for v in m["variables"]:
            t = VarType.from_manifest(v)
            if not t.size and t.kind in "sw" and t.length is not None:
                t.size = (t.length + 2) * (2 if t.kind == "w" else 1) + 2 - \
                    (0 if t.kind == "w" else 1)
            vs[t.path.lower()] = t
            order.append(t.path)
        tasks = [Task(r["name"], t["name"], t.get("interval_ns"), list(t.get("programs", [])))
                 for r in m.get("resources", []) for t in r.get("tasks", [])]
        loc = {}
        for v in m["variables"]:
            if v.get("owner") == "direct":
                loc[v["path"].upper()] = v["path"]
        for addr, path in m.get("addresses", {}).items():
            if path.lower() in vs:
                loc.setdefault(addr.upper(), vs[path.lower()].path)
        acc = []
        for a in m["access"]:
            rw = a["access"] == "READ_WRITE"
            p = a["path"].lower()
            if p in vs:
                acc.append(AccessPath(name=a["name"], path=vs[p].path, read_write=rw))
                continue
            for q in order:
                if q.lower().startswith((p + ".", p + "[")):
                    acc.append(AccessPath(name=a["name"] + q[len(p):], path=q,
                                          read_write=rw))
        return cls(configuration=m["configuration"], interface_hash=m.get("interface_hash", ""),
                   source_hash=m.get("source_hash", ""), variables=vs, order=order,
                   resources=[r["name"] for r in m.get("resources", [])], tasks=tasks,
                   instances={i["path"].lower(): i for i in m.get("instances", [])},
                   access=acc, located=loc, generator=m.get("generator", ""),
                   programs=[f"{p['name']} {p.get('build_id', '')}"
                             for p in m.get("program_types", [])])

    def var(self, path: str) -> VarType:
        return self.variables[path.lower()]

    def fastest_interval_ns(self) -> Optional[int]:
        ivs = [t.interval_ns for t in self.tasks if t.interval_ns]
        return min(ivs) if ivs else None

    def access_of(self, path: str) -> Optional[AccessPath]:
        for a in self.access:
            if a.path.lower() == path.lower():
                return a
        return None

    def client_writable(self, path: str, writable_all: bool) -> bool:
        """What a client may write: an access path READ_WRITE (when the
        project declares access paths, only those); without access paths,
        nothing unless *writable_all* (then what the kernel lets write)."""
        t = self.var(path)
        if not t.writable:
            return False
        a = self.access_of(path)
        if a is not None:
            return a.read_write
        return writable_all and not self.access


# ---------------------------------------------------------------------------
# Modbus map

@dataclass
class Cell:
    """One coil/discrete input, or one register of a variable."""
    path: str
    word: int = 0        # which register of the variable (0: most significant)
    writable: bool = False


@dataclass
class ModbusMap:
    coils: Dict[int, Cell] = field(default_factory=dict)
    discrete: Dict[int, Cell] = field(default_factory=dict)
    inputs: Dict[int, Cell] = field(default_factory=dict)
    holding: Dict[int, Cell] = field(default_factory=dict)
    skipped: List[str] = field(default_factory=list)   # why a variable is not mapped

    def table(self, name: str) -> Dict[int, Cell]:
        return {"co": self.coils, "di": self.discrete, "ir": self.inputs,
                "hr": self.holding}[name]


def parse_address(addr: str) -> Optional[Tuple[str, str, int, Optional[int]]]:
    """'%QX1.3' -> ('Q', 'X', 1, 3); '%MW10' -> ('M', 'W', 10, None);
    None when it is no simple direct address."""
    m = _ADDR.match(addr.strip())
    if not m:
        return None
    area, size = m.group(1).upper(), (m.group(2) or "X").upper()
    return area, size, int(m.group(3)), int(m.group(4)) if m.group(4) is not None else None


def openplc_cell(addr: str) -> Optional[Tuple[str, int, int]]:
    """OpenPLC's place of a located variable: (table, first address,
    registers), or None when OpenPLC has no place for it."""
    p = parse_address(addr)
    if p is None:
        return None
    area, size, n, bit = p
    if size == "X":
        if bit is None or bit > 7 or area == "M":
            return None
        return ({"I": "di", "Q": "co"}[area], 8 * n + bit, 1)
    if bit is not None:
        return None
    if area == "I" and size == "W":
        return ("ir", n, 1)
    if area == "Q" and size == "W" and n < MW_BASE:
        return ("hr", n, 1)
    if area == "M" and size == "W" and n < MD_BASE - MW_BASE:
        return ("hr", MW_BASE + n, 1)
    if area == "M" and size == "D" and MD_BASE + 2 * n + 1 < ML_BASE:
        return ("hr", MD_BASE + 2 * n, 2)
    if area == "M" and size == "L" and ML_BASE + 4 * n + 3 < ACCESS_BASE:
        return ("hr", ML_BASE + 4 * n, 4)
    return None


def modbus_map(model: Model, writable_all: bool = False) -> ModbusMap:
    """The Modbus tables of *model*: OpenPLC's mapping of the located
    variables, then the access paths from register (and coil) 8192.

    What a client may write: a coil or holding register whose variable
    the kernel lets write and, when the project declares access paths,
    that is a READ_WRITE access path or a memory variable (%M) -- OpenPLC's
    HMIs write %QX coils and %MW registers; without access paths every
    kernel-writable located variable."""
    mm = ModbusMap()
    for addr, path in sorted(model.located.items()):
        t = model.var(path)
        place = openplc_cell(addr)
        if place is None:
            mm.skipped.append(f"{addr} ({path}): no place in OpenPLC's Modbus map")
            continue
        table, first, n = place
        if registers_of(t) != n and table in ("hr", "ir"):
            mm.skipped.append(f"{addr} ({path}): {t.shown} does not fit {n} register(s)")
            continue
        if table in ("co", "di") and t.kind != "b":
            mm.skipped.append(f"{addr} ({path}): not a BOOL")
            continue
        acc = model.access_of(path)
        w = t.writable and table in ("co", "hr") and (
            acc.read_write if acc is not None else
            (writable_all or not model.access or addr.upper().startswith("%M")))
        for i in range(n):
            mm.table(table)[first + i] = Cell(path=t.path, word=i, writable=w)
    reg, coil = ACCESS_BASE, ACCESS_BASE
    for a in model.access:
        t = model.var(a.path)
        n = registers_of(t)
        if n == 0:
            mm.skipped.append(f"access path {a.name} ({t.shown}): no capacity known")
            continue
        w = a.read_write and t.writable
        for i in range(n):
            mm.holding[reg + i] = Cell(path=t.path, word=i, writable=w)
        reg += n
        if t.kind == "b":
            mm.coils[coil] = Cell(path=t.path, word=0, writable=w)
            coil += 1
    return mm


# ---------------------------------------------------------------------------
# the address space tree

def split_path(path: str) -> List[str]:
    """'plc.line1.run_latch.S1' -> ['plc', 'line1', 'run_latch', 'S1'];
    'recipes[1].steps[2].kind' -> ['recipes', '[1]', 'steps', '[2]',
    'kind'] (an array is a folder of its elements)."""
    out: List[str] = []
    for part in path.split("."):
        m = re.match(r"^([^\[]+)((?:\[[^\]]*\])*)$", part)
        if not m:
            out.append(part)
            continue
        out.append(m.group(1))
        out += re.findall(r"\[[^\]]*\]", m.group(2))
    return out


def placement(model: Model, path: str) -> Tuple[List[str], List[str]]:
    """Where a variable goes in the address space: (the folders from the
    configuration node, the remaining name parts).  Configuration globals
    under Globals; a resource's globals under <resource>/Globals; a
    program instance's variables under <resource>/<task>/<instance>;
    direct variables under DirectVariables."""
    if path.startswith("%"):
        return ["DirectVariables"], [path]
    parts = split_path(path)
    res = {r.lower(): r for r in model.resources}
    if len(parts) >= 3 and parts[0].lower() in res:
        inst = model.instances.get(f"{parts[0]}.{parts[1]}".lower())
        if inst is not None:
            return [res[parts[0].lower()], inst.get("task") or "Programs",
                    parts[1]], parts[2:]
    if len(parts) >= 2 and parts[0].lower() in res:
        return [res[parts[0].lower()], "Globals"], parts[1:]
    return ["Globals"], parts


def array_groups(model: Model) -> Dict[str, List[str]]:
    """The one-dimensional arrays of elementary elements (``tab[1]``,
    ``tab[2]``, ... leaves of the same type, integer indexes): array
    path -> its elements' paths in index order.  OPC UA shows each as one
    array variable (ValueRank 1, ArrayDimensions [n]); arrays of
    structures, of function blocks and of several dimensions stay folders
    of their elements."""
    groups: Dict[str, List[Tuple[int, str]]] = {}
    kinds: Dict[str, set] = {}
    for p in model.order:
        m = re.match(r"^(.*[^\]])\[(-?\d+)\]$", p)
        if not m or p.startswith("%"):
            continue
        groups.setdefault(m.group(1), []).append((int(m.group(2)), p))
        t = model.var(p)
        kinds.setdefault(m.group(1), set()).add((t.kind, t.size, t.base, t.length))
    return {a: [p for _, p in sorted(els)] for a, els in groups.items()
            if len(kinds[a]) == 1 and a.lower() not in model.variables}
