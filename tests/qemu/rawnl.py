# SPDX-License-Identifier: MIT
"""Raw generic netlink, raw sysfs and capability dropping for the QEMU tier
(issue 23): what a client other than plc-manager sends the kernel, with no
check of plc-manager's in between.  Runs in the guest (the host's Python in
the chroot); the numbers come from kmod_templates/kernel/iec_nl.h, parsed
here, so they are the kernel's own.

    nl = Genl()                     # resolves the "iec2kmod" family
    err, replies = nl.cmd("IEC_CMD_VAR_GET", var(path="plc.ticks"))
    err is 0 or a positive errno; replies: the attribute lists of the replies
"""

from __future__ import annotations

import ctypes
import re
import socket
import struct
from pathlib import Path

NL_H = Path(__file__).resolve().parents[2] / "kmod_templates" / "kernel" / "iec_nl.h"


def _enum(text: str, name: str) -> dict:
    body = re.search(r"enum %s \{(.*?)\};" % name, text, re.S).group(1)
    names = [m.group(1) for m in re.finditer(r"^\s*(\w+),", body, re.M)]
    return {n: i for i, n in enumerate(names)}


_TEXT = NL_H.read_text()
CMD = _enum(_TEXT, "iec_nl_cmd")
A = _enum(_TEXT, "iec_nl_attr")

NLM_F_REQUEST, NLM_F_ACK = 1, 4
NLMSG_ERROR, NLMSG_DONE = 2, 3
NLM_F_DUMP = 0x300
GENL_ID_CTRL, CTRL_CMD_GETFAMILY = 0x10, 3
CTRL_ATTR_FAMILY_ID, CTRL_ATTR_FAMILY_NAME = 1, 2
NLA_F_NESTED = 0x8000


def attr(t, data: bytes) -> bytes:
    if isinstance(t, str):
        t = A[t]
    n = 4 + len(data)
    return struct.pack("=HH", n, t) + data + b"\0" * (-n % 4)


def nest(t, *parts: bytes) -> bytes:
    return attr((A[t] if isinstance(t, str) else t) | NLA_F_NESTED, b"".join(parts))


def var(path=None, value: bytes | None = None, raw_path: bytes | None = None) -> bytes:
    """A VAR nest: PATH (raw_path: exactly these bytes) and VALUE."""
    parts = []
    if raw_path is not None:
        parts.append(attr("IEC_A_PATH", raw_path))
    elif path is not None:
        parts.append(attr("IEC_A_PATH", path.encode() + b"\0"))
    if value is not None:
        parts.append(attr("IEC_A_VALUE", value))
    return nest("IEC_A_VAR", *parts)


def parse(buf: bytes) -> list:
    out, off = [], 0
    while off + 4 <= len(buf):
        n, t = struct.unpack_from("=HH", buf, off)
        if n < 4:
            break
        out.append((t & 0x3FFF, buf[off + 4:off + n]))
        off += (n + 3) & ~3
    return out


def string_value(text: str) -> bytes:
    """A STRING's VALUE: its length (u16), its characters and the NUL."""
    b = text.encode()
    return struct.pack("=H", len(b)) + b + b"\0"


class Genl:
    def __init__(self, family: str = "iec2kmod"):
        self.s = socket.socket(socket.AF_NETLINK, socket.SOCK_RAW, 16)  # NETLINK_GENERIC
        self.s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 21)
        self.s.bind((0, 0))
        self.s.settimeout(30)
        self.seq = 0
        err, replies = self.request(GENL_ID_CTRL, CTRL_CMD_GETFAMILY,
                                    attr(CTRL_ATTR_FAMILY_NAME, family.encode() + b"\0"))
        assert err == 0, f"family {family}: errno {err}"
        self.family = struct.unpack("=H", dict(replies[0])[CTRL_ATTR_FAMILY_ID][:2])[0]

    def request(self, ftype: int, cmd: int, payload: bytes = b"", dump: bool = False):
        """(0 or the errno, the replies' attribute lists); a dump ends
        with NLMSG_DONE (its error), a request with its ack."""
        self.seq += 1
        body = struct.pack("=BBH", cmd, 1, 0) + payload
        flags = NLM_F_REQUEST | (NLM_F_DUMP if dump else NLM_F_ACK)
        self.s.send(struct.pack("=IHHII", 16 + len(body), ftype, flags, self.seq, 0) + body)
        replies = []
        while True:
            data = self.s.recv(1 << 21)
            off = 0
            while off + 16 <= len(data):
                ln, typ, _flags, seq, _pid = struct.unpack_from("=IHHII", data, off)
                if seq == self.seq:
                    if typ in (NLMSG_ERROR, NLMSG_DONE):
                        return -struct.unpack_from("=i", data, off + 16)[0], replies
                    replies.append(parse(data[off + 20:off + ln]))
                off += (ln + 3) & ~3

    def cmd(self, cmd: str, *attrs: bytes, dump: bool = False):
        return self.request(self.family, CMD[cmd], b"".join(attrs), dump=dump)

    def get(self, *paths: str) -> dict:
        """VAR_GET: {path: VALUE bytes}; raises on an error."""
        err, replies = self.cmd("IEC_CMD_VAR_GET", *(var(p) for p in paths))
        assert err == 0, f"VAR_GET {paths}: errno {err}"
        out = {}
        for t, data in replies[0]:
            if t == A["IEC_A_VAR"]:
                d = dict(parse(data))
                out[d[A["IEC_A_PATH"]].rstrip(b"\0").decode()] = d[A["IEC_A_VALUE"]]
        return out

    def get_int(self, path: str, fmt: str = "=h") -> int:
        return struct.unpack(fmt, self.get(path)[path])[0]


def drop_capabilities():
    """capset(): no capability left (uid stays 0), as `capsh --drop=all`."""
    class Hdr(ctypes.Structure):
        _fields_ = [("version", ctypes.c_uint32), ("pid", ctypes.c_int)]

    class Data(ctypes.Structure):
        _fields_ = [("effective", ctypes.c_uint32), ("permitted", ctypes.c_uint32),
                    ("inheritable", ctypes.c_uint32)]

    libc = ctypes.CDLL(None, use_errno=True)
    hdr, data = Hdr(0x20080522, 0), (Data * 2)()      # _LINUX_CAPABILITY_VERSION_3
    if libc.capset(ctypes.byref(hdr), data) != 0:
        raise OSError(ctypes.get_errno(), "capset")
    status = Path("/proc/self/status").read_text()
    assert re.search(r"^CapEff:\s+0+$", status, re.M), status


def become(uid: int, groups: list):
    """setgroups/setgid/setuid: an ordinary user (no capability left)."""
    import os
    os.setgroups(groups)
    os.setgid(groups[0] if groups else uid)
    os.setuid(uid)


def sysfs_write(path: str, data: bytes) -> int:
    """One write(2) of exactly these bytes; 0 or the errno."""
    import os
    try:
        fd = os.open(path, os.O_WRONLY)
    except OSError as e:
        return e.errno
    try:
        os.write(fd, data)
        return 0
    except OSError as e:
        return e.errno
    finally:
        os.close(fd)
