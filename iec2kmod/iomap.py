"""The I/O map: which device channel a located address reads or drives.

A project's ``.iomap`` files (named on the command line beside the sources,
or found in a project directory) bind the located variables of a resource to
device channels.  ``iec2kmod check`` and ``gen`` read them after the
configuration is checked; every error is ``file:line:col: error:`` with the
line and a caret.  The format, one statement a line, ``#`` starts a comment,
keywords in any case::

    RESOURCE Station                         # the bindings below belong to it
    DEVICE daq : comedi comedi_test MINOR 0  # /dev/comedi0, a known board
    DEVICE card : comedi MINOR 1             # another board: declare it
    SUBDEVICE card.2 : DIO 24
    SUBDEVICE card.0 : AI 16 BITS 12 RANGE -10..10, 0..5
    %IW0   : daq.0.0                         # subdevice 0, channel 0: raw count
    %ID4   : daq.0.1 RANGE 1                 # REAL: volts of range 1
    %QW0   : daq.1.0 SAFE 32768              # safe state: this value
    %QX0.0 : card.2.5 SAFE HOLD              # safe state: the last value

``RESOURCE`` may be left out when the configuration has one resource.  A
binding's variable must be one the resource declares or uses; one address
is bound once.  Scaling: a digital channel is a BOOL at a bit address
(%IX/%QX); an analog channel gives an unsigned or bit-string variable
(UINT, WORD, UDINT, DWORD) the raw sample 0..2**bits-1, a signed one (INT,
DINT) the same count when it fits, and a REAL or LREAL the physical value of
the range (lo + raw * (hi - lo) / (2**bits - 1), written back by the inverse,
rounded and clamped: phys_of and raw_of below, which the kernel's
iec_io_real.c computes bit for bit; a SAFE value of a REAL is in volts).  An output's safe state (on stop, fault and unload) is
0 / FALSE unless ``SAFE value`` or ``SAFE HOLD`` says otherwise.

The boards in BOARDS are described as their drivers report them; the kernel
module compares each bound subdevice with the device at load (kind, channel
count, resolution) and refuses the load naming the device when they differ.

Interrupts.  An event task (``TASK t (SINGLE := ack, PRIORITY := 0)``) can
be woken by a hardware interrupt instead of a rising edge written by a
program: its SINGLE variable is a located BOOL input, and the I/O map binds
that address to an interrupt source of a device::

    VAR_GLOBAL ack AT %IX9.0 : BOOL; END_VAR          (the configuration)
    INTERRUPT %IX9.0 : lpt.ACK IRQ 7                  (the .iomap)

Every interrupt runs each task whose SINGLE is that variable once (one
that comes during a cycle gives one more cycle after it; interrupts that
come before the task has taken the previous one merge into one cycle).  The cycle's release time,
which the programs' timers and the task's latency statistics use, is the
moment the interrupt handler ran.  The variable itself is not written by
the interrupt (it keeps its value, FALSE unless forced; a write of TRUE
over FALSE by the manager still wakes the tasks, as for any SINGLE, and
is all ``iec2kmod sim``, which has no interrupts, runs them on).  The
sources a board has are in INTERRUPTS; IRQ names the line, which the
resource module requests at load (a threaded handler: on PREEMPT_RT it
runs in its irq/N thread, at SCHED_FIFO 50, above every PLC task) and frees
at unload before its task threads stop.  comedi_parport's ACK (pin 10):
the driver must be attached without an IRQ (options: the I/O base only),
since the resource module requests the line itself and sets the control
register's interrupt enable bit (comedi_parport's control-line writes keep
it).
The user-space provider (kmod_templates/kernel/iec_io_user.c): a device
whose channels are 32-bit slots of a shared memory that a user-space daemon
(a fieldbus master, a test harness: ``plc-manager io-daemon``) maps::

    DEVICE fb : user INPUTS 4 OUTPUTS 4 STALE 500   # slots; ms, or STALE OFF
    %ID0   : fb.0                            # input slot 0
    %QW2   : fb.1 SAFE -1                    # output slot 1
    %QX0.0 : fb.3 SAFE HOLD

A user device is the character device /dev/iec_io_<config>_<resource>_<device>
(lower case) while the resource module is loaded.  A binding is
``device.slot``; the slot is an input slot for an %I address and an output
slot for a %Q address (0..INPUTS-1, 0..OUTPUTS-1).  The variable is BOOL,
SINT, INT, DINT, USINT, UINT, UDINT, BYTE, WORD, DWORD or REAL (a slot holds
32 bits: 0/1, the value sign- or zero-extended, or the IEEE-754 bits of a
REAL).  ``STALE n`` (default 1000) faults the task with an I/O fault when the
daemon has not published inputs for n ms; ``STALE OFF`` keeps the last
inputs for ever.  All the bound inputs and outputs of one user device belong
to one task (its cycle is the device's cycle): declare a device per task.
The shared-memory protocol is documented in iec_io_user.c and README.md.
"""

