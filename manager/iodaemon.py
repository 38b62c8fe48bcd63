# SPDX-License-Identifier: MIT
"""`plc-manager io-daemon`: the reference daemon of the user-space I/O
provider (kmod_templates/kernel/iec_io_user.c, README "Real I/O").

A user device of the I/O map (``DEVICE fb : user INPUTS n OUTPUTS m``) is the
character device /dev/iec_io_<config>_<resource>_<device> while its resource
module is loaded.  Its mmap() is the shared memory documented in
iec_io_user.c (version 1, host byte order): a header, slot descriptors
(address and type of each slot), two input records the daemon writes and
two output records the kernel writes, each pair a latch sequence.  This
module reads and writes that layout (:class:`UserDevice`, which also works
on a plain file of the same layout, for tests) and runs a loopback: after
each publication of the task's outputs (read() of the device wakes it) it
computes inputs from outputs (``--map %ID0=%QD0+1``) and publishes them,
tagged with the output cycle they answer, so that every output record tells
how many cycles the loop took (``cycle - in_tag``).  With ``--modbus`` it
is also a Modbus TCP master (pymodbus' client): ``--reg`` rules write output
slots to a server's registers or coils and read input slots from it, each
cycle.

Memory order: the latch needs the daemon's stores in program order and its
loads in program order.  CPython performs each struct.pack_into/unpack_from
as one C call, in order; x86-64 keeps stores (and loads) in order, so the
protocol holds there.  On a weakly ordered CPU (arm64) a daemon needs
barriers: write it in C with __atomic_* release/acquire.
"""

from __future__ import annotations

import argparse
import errno
import json
import math
import mmap
import os
import re
import select
import signal
import statistics
import struct
import sys
import time
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Tuple

MAGIC = 0x55434549
VERSION = 1
HEADER = struct.Struct("=IHHIIIIIIIIQIIII")   # offsets 0..63
IN_SEQ = 64                                   # u32, written by the daemon
DESC = struct.Struct("=24sHHI")               # 32 bytes per slot
OUT_SEQ, IN_TAKEN, STATUS = 48, 52, 56
SAFE, STALE = 1, 2                            # status / record flag bits
TRIES = 100

# type codes of the slot descriptors (iec2kmod/iomap.py USER_TYPES)
TYPES = {1: "BOOL", 2: "SINT", 3: "INT", 4: "DINT", 5: "USINT", 6: "UINT", 7: "UDINT",
         8: "BYTE", 9: "WORD", 10: "DWORD", 11: "REAL"}
_SIGNED = {"SINT": 8, "INT": 16, "DINT": 32}
_UNSIGNED = {"USINT": 8, "BYTE": 8, "UINT": 16, "WORD": 16, "UDINT": 32, "DWORD": 32}


class ProtocolError(Exception):
    """The device or file is not a user device of a known version."""


def decode(type_name: str, raw: int):
    """A slot's 32 bits as the value of its variable."""
    raw &= 0xFFFFFFFF
    if type_name == "BOOL":
        return raw != 0
    if type_name == "REAL":
        return struct.unpack("=f", struct.pack("=I", raw))[0]
    if type_name in _SIGNED:
        return raw - (1 << 32) if raw & 0x80000000 else raw
    return raw


def encode(type_name: str, value) -> int:
    """A value as a slot's 32 bits (the kernel saturates it to the type)."""
    if type_name == "BOOL":
        return 1 if value else 0
    if type_name == "REAL":
        return struct.unpack("=I", struct.pack("=f", float(value)))[0]
    v = int(value)
    if type_name in _SIGNED:
        v = max(-(1 << 31), min((1 << 31) - 1, v))
    else:
        v = max(0, min(0xFFFFFFFF, v))
    return v & 0xFFFFFFFF


@dataclass
class Slot:
    index: int
    address: str          # "" if not bound
    type: str             # "" if not bound


