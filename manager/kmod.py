# SPDX-License-Identifier: MIT
"""Kernel modules without kmod's tools: finit_module(2) and delete_module(2)
through ctypes (no fork/exec on the swap path), /proc/modules, a module
file's .modinfo (vermagic, name), and the kernel log lines a failed insert
leaves behind (/dev/kmsg)."""

from __future__ import annotations

import ctypes
import errno
import os
import platform
import struct
from typing import Dict, List, Optional

from .errors import PLCError

# syscall numbers: finit_module, delete_module
_SYSCALLS = {"x86_64": (313, 176), "aarch64": (273, 106), "riscv64": (273, 106),
             "i686": (350, 129), "armv7l": (379, 129)}

CAP_NET_ADMIN = 12
CAP_SYS_MODULE = 16


class ModuleError(PLCError):
    def __init__(self, message: str, code: int = 0) -> None:
        super().__init__(message)
        self.code = code


_libc = None


def _syscall(nr_index: int, *args) -> int:
    global _libc
    if _libc is None:
        _libc = ctypes.CDLL(None, use_errno=True)
    nrs = _SYSCALLS.get(platform.machine())
    if nrs is None:
        raise ModuleError(f"unsupported architecture {platform.machine()}")
    ret = _libc.syscall(ctypes.c_long(nrs[nr_index]), *args)
    return 0 if ret == 0 else ctypes.get_errno()


def capabilities() -> int:
    """The effective capability set of this process."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("CapEff:"):
                    return int(line.split()[1], 16)
    except OSError:
        pass
    return 0


def require(cap: int, what: str) -> None:
    if not capabilities() & (1 << cap):
        name = {CAP_SYS_MODULE: "CAP_SYS_MODULE", CAP_NET_ADMIN: "CAP_NET_ADMIN"}[cap]
        raise PLCError(f"{what} needs {name}: run plc-manager as root")


# --------------------------------------------------------------- kmsg ----

class KernelLog:
    """New kernel log records since construction (needs /dev/kmsg)."""

    def __init__(self) -> None:
        self.fd: Optional[int] = None
        try:
            self.fd = os.open("/dev/kmsg", os.O_RDONLY | os.O_NONBLOCK)
            os.lseek(self.fd, 0, os.SEEK_END)
        except OSError:
            self.fd = None

    def lines(self) -> List[str]:
        out: List[str] = []
        if self.fd is None:
            return out
        while True:
            try:
                rec = os.read(self.fd, 8192)
            except BlockingIOError:
                break
            except OSError as e:
                if e.errno == errno.EPIPE:       # overwritten records: go on
                    continue
                break
            if not rec:
                break
            text = rec.decode("utf-8", "replace")
            msg = text.split(";", 1)[1] if ";" in text else text
            out.append(msg.split("\n", 1)[0])
        return out

    def close(self) -> None:
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None


# ------------------------------------------------------------ modules ----

def loaded() -> Dict[str, dict]:
    """/proc/modules: name -> {refcnt, holders (by name), state}."""
    out: Dict[str, dict] = {}
    try:
        with open("/proc/modules") as f:
            for line in f:
                w = line.split()
                if len(w) < 5:
                    continue
                deps = [d for d in w[3].split(",") if d and d != "-"]
                out[w[0]] = {"refcnt": int(w[2]), "used_by": deps, "state": w[4]}
    except OSError:
        pass
    return out


def holders(name: str) -> List[str]:
    """Modules that use symbols of *name*."""
    try:
        return sorted(os.listdir(f"/sys/module/{name}/holders"))
    except OSError:
        return []


def refcnt(name: str) -> Optional[int]:
    try:
        with open(f"/sys/module/{name}/refcnt") as f:
            return int(f.read())
    except (OSError, ValueError):
        return None


def insert(path: str, params: str = "") -> None:
    """finit_module(2); raises :class:`ModuleError` with the kernel's reason."""
    log = KernelLog()
    try:
        fd = os.open(path, os.O_RDONLY | os.O_CLOEXEC)
    except OSError as e:
        log.close()
        raise ModuleError(f"{path}: {e.strerror}", e.errno) from None
    try:
        err = _syscall(0, ctypes.c_int(fd), ctypes.c_char_p(params.encode()), ctypes.c_int(0))
    finally:
        os.close(fd)
    if err:
        name = os.path.basename(path)[:-3] if path.endswith(".ko") else os.path.basename(path)
        detail = [ln for ln in log.lines() if name in ln or "iec2kmod" in ln]
        log.close()
        why = {
            errno.EEXIST: "a module of that name is already loaded",
            errno.ENOEXEC: "invalid module format (built for another kernel?)",
            errno.ENOENT: "unknown symbol (the configuration module it needs is not loaded?)",
            errno.EPERM: "operation not permitted (inserting modules needs CAP_SYS_MODULE: "
                         "run as root)",
            errno.EKEYREJECTED: "the module's signature was rejected",
            errno.EPROTO: "the interface of the program type does not match its slot",
        }.get(err, os.strerror(err))
        msg = f"insert {os.path.basename(path)}: {why}"
        if detail:
            msg += " -- kernel: " + "; ".join(d.strip() for d in detail[-3:])
        raise ModuleError(msg, err)
    log.close()