from __future__ import annotations

import math
import re
import struct
from dataclasses import dataclass, field

from .diagnostics import SourceFile

SUFFIX = ".iomap"

# comedi subdevice kinds: the direction they serve
INPUT_KINDS = ("AI", "DI", "DIO")
OUTPUT_KINDS = ("AO", "DO", "DIO")
ANALOG = ("AI", "AO")
KINDS = ("AI", "AO", "DI", "DO", "DIO")
PROVIDERS = ("comedi", "user")

# the user provider: the variable types a 32-bit slot carries, and their
# codes in the device's slot descriptors (iec_io_user.c, manager/iodaemon.py)
USER_TYPES = {"BOOL": 1, "SINT": 2, "INT": 3, "DINT": 4, "USINT": 5, "UINT": 6,
              "UDINT": 7, "BYTE": 8, "WORD": 9, "DWORD": 10, "REAL": 11}
USER_RANGES = {"SINT": (-128, 127), "INT": (-32768, 32767), "DINT": (-(1 << 31), (1 << 31) - 1),
               "USINT": (0, 255), "UINT": (0, 65535), "UDINT": (0, (1 << 32) - 1),
               "BYTE": (0, 255), "WORD": (0, 65535), "DWORD": (0, (1 << 32) - 1)}
USER_MAX_SLOTS = 1024
USER_STALE_MS = 1000


@dataclass
class Subdevice:
    index: int
    kind: str                      # AI AO DI DO DIO
    channels: int
    bits: int = 1                  # resolution of an analog channel
    ranges: list = field(default_factory=list)     # [(lo, hi)] in volts


def _sub(index, kind, channels, bits=1, ranges=()):
    return Subdevice(index, kind, channels, bits, list(ranges))


# Boards known by name (the driver's subdevices on Linux 6.1).
BOARDS = {
    # drivers/comedi/drivers/comedi_test.c: fake waveforms on 8 AI channels
    # (±10 V, ±5 V), 8 AO channels read back on the AI channels
    "comedi_test": [_sub(0, "AI", 8, 16, [(-10.0, 10.0), (-5.0, 5.0)]),
                    _sub(1, "AO", 8, 16, [(-10.0, 10.0)])],
    # drivers/comedi/drivers/comedi_parport.c: the data register (8 lines),
    # the status lines (5 inputs), the control lines (4 outputs); subdevice
    # 3 is the ACK interrupt
    "comedi_parport": [_sub(0, "DIO", 8), _sub(1, "DI", 5), _sub(2, "DO", 4)],
}


# The interrupt sources of a board: name -> what it is.
INTERRUPTS = {
    "comedi_parport": {"ACK": "the ACK status line (pin 10), with the control "
                              "register's interrupt enable set"},
}


@dataclass
class Device:
    name: str
    provider: str
    board: str | None
    minor: int
    subdevices: dict               # index -> Subdevice
    place: str                     # file:line of its declaration
    inputs: int = 0                # user provider: input and output slots
    outputs: int = 0
    stale_ms: int = 0              # user provider: 0 = STALE OFF


@dataclass
class Binding:
    address: str
    device: str
    subdevice: int
    channel: int
    kind: str                      # the subdevice's kind
    type: str                      # the variable's type name
    scale: str                     # "bit", "raw" or "phys"
    bits: int
    range: int
    lo: float
    hi: float
    safe: object                   # "HOLD" or a number (0 when not given)
    place: str


@dataclass
class Interrupt:
    address: str                   # %IX9.0: the SINGLE variable's address
    device: str
    source: str                    # ACK
    irq: int                       # the line the resource module requests
    tasks: list                    # the resource's tasks it wakes (names)
    place: str


