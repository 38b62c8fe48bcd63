# SPDX-License-Identifier: MIT
"""Generic netlink client of the configuration module (pyroute2 0.9).

The protocol is defined in ``kmod_templates/kernel/iec_nl.h``; the numbers
below mirror it (a unit test compares both).  One attribute space serves
every nest, so one pyroute2 ``nla`` class decodes resources, tasks, slots
and variables alike.
"""

from __future__ import annotations

import errno
import logging
from dataclasses import dataclass, field
from typing import Iterable, List, Optional, Sequence, Tuple

from .errors import NotLoaded, PLCError

FAMILY = "iec2kmod"
VERSION = 1
VALUE_MAX = 65000
MAX_VARS = 256
MAX_FORCES = 128

COMMANDS = ["IEC_CMD_UNSPEC", "IEC_CMD_STATUS", "IEC_CMD_VAR_GET", "IEC_CMD_VAR_LIST",
            "IEC_CMD_VAR_SET", "IEC_CMD_VAR_FORCE", "IEC_CMD_VAR_UNFORCE",
            "IEC_CMD_RES_START", "IEC_CMD_RES_STOP", "IEC_CMD_SLOT_CLEAR",
            "IEC_CMD_SLOT_PUBLISH", "IEC_CMD_SLOT_UNSTAGE"]
CMD = {name: i for i, name in enumerate(COMMANDS)}

NEST = "nest"
# (attribute, pyroute2 type); the index is the attribute number
ATTRIBUTES = [
    ("IEC_A_UNSPEC", "none"),
    ("IEC_A_PAD", "none"),
    ("IEC_A_ABI", "uint32"),
    ("IEC_A_NAME", "asciiz"),
    ("IEC_A_MODULE", "asciiz"),
    ("IEC_A_SOURCE_HASH", "asciiz"),
    ("IEC_A_IFACE_HASH", "asciiz"),
    ("IEC_A_NOW_NS", "int64"),
    ("IEC_A_RESOURCE", NEST),
    ("IEC_A_TASK", NEST),
    ("IEC_A_SLOT", NEST),
    ("IEC_A_SLOT_INDEX", "uint32"),
    ("IEC_A_CPU", "int32"),
    ("IEC_A_LAST_CPU", "uint32"),
    ("IEC_A_STATE", "uint8"),
    ("IEC_A_INTERVAL_NS", "int64"),
    ("IEC_A_PRIORITY", "int32"),
    ("IEC_A_CYCLES", "uint64"),
    ("IEC_A_OVERRUNS", "uint64"),
    ("IEC_A_FAULTS", "uint64"),
    ("IEC_A_EXEC_MIN_NS", "int64"),
    ("IEC_A_EXEC_AVG_NS", "int64"),
    ("IEC_A_EXEC_MAX_NS", "int64"),
    ("IEC_A_LAT_AVG_NS", "int64"),
    ("IEC_A_LAT_MAX_NS", "int64"),
    ("IEC_A_HIST", "cdata"),
    ("IEC_A_FAULT_NAME", "asciiz"),
    ("IEC_A_FAULT_POU", "asciiz"),
    ("IEC_A_FAULT_LINE", "int32"),
    ("IEC_A_BUILD_ID", "asciiz"),
    ("IEC_A_SLOT_IFACE", "uint64"),
    ("IEC_A_SINCE_NS", "int64"),
    ("IEC_A_PUBLICATIONS", "uint64"),
    ("IEC_A_NFORCED", "uint32"),
    ("IEC_A_VAR", NEST),
    ("IEC_A_PATH", "asciiz"),
    ("IEC_A_TABLE", "asciiz"),
    ("IEC_A_INDEX", "uint32"),
    ("IEC_A_KIND", "uint8"),
    ("IEC_A_SIZE", "uint32"),
    ("IEC_A_WRITABLE", "uint8"),
    ("IEC_A_FORCED", "uint8"),
    ("IEC_A_EVENT", "uint32"),
    ("IEC_A_TASK_INDEX", "uint32"),
    ("IEC_A_VALUE", "cdata"),
    ("IEC_A_ALL", "flag"),
    ("IEC_A_IN_CYCLE_NS", "int64"),
    ("IEC_A_SEL_EVALUATED", "uint64"),
    ("IEC_A_SEL_SKIPPED", "uint64"),
    ("IEC_A_STARTS", "uint64"),
    ("IEC_A_STARTED_NS", "int64"),
    ("IEC_A_FAULT_NS", "int64"),
    ("IEC_A_STAGED", "asciiz"),
    ("IEC_A_FIRST_RUN_NS", "int64"),
    ("IEC_A_SLOTS_ONLY", "flag"),
    ("IEC_A_FIRST_RUN_TASK", "asciiz"),
    ("IEC_A_LAST_END_NS", "int64"),
]