@dataclass
class Outputs:
    cycle: int            # the task's cycle count since the load
    in_tag: int           # tag of the inputs that cycle read
    flags: int            # SAFE: the safe state
    raw: List[int]
    values: Dict[str, object] = field(default_factory=dict)   # address -> value

    @property
    def safe(self) -> bool:
        return bool(self.flags & SAFE)


class UserDevice:
    """The shared memory of one user device (or a file of its layout)."""

    def __init__(self, path: str, writable: bool = True):
        self.path = path
        self.fd = os.open(path, os.O_RDWR if writable else os.O_RDONLY)
        try:
            size = os.fstat(self.fd).st_size
            if size == 0:       # a character device: map the first page, read the size
                self.mm = mmap.mmap(self.fd, mmap.PAGESIZE, mmap.MAP_SHARED,
                                    mmap.PROT_READ | (mmap.PROT_WRITE if writable else 0))
                size = struct.unpack_from("=I", self.mm, 60)[0]
                if size > mmap.PAGESIZE:
                    self.mm.close()
                    self.mm = None
            else:
                self.mm = None
            if self.mm is None:
                self.mm = mmap.mmap(self.fd, size, mmap.MAP_SHARED,
                                    mmap.PROT_READ | (mmap.PROT_WRITE if writable else 0))
            self._parse()
        except BaseException:
            self.close()
            raise
        self.in_seq = struct.unpack_from("=I", self.mm, IN_SEQ)[0]
        self.is_char = os.path.exists(path) and not os.path.isfile(path)

    def _parse(self):
        if len(self.mm) < 128:
            raise ProtocolError(f"{self.path}: {len(self.mm)} bytes, less than a header")
        (magic, version, hsize, self.n_in, self.n_out, self.in_off, self.in_stride,
         self.out_off, self.out_stride, self.desc_off, self.stale_ms, self.interval_ns,
         _, _, _, size) = HEADER.unpack_from(self.mm, 0)
        if magic != MAGIC:
            raise ProtocolError(f"{self.path}: not an iec2kmod user device (magic "
                                f"{magic:#010x}, want {MAGIC:#010x})")
        if version != VERSION:
            raise ProtocolError(f"{self.path}: protocol version {version}; this daemon "
                                f"knows {VERSION}")
        end = max(self.out_off + 2 * self.out_stride, self.in_off + 2 * self.in_stride,
                  self.desc_off + DESC.size * (self.n_in + self.n_out))
        if hsize != 128 or end > len(self.mm) or self.in_stride < 8 + 4 * self.n_in or \
                self.out_stride < 24 + 4 * self.n_out:
            raise ProtocolError(f"{self.path}: inconsistent layout (header {hsize} bytes, "
                                f"records end at {end}, {len(self.mm)} mapped)")
        self.inputs: List[Slot] = []
        self.outputs: List[Slot] = []
        for i in range(self.n_in + self.n_out):
            addr, code, _, _ = DESC.unpack_from(self.mm, self.desc_off + i * DESC.size)
            name = addr.split(b"\0", 1)[0].decode("ascii", "replace")
            slot = Slot(i if i < self.n_in else i - self.n_in, name, TYPES.get(code, ""))
            (self.inputs if i < self.n_in else self.outputs).append(slot)
        self.by_address = {s.address.upper(): ("I" if s in self.inputs else "Q", s)
                           for s in self.inputs + self.outputs if s.address}

    def close(self):
        mm, self.mm = getattr(self, "mm", None), None
        if mm is not None:
            mm.close()
        if getattr(self, "fd", -1) >= 0:
            os.close(self.fd)
            self.fd = -1

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # ------------------------------------------------------------------
    def status(self) -> int:
        return struct.unpack_from("=I", self.mm, STATUS)[0]

    def in_taken(self) -> int:
        return struct.unpack_from("=I", self.mm, IN_TAKEN)[0]

    def read_outputs(self) -> Outputs:
        """The latest output record, whole (latch read, retried)."""
        fmt = struct.Struct(f"=QQII{self.n_out}I")
        for _ in range(TRIES):
            seq = struct.unpack_from("=I", self.mm, OUT_SEQ)[0]
            rec = fmt.unpack_from(self.mm, self.out_off + (seq & 1) * self.out_stride)
            if struct.unpack_from("=I", self.mm, OUT_SEQ)[0] == seq:
                cycle, in_tag, flags, _, *raw = rec
                out = Outputs(cycle, in_tag, flags, list(raw))
                out.values = {s.address: decode(s.type, raw[s.index])
                              for s in self.outputs if s.address}
                return out
        raise ProtocolError(f"{self.path}: the output records change faster than they "
                            "can be read")

    def write_inputs(self, raw: List[int], tag: int = 0) -> None:
        """Publishes the input slots (raw 32-bit values, all of them): the
        latch update (seq odd, record 0, seq even, record 1)."""
        if len(raw) != self.n_in:
            raise ValueError(f"{self.n_in} input slots, {len(raw)} values")
        rec = struct.pack(f"=Q{self.n_in}I", tag & 0xFFFFFFFFFFFFFFFF,
                          *(v & 0xFFFFFFFF for v in raw))
        mm, o = self.mm, self.in_off
        self.in_seq = (self.in_seq + 1) & 0xFFFFFFFF
        struct.pack_into("=I", mm, IN_SEQ, self.in_seq)      # odd: the kernel reads 1
        mm[o:o + len(rec)] = rec
        self.in_seq = (self.in_seq + 1) & 0xFFFFFFFF
        struct.pack_into("=I", mm, IN_SEQ, self.in_seq)      # even: the kernel reads 0
        o += self.in_stride
        mm[o:o + len(rec)] = rec

    def current_inputs(self) -> List[int]:
        """The input record the kernel would take now."""
        seq = struct.unpack_from("=I", self.mm, IN_SEQ)[0]
        o = self.in_off + (seq & 1) * self.in_stride
        return list(struct.unpack_from(f"={self.n_in}I", self.mm, o + 8))

    def wait(self, timeout: Optional[float]) -> Optional[int]:
        """Blocks until the kernel publishes outputs not yet seen by this
        file (read() of the device); the publication count, or None on
        timeout.  A plain file is always ready."""
        if not self.is_char:
            return 0
        r, _, _ = select.select([self.fd], [], [], timeout)
        if not r:
            return None
        try:
            return struct.unpack("=Q", os.read(self.fd, 8))[0]
        except BlockingIOError:
            return None


