# SPDX-License-Identifier: MIT
"""Bound I/O as plc-manager sees it (issue 26): the bindings of the I/O map
(the manifest's "io", written by `iec2kmod gen` from the project's .iomap
files), the device check `load` makes before it inserts anything, and the
last value each binding exchanged with its device.

Last values come from the kernel, /sys/module/<resource module>/iec_io
(kmod_templates/kernel/iec_io.c): per binding the raw sample last read
from the device, last written to it (a forced output's forced value), or
the safe value written on stop, fault, load or unload.  They are not the
located variables' values, which the variable read path returns: a forced
input holds the forced value while the device gives another, a REAL holds
volts while the device exchanges counts, an integer output above the
channel's range is clamped on its way out, and after a stop the device
holds the safe value while the variable keeps the program's last one.

Interrupts (INTERRUPT of the I/O map, an event task woken by a device's
IRQ): the same file ends with one line a source, "irq <address>
<device.source> <line> <count>", the interrupts its handler took since
the load.
"""

from __future__ import annotations

import os
import stat
from dataclasses import dataclass
from typing import Dict, List, Optional

from .errors import PLCError

PROC_COMEDI = "/proc/comedi"
SYSFS = "/sys"             # where last_values() looks (tests point it elsewhere)


def phys_of(lo: float, hi: float, bits: int, raw: int, type_name: str = "REAL") -> float:
    """The REAL/LREAL a raw sample gives: iec2kmod.iomap.phys_of (the
    kernel's arithmetic, kmod_templates/kernel/iec_io_real.c); the two are
    compared by tests/unit/test_iomap_gen.py."""
    import struct
    v = float(lo) + float(raw) * (float(hi) - float(lo)) / float((1 << bits) - 1)
    if type_name.upper() == "LREAL":
        return v
    return struct.unpack("<f", struct.pack("<f", v))[0]


@dataclass
class Binding:
    resource: str
    module: str
    address: str
    variable: str
    device: str
    subdevice: Optional[int]    # None: a user device's slot
    channel: int
    input: bool
    type: str
    scale: str              # bit, raw, phys
    bits: int
    lo: float
    hi: float
    safe: object            # None (input), "HOLD" or a value
    last: Optional[int] = None      # raw sample last exchanged; None: none yet

    @property
    def where(self) -> str:
        if self.subdevice is None:
            return f"{self.device}.{self.channel}"
        return f"{self.device}.{self.subdevice}.{self.channel}"

    @property
    def value(self) -> Optional[str]:
        """The last sample as the variable's type reads it."""
        if self.last is None:
            return None
        if self.scale == "bit":
            return "TRUE" if self.last else "FALSE"
        if self.scale == "phys":
            return f"{phys_of(self.lo, self.hi, self.bits, self.last, self.type):.6g} V"
        if self.scale == "word":        # a user slot: 32 bits (iec_io_user.c)
            return _slot_text(self.last, self.type)
        return str(self.last)

    @property
    def safe_text(self) -> str:
        if self.input:
            return "-"
        if self.safe == "HOLD":
            return "hold"
        if self.scale == "bit":
            return "TRUE" if self.safe else "FALSE"
        return f"{self.safe:g} V" if self.scale == "phys" else str(self.safe)


def _slot_text(raw: int, type_name: str) -> str:
    """A user slot's 32 bits as its variable's type reads them."""
    import struct
    t = type_name.upper()
    raw &= 0xFFFFFFFF
    if t == "BOOL":
        return "TRUE" if raw else "FALSE"
    if t == "REAL":
        return f"{struct.unpack('<f', struct.pack('<I', raw))[0]:.6g}"
    if t in ("SINT", "INT", "DINT"):
        return str(raw - (1 << 32) if raw & 0x80000000 else raw)
    return str(raw)


def summary(m: dict) -> Dict[str, list]:
    """The manifest's bindings with their variables' paths, per resource:
    what the small state file keeps (status reads it, not the manifest)."""
    addresses = {a.upper(): p for a, p in (m.get("addresses") or {}).items()}
    modules = {r["name"].upper(): r["module"] for r in m.get("resources", [])}
    out = {}
    for res, io in sorted((m.get("io") or {}).items()):
        out[res] = [dict(b, variable=addresses.get(b["address"].upper(), "?"),
                         module=modules.get(res.upper(), "?"))
                    for b in io.get("bindings", [])]
    return out


def _iec_io(module: str, sysroot: Optional[str]) -> str:
    """The resource module's iec_io file; "" when it has none."""
    try:
        with open(f"{sysroot or SYSFS}/module/{module}/iec_io") as f:
            return f.read()
    except OSError:
        return ""


def last_values(module: str, sysroot: Optional[str] = None) -> Dict[str, Optional[int]]:
    """Address -> the raw sample last exchanged (None: none yet), from the
    resource module's iec_io file; {} when the module has none."""
    out: Dict[str, Optional[int]] = {}
    for line in _iec_io(module, sysroot).splitlines():
        words = line.split()
        if len(words) == 3:
            out[words[0].upper()] = None if words[2] == "-" else int(words[2])
    return out


def interrupt_counts(module: str, sysroot: Optional[str] = None) -> Dict[str, int]:
    """Address -> the interrupts taken since the load, from the resource
    module's iec_io file ("irq <address> <source> <line> <count>")."""
    out: Dict[str, int] = {}
    for line in _iec_io(module, sysroot).splitlines():
        words = line.split()
        if len(words) == 5 and words[0] == "irq" and words[4].isdigit():
            out[words[1].upper()] = int(words[4])
    return out