STATES = {0: "stopped", 1: "running", 2: "fault"}


def _classes():
    """The pyroute2 message classes (built lazily: importing pyroute2 costs
    seconds under emulation, and commands such as --help need none)."""
    from pyroute2.netlink import NLA_F_NESTED, genlmsg, nla

    class iecnla(nla):
        nla_map = tuple((i, name, "nested" if t == NEST else t)
                        for i, (name, t) in enumerate(ATTRIBUTES))

    class iecmsg(genlmsg):
        nla_map = tuple((i, name, "iecnla" if t == NEST else t,
                         NLA_F_NESTED if t == NEST else 0)
                        for i, (name, t) in enumerate(ATTRIBUTES))

    iecmsg.iecnla = iecnla
    return iecmsg


_MSG = None


def _msg_class():
    global _MSG
    if _MSG is None:
        _MSG = _classes()
    return _MSG


@dataclass
class Task:
    name: str
    resource: str
    state: str
    interval_ns: int
    priority: int
    last_cpu: int
    cycles: int
    overruns: int
    faults: int
    exec_min_ns: int
    exec_avg_ns: int
    exec_max_ns: int
    latency_avg_ns: int
    latency_max_ns: int
    histogram: List[int]
    # the last fault since the load (kept across a restart; the state says
    # whether the task is stopped on it), when it happened (CLOCK_REALTIME)
    fault: Optional[str] = None
    fault_pou: Optional[str] = None
    fault_line: Optional[int] = None
    in_cycle_ns: Optional[int] = None    # inside a cycle now, for so long
    sel_evaluated: Optional[int] = None  # --selective modules: blocks evaluated
    sel_skipped: Optional[int] = None    # and skipped
    fault_ns: Optional[int] = None
    starts: int = 0                      # since the load: more than one, restarted
    started_ns: int = 0                  # CLOCK_REALTIME of the last start
    last_end_ns: int = 0                 # CLOCK_REALTIME of the end of the last cycle

    @property
    def path(self) -> str:
        return f"{self.resource}.{self.name}"


@dataclass
class Resource:
    name: str
    module: str
    cpu: int
    tasks: List[Task] = field(default_factory=list)


@dataclass
class Slot:
    index: int
    type_name: str
    interface: str          # 16 hex digits
    module: Optional[str]
    build_id: Optional[str]
    since_ns: int
    publications: int
    staged: Optional[str] = None        # build id inserted with stage=1, not published
    first_run_ns: Optional[int] = None  # CLOCK_REALTIME of the running body's first cycle
    first_run_task: Optional[str] = None  # "res.task" whose cycle that was


@dataclass
class Status:
    abi: int
    configuration: str
    module: str
    source_hash: str
    interface_hash: str
    now_ns: int
    forced: int
    resources: List[Resource]
    slots: List[Slot]

    def slot(self, type_name: str) -> Optional[Slot]:
        for s in self.slots:
            if s.type_name.upper() == type_name.upper():
                return s
        return None

    def tasks(self) -> List[Task]:
        return [t for r in self.resources for t in r.tasks]


@dataclass
class VarValue:
    path: str
    table: str
    index: int
    kind: str
    size: int
    writable: bool
    forced: bool
    event: int
    task: int
    value: Optional[bytes] = None


_NESTS = {name for name, t in ATTRIBUTES if t == NEST}


def _flat(nl) -> dict:
    """The attributes of a message or nest in one pass (pyroute2's get_attr
    walks the list each time): name -> value, nests -> list of nests."""
    d: dict = {}
    for slot in nl["attrs"]:
        name = slot.name
        if name in _NESTS:
            d.setdefault(name, []).append(slot.get_value())
        else:
            d[name] = slot.get_value()
    return d


def _var_from(nl) -> VarValue:
    a = _flat(nl)
    return VarValue(path=a.get("IEC_A_PATH"), table=a.get("IEC_A_TABLE"),
                    index=a.get("IEC_A_INDEX"), kind=chr(a.get("IEC_A_KIND", 63)),
                    size=a.get("IEC_A_SIZE"), writable=bool(a.get("IEC_A_WRITABLE")),
                    forced=bool(a.get("IEC_A_FORCED")), event=a.get("IEC_A_EVENT"),
                    task=a.get("IEC_A_TASK_INDEX"), value=a.get("IEC_A_VALUE"))