# ----------------------------------------------------------------- map --

_MAP = re.compile(r"""^\s*(?P<dst>%I[A-Z]*[0-9.]+)\s*=\s*
    (?:(?P<src>%Q[A-Z]*[0-9.]+)\s*(?:(?P<op>[-+*])\s*(?P<k>-?[0-9.]+(?:[eE]-?\d+)?))?
      |(?P<const>-?[0-9.]+(?:[eE]-?\d+)?|TRUE|FALSE))\s*$""", re.X | re.I)


@dataclass
class Rule:
    dst: Slot
    src: Optional[Slot]
    op: str = ""
    k: float = 0
    const: object = None

    def value(self, out: Outputs):
        if self.src is None:
            return self.const
        v = decode(self.src.type, out.raw[self.src.index])
        if self.op == "+":
            v = v + self.k
        elif self.op == "-":
            v = v - self.k
        elif self.op == "*":
            v = v * self.k
        if self.dst.type != "REAL" and self.dst.type != "BOOL":
            v = int(math.floor(v + 0.5)) if isinstance(v, float) else int(v)
        return v


def parse_rules(dev: UserDevice, specs: List[str]) -> List[Rule]:
    """``%IW0=%QW0``, ``%ID0=%QD0+1``, ``%IW2=%QW2*2``, ``%IX0.0=TRUE``, ``%IW4=12``."""
    rules = []
    for spec in specs:
        m = _MAP.match(spec)
        if not m:
            raise ValueError(f"{spec!r}: expected %I... = %Q... [+-* number] or a constant")
        dst = dev.by_address.get(m["dst"].upper())
        if dst is None or dst[0] != "I":
            raise ValueError(f"{spec!r}: {m['dst']} is not an input slot of {dev.path} "
                             f"(its inputs: {', '.join(s.address for s in dev.inputs if s.address) or 'none'})")
        if m["src"]:
            src = dev.by_address.get(m["src"].upper())
            if src is None or src[0] != "Q":
                raise ValueError(f"{spec!r}: {m['src']} is not an output slot of {dev.path} "
                                 f"(its outputs: {', '.join(s.address for s in dev.outputs if s.address) or 'none'})")
            rules.append(Rule(dst[1], src[1], m["op"] or "", float(m["k"] or 0)))
        else:
            c = m["const"].upper()
            const = c == "TRUE" if c in ("TRUE", "FALSE") else float(c) if "." in c or "E" in c \
                else int(c)
            rules.append(Rule(dst[1], None, const=const))
    return rules