@dataclass
class ResourceIO:
    resource: str
    devices: dict = field(default_factory=dict)    # upper name -> Device
    bindings: list = field(default_factory=list)
    interrupts: list = field(default_factory=list)
    config: str = ""

    def user_node(self, dev) -> str:
        """The character device of user device *dev* (iec_io_user.c)."""
        return f"/dev/iec_io_{self.config}_{self.resource}_{dev.name}".lower()

    def _device_manifest(self, d) -> dict:
        m = {"name": d.name, "provider": d.provider, "board": d.board, "minor": d.minor}
        if d.provider == "user":
            m.update(node=self.user_node(d), inputs=d.inputs, outputs=d.outputs,
                     stale_ms=d.stale_ms)
        return m

    def manifest(self) -> dict:
        return {
            "devices": [self._device_manifest(d) for d in self.devices.values()],
            "bindings": [{"address": b.address, "device": b.device, "subdevice": b.subdevice,
                          "channel": b.channel, "kind": b.kind, "type": b.type,
                          "scale": b.scale, "range": b.range, "safe": b.safe,
                          "bits": b.bits, "lo": b.lo, "hi": b.hi}
                         for b in self.bindings],
            "interrupts": [{"address": q.address, "device": q.device, "source": q.source,
                            "irq": q.irq, "tasks": q.tasks} for q in self.interrupts],
        }


_TOKEN = re.compile(r"""
    (?P<addr>%[A-Za-z*]+[0-9.]*)
  | (?P<target>[A-Za-z_]\w*(?:\.\w+)+)
  | (?P<span>-?\d+(?:\.\d+)?\.\.-?\d+(?:\.\d+)?)
  | (?P<num>-?\d+(?:\.\d+)?)
  | (?P<word>[A-Za-z_]\w*)
  | (?P<punct>[:,])
  | (?P<other>\S+)
""", re.X)


class _Line:
    """The tokens of one statement: (kind, text, column)."""

    def __init__(self, text):
        self.toks = [(m.lastgroup, m.group(), m.start() + 1) for m in _TOKEN.finditer(text)]
        self.i = 0
        self.end_col = len(text.rstrip()) + 1

    def peek(self):
        return self.toks[self.i] if self.i < len(self.toks) else (None, "", self.end_col)

    def take(self):
        t = self.peek()
        self.i += 1
        return t

    def keyword(self, word):
        k, text, _ = self.peek()
        if k == "word" and text.upper() == word:
            self.i += 1
            return True
        return False


class _Error(Exception):
    def __init__(self, col, message):
        super().__init__(message)
        self.col = col
        self.message = message


def _strip_comment(line: str) -> str:
    i = line.find("#")
    return line if i < 0 else line[:i]


def _int(tok, what):
    kind, text, col = tok
    if kind != "num" or "." in text or text.startswith("-"):
        raise _Error(col, f"expected {what} (a whole number), found "
                          f"{repr(text) if text else 'the end of the line'}")
    return int(text)


def _expect(line, kind, what):
    tok = line.take()
    if tok[0] != kind:
        raise _Error(tok[2], f"expected {what}, found "
                             f"{repr(tok[1]) if tok[1] else 'the end of the line'}")
    return tok


def _end(line):
    k, text, col = line.peek()
    if k is not None:
        raise _Error(col, f"unexpected {text!r}")


