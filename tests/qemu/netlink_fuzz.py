# SPDX-License-Identifier: MIT
"""A structure-aware fuzzer of the ``iec2kmod`` generic netlink family
(issue 23, item 5), used by tests/qemu/test_netlink_fuzz.py (CI: 20,000
messages) and benchmarks/netlink_fuzz.py (any number).

How it runs, against a configuration loaded in a QEMU guest with its tasks
running:

1. in the guest (:data:`GUEST_PROBE`): the family's variables as the kernel
   lists them (path, table, index, kind, size, writable), the slots, the
   tasks' counters and every variable's value;
2. on the host (:class:`Fuzzer`, seeded: the same seed gives the same
   messages): N raw messages, written to one file in the shared work
   directory.  Each message is a random command (the family's and invalid
   numbers) with random attributes built from the protocol (iec_nl.h) and
   the variables: selectors by path or table+index, values of the right
   and wrong sizes, in and out of range, strings without their NUL, with
   bytes after it, over capacity, attributes of unknown types, wrong
   lengths, missing or extra nesting, too many variables, truncated,
   oversized and misaligned messages and attributes, random flags;
3. in the guest (:data:`GUEST_SENDER`): the messages go out on a raw
   NETLINK_GENERIC socket, one send each, the replies read in batches (no
   host round trip per message), every reply matched by sequence number;
4. the oracle: every message the generator made invalid in a way the
   kernel must refuse (the reason is recorded with it) must get an error;
   one that is acknowledged is a violation.  Messages whose outcome depends
   on the state (a write to a forced variable, the force limit, duplicates)
   are only counted.  Then (:func:`check_after`): every task still runs and
   has not faulted, its cycle count advances, every variable holds a value
   of its type (BOOL 0/1, subrange and enumeration in range, a string's
   length within its capacity and its NUL in place), CONSTANTs (``k_``
   names) are unchanged; the caller checks the kernel log and that
   ``plc-manager stop`` leaves no module.

Destructive commands are sent only in forms the kernel must refuse: a valid
RES_STOP or SLOT_CLEAR would stop the tasks the fuzzer needs running (a
stop or clear that gets through is a violation, and shows up as stopped
tasks).  RES_START in every form (starting a running task does nothing).
"""

from __future__ import annotations

import json
import random
import struct
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional, Tuple

# the protocol's numbers, from plc-manager's mirror of iec_nl.h (a unit test
# compares that with the header)
from plc_manager.netlink import ATTRIBUTES, CMD, MAX_VARS, VALUE_MAX  # noqa: E402

_A = {name: i for i, (name, _t) in enumerate(ATTRIBUTES)}
CMD_STATUS, CMD_VAR_GET, CMD_VAR_LIST, CMD_VAR_SET, CMD_VAR_FORCE, CMD_VAR_UNFORCE, \
    CMD_RES_START, CMD_RES_STOP, CMD_SLOT_CLEAR, CMD_SLOT_PUBLISH, CMD_SLOT_UNSTAGE = (
        CMD[f"IEC_CMD_{n}"] for n in ("STATUS", "VAR_GET", "VAR_LIST", "VAR_SET", "VAR_FORCE",
                                      "VAR_UNFORCE", "RES_START", "RES_STOP", "SLOT_CLEAR",
                                      "SLOT_PUBLISH", "SLOT_UNSTAGE"))
N_CMDS = len(CMD)
A_NAME, A_SLOT_INDEX = _A["IEC_A_NAME"], _A["IEC_A_SLOT_INDEX"]
A_VAR, A_PATH, A_TABLE, A_INDEX = (_A[f"IEC_A_{n}"] for n in ("VAR", "PATH", "TABLE", "INDEX"))
A_VALUE, A_ALL, A_SLOTS_ONLY = _A["IEC_A_VALUE"], _A["IEC_A_ALL"], _A["IEC_A_SLOTS_ONLY"]
A_MAX = len(ATTRIBUTES) - 1
NAME_MAX, PATH_MAX, TABLE_MAX = 63, 511, 63      # policy .len (without the NUL)

NLA_F_NESTED = 1 << 15
NLM_F_REQUEST, NLM_F_MULTI, NLM_F_ACK, NLM_F_ECHO = 1, 2, 4, 8
NLM_F_ROOT, NLM_F_MATCH = 0x100, 0x200
NLM_F_DUMP = NLM_F_ROOT | NLM_F_MATCH

# attributes each command takes (top level)
TAKES = {
    CMD_STATUS: {A_SLOTS_ONLY}, CMD_VAR_GET: {A_VAR}, CMD_VAR_LIST: set(),
    CMD_VAR_SET: {A_VAR}, CMD_VAR_FORCE: {A_VAR}, CMD_VAR_UNFORCE: {A_VAR, A_ALL},
    CMD_RES_START: {A_NAME}, CMD_RES_STOP: {A_NAME}, CMD_SLOT_CLEAR: {A_SLOT_INDEX},
    CMD_SLOT_PUBLISH: {A_SLOT_INDEX}, CMD_SLOT_UNSTAGE: {A_SLOT_INDEX},
}

# one record of the message file: payload length, flags, reason index
REC = struct.Struct("<IHH")
F_MUST_REFUSE = 1      # the kernel must answer with an error
F_DUMP = 2             # a dump: read its replies to the end at once
F_NO_REPLY = 4         # the kernel drops it silently (header cut, length beyond the data)