# --------------------------------------------------------- Modbus TCP --
#
# A register rule binds a slot to a Modbus table of a server (the daemon is
# the master, pymodbus' client): an input slot is read from it after each
# publication, an output slot written to it before.  Tables: hr (holding
# registers), ir (input registers, read only), co (coils), di (discrete
# inputs, read only); addresses from 0 as on the wire.  BOOL goes to a coil
# or a discrete input (or a register, 0/1); a 16-bit type is one register
# (two's complement for INT); a 32-bit type (DINT, UDINT, DWORD, REAL) is two
# registers, the high word first (the common Modbus convention).

_REG = re.compile(r"^\s*(?P<addr>%[IQ][A-Z]*[0-9.]+)\s*=\s*(?P<table>hr|ir|co|di)\s*:?\s*"
                  r"(?P<at>\d+)\s*$", re.I)
_WIDE = ("DINT", "UDINT", "DWORD", "REAL")


@dataclass
class RegRule:
    slot: Slot
    input: bool
    table: str
    at: int

    @property
    def count(self) -> int:
        return 2 if self.slot.type in _WIDE else 1


def parse_registers(dev: UserDevice, specs: List[str]) -> List[RegRule]:
    """``%IW8=hr100``, ``%QD0=hr:200``, ``%IX0.0=di3``, ``%QX0.0=co5``."""
    rules = []
    for spec in specs:
        m = _REG.match(spec)
        if not m:
            raise ValueError(f"{spec!r}: expected %I.../%Q... = hr|ir|co|di address "
                             "(e.g. %IW8=hr100)")
        hit = dev.by_address.get(m["addr"].upper())
        if hit is None:
            raise ValueError(f"{spec!r}: {m['addr']} is not a slot of {dev.path}")
        kind, slot = hit
        table = m["table"].lower()
        if kind == "Q" and table in ("ir", "di"):
            raise ValueError(f"{spec!r}: {table} is read-only: an output goes to hr or co")
        if table in ("co", "di") and slot.type != "BOOL":
            raise ValueError(f"{spec!r}: {slot.address} is {slot.type}: coils and discrete "
                             "inputs carry BOOL")
        rules.append(RegRule(slot, kind == "I", table, int(m["at"])))
    return rules


def _to_registers(type_name: str, raw: int) -> List[int]:
    if type_name in _WIDE:
        return [(raw >> 16) & 0xFFFF, raw & 0xFFFF]
    return [raw & 0xFFFF]


def _from_registers(type_name: str, regs: List[int]) -> int:
    """Registers as a slot's 32 bits."""
    if type_name in _WIDE:
        return ((regs[0] & 0xFFFF) << 16) | (regs[1] & 0xFFFF)
    v = regs[0] & 0xFFFF
    if type_name in _SIGNED:
        v = v - 0x10000 if v & 0x8000 else v
    return encode(type_name, v)


class ModbusError(Exception):
    """The server refused or did not answer."""


def _modbus_exception():
    from pymodbus.exceptions import ModbusException
    return ModbusException