class _MapChecker:
    def __init__(self, cfg, diags):
        self.cfg = cfg
        self.diags = diags
        self.res_names = {r.name.upper(): r.name for r in cfg.resources}
        self.bound = {}            # address -> place of its binding
        self.user_out = {}         # (resource, device, output slot) -> place

    def error(self, src, line, col, message):
        self.diags.error(src, None, message, line=line, col=col)

    def check(self, src: SourceFile):
        resource = None
        devices = None
        for n, raw in enumerate(src.text.split("\n"), 1):
            line = _Line(_strip_comment(raw))
            if not line.toks:
                continue
            try:
                kind, text, col = line.peek()
                up = text.upper()
                if kind == "word" and up == "RESOURCE":
                    line.take()
                    tok = _expect(line, "word", "a resource name")
                    _end(line)
                    name = self.res_names.get(tok[1].upper())
                    if name is None:
                        raise _Error(tok[2], f"unknown resource '{tok[1]}': the configuration "
                                             f"has {', '.join(self.res_names.values()) or 'none'}")
                    resource = self.cfg.io.setdefault(name.upper(),
                                                      ResourceIO(name, config=self.cfg.name))
                    devices = resource.devices
                    continue
                if resource is None:
                    if len(self.res_names) != 1:
                        raise _Error(col, "which resource: the configuration has "
                                          f"{len(self.res_names)}; begin with RESOURCE name")
                    name = next(iter(self.res_names.values()))
                    resource = self.cfg.io.setdefault(name.upper(),
                                                      ResourceIO(name, config=self.cfg.name))
                    devices = resource.devices
                if kind == "word" and up == "DEVICE":
                    line.take()
                    self.device(src, n, line, devices)
                elif kind == "word" and up == "SUBDEVICE":
                    line.take()
                    self.subdevice(src, n, line, devices)
                elif kind == "word" and up == "INTERRUPT":
                    line.take()
                    self.interrupt(src, n, line, resource)
                elif kind == "addr":
                    self.binding(src, n, line, resource)
                else:
                    raise _Error(col, f"expected RESOURCE, DEVICE, SUBDEVICE, INTERRUPT or an "
                                      f"address (%IX0.0 : device.subdevice.channel), found "
                                      f"{text!r}")
            except _Error as exc:
                self.error(src, n, exc.col, exc.message)

    # -----------------------------------------------------------------
    def device(self, src, n, line, devices):
        name_tok = _expect(line, "word", "a device name")
        _expect(line, "punct", "':' and a provider")
        prov = _expect(line, "word", "a provider")
        if prov[1].lower() not in PROVIDERS:
            raise _Error(prov[2], f"unknown provider '{prov[1]}': the providers are "
                                  f"{', '.join(PROVIDERS)}")
        if prov[1].lower() == "user":
            return self.user_device(src, n, line, devices, name_tok)
        board = None
        subs = {}
        k, text, col = line.peek()
        if k == "word" and text.upper() != "MINOR":
            line.take()
            if text.lower() not in BOARDS:
                raise _Error(col, f"unknown board '{text}': the known boards are "
                                  f"{', '.join(sorted(BOARDS))}; for another, leave the board "
                                  "out and declare its subdevices (SUBDEVICE name.N : kind "
                                  "channels)")
            board = text.lower()
            subs = {s.index: Subdevice(s.index, s.kind, s.channels, s.bits, list(s.ranges))
                    for s in BOARDS[board]}
        minor = 0
        if line.keyword("MINOR"):
            minor = _int(line.take(), "a comedi minor number")
            if minor > 15:
                raise _Error(line.toks[line.i - 1][2], f"minor {minor} is out of range: "
                                                        "comedi has /dev/comedi0..15")
        _end(line)
        key = name_tok[1].upper()
        if key in devices:
            raise _Error(name_tok[2], f"device '{name_tok[1]}' is already declared "
                                      f"({devices[key].place})")
        for d in devices.values():
            if d.provider == "comedi" and d.minor == minor:
                raise _Error(name_tok[2], f"device '{name_tok[1]}' is /dev/comedi{minor}, "
                                          f"already declared as '{d.name}' ({d.place})")
        devices[key] = Device(name_tok[1], prov[1].lower(), board, minor, subs,
                              f"{src.path}:{n}")

    def user_device(self, src, n, line, devices, name_tok):
        counts = {"INPUTS": None, "OUTPUTS": None}
        stale = None
        while line.peek()[0] is not None:
            k, text, col = line.peek()
            up = text.upper()
            if k == "word" and up in counts:
                line.take()
                if counts[up] is not None:
                    raise _Error(col, f"{up} is given twice")
                ct = line.peek()
                counts[up] = _int(line.take(), f"a number of {up.lower()[:-1]} slots")
                if counts[up] > USER_MAX_SLOTS:
                    raise _Error(ct[2], f"{counts[up]} {up.lower()}: a user device has at "
                                        f"most {USER_MAX_SLOTS}")
            elif k == "word" and up == "STALE":
                line.take()
                if stale is not None:
                    raise _Error(col, "STALE is given twice")
                if line.keyword("OFF"):
                    stale = 0
                else:
                    st = line.peek()
                    stale = _int(line.take(), "a staleness timeout in ms, or OFF")
                    if not 1 <= stale <= 3_600_000:
                        raise _Error(st[2], f"STALE {stale}: 1 to 3600000 ms, or OFF")
            elif k == "word" and up == "MINOR":
                raise _Error(col, "a user device has no minor: its character device is "
                                  "named after the configuration, resource and device")
            else:
                raise _Error(col, f"unexpected {text!r}: a user device takes INPUTS n, "
                                  "OUTPUTS n and STALE ms|OFF")
        if not counts["INPUTS"] and not counts["OUTPUTS"]:
            raise _Error(line.end_col, "a user device needs slots: INPUTS n and/or OUTPUTS n")
        key = name_tok[1].upper()
        if key in devices:
            raise _Error(name_tok[2], f"device '{name_tok[1]}' is already declared "
                                      f"({devices[key].place})")
        devices[key] = Device(name_tok[1], "user", None, 0, {}, f"{src.path}:{n}",
                              inputs=counts["INPUTS"] or 0, outputs=counts["OUTPUTS"] or 0,
                              stale_ms=USER_STALE_MS if stale is None else stale)

    def subdevice(self, src, n, line, devices):
        k, text, col = _expect(line, "target", "device.N")
        dev_name, _, index = text.partition(".")
        dev = devices.get(dev_name.upper())
        if dev is None:
            raise _Error(col, f"unknown device '{dev_name}': declare it first "
                              "(DEVICE name : comedi MINOR n)")
        if dev.provider == "user":
            raise _Error(col, f"device '{dev.name}' is a user device: its slots are "
                              "declared by INPUTS and OUTPUTS")
        if dev.board is not None:
            raise _Error(col, f"device '{dev.name}' is a {dev.board}, whose subdevices are "
                              "known; SUBDEVICE describes a board given without a name")
        if not index.isdigit():
            raise _Error(col + len(dev_name) + 1, "expected a subdevice number after the '.'")
        _expect(line, "punct", "':' and a kind (AI, AO, DI, DO, DIO)")
        kt = _expect(line, "word", "a kind (AI, AO, DI, DO, DIO)")
        kind = kt[1].upper()
        if kind not in KINDS:
            raise _Error(kt[2], f"unknown subdevice kind '{kt[1]}': AI, AO, DI, DO or DIO")
        ct = line.peek()
        channels = _int(line.take(), "a channel count")
        if not 1 <= channels <= 256:
            raise _Error(ct[2], f"{channels} channels: a subdevice has 1 to 256")
        bits, ranges = 1, []
        if kind in ANALOG:
            bits = 16
            if line.keyword("BITS"):
                bt = line.peek()
                bits = _int(line.take(), "a resolution in bits")
                if not 1 <= bits <= 32:
                    raise _Error(bt[2], f"{bits} bits: a sample has 1 to 32")
            if line.keyword("RANGE"):
                while True:
                    st = _expect(line, "span", "a range lo..hi (volts)")
                    lo, hi = (float(x) for x in st[1].split(".."))
                    if not lo < hi:
                        raise _Error(st[2], f"range {st[1]}: lo must be below hi")
                    ranges.append((lo, hi))
                    if line.peek()[1] != ",":
                        break
                    line.take()
        _end(line)
        i = int(index)
        if i in dev.subdevices:
            raise _Error(col, f"subdevice {dev.name}.{i} is already declared")
        dev.subdevices[i] = Subdevice(i, kind, channels, bits, ranges)

    # -----------------------------------------------------------------
    def interrupt(self, src, n, line, resource):
        """INTERRUPT %IXa.b : device.SOURCE IRQ n"""
        _, addr, acol = _expect(line, "addr", "the address of an event task's SINGLE "
                                              "variable (%IX0.0)")
        addr = addr.upper()
        _expect(line, "punct", "':' and device.SOURCE")
        _, target, tcol = _expect(line, "target", "device.SOURCE (e.g. lpt.ACK)")
        if not line.keyword("IRQ"):
            k, text, col = line.peek()
            raise _Error(col, f"expected IRQ and the interrupt line's number, found "
                              f"{repr(text) if text else 'the end of the line'}")
        irq_tok = line.peek()
        irq = _int(line.take(), "an IRQ number")
        _end(line)
        if not 1 <= irq <= 255:
            raise _Error(irq_tok[2], f"IRQ {irq} is out of range: 1..255")
        if not addr.startswith("%IX") or addr.endswith("*"):
            raise _Error(acol, f"{addr}: an interrupt wakes the tasks whose SINGLE is a "
                               "BOOL input: bind a bit input address (%IX)")
        info = self.cfg.located.get(addr)
        if info is None:
            raise _Error(acol, f"no located variable at {addr}: declare one (name AT {addr} : "
                               "BOOL) and name it in a TASK's SINGLE")
        res = next(r for r in self.cfg.resources
                   if r.name.upper() == resource.resource.upper())
        tasks = [t.name for t in res.tasks.values()
                 if t.single is not None and (t.single.location or "").upper() == addr]
        if not tasks:
            raise _Error(acol, f"no TASK of resource {resource.resource} has SINGLE := the "
                               f"variable at {addr}: an interrupt wakes event tasks")
        first = self.bound.get(addr)
        if first is not None:
            raise _Error(acol, f"{addr} is already bound ({first}): one address is bound "
                               "to one channel or interrupt")
        dev_name, _, source = target.partition(".")
        dev = resource.devices.get(dev_name.upper())
        if dev is None:
            raise _Error(tcol, f"unknown device '{dev_name}' in resource "
                               f"{resource.resource}: declare it with DEVICE {dev_name} : "
                               "comedi ... before its interrupts")
        scol = tcol + len(dev_name) + 1
        sources = INTERRUPTS.get(dev.board or "", {})
        if source.upper() not in sources:
            have = (f"its interrupt sources are {', '.join(sorted(sources))}" if sources else
                    "it has no interrupt source the provider knows (boards with one: "
                    f"{', '.join(sorted(INTERRUPTS))})")
            raise _Error(scol, f"device '{dev.name}' ({dev.board or 'board not named'}) has no "
                               f"interrupt source '{source}': {have}")
        for q in resource.interrupts:
            if q.device.upper() == dev.name.upper() and q.source == source.upper():
                raise _Error(tcol, f"{dev.name}.{q.source} already wakes the tasks of "
                                   f"{q.address} ({q.place})")
        place = f"{src.path}:{n}:{acol}"
        self.bound[addr] = place
        resource.interrupts.append(Interrupt(addr, dev.name, source.upper(), irq, tasks, place))

    # -----------------------------------------------------------------
    def binding(self, src, n, line, resource):
        _, addr, acol = line.take()
        addr = addr.upper()
        _expect(line, "punct", "':' and device.subdevice.channel")
        tk, target, tcol = _expect(line, "target", "device.subdevice.channel")
        range_tok = safe_tok = None
        rng, safe = 0, None
        while line.peek()[0] is not None:
            k, text, col = line.peek()
            if line.keyword("RANGE"):
                range_tok = line.peek()
                rng = _int(line.take(), "a range number")
            elif line.keyword("SAFE"):
                safe_tok = line.take()
                if safe_tok[0] == "word" and safe_tok[1].upper() in ("HOLD", "TRUE", "FALSE"):
                    safe = safe_tok[1].upper()
                elif safe_tok[0] == "num":
                    safe = float(safe_tok[1]) if "." in safe_tok[1] else int(safe_tok[1])
                else:
                    raise _Error(safe_tok[2], "expected a safe value: HOLD, TRUE, FALSE or "
                                              "a number")
            else:
                raise _Error(col, f"unexpected {text!r}: a binding may end with RANGE n "
                                  "and SAFE value")
        place = f"{src.path}:{n}:{acol}"
        if addr[1] == "M":
            raise _Error(acol, f"{addr} is memory: only %I and %Q addresses reach devices")
        if addr[1] not in "IQ" or addr.endswith("*"):
            raise _Error(acol, f"{addr} is not a complete input or output address")
        info = self.cfg.located.get(addr)
        if info is None:
            raise _Error(acol, f"no located variable at {addr}: declare one (name AT {addr} : "
                               "type) in the configuration, the resource or a program")
        vtype, owners = info
        if resource.resource.upper() not in {o.upper() for o in owners}:
            where = f"resource {', '.join(sorted(owners))}" if owners else "no resource"
            raise _Error(acol, f"{addr} is used by {where}, not by {resource.resource}")
        first = self.bound.get(addr)
        if first is not None:
            raise _Error(acol, f"{addr} is already bound ({first}): one address is bound "
                               "to one channel")
        parts = target.split(".")
        dev = resource.devices.get(parts[0].upper())
        if dev is None:
            raise _Error(tcol, f"unknown device '{parts[0]}' in resource "
                               f"{resource.resource}: declare it with DEVICE "
                               f"{parts[0]} : comedi ... before its bindings")
        if dev.provider == "user":
            return self.user_binding(src, n, resource, dev, addr, acol, target, tcol,
                                     vtype, range_tok, safe_tok, safe, place)
        if len(parts) != 3 or not all(p.isdigit() for p in parts[1:]):
            raise _Error(tcol, f"expected device.subdevice.channel (numbers), found {target!r}")
        si, ch = int(parts[1]), int(parts[2])
        sub = dev.subdevices.get(si)
        scol = tcol + len(parts[0]) + 1
        ccol = scol + len(parts[1]) + 1
        if sub is None:
            have = ", ".join(f"{s.index} ({s.kind})" for s in
                             sorted(dev.subdevices.values(), key=lambda s: s.index)) or "none"
            raise _Error(scol, f"device '{dev.name}' has no subdevice {si}; it has {have}")
        if ch >= sub.channels:
            raise _Error(ccol, f"channel {ch} is out of range: subdevice {dev.name}.{si} "
                               f"({sub.kind}) has channels 0..{sub.channels - 1}")
        is_input = addr[1] == "I"
        if is_input and sub.kind not in INPUT_KINDS:
            raise _Error(scol, f"{addr} is an input; subdevice {dev.name}.{si} is {sub.kind}, "
                               "an output")
        if not is_input and sub.kind not in OUTPUT_KINDS:
            raise _Error(scol, f"{addr} is an output; subdevice {dev.name}.{si} is {sub.kind}, "
                               "an input")
        base = getattr(vtype, "base", vtype)
        tname = getattr(base, "name", "?")
        cat = getattr(base, "cat", None)
        tbits = getattr(base, "bits", 0)
        lo = hi = 0.0
        if sub.kind in ANALOG:
            if cat == "bool":
                raise _Error(acol, f"{addr} is a bit (BOOL); channel {dev.name}.{si}.{ch} is "
                                   f"analog ({sub.bits} bits): bind a word (%{addr[1]}W, UINT "
                                   "or WORD) or a double word (%" + addr[1] + "D, REAL)")
            if cat == "real":
                scale = "phys"
            elif cat in ("uint", "bit"):
                scale = "raw"
                if tbits < sub.bits:
                    raise _Error(acol, f"{addr} is {tname} ({tbits} bits); channel "
                                       f"{dev.name}.{si}.{ch} gives {sub.bits}-bit samples")
            elif cat == "sint":
                scale = "raw"
                if tbits <= sub.bits:
                    raise _Error(acol, f"{addr} is {tname}, up to {(1 << (tbits - 1)) - 1}; "
                                       f"channel {dev.name}.{si}.{ch} gives samples up to "
                                       f"{(1 << sub.bits) - 1}: use an unsigned type (U{tname}) "
                                       "or REAL")
            else:
                raise _Error(acol, f"{addr} is {tname}: an analog channel gives an integer "
                                   "count or a REAL value")
            if range_tok is not None and rng >= len(sub.ranges):
                raise _Error(range_tok[2], f"range {rng} is out of range: subdevice "
                                           f"{dev.name}.{si} has {len(sub.ranges)} "
                                           f"(0..{len(sub.ranges) - 1})" if sub.ranges else
                             f"range {rng}: subdevice {dev.name}.{si} declares no range")
            if scale == "phys":
                if not sub.ranges:
                    raise _Error(acol, f"{addr} is {tname}: a physical value needs the "
                                       f"ranges of subdevice {dev.name}.{si} (RANGE lo..hi)")
                lo, hi = sub.ranges[rng]
        else:
            if cat != "bool":
                raise _Error(acol, f"{addr} is {tname}; channel {dev.name}.{si}.{ch} is one "
                                   f"digital line: bind a bit address (%{addr[1]}X) of a BOOL")
            if range_tok is not None:
                raise _Error(range_tok[2], "RANGE applies to analog channels only")
            scale = "bit"
        if safe_tok is not None:
            safe = _safe_value(safe_tok, safe, is_input, scale == "bit", "an analog output")
            if scale != "bit" and safe != "HOLD":
                if scale == "raw" and (not isinstance(safe, int) or
                                       not 0 <= safe <= (1 << sub.bits) - 1):
                    raise _Error(safe_tok[2], f"safe value {safe_tok[1]} does not fit: "
                                              f"{tname} counts 0..{(1 << sub.bits) - 1} on "
                                              f"this channel")
                if scale == "phys" and not lo <= safe <= hi:
                    raise _Error(safe_tok[2], f"safe value {safe_tok[1]} is outside the "
                                              f"channel's range {lo:g}..{hi:g}")
        elif not is_input:
            safe = 0
        self.bound[addr] = place
        resource.bindings.append(Binding(addr, dev.name, si, ch, sub.kind, tname, scale,
                                         sub.bits, rng, lo, hi, safe, place))

    def user_binding(self, src, n, resource, dev, addr, acol, target, tcol, vtype,
                     range_tok, safe_tok, safe, place):
        parts = target.split(".")
        if len(parts) != 2 or not parts[1].isdigit():
            raise _Error(tcol, f"expected device.slot (a number) for user device "
                               f"'{dev.name}', found {target!r}")
        slot = int(parts[1])
        is_input = addr[1] == "I"
        count = dev.inputs if is_input else dev.outputs
        what = "input" if is_input else "output"
        scol = tcol + len(parts[0]) + 1
        if slot >= count:
            raise _Error(scol, f"{what} slot {slot} is out of range: user device '{dev.name}' "
                               f"has {count} {what} slots" +
                               (f" (0..{count - 1})" if count else
                                f"; declare them with {what.upper()}S n"))
        base = getattr(vtype, "base", vtype)
        tname = getattr(base, "name", "?")
        if tname not in USER_TYPES:
            raise _Error(acol, f"{addr} is {tname}: a user slot carries 32 bits: BOOL, SINT, "
                               "INT, DINT, USINT, UINT, UDINT, BYTE, WORD, DWORD or REAL")
        if range_tok is not None:
            raise _Error(range_tok[2], "RANGE applies to analog comedi channels only")
        if safe_tok is not None:
            safe = _safe_value(safe_tok, safe, is_input, tname == "BOOL", f"a {tname} output")
            if tname not in ("BOOL", "REAL") and safe != "HOLD":
                lo, hi = USER_RANGES[tname]
                if not isinstance(safe, int) or not lo <= safe <= hi:
                    raise _Error(safe_tok[2], f"safe value {safe_tok[1]} does not fit "
                                              f"{tname} ({lo}..{hi})")
        elif not is_input:
            safe = 0
        if not is_input:
            key = (resource.resource.upper(), dev.name.upper(), slot)
            if key in self.user_out:
                raise _Error(scol, f"output slot {dev.name}.{slot} is already driven "
                                   f"({self.user_out[key]}): one output per slot")
            self.user_out[key] = place
        self.bound[addr] = place
        resource.bindings.append(Binding(addr, dev.name, None, slot, "USER", tname, "word",
                                         32, 0, 0.0, 0.0, safe, place))

