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
how many cycles the loop took (``cycle - in_tag``).

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


def answer(dev: UserDevice, rules: List[Rule], out: Outputs) -> List[int]:
    """The input slots for outputs *out*: the rules applied, other slots kept."""
    raw = dev.current_inputs()
    for r in rules:
        raw[r.dst.index] = encode(r.dst.type, r.value(out))
    return raw


def loop(dev: UserDevice, rules: List[Rule], *, cycles: Optional[int] = None,
         duration: Optional[float] = None, stats: Optional[LoopStats] = None,
         trace=None, stop=lambda: False) -> LoopStats:
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
            if trace:
                trace(out)
            continue
        if last is not None and out.cycle > last + 1:
            st.missed += out.cycle - last - 1
        last = out.cycle
        dev.write_inputs(answer(dev, rules, out), tag=out.cycle)
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
        except ValueError as e:
            print(f"io-daemon: {e}", file=sys.stderr)
            return 2
        stopping = []
        signal.signal(signal.SIGTERM, lambda *_: stopping.append(1))
        trace = None
        if a.trace:
            def trace(out):
                print(json.dumps({"cycle": out.cycle, "in_tag": out.in_tag, "flags": out.flags,
                                  "values": out.values}), flush=True)
        print(f"io-daemon: {path}: {len(rules)} rules, answering each cycle", flush=True)
        try:
            st = loop(dev, rules, cycles=a.cycles, duration=a.duration, trace=trace,
                      stop=lambda: bool(stopping))
        except KeyboardInterrupt:
            return 130
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