def _pad(b: bytes) -> bytes:
    return b + b"\0" * (-len(b) % 4)


def nla(atype: int, payload: bytes, *, flags: int = 0, length: Optional[int] = None,
        pad: bool = True) -> bytes:
    """One attribute; *length* overrides nla_len, *pad* False leaves it
    unaligned (the next attribute then starts at a misaligned offset)."""
    n = 4 + len(payload) if length is None else length
    b = struct.pack("<HH", n & 0xFFFF, (atype | flags) & 0xFFFF) + payload
    return _pad(b) if pad else b


@dataclass
class Var:
    path: str
    table: str
    index: int
    kind: str
    size: int
    writable: bool
    base: Optional[str] = None
    range: Optional[Tuple[int, int]] = None
    enum: List[int] = field(default_factory=list)
    length: Optional[int] = None
    constant: bool = False


def variables(listed: List[dict], manifest: dict) -> List[Var]:
    """The kernel's variable list joined with the manifest's types."""
    types = {v["path"].lower(): v for v in manifest["variables"]}
    out = []
    for k in listed:
        t = types.get(k["path"].lower(), {})
        out.append(Var(path=k["path"], table=k["table"], index=k["index"], kind=k["kind"],
                       size=k["size"], writable=k["writable"], base=t.get("base"),
                       range=tuple(t["range"]) if t.get("range") else None,
                       enum=sorted((t.get("enum") or {}).values()), length=t.get("length"),
                       constant=k["path"].split(".")[-1].lower().startswith("k_")))
    return out


INT_LIMITS = {("i", 1): (-2**7, 2**7 - 1), ("i", 2): (-2**15, 2**15 - 1),
              ("i", 4): (-2**31, 2**31 - 1), ("i", 8): (-2**63, 2**63 - 1),
              ("u", 1): (0, 2**8 - 1), ("u", 2): (0, 2**16 - 1),
              ("u", 4): (0, 2**32 - 1), ("u", 8): (0, 2**64 - 1),
              ("t", 8): (-2**63, 2**63 - 1), ("e", 4): (-2**31, 2**31 - 1),
              ("e", 2): (-2**15, 2**15 - 1), ("e", 1): (-2**7, 2**7 - 1)}


def _int_bytes(v: int, size: int, signed: bool) -> bytes:
    return v.to_bytes(size, "little", signed=signed)


def value_problem(var: Var, data: bytes) -> Optional[str]:
    """Why *data* (the kernel's bytes of *var*) is not a value of its type,
    or None."""
    k = var.kind
    if k in "sw":
        cs = 2 if k == "w" else 1
        if len(data) < 2 + cs:
            return f"{len(data)} bytes"
        n = int.from_bytes(data[:2], "little")
        cap = var.length
        if cap is not None and n > cap:
            return f"length {n} over its capacity {cap}"
        end = 2 + n * cs
        if end + cs > len(data):
            return f"length {n} beyond the object ({len(data)} bytes)"
        if any(data[end:end + cs]):
            return f"no NUL after its {n} characters"
        return None
    if len(data) != var.size:
        return f"{len(data)} bytes, the variable has {var.size}"
    if k == "b":
        return None if data[0] in (0, 1) else f"BOOL byte {data[0]}"
    if k in "iute":
        v = int.from_bytes(data, "little", signed=(k != "u"))
        if var.range and not var.range[0] <= v <= var.range[1]:
            return f"{v} outside its subrange {var.range[0]}..{var.range[1]}"
        if k == "e" and var.enum and v not in var.enum:
            return f"{v} not one of its enumeration's values {var.enum}"
    return None