def _task_from(nl, resource: str) -> Task:
    a = _flat(nl)
    hist = a.get("IEC_A_HIST") or b""
    return Task(
        name=a["IEC_A_NAME"], resource=resource, state=STATES.get(a["IEC_A_STATE"], "?"),
        interval_ns=a["IEC_A_INTERVAL_NS"], priority=a["IEC_A_PRIORITY"],
        last_cpu=a["IEC_A_LAST_CPU"], cycles=a["IEC_A_CYCLES"], overruns=a["IEC_A_OVERRUNS"],
        faults=a["IEC_A_FAULTS"], exec_min_ns=a["IEC_A_EXEC_MIN_NS"],
        exec_avg_ns=a["IEC_A_EXEC_AVG_NS"], exec_max_ns=a["IEC_A_EXEC_MAX_NS"],
        latency_avg_ns=a["IEC_A_LAT_AVG_NS"], latency_max_ns=a["IEC_A_LAT_MAX_NS"],
        histogram=[int.from_bytes(hist[i:i + 8], "little") for i in range(0, len(hist), 8)],
        fault=a.get("IEC_A_FAULT_NAME"), fault_pou=a.get("IEC_A_FAULT_POU"),
        fault_line=a.get("IEC_A_FAULT_LINE"), in_cycle_ns=a.get("IEC_A_IN_CYCLE_NS"),
        sel_evaluated=a.get("IEC_A_SEL_EVALUATED"), sel_skipped=a.get("IEC_A_SEL_SKIPPED"),
        fault_ns=a.get("IEC_A_FAULT_NS"), starts=a.get("IEC_A_STARTS", 0),
        started_ns=a.get("IEC_A_STARTED_NS", 0), last_end_ns=a.get("IEC_A_LAST_END_NS", 0))


def _status_from(msg) -> Status:
    a = _flat(msg)
    resources = []
    for rn in a.get("IEC_A_RESOURCE", []):
        r = _flat(rn)
        name = r["IEC_A_NAME"]
        resources.append(Resource(name=name, module=r["IEC_A_MODULE"], cpu=r["IEC_A_CPU"],
                                  tasks=[_task_from(t, name) for t in r.get("IEC_A_TASK", [])]))
    slots = []
    for sn in a.get("IEC_A_SLOT", []):
        s = _flat(sn)
        slots.append(Slot(index=s["IEC_A_SLOT_INDEX"], type_name=s["IEC_A_NAME"],
                          interface="%016x" % s["IEC_A_SLOT_IFACE"],
                          module=s.get("IEC_A_MODULE"), build_id=s.get("IEC_A_BUILD_ID"),
                          since_ns=s["IEC_A_SINCE_NS"], publications=s["IEC_A_PUBLICATIONS"],
                          staged=s.get("IEC_A_STAGED"),
                          first_run_ns=s.get("IEC_A_FIRST_RUN_NS") or None,
                          first_run_task=s.get("IEC_A_FIRST_RUN_TASK")))
    return Status(abi=a["IEC_A_ABI"], configuration=a["IEC_A_NAME"], module=a["IEC_A_MODULE"],
                  source_hash=a["IEC_A_SOURCE_HASH"], interface_hash=a["IEC_A_IFACE_HASH"],
                  now_ns=a["IEC_A_NOW_NS"], forced=a["IEC_A_NFORCED"],
                  resources=resources, slots=slots)


_ERRNO_TEXT = {
    errno.EPERM: "permission denied: the iec2kmod netlink commands need CAP_NET_ADMIN "
                 "(run plc-manager as root; status and read also admit the group given "
                 "to the configuration module as monitor_gid)",
    errno.EACCES: "the variable is read-only",
    errno.ERANGE: "the value is out of the variable's range",
    errno.EBUSY: "busy",
}