@dataclass
class Interrupt:
    resource: str
    module: str
    address: str            # the SINGLE variable's address, %IX9.0
    variable: str
    device: str
    source: str             # ACK
    irq: int
    tasks: List[str]        # the event tasks it wakes
    count: Optional[int] = None     # taken since the load; None: not known

    @property
    def where(self) -> str:
        return f"{self.device}.{self.source}"


def interrupt_summary(m: dict) -> Dict[str, list]:
    """The manifest's interrupt sources with their variables' paths, per
    resource (what the state file keeps beside summary()); {} for none."""
    addresses = {a.upper(): p for a, p in (m.get("addresses") or {}).items()}
    modules = {r["name"].upper(): r["module"] for r in m.get("resources", [])}
    out = {}
    for res, io in sorted((m.get("io") or {}).items()):
        if io.get("interrupts"):
            out[res] = [dict(q, variable=addresses.get(q["address"].upper(), "?"),
                             module=modules.get(res.upper(), "?"))
                        for q in io["interrupts"]]
    return out


def interrupts(irqs: Dict[str, list], sysroot: Optional[str] = None) -> List[Interrupt]:
    """The sources of interrupt_summary() with their counts."""
    out = []
    for res, qs in sorted(irqs.items()):
        counts = interrupt_counts(qs[0]["module"], sysroot) if qs else {}
        for q in qs:
            out.append(Interrupt(res, q["module"], q["address"], q["variable"], q["device"],
                                 q["source"], int(q["irq"]), list(q.get("tasks") or []),
                                 counts.get(q["address"].upper())))
    return out


def bindings(io: Dict[str, list], sysroot: Optional[str] = None) -> List[Binding]:
    """The bindings of summary() with their last values."""
    out = []
    for res, binds in sorted(io.items()):
        last = last_values(binds[0]["module"], sysroot) if binds else {}
        for b in binds:
            safe = b.get("safe")
            out.append(Binding(res, b["module"], b["address"], b["variable"], b["device"],
                               None if b.get("subdevice") is None else int(b["subdevice"]),
                               int(b["channel"]),
                               b["address"].upper().startswith("%I"), b.get("type", "?"),
                               b.get("scale", "raw"), int(b.get("bits", 1)),
                               float(b.get("lo", 0.0)), float(b.get("hi", 0.0)),
                               safe, last.get(b["address"].upper())))
    return out


def _proc_comedi(path: str) -> Optional[Dict[int, tuple]]:
    """Minor -> (driver, board, subdevices) of the attached comedi devices,
    from /proc/comedi (drivers/comedi/proc.c: "%2d: %-20s %-20s %4d");
    None when comedi is not loaded."""
    try:
        with open(path) as f:
            text = f.read()
    except OSError:
        return None
    out = {}
    for line in text.splitlines():
        head, sep, rest = line.partition(":")
        words = rest.split()
        if sep and head.strip().isdigit() and len(words) == 3 and words[2].isdigit():
            out[int(head)] = (words[0], words[1], int(words[2]))
    return out


def check_devices(m: dict, dev_dir: str = "/dev", proc_comedi: str = PROC_COMEDI) -> int:
    """Before `load` inserts anything: every comedi device of the I/O map is
    there.  Checked per device: /dev/comedi<minor> exists and is a character
    device; /proc/comedi lists that minor as attached; its driver or board
    name is the board the I/O map names (when it names one); it has every
    subdevice a binding uses.  Refuses with a PLCError naming the resource
    and the device.  The resource module checks again at insert, channel by
    channel (kind, channel count, resolution, range): the second line of
    defence.  Returns the number of devices checked."""
    devices = []
    used: Dict[tuple, int] = {}
    for res, io in sorted((m.get("io") or {}).items()):
        for d in io.get("devices", []):
            if d.get("provider") == "comedi":
                devices.append((res, d))
        for b in io.get("bindings", []):
            if b.get("subdevice") is None:      # a user device's slot
                continue
            key = (res, b["device"].upper())
            used[key] = max(used.get(key, -1), int(b["subdevice"]))
    if not devices:
        return 0
    attached = None
    for res, d in devices:
        minor = int(d.get("minor", 0))
        path = f"{dev_dir}/comedi{minor}"
        what = f"resource {res}: device {d['name']} ({path}"
        board = d.get("board")
        what += f", {board})" if board else ")"
        try:
            mode = os.stat(path).st_mode
        except OSError:
            raise PLCError(f"{what} is missing: load its comedi driver first"
                           f"{' (modprobe ' + board + ')' if board else ''}; nothing inserted") \
                from None
        if not stat.S_ISCHR(mode):
            raise PLCError(f"{what} is not a character device; nothing inserted")
        if attached is None:
            attached = _proc_comedi(proc_comedi)
            if attached is None:
                raise PLCError(f"{what}: {proc_comedi} cannot be read (is comedi loaded?); "
                               "nothing inserted")
        if minor not in attached:
            raise PLCError(f"{what} has no board attached ({proc_comedi}; comedi_config); "
                           "nothing inserted")
        driver, name, nsub = attached[minor]
        if board and board not in (driver, name):
            raise PLCError(f"{what} is a {name} (driver {driver}), not a {board}; nothing "
                           "inserted")
        top = used.get((res, d["name"].upper()), -1)
        if top >= nsub:
            raise PLCError(f"{what} has {nsub} subdevices, the I/O map uses subdevice {top}; "
                           "nothing inserted")
    return len(devices)