def _safe_value(safe_tok, safe, is_input: bool, is_bool: bool, what: str):
    """What every provider's SAFE shares: an input has none; a BOOL output's
    is TRUE, FALSE (1, 0) or HOLD; another output's a number or HOLD (what:
    the output, for the message).  Returns the value, 1/0 for TRUE/FALSE;
    the range of a number is the provider's to check."""
    if is_input:
        raise _Error(safe_tok[2], "SAFE applies to outputs: an input has no safe state")
    if is_bool:
        if safe not in ("HOLD", "TRUE", "FALSE", 0, 1):
            raise _Error(safe_tok[2], f"safe value {safe_tok[1]} of a BOOL output: "
                                      "TRUE, FALSE or HOLD")
        return {"TRUE": 1, "FALSE": 0}.get(safe, safe)
    if safe != "HOLD" and isinstance(safe, str):
        raise _Error(safe_tok[2], f"safe value {safe_tok[1]} of {what}: a number or HOLD")
    return safe


def _real(x: float, type_name: str) -> float:
    """x as the variable holds it: a REAL is the nearest binary32."""
    if type_name.upper() == "LREAL":
        return float(x)
    return struct.unpack("<f", struct.pack("<f", float(x)))[0]


def phys_of(lo: float, hi: float, bits: int, raw: int, type_name: str = "REAL") -> float:
    """The REAL/LREAL value of raw sample *raw* of a channel with range
    lo..hi: the kernel's arithmetic (kmod_templates/kernel/iec_io_real.c),
    IEEE binary64 operation by operation, then rounded to a REAL."""
    maxdata = (1 << bits) - 1
    return _real(float(lo) + float(raw) * (float(hi) - float(lo)) / float(maxdata), type_name)