class Client:
    """One generic netlink socket bound to the family.  Raises
    :class:`NotLoaded` when no configuration module is loaded."""

    def __init__(self) -> None:
        from pyroute2.netlink.exceptions import NetlinkError
        from pyroute2.netlink.generic import GenericNetlinkSocket
        self._NetlinkError = NetlinkError
        # pyroute2 logs a missing family at ERROR level; we say it ourselves
        logging.getLogger("pyroute2").setLevel(logging.CRITICAL)
        self.sock = GenericNetlinkSocket(ext_ack=True)
        try:
            self.sock.bind(FAMILY, _msg_class())
        except NetlinkError as e:
            self.sock.close()
            if e.code == errno.ENOENT:
                raise NotLoaded("no iec2kmod configuration is loaded") from None
            raise PLCError(f"generic netlink family {FAMILY}: {e.args[1]}") from None

    def close(self) -> None:
        self.sock.close()

    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # ------------------------------------------------------------------
    def _request(self, cmd: str, attrs: Sequence = (), dump: bool = False) -> list:
        from pyroute2.netlink import NLM_F_ACK, NLM_F_DUMP, NLM_F_REQUEST
        msg = _msg_class()()
        msg["cmd"] = CMD[cmd]
        msg["version"] = VERSION
        msg["attrs"] = [list(a) for a in attrs]
        flags = NLM_F_REQUEST | (NLM_F_DUMP if dump else NLM_F_ACK)
        try:
            return list(self.sock.nlm_request(msg, msg_type=self.sock.prid, msg_flags=flags))
        except self._NetlinkError as e:
            text = e.args[1] if len(e.args) > 1 and e.args[1] else ""
            raise KernelError(e.code, _ERRNO_TEXT.get(e.code) if e.code == errno.EPERM
                              else text or _ERRNO_TEXT.get(e.code) or "") from None

    @staticmethod
    def _sel(path: str, value: Optional[bytes] = None):
        attrs = [["IEC_A_PATH", path]]
        if value is not None:
            attrs.append(["IEC_A_VALUE", value])
        return ["IEC_A_VAR", {"attrs": attrs}]

    def status(self, slots_only: bool = False) -> Status:
        """The status; *slots_only*: without the resources (resources is
        empty: a reply a fraction of the size, for polling the slots)."""
        attrs = [["IEC_A_SLOTS_ONLY", True]] if slots_only else []
        try:
            msgs = self._request("IEC_CMD_STATUS", attrs)
        except KernelError as e:
            if not (slots_only and e.code == errno.EINVAL):
                raise
            msgs = self._request("IEC_CMD_STATUS")  # a module older than the flag
        for m in msgs:
            if m["cmd"] == CMD["IEC_CMD_STATUS"] and m["attrs"]:
                return _status_from(m)
        raise PLCError("the configuration module sent no status")

    def var_list(self) -> List[VarValue]:
        return [_var_from(m) for m in self._request("IEC_CMD_VAR_LIST", dump=True)
                if m["cmd"] == CMD["IEC_CMD_VAR_LIST"] and m["attrs"]]

    def var_get(self, paths: Iterable[str]) -> List[VarValue]:
        paths = list(paths)
        out: List[VarValue] = []
        for i in range(0, len(paths), 32):
            for m in self._request("IEC_CMD_VAR_GET", [self._sel(p) for p in paths[i:i + 32]]):
                if m["cmd"] == CMD["IEC_CMD_VAR_GET"]:
                    out += [_var_from(v) for v in _flat(m).get("IEC_A_VAR", [])]
        return out

    def var_set(self, items: Sequence[Tuple[str, bytes]]) -> None:
        self._request("IEC_CMD_VAR_SET", [self._sel(p, v) for p, v in items])

    def var_force(self, items: Sequence[Tuple[str, bytes]]) -> None:
        self._request("IEC_CMD_VAR_FORCE", [self._sel(p, v) for p, v in items])

    def var_unforce(self, paths: Sequence[str] = (), everything: bool = False) -> None:
        if everything:
            self._request("IEC_CMD_VAR_UNFORCE", [["IEC_A_ALL", True]])
        else:
            self._request("IEC_CMD_VAR_UNFORCE", [self._sel(p) for p in paths])

    def start(self, resource: Optional[str] = None) -> None:
        self._request("IEC_CMD_RES_START", [["IEC_A_NAME", resource]] if resource else [])

    def stop(self, resource: Optional[str] = None) -> None:
        self._request("IEC_CMD_RES_STOP", [["IEC_A_NAME", resource]] if resource else [])

    def clear(self, slot: Optional[int] = None) -> None:
        self._request("IEC_CMD_SLOT_CLEAR", [["IEC_A_SLOT_INDEX", slot]]
                      if slot is not None else [])

    def publish(self, slot: Optional[int] = None) -> None:
        """Publishes the builds staged (insmod stage=1) in one slot or in
        every slot; returns after one grace period for the old bodies."""
        self._request("IEC_CMD_SLOT_PUBLISH", [["IEC_A_SLOT_INDEX", slot]]
                      if slot is not None else [])

    def unstage(self, slot: Optional[int] = None) -> None:
        self._request("IEC_CMD_SLOT_UNSTAGE", [["IEC_A_SLOT_INDEX", slot]]
                      if slot is not None else [])


class KernelError(PLCError):
    """A netlink command refused by the kernel: errno and its message."""

    def __init__(self, code: int, text: str) -> None:
        import os
        self.code = code
        self.text = text
        super().__init__(text or os.strerror(code))