def modbus_exchange(client, unit: int, rules: List[RegRule], out: Optional[Outputs],
                    raw: List[int]) -> None:
    """Writes the output rules' slots of *out* to the server, then reads the
    input rules' registers into *raw* (the input slots)."""
    def ok(rr, what):
        if rr is None or rr.isError():
            raise ModbusError(f"{what}: {rr}")
        return rr
    if out is not None:
        for r in rules:
            if r.input:
                continue
            v = out.raw[r.slot.index]
            if r.table == "co":
                ok(client.write_coil(r.at, bool(v), device_id=unit), f"write coil {r.at}")
            else:
                ok(client.write_registers(r.at, _to_registers(r.slot.type, v), device_id=unit),
                   f"write hr {r.at}")
    for r in rules:
        if not r.input:
            continue
        if r.table in ("co", "di"):
            fn = client.read_coils if r.table == "co" else client.read_discrete_inputs
            rr = ok(fn(r.at, count=1, device_id=unit), f"read {r.table} {r.at}")
            raw[r.slot.index] = 1 if rr.bits[0] else 0
        else:
            fn = client.read_holding_registers if r.table == "hr" else \
                client.read_input_registers
            rr = ok(fn(r.at, count=r.count, device_id=unit), f"read {r.table} {r.at}")
            raw[r.slot.index] = _from_registers(r.slot.type, rr.registers) \
                if r.slot.type != "BOOL" else int(rr.registers[0] != 0)


@dataclass
class LoopStats:
    publications: int = 0
    answered: int = 0
    missed: int = 0                    # cycles whose outputs it never saw
    lags: List[int] = field(default_factory=list)     # cycle - in_tag, per record seen
    react_us: List[float] = field(default_factory=list)   # wake-up -> inputs written

    def summary(self) -> dict:
        def q(xs, p):
            xs = sorted(xs)
            return xs[min(len(xs) - 1, int(math.ceil(p * len(xs))) - 1)] if xs else None
        return {"publications": self.publications, "answered": self.answered,
                "missed": self.missed,
                "lag_cycles": {"n": len(self.lags), "min": min(self.lags, default=None),
                               "median": statistics.median(self.lags) if self.lags else None,
                               "p99": q(self.lags, 0.99), "max": max(self.lags, default=None)},
                "react_us": {"n": len(self.react_us),
                             "min": round(min(self.react_us), 1) if self.react_us else None,
                             "median": round(statistics.median(self.react_us), 1)
                             if self.react_us else None,
                             "p99": round(q(self.react_us, 0.99), 1) if self.react_us else None,
                             "max": round(max(self.react_us), 1) if self.react_us else None}}


def answer(dev: UserDevice, rules: List[Rule], out: Outputs, modbus=None) -> List[int]:
    """The input slots for outputs *out*: the Modbus exchange (modbus:
    (client, unit, register rules)) then the rules applied, other slots
    kept."""
    raw = dev.current_inputs()
    if modbus is not None:
        client, unit, regs = modbus
        modbus_exchange(client, unit, regs, out, raw)
    for r in rules:
        raw[r.dst.index] = encode(r.dst.type, r.value(out))
    return raw