def raw_of(lo: float, hi: float, bits: int, value: float, type_name: str = "REAL") -> int:
    """The raw sample the kernel writes for output value *value*: the
    nearest one (halves up), clamped to 0..2**bits-1, NaN gives 0
    (iec_io_real.c, the same binary64 arithmetic)."""
    maxdata = (1 << bits) - 1
    v = _real(value, type_name)
    t = (v - float(lo)) * float(maxdata) / (float(hi) - float(lo)) + 0.5
    if not t >= 1.0:
        return 0
    if t >= float(maxdata):
        return maxdata
    return int(math.floor(t))


def check_maps(project, sources, diags) -> None:
    """Reads the .iomap sources into project.configurations[0].io (resource
    name upper -> ResourceIO), reporting every error to diags."""
    cfgs = getattr(project, "configurations", None) or []
    if not sources:
        return
    if not cfgs:
        src = sources[0]
        diags.error(src, 0, "an I/O map needs a CONFIGURATION whose resources it binds")
        return
    checker = _MapChecker(cfgs[0], diags)
    for src in sources:
        checker.check(src)


def io_of(project) -> dict:
    """Resource name (upper) -> ResourceIO of the project's I/O map."""
    cfgs = getattr(project, "configurations", None) or []
    return dict(getattr(cfgs[0], "io", {}) or {}) if cfgs else {}