def remove(name: str) -> None:
    """delete_module(2), never forced; raises :class:`ModuleError`."""
    err = _syscall(1, ctypes.c_char_p(name.encode()), ctypes.c_int(os.O_NONBLOCK))
    if err:
        why = {
            errno.EWOULDBLOCK: "in use",
            errno.EBUSY: "busy",
            errno.ENOENT: "not loaded",
            errno.EPERM: "operation not permitted (removing modules needs CAP_SYS_MODULE: "
                         "run as root)",
        }.get(err, os.strerror(err))
        raise ModuleError(f"remove {name}: {why}", err)


# ------------------------------------------------------------ modinfo ----

_MODINFO_CACHE: Dict[tuple, Dict[str, List[str]]] = {}
# ELF e_machine of the architectures plc-manager knows, e_type names
_EM = {"x86_64": 62, "aarch64": 183, "riscv64": 243, "i686": 3, "armv7l": 40,
       "ppc64le": 21, "s390x": 22}
_ET = {2: "executable", 3: "shared object or position-independent executable", 4: "core file"}


def modinfo(path: str) -> Dict[str, List[str]]:
    """The .modinfo section of a module file: key -> values.  Reads only the
    ELF header, the section headers and the two sections it needs (module
    files carry megabytes of debug information)."""
    st = os.stat(path)
    key = (path, st.st_mtime_ns, st.st_size)
    if key in _MODINFO_CACHE:
        return _MODINFO_CACHE[key]
    try:
        out = _read_modinfo(path, st.st_size)
    except (struct.error, ValueError, IndexError, OSError, MemoryError, OverflowError) as exc:
        # a truncated or corrupt file: offsets past its end, no string end
        raise ModuleError(f"{path}: not a valid kernel module (truncated or corrupt: "
                          f"{exc})") from None
    _MODINFO_CACHE[key] = out
    return out


def _read_modinfo(path: str, size: int) -> Dict[str, List[str]]:
    with open(path, "rb") as f:
        head = f.read(64)
        if len(head) < 64 or head[:4] != b"\x7fELF" or head[4] != 2:
            raise ModuleError(f"{path}: not a 64-bit ELF kernel module")
        end = "<" if head[5] == 1 else ">"
        e_type, e_machine = struct.unpack_from(end + "HH", head, 0x10)
        if e_type != 1:         # ET_REL: a module is a relocatable object
            raise ModuleError(f"{path}: not a kernel module (an ELF "
                              f"{_ET.get(e_type, f'file of type {e_type}')})")
        here = _EM.get(platform.machine())
        if here is not None and e_machine != here:
            other = next((a for a, m in _EM.items() if m == e_machine), f"machine {e_machine}")
            raise ModuleError(f"{path}: a module for another architecture ({other}), this "
                              f"machine is {platform.machine()}")
        shoff, = struct.unpack_from(end + "Q", head, 0x28)
        shentsize, shnum, shstrndx = struct.unpack_from(end + "HHH", head, 0x3A)
        if shoff + shentsize * shnum > size or shentsize < 64:
            raise ValueError("section header table past the end of the file")
        f.seek(shoff)
        table = f.read(shentsize * shnum)

        def sh(i):
            return struct.unpack_from(end + "IIQQQQIIQQ", table, i * shentsize)

        def section(i):
            s = sh(i)
            if s[4] + s[5] > size:
                raise ValueError(f"section {i} past the end of the file")
            f.seek(s[4])
            return f.read(s[5])

        names = section(shstrndx)
        out: Dict[str, List[str]] = {}
        for i in range(shnum):
            s = sh(i)
            if names[s[0]:names.index(b"\0", s[0])] == b".modinfo":
                for item in section(i).split(b"\0"):
                    if b"=" in item:
                        k, v = item.decode("utf-8", "replace").split("=", 1)
                        out.setdefault(k, []).append(v)
    if "vermagic" not in out:
        raise ModuleError(f"{path}: not a kernel module (no .modinfo vermagic)")
    return out


def vermagic_release(path: str) -> str:
    info = modinfo(path)
    vm = (info.get("vermagic") or [""])[0]
    return vm.split()[0] if vm else ""