class Fuzzer:
    """Seeded generator of raw messages (nlmsghdr + genlmsghdr + attributes;
    nlmsg_type and nlmsg_seq are filled in by the sender)."""

    def __init__(self, seed: int, vars_: List[Var], resources: List[str], tasks: List[str],
                 nslots: int) -> None:
        self.rnd = random.Random(seed)
        self.vars = vars_
        self.writable = [v for v in vars_ if v.writable]
        self.readonly = [v for v in vars_ if not v.writable]
        self.paths = {v.path.lower() for v in vars_}
        self.resources = resources
        self.tasks = tasks          # "res.task"
        self.nslots = nslots
        self.reasons: List[str] = ["(valid)"]
        self._reason_ix: Dict[str, int] = {"(valid)": 0}

    # ---------------------------------------------------------------- values
    def _valid_value(self, v: Var) -> bytes:
        r = self.rnd
        k = v.kind
        if k in "sw":
            cs = 2 if k == "w" else 1
            cap = v.length if v.length is not None else max(0, (v.size - 2) // cs - 1)
            n = r.choice([0, cap, r.randint(0, cap)])
            chars = [r.randint(0x20, 0x7E) for _ in range(n)]
            body = b"".join(c.to_bytes(cs, "little") for c in chars)
            return struct.pack("<H", n) + body + b"\0" * cs
        if k == "b":
            return bytes([r.randint(0, 1)])
        if k == "f":
            if v.size == 4:
                return struct.pack("<f", r.choice([0.0, 1.5, -2.25, r.uniform(-1e6, 1e6)]))
            return struct.pack("<d", r.choice([0.0, 1e300, -3.5, r.uniform(-1e9, 1e9)]))
        if v.range:
            return _int_bytes(r.randint(*v.range), v.size, True)
        if k == "e" and v.enum:
            return _int_bytes(r.choice(v.enum), v.size, True)
        lo, hi = INT_LIMITS.get((k, v.size), (0, 2**(8 * v.size) - 1))
        x = r.choice([lo, hi, 0, r.randint(lo, hi)])
        return _int_bytes(x, v.size, k != "u" and lo < 0)

    def _bad_value(self, v: Var, big_ok: bool) -> Tuple[bytes, str]:
        """A VALUE the kernel must refuse for *v*, and why."""
        r = self.rnd
        k = v.kind
        good = self._valid_value(v)
        choices = ["size"]
        if k == "b":
            choices.append("bool")
        if v.range:
            choices.append("subrange")
        if k == "e" and v.enum:
            choices.append("enum")
        if k in "sw":
            choices += ["over_capacity", "no_nul", "after_nul", "length_field"] * 2
        if big_ok and r.random() < 0.2:
            choices.append("oversized")
        what = r.choice(choices)
        if what == "size":
            n = len(good)
            bad = r.choice([0, 1, n - 1, n + 1, n + 4, 2 * n + 3] if n > 1 else [0, 2, 3, 8])
            bad = max(0, bad) if bad != n else n + 1
            if k in "sw":      # a string of the wrong size: length field says otherwise
                return (good + b"\x01" * (bad - n) if bad > n else good[:bad]), "value: size"
            return bytes(r.randint(0, 255) for _ in range(bad)), "value: size"
        if what == "bool":
            return bytes([r.randint(2, 255)]), "value: BOOL not 0/1"
        if what == "subrange":
            lo, hi = v.range
            tlo, thi = INT_LIMITS[("i", v.size)]
            x = r.choice([hi + 1, lo - 1, r.randint(hi + 1, thi), r.randint(tlo, lo - 1)])
            x = min(max(x, tlo), thi)
            if lo <= x <= hi:
                x = hi + 1
            return _int_bytes(x, v.size, True), "value: subrange out of range"
        if what == "enum":
            tlo, thi = INT_LIMITS[("i", v.size)]
            x = r.choice([max(v.enum) + 1, min(v.enum) - 1, 99, r.randint(tlo, thi)])
            while x in v.enum:
                x += 7
            return _int_bytes(x, v.size, True), "value: enumeration value not in the type"
        if what == "oversized":
            return b"\x41" * (VALUE_MAX + r.randint(1, 20)), "value: over VALUE_MAX"
        cs = 2 if k == "w" else 1
        cap = v.length if v.length is not None else max(0, (v.size - 2) // cs - 1)
        if what == "over_capacity":
            n = cap + r.choice([1, 1, 1, 2, 5, 100])
            body = b"".join(r.randint(0x41, 0x5A).to_bytes(cs, "little") for _ in range(n))
            return struct.pack("<H", n) + body + b"\0" * cs, "value: string over its capacity"
        n = r.randint(0, cap)
        body = b"".join(r.randint(0x41, 0x5A).to_bytes(cs, "little") for _ in range(n))
        if what == "no_nul":
            # the length field and the size agree, the last character is not NUL
            return struct.pack("<H", n) + body + b"Z" * cs, "value: string without its NUL"
        if what == "after_nul":
            return (struct.pack("<H", n) + body + b"\0" * cs + b"junk"[:r.randint(1, 4)] * cs,
                    "value: string with bytes after its NUL")
        m = n + r.choice([1, 2, -1] if n else [1, 2])
        return struct.pack("<H", m & 0xFFFF) + body + b"\0" * cs, "value: length field"

    # ------------------------------------------------------------- selectors
    @staticmethod
    def _str(s: str) -> bytes:
        return s.encode() + b"\0"

    def _case(self, s: str) -> str:
        r = self.rnd.random()
        return s.upper() if r < 0.2 else (s.swapcase() if r < 0.3 else s)

    def _selector(self, v: Var, bad: bool) -> Tuple[bytes, Optional[str]]:
        """Attributes naming *v* inside a VAR nest, or (*bad*) naming
        nothing or naming it wrongly; (bytes, must-refuse reason)."""
        r = self.rnd
        if not bad:
            x = r.random()
            if x < 0.65:
                return nla(A_PATH, self._str(self._case(v.path))), None
            if x < 0.9:
                return (nla(A_TABLE, self._str(self._case(v.table))) +
                        nla(A_INDEX, struct.pack("<I", v.index))), None
            return (nla(A_TABLE, self._str(v.table)) + nla(A_INDEX, struct.pack("<I", v.index)) +
                    nla(A_PATH, self._str(v.path))), None
        bad = r.choice(["nosuch", "nosuch", "after_nul", "no_nul", "long", "table", "index", "disagree",
                        "index_size", "empty", "unknown_attr", "prefix", "path_empty"])
        if bad == "prefix" and v.path[:-1].lower() not in self.paths and len(v.path) > 1:
            return nla(A_PATH, self._str(v.path[:-1])), "selector: no such variable (a prefix)"
        if bad in ("nosuch", "prefix"):
            p = v.path + r.choice(["x", ".y", "[9]", "_"])
            while p.lower() in self.paths:
                p += "x"
            return nla(A_PATH, self._str(p)), "selector: no such variable"
        if bad == "after_nul":
            junk = bytes(r.randint(1, 255) for _ in range(r.randint(1, 12)))
            return nla(A_PATH, self._str(v.path) + junk + b"\0"), \
                "selector: PATH with bytes after its NUL"
        if bad == "no_nul":
            return nla(A_PATH, v.path.encode()), "selector: PATH without NUL"
        if bad == "long":
            return nla(A_PATH, self._str("p" * r.randint(PATH_MAX + 1, PATH_MAX + 300))), \
                "selector: PATH over its policy length"
        if bad == "table":
            return (nla(A_TABLE, self._str("nosuch")) +
                    nla(A_INDEX, struct.pack("<I", 0))), "selector: no such table"
        if bad == "index":
            n = sum(1 for w in self.vars if w.table == v.table)
            return (nla(A_TABLE, self._str(v.table)) +
                    nla(A_INDEX, struct.pack("<I", r.choice([n, n + 1, 2**32 - 1])))), \
                "selector: index out of range"
        if bad == "disagree":
            others = [w for w in self.vars if w.table == v.table and w.path.lower() != v.path.lower()]
            if not others:
                return nla(A_PATH, self._str("")), "selector: empty PATH"
            return (nla(A_TABLE, self._str(v.table)) + nla(A_INDEX, struct.pack("<I", v.index)) +
                    nla(A_PATH, self._str(r.choice(others).path))), \
                "selector: index and path disagree"
        if bad == "index_size":
            return (nla(A_TABLE, self._str(v.table)) +
                    nla(A_INDEX, struct.pack("<Q", v.index)[:r.choice([0, 1, 2, 3, 8])])), \
                "selector: INDEX of the wrong size"
        if bad == "empty":
            return b"", "selector: empty VAR nest"
        if bad == "unknown_attr":
            t = r.choice([0, 1, A_NAME, A_SLOT_INDEX, A_ALL, A_MAX + 1, A_MAX + r.randint(2, 200),
                          0x3FFF])
            return nla(A_PATH, self._str(v.path)) + nla(t, b"\x01\0\0\0"), \
                "selector: an attribute the nest does not take"
        return nla(A_PATH, b"\0"), "selector: empty PATH"

    def _var_nest(self, with_value: bool, bad: bool, big_ok: bool,
                  used: set) -> Tuple[bytes, Optional[str]]:
        """One VAR nest; *bad*: one thing in it the kernel must refuse."""
        r = self.rnd
        what = None
        if bad:
            opts = ["selector"] * 4
            if with_value:
                opts += ["value"] * 5 + ["missing"] + (["readonly"] if self.readonly else [])
            else:
                opts += ["extra_value"]
            what = r.choice(opts)
        pool = (self.writable if with_value and what != "readonly" else
                self.readonly if what == "readonly" else self.vars)
        fresh = [w for w in pool if w.path not in used]
        v = r.choice(fresh or pool)
        used.add(v.path)
        sel, why = self._selector(v, what == "selector")
        body = sel
        if with_value and what != "missing":
            if what == "value":
                val, why = self._bad_value(v, big_ok)
            else:
                val = self._valid_value(v)
            body += nla(A_VALUE, val)
        elif what == "missing":
            why = "value: missing"
        if what == "readonly":
            why = "write/force of a read-only variable"
        if what == "extra_value":
            body += nla(A_VALUE, self._valid_value(v))
            why = "value in a request that takes none"
        flags = NLA_F_NESTED
        if not bad and big_ok and r.random() < 0.03:
            flags = 0
            why = "(any) VAR nest without NLA_F_NESTED"
        return nla(A_VAR, body, flags=flags), why

    def _vars(self, cmd: int) -> Tuple[bytes, Optional[str]]:
        """VAR nests: all valid, or exactly one of them invalid (the whole
        request must then be refused, nothing written)."""
        r = self.rnd
        with_value = cmd in (CMD_VAR_SET, CMD_VAR_FORCE)
        x = r.random()
        if x < 0.6:
            n = 1
        elif x < 0.88:
            n = r.randint(2, 8)
        elif x < 0.97:
            n = r.randint(9, MAX_VARS)
        elif x < 0.99:
            n = MAX_VARS + r.randint(1, 20)
        else:
            return b"", "no variable named"
        bad_at = r.randrange(n) if r.random() < 0.4 else -1
        parts, why, used = [], None, set()
        for i in range(n):
            b, w = self._var_nest(with_value, i == bad_at, n == 1, used)
            parts.append(b)
            if w and (why is None or (why.startswith("(") and not w.startswith("("))):
                why = w
        if n > MAX_VARS and (why is None or why.startswith("(")):
            why = "more than 256 variables"
        if len(used) < n and why is None:
            # more variables than the configuration has: some twice (the
            # kernel refuses or merges duplicates)
            why = "(any) a variable named twice"
        return b"".join(parts), why

    # -------------------------------------------------------------- commands
    def _bad_name(self) -> Tuple[bytes, str]:
        r = self.rnd
        res = r.choice(self.resources)
        x = r.choice(["nosuch", "after_nul", "no_nul", "long", "empty", "task_stop", "task_nosuch"])
        if x == "nosuch":
            return nla(A_NAME, self._str(res + "x")), "name: no such resource"
        if x == "after_nul":
            return nla(A_NAME, self._str(r.choice([res, "all"])) + b"junk\0"), \
                "name: NAME with bytes after its NUL"
        if x == "no_nul":
            return nla(A_NAME, b"nosuch"), "name: NAME without NUL"
        if x == "long":
            return nla(A_NAME, self._str("r" * (NAME_MAX + 1 + r.randint(0, 50)))), \
                "name: NAME over its policy length"
        if x == "empty":
            return nla(A_NAME, b"\0"), "name: empty NAME"
        if x == "task_nosuch":
            return nla(A_NAME, self._str(res + ".nosuch")), "name: no such task"
        return nla(A_NAME, self._str(r.choice(self.tasks))), "name: a stop names a task"

    def _junk_attrs(self, cmd: int) -> Tuple[bytes, str]:
        """Random top-level attributes, at least one the command does not take."""
        r = self.rnd
        takes = TAKES.get(cmd, set())
        out = []
        for _ in range(r.randint(0, 3)):
            t = r.randint(0, A_MAX + 8)
            out.append(nla(t, bytes(r.randint(0, 255) for _ in range(r.choice([0, 1, 2, 4, 8, 13])))))
        t = r.choice([t for t in range(A_MAX + 10) if t not in takes] + [0x7FFF, 0x1234])
        out.insert(r.randint(0, len(out)), nla(t, struct.pack("<I", r.getrandbits(32))))
        return b"".join(out), "an attribute the command does not take"

    def _command(self) -> Tuple[int, bytes, Optional[str], bool]:
        """(cmd, attributes, must-refuse reason, dump)."""
        r = self.rnd
        x = r.random()
        if x < 0.28:
            cmd = CMD_VAR_SET
        elif x < 0.40:
            cmd = CMD_VAR_FORCE
        elif x < 0.58:
            cmd = CMD_VAR_GET
        elif x < 0.65:
            cmd = CMD_VAR_UNFORCE
        elif x < 0.72:
            cmd = CMD_STATUS
        elif x < 0.725:
            cmd = CMD_VAR_LIST
        elif x < 0.77:
            cmd = CMD_RES_START
        elif x < 0.81:
            cmd = CMD_RES_STOP
        elif x < 0.85:
            cmd = CMD_SLOT_CLEAR
        elif x < 0.87:
            cmd = CMD_SLOT_PUBLISH
        elif x < 0.89:
            cmd = CMD_SLOT_UNSTAGE
        elif x < 0.93:
            c = r.choice([0, N_CMDS, N_CMDS + 1, r.randint(N_CMDS, 255)])
            attrs, _ = self._junk_attrs(CMD_STATUS) if r.random() < 0.5 else (b"", None)
            return c, attrs, "command: no such command", False
        else:
            cmd = r.randint(1, N_CMDS - 1)
            attrs, why = self._junk_attrs(cmd)
            if cmd == CMD_VAR_LIST:     # how strictly a dump's request is parsed: not asserted
                why = "(any) dump request with attributes"
            return cmd, attrs, why, cmd == CMD_VAR_LIST
        if cmd in (CMD_VAR_GET, CMD_VAR_SET, CMD_VAR_FORCE):
            attrs, why = self._vars(cmd)
            return cmd, attrs, why, False
        if cmd == CMD_VAR_UNFORCE:
            y = r.random()
            if y < 0.15:
                return cmd, nla(A_ALL, b""), None, False
            if y < 0.2:
                return cmd, nla(A_ALL, b"\x01\0\0\0"), "flag: ALL with a payload", False
            attrs, why = self._vars(cmd)
            return cmd, attrs, why, False
        if cmd == CMD_STATUS:
            y = r.random()
            if y < 0.5:
                return cmd, b"", None, False
            if y < 0.9:
                return cmd, nla(A_SLOTS_ONLY, b""), None, False
            return cmd, nla(A_SLOTS_ONLY, b"\0\0\0\0"), "flag: SLOTS_ONLY with a payload", False
        if cmd == CMD_VAR_LIST:
            return cmd, b"", None, True
        if cmd == CMD_RES_START:
            y = r.random()
            if y < 0.4:
                name = r.choice(self.resources + self.tasks + ["all"])
                return cmd, (nla(A_NAME, self._str(self._case(name))) if r.random() < 0.8
                             else b""), None, False
            attrs, why = self._bad_name()
            if why == "name: a stop names a task":
                return cmd, attrs, None, False      # a start of one task: valid
            return cmd, attrs, why, False
        if cmd == CMD_RES_STOP:
            attrs, why = self._bad_name()
            return cmd, attrs, why, False
        # slot commands
        y = r.random()
        if y < 0.5:
            attrs, why = nla(A_SLOT_INDEX, struct.pack(
                "<I", r.choice([self.nslots, self.nslots + 1, 2**31, 2**32 - 1]))), \
                "slot: no such slot"
        elif y < 0.8:
            attrs, why = nla(A_SLOT_INDEX, struct.pack("<Q", 0)[:r.choice([0, 1, 2, 3, 8])]), \
                "slot: SLOT_INDEX of the wrong size"
        else:
            attrs, why = self._junk_attrs(cmd)
        if cmd == CMD_SLOT_PUBLISH and y >= 0.8 and r.random() < 0.3:
            # nothing is ever staged here: a publication of nothing
            return cmd, b"", "slot: nothing staged", False
        return cmd, attrs, why, False

    # --------------------------------------------------------------- framing
    def message(self) -> Tuple[bytes, int, str]:
        """One message: (bytes, F_* flags, reason)."""
        r = self.rnd
        cmd, attrs, why, dump = self._command()
        flags = NLM_F_REQUEST | NLM_F_ACK
        rflags = 0
        if dump:
            flags |= NLM_F_DUMP
            rflags |= F_DUMP
        elif r.random() < 0.03:
            flags |= NLM_F_DUMP                        # a dump of a command that has none
            why = why or "flags: dump of a command without one"
            rflags |= F_DUMP
        elif r.random() < 0.05:
            flags |= r.choice([NLM_F_ECHO, NLM_F_MULTI, 0x800, 0x1000, NLM_F_ROOT])
            why = why or "(any) unusual nlmsg flags"
        version = 1 if r.random() < 0.9 else r.randint(0, 255)
        reserved = 0
        if r.random() < 0.05:
            reserved = r.randint(1, 0xFFFF)
            why = why or "(any) genlmsghdr reserved field set"
        genl = struct.pack("<BBH", cmd & 0xFF, version, reserved)
        body = genl + attrs
        x = r.random()
        if x < 0.03 and attrs:
            # cut inside a top-level attribute (never at a boundary: that
            # would be a shorter, valid message)
            spans, off = [], 4
            while off + 4 <= len(body):
                n = struct.unpack_from("<H", body, off)[0]
                if n > 4:
                    spans.append((off + 1, min(off + n, len(body)) - 1))
                off += max(4, (n + 3) & ~3)
            lo, hi = r.choice(spans) if spans else (5, 5)
            body = body[:r.randint(lo, max(lo, hi))]
            why = why or "framing: message cut inside an attribute"
        elif x < 0.05:
            body = body[:r.randint(0, 3)]
            why = why or "framing: shorter than the generic netlink header"
        elif x < 0.07:
            body = body + bytes(r.randint(1, 255) for _ in range(r.randint(1, 3)))
            why = why or "framing: misaligned, bytes after the attributes"
        elif x < 0.09 and attrs:
            # the first attribute claims more than the message holds
            n = struct.unpack_from("<H", body, 4)[0]
            body = body[:4] + struct.pack("<H", min(0xFFFF, len(body) + r.randint(1, 64))) + \
                body[6:]
            why = why or "framing: attribute longer than the message"
        elif x < 0.10 and attrs:
            body = body[:4] + struct.pack("<H", r.randint(0, 3)) + body[6:]
            why = why or "framing: attribute length under its header"
        total = 16 + len(body)
        nl_len = total
        if r.random() < 0.01:
            nl_len = total + r.randint(1, 400)            # beyond the data: dropped
            rflags |= F_NO_REPLY
            why = "(dropped) nlmsg_len beyond the data"
        hdr = struct.pack("<IHHII", nl_len, 0, flags, 0, 0)
        msg = hdr + body
        if r.random() < 0.005:
            msg = msg[:r.randint(0, 15)]                  # not even a header: dropped
            rflags |= F_NO_REPLY
            why = "(dropped) shorter than a netlink header"
        if rflags & F_NO_REPLY:
            rflags &= ~F_DUMP
        if why and not why.startswith("(") and not rflags & F_NO_REPLY:
            rflags |= F_MUST_REFUSE
        reason = why or "(valid)"
        return msg, rflags, reason

    def reason_index(self, reason: str) -> int:
        if reason not in self._reason_ix:
            self._reason_ix[reason] = len(self.reasons)
            self.reasons.append(reason)
        return self._reason_ix[reason]

    def write(self, path: Path, count: int) -> Dict[str, int]:
        """*count* messages into *path*; returns how many per reason."""
        tally: Dict[str, int] = {}
        with open(path, "wb") as f:
            for _ in range(count):
                msg, fl, reason = self.message()
                tally[reason] = tally.get(reason, 0) + 1
                f.write(REC.pack(len(msg), fl, self.reason_index(reason)) + msg)
        return tally


# ----------------------------------------------------------------- the guest
GUEST_PROBE = r'''
import json, sys
from plc_manager.netlink import Client
with Client() as c:
    st = c.status()
    vs = c.var_list()
    vals = {}
    paths = [v.path for v in vs]
    for v in c.var_get(paths):
        vals[v.path] = v.value.hex()
print("PROBE " + json.dumps({
    "vars": [dict(path=v.path, table=v.table, index=v.index, kind=v.kind, size=v.size,
                  writable=v.writable, forced=v.forced) for v in vs],
    "values": vals,
    "resources": [r.name for r in st.resources],
    "tasks": {t.path: dict(state=t.state, cycles=t.cycles, faults=t.faults,
                           overruns=t.overruns, interval_ns=t.interval_ns)
              for t in st.tasks()},
    "nslots": len(st.slots), "forced": st.forced}))
'''

GUEST_SENDER = r'''
import errno, json, os, select, socket, struct, sys, time
path, batch = sys.argv[1], int(sys.argv[2])
data = open(path, "rb").read()
REC = struct.Struct("<IHH")
NETLINK_GENERIC, SOL_NETLINK = 16, 270
NETLINK_CAP_ACK = 10
s = socket.socket(socket.AF_NETLINK, socket.SOCK_RAW, NETLINK_GENERIC)
s.setsockopt(socket.SOL_SOCKET, 33, 32 << 20)          # SO_RCVBUFFORCE
s.setsockopt(SOL_NETLINK, NETLINK_CAP_ACK, 1)
s.bind((0, 0))

def family_id(name):
    attr = struct.pack("<HH", 4 + len(name) + 1, 2) + name + b"\0"
    attr += b"\0" * (-len(attr) % 4)
    body = struct.pack("<BBH", 3, 1, 0) + attr
    s.send(struct.pack("<IHHII", 16 + len(body), 16, 5, 1, 0) + body)
    reply = s.recv(65536)
    off = 20
    while off + 4 <= len(reply):
        n, t = struct.unpack_from("<HH", reply, off)
        if t == 1:
            return struct.unpack_from("<H", reply, off + 4)[0]
        off += (n + 3) & ~3
    raise SystemExit("family iec2kmod not found")

fam = family_id(b"iec2kmod")
err = {}             # seq -> errno (0: acknowledged)
replied = set()      # seq with a data reply
dumps_done = set()
enobufs = 0

def parse(buf):
    off = 0
    while off + 16 <= len(buf):
        n, t, fl, seq, pid = struct.unpack_from("<IHHII", buf, off)
        if n < 16:
            break
        if t == 2:
            e = struct.unpack_from("<i", buf, off + 16)[0]
            err[seq] = -e
            if seq in pending_dump:
                dumps_done.add(seq)
        elif t == 3:
            dumps_done.add(seq)
            err.setdefault(seq, 0)
        else:
            replied.add(seq)
        off += (n + 3) & ~3

rbuf = bytearray(1 << 20)
rview = memoryview(rbuf)

def drain(block_for=None, until=None):
    global enobufs
    deadline = time.monotonic() + (block_for or 0)
    while True:
        try:
            n = s.recv_into(rbuf, 0, socket.MSG_DONTWAIT)
            buf = rview[:n]
        except BlockingIOError:
            if until is not None and not until() and time.monotonic() < deadline:
                select.select([s], [], [], 0.05)
                continue
            return
        except OSError as e:
            if e.errno == errno.ENOBUFS:
                enobufs += 1
                continue
            raise
        parse(buf)

pending_dump = set()
cost = {}
slow = []
meta = []
off = 0
t0 = time.monotonic()
seq = 100
sent = 0
while off < len(data):
    n, fl, why = REC.unpack_from(data, off)
    off += REC.size
    msg = bytearray(data[off:off + n])
    off += n
    seq += 1
    if len(msg) >= 16:
        struct.pack_into("<H", msg, 4, fam)
        struct.pack_into("<I", msg, 8, seq)
    meta.append((seq, fl, why))
    cmd = msg[16] if len(msg) > 16 else -1
    ts = time.monotonic()
    try:
        s.send(msg)
    except OSError as e:
        err[seq] = e.errno      # refused at send (the kernel returned an error)
    sent += 1
    if fl & 2:
        pending_dump.add(seq)
        drain(block_for=10, until=lambda q=seq: q in dumps_done or q in err)
        pending_dump.discard(seq)
    elif sent % batch == 0:
        drain()
    dt = time.monotonic() - ts
    cost[cmd] = cost.get(cmd, 0.0) + dt
    if dt > 0.05:
        slow.append((round(dt, 3), sent - 1, why))
drain(block_for=2, until=lambda: all(m[0] in err for m in meta[-50:] if not m[1] & 4))
elapsed = time.monotonic() - t0
out = {"sent": sent, "seconds": elapsed, "enobufs": enobufs, "replies": len(replied),
       "outcomes": {}, "violations": [], "unanswered": 0,
       "slow": sorted(slow, reverse=True)[:10],
       "cost": {str(k): round(v, 2) for k, v in sorted(cost.items(), key=lambda kv: -kv[1])}}
for q, fl, why in meta:
    e = err.get(q)
    if e is None and not fl & 4:
        out["unanswered"] += 1
    key = "%d:%s" % (why, "none" if e is None else errno.errorcode.get(e, str(e)) if e else "ok")
    out["outcomes"][key] = out["outcomes"].get(key, 0) + 1
    smp = out.setdefault("samples", {}).setdefault(key, [])
    if len(smp) < 3:
        smp.append(q - 101)
    if fl & 1 and e == 0:
        out["violations"].append([q - 101, why])
print("SENT " + json.dumps(out))
'''


def describe(path: Path, index: int) -> str:
    """Message *index* of a message file, decoded (attributes as a tree)."""
    data = Path(path).read_bytes()
    off = 0
    for i in range(index + 1):
        n, fl, why = REC.unpack_from(data, off)
        off += REC.size
        msg = data[off:off + n]
        off += n

    def attrs(b: bytes, depth: int) -> List[str]:
        out, o = [], 0
        while o + 4 <= len(b):
            ln, t = struct.unpack_from("<HH", b, o)
            p = b[o + 4:o + max(ln, 4)]
            line = f"{'  ' * depth}type {t & 0x3FFF}{' N' if t & NLA_F_NESTED else ''} len {ln}"
            out.append(line + f" {p[:40]!r}")
            if t & NLA_F_NESTED:
                out += attrs(p, depth + 1)
            o += max(4, (ln + 3) & ~3)
        if o < len(b):
            out.append(f"{'  ' * depth}{len(b) - o} trailing bytes")
        return out
    head = struct.unpack_from("<IHHII", msg) if len(msg) >= 16 else msg
    gen = msg[16:20]
    return "\n".join([f"nlmsghdr {head} flags {fl} reason {why} genl {gen!r}"] +
                     attrs(msg[20:], 1))


def probe(guest) -> dict:
    r = guest.pyrun(GUEST_PROBE, timeout=300)
    assert r.exit_code == 0 and "PROBE " in r.output, r.output[-3000:]
    return json.loads(r.output.split("PROBE ", 1)[1])


@dataclass
class FuzzResult:
    seed: int
    count: int
    seconds: float
    sent: int
    violations: List[Tuple[int, str]]
    outcomes: Dict[str, int]
    unanswered: int
    enobufs: int
    by_reason: Dict[str, int]
    must_refuse: int
    samples: Dict[str, List[int]] = field(default_factory=dict)   # reason|outcome -> indices
    file: Optional[Path] = None          # the message file, kept if a message was accepted

    def summary(self) -> str:
        lines = [f"netlink fuzz: seed {self.seed}, {self.sent} messages in {self.seconds:.1f} s "
                 f"in the guest ({self.sent / max(self.seconds, 1e-9):.0f}/s); "
                 f"{self.must_refuse} must be refused; {len(self.violations)} accepted that "
                 f"must not be; {self.unanswered} unanswered; ENOBUFS {self.enobufs}"]
        agg: Dict[str, Dict[str, int]] = {}
        for k, n in self.outcomes.items():
            why, res = k.rsplit("|", 1)
            agg.setdefault(why, {})[res] = agg.setdefault(why, {}).get(res, 0) + n
        for why in sorted(agg, key=lambda w: -sum(agg[w].values())):
            lines.append(f"  {sum(agg[why].values()):6}  {why}: " +
                         ", ".join(f"{k} {v}" for k, v in sorted(agg[why].items(),
                                                                 key=lambda kv: -kv[1])))
        return "\n".join(lines)


def run(guest, workdir: Path, manifest: dict, seed: int, count: int,
        batch: int = 32, timeout: float = 1800) -> Tuple[FuzzResult, dict]:
    """Probe, generate *count* messages from *seed*, send them in the guest.
    Returns the result and the probe taken before."""
    before = probe(guest)
    vs = variables(before["vars"], manifest)
    fz = Fuzzer(seed, vs, before["resources"], list(before["tasks"]), before["nslots"])
    f = Path(workdir) / f"nlfuzz-{seed}.bin"
    by_reason = fz.write(f, count)
    r = guest.pyrun(GUEST_SENDER, argv=[str(f), str(batch)], timeout=timeout)
    assert r.exit_code == 0 and "SENT " in r.output, r.output[-3000:]
    sent = json.loads(r.output.split("SENT ", 1)[1])
    if not sent["violations"]:
        f.unlink()          # else kept: describe(f, index) decodes a message
    print(f"seconds per command number (send + reply): "
          f"{dict(list(sent['cost'].items())[:12])}; slowest messages: "
          f"{[(t, i, fz.reasons[w]) for t, i, w in sent['slow']]}")
    outcomes = {}
    for k, n in sent["outcomes"].items():
        why, res = k.split(":", 1)
        key = f"{fz.reasons[int(why)]}|{res}"
        outcomes[key] = outcomes.get(key, 0) + n
    must = sum(n for w, n in by_reason.items() if not w.startswith("("))
    samples = {}
    for k, idx in sent.get("samples", {}).items():
        why, res_ = k.split(":", 1)
        samples[f"{fz.reasons[int(why)]}|{res_}"] = idx
    res = FuzzResult(seed=seed, count=count, seconds=sent["seconds"], sent=sent["sent"],
                     violations=[(i, fz.reasons[w]) for i, w in sent["violations"]],
                     outcomes=outcomes, unanswered=sent["unanswered"], enobufs=sent["enobufs"],
                     by_reason=by_reason, must_refuse=must, samples=samples, file=f)
    return res, before


def check_after(guest, manifest: dict, before: dict, settle: float = 0.3) -> List[str]:
    """Unforce everything, then the invariants; returns the problems found."""
    import time
    r = guest.pyrun("from plc_manager.netlink import Client\n"
                    "with Client() as c:\n    c.var_unforce(everything=True)", timeout=120)
    problems = [] if r.exit_code == 0 else [f"unforce --all failed: {r.output[-500:]}"]
    a = probe(guest)
    time.sleep(settle)
    b = probe(guest)
    vs = {v.path: v for v in variables(b["vars"], manifest)}
    for path, t in b["tasks"].items():
        t0, ta = before["tasks"][path], a["tasks"][path]
        if t["state"] != "running":
            problems.append(f"task {path} is {t['state']} after the fuzz")
        if t["faults"] != t0["faults"]:
            problems.append(f"task {path} faulted {t['faults'] - t0['faults']} times "
                            "during the fuzz")
        if t["interval_ns"] and not t["cycles"] > ta["cycles"] > t0["cycles"]:
            problems.append(f"task {path}: cycles {t0['cycles']} before, {ta['cycles']} "
                            f"after, {t['cycles']} {settle} s later: not advancing")
    for path, hexval in b["values"].items():
        v = vs[path]
        why = value_problem(v, bytes.fromhex(hexval))
        if why:
            problems.append(f"variable {path} ({v.base or v.kind}): {why}")
        if v.constant and before["values"].get(path) != hexval:
            problems.append(f"CONSTANT {path} changed: {before['values'].get(path)} -> {hexval}")
    if b["forced"]:
        problems.append(f"{b['forced']} variables still forced after unforce --all")
    return problems