def loop(dev: UserDevice, rules: List[Rule], *, cycles: Optional[int] = None,
         duration: Optional[float] = None, stats: Optional[LoopStats] = None,
         trace=None, stop=lambda: False, modbus=None) -> LoopStats:
    """The loopback: at each publication, the inputs computed from the
    outputs, tagged with the output cycle.  Ends after *cycles* answered
    publications, *duration* seconds, or when stop() is true."""
    st = stats or LoopStats()
    end = None if duration is None else time.monotonic() + duration
    last = last_rec = None
    if not dev.is_char:
        raise ProtocolError(f"{dev.path}: the loopback needs the device (read() wakes it)")
    while not stop():
        timeout = 0.5 if end is None else min(0.5, end - time.monotonic())
        if timeout <= 0:
            break
        n = dev.wait(timeout)
        if n is None:
            continue
        t0 = time.perf_counter()
        out = dev.read_outputs()
        if (out.cycle, out.flags) == last_rec:
            # woken for a publication already read (it came between the
            # wake-up and the read of the record): nothing new
            continue
        last_rec = (out.cycle, out.flags)
        st.publications += 1
        if out.safe:
            if modbus is not None:      # the safe state reaches the server too
                raw = dev.current_inputs()
                modbus_exchange(modbus[0], modbus[1], modbus[2], out, raw)
            if trace:
                trace(out)
            continue
        if last is not None and out.cycle > last + 1:
            st.missed += out.cycle - last - 1
        last = out.cycle
        dev.write_inputs(answer(dev, rules, out, modbus), tag=out.cycle)
        st.react_us.append((time.perf_counter() - t0) * 1e6)
        st.answered += 1
        if out.in_tag:
            st.lags.append(out.cycle - out.in_tag)
        if trace:
            trace(out)
        if cycles is not None and st.answered >= cycles:
            break
    return st


def device_path(name: str) -> str:
    """A path, or config.resource.device / config_resource_device."""
    if "/" in name:
        return name
    return "/dev/iec_io_" + name.replace(".", "_").lower()


def main(argv: Optional[List[str]] = None) -> int:
    p = argparse.ArgumentParser(
        prog="plc-manager io-daemon",
        description="Reference daemon of the user-space I/O provider: maps a user device "
                    "and answers each published cycle of outputs with inputs.")
    add_arguments(p)
    return run(p.parse_args(argv))


def add_arguments(p):
    p.add_argument("device", help="/dev/iec_io_<config>_<resource>_<device>, or "
                                  "config.resource.device")
    p.add_argument("--map", action="append", default=[], metavar="RULE",
                   help="an input from the outputs: %%ID0=%%QD0, %%IW2=%%QW2+1, "
                        "%%IW4=%%QW4*0.5, %%IX0.0=TRUE (repeatable)")
    p.add_argument("--modbus", metavar="HOST[:PORT]",
                   help="Modbus TCP master: exchange the --reg slots with this server "
                        "each cycle (outputs written, then inputs read)")
    p.add_argument("--unit", type=int, default=1, help="Modbus device id (default 1)")
    p.add_argument("--reg", action="append", default=[], metavar="RULE",
                   help="a slot on a Modbus table: %%IW8=hr100, %%ID0=ir4 (two registers, "
                        "high word first), %%IX0.0=di3, %%QW8=hr101, %%QX0.0=co5 "
                        "(repeatable)")
    p.add_argument("--cycles", type=int, help="stop after answering N publications")
    p.add_argument("--duration", type=float, metavar="S", help="stop after S seconds")
    p.add_argument("--show", action="store_true", help="print the device's slots and exit")
    p.add_argument("--trace", action="store_true",
                   help="one JSON line per publication seen (cycle, in_tag, flags, values)")
    p.add_argument("--json", action="store_true", help="the statistics at the end as JSON")


def run(a) -> int:
    path = device_path(a.device)
    try:
        dev = UserDevice(path, writable=not a.show)
    except FileNotFoundError:
        print(f"io-daemon: {path}: no such device (is the configuration loaded? its I/O "
              "map declares the user device)", file=sys.stderr)
        return 2
    except OSError as e:
        why = "another daemon has it open read-write" if e.errno == errno.EBUSY else \
            "the configuration is still loading" if e.errno == errno.EAGAIN else e.strerror
        print(f"io-daemon: {path}: {why}", file=sys.stderr)
        return 2
    except ProtocolError as e:
        print(f"io-daemon: {e}", file=sys.stderr)
        return 2
    with dev:
        if a.show:
            print(f"{path}: {dev.n_in} inputs, {dev.n_out} outputs, interval "
                  f"{dev.interval_ns / 1e6:g} ms, stale "
                  f"{str(dev.stale_ms) + ' ms' if dev.stale_ms else 'off'}")
            for kind, slots in (("in", dev.inputs), ("out", dev.outputs)):
                for s in slots:
                    print(f"  {kind} {s.index:4} {s.address or '-':12} {s.type or '-'}")
            return 0
        try:
            rules = parse_rules(dev, a.map)
            regs = parse_registers(dev, a.reg)
            if regs and not a.modbus:
                raise ValueError("--reg needs --modbus HOST[:PORT]")
        except ValueError as e:
            print(f"io-daemon: {e}", file=sys.stderr)
            return 2
        modbus = None
        if a.modbus:
            from pymodbus.client import ModbusTcpClient
            host, _, port = a.modbus.rpartition(":") if ":" in a.modbus else (a.modbus, "", "")
            client = ModbusTcpClient(host, port=int(port or 502), timeout=1, retries=1)
            if not client.connect():
                print(f"io-daemon: no Modbus TCP server at {a.modbus}", file=sys.stderr)
                return 2
            modbus = (client, a.unit, regs)
        stopping = []
        signal.signal(signal.SIGTERM, lambda *_: stopping.append(1))
        trace = None
        if a.trace:
            def trace(out):
                print(json.dumps({"cycle": out.cycle, "in_tag": out.in_tag, "flags": out.flags,
                                  "values": out.values}), flush=True)
        print(f"io-daemon: {path}: {len(rules)} rules"
              f"{f', {len(regs)} Modbus registers at {a.modbus}' if modbus else ''}, "
              "answering each cycle", flush=True)
        try:
            st = loop(dev, rules, cycles=a.cycles, duration=a.duration, trace=trace,
                      stop=lambda: bool(stopping), modbus=modbus)
        except KeyboardInterrupt:
            return 130
        except Exception as e:
            if modbus is None or not isinstance(e, (ModbusError, _modbus_exception())):
                raise
            # no answer: the inputs go stale (the task faults after STALE ms)
            print(f"io-daemon: Modbus {a.modbus}: {e}; stopping", file=sys.stderr)
            return 1
        finally:
            if modbus is not None:
                modbus[0].close()
        s = st.summary()
        print(json.dumps(s) if a.json else
              f"io-daemon: {s['answered']} cycles answered, {s['missed']} cycles "
              f"not seen; loop lag cycles min/median/p99/max {s['lag_cycles']['min']}/"
              f"{s['lag_cycles']['median']}/{s['lag_cycles']['p99']}/"
              f"{s['lag_cycles']['max']}; reaction us median {s['react_us']['median']}",
              flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())


def device_holders(module: str) -> List[Tuple[int, str, str]]:
    """The processes holding a user device of resource module *module*
    (iec_<config>_r_<resource> -> /dev/iec_io_<config>_<resource>_*), open
    or mapped: (pid, command, device).  Such a process keeps the module
    loaded."""
    if not module.startswith("iec_") or "_r_" not in module:
        return []
    prefix = "/dev/iec_io_" + module[4:].replace("_r_", "_", 1) + "_"
    found = {}
    try:
        pids = [p for p in os.listdir("/proc") if p.isdigit()]
    except OSError:
        return []
    for pid in pids:
        devs = set()
        try:
            fd_dir = f"/proc/{pid}/fd"
            for fd in os.listdir(fd_dir):
                with_link = os.readlink(f"{fd_dir}/{fd}")
                if with_link.startswith(prefix):
                    devs.add(with_link)
            with open(f"/proc/{pid}/maps") as f:
                for line in f:
                    if prefix in line:
                        devs.add(line.split()[-1])
            with open(f"/proc/{pid}/comm") as f:
                comm = f.read().strip()
        except OSError:
            continue
        for d in sorted(devs):
            found[(int(pid), d)] = comm
    return [(pid, comm, d) for (pid, d), comm in sorted(found.items())]


def holders_hint(module: str) -> str:
    """' (held by pid N (comm) through /dev/...)' or ''."""
    h = device_holders(module)
    if not h:
        return ""
    return " (held by " + ", ".join(f"pid {p} ({c}) through {d}" for p, c, d in h) + \
        ": stop that I/O daemon first)"
