# SPDX-License-Identifier: MIT
"""A PREEMPT_RT QEMU guest (TCG) that stays up for many commands.

The guest boots Debian's RT kernel from a busybox initramfs written in
Python.  The host's root file system is mounted read-only over virtio-9p at
``/host`` and a read-write *work directory* is mounted at the same absolute
path as on the host, both in the initramfs and in a chroot of ``/host``.  So:

* ``.ko`` files built on the host into the work directory (even after boot) can
  be ``insmod``-ed in the guest by their host path;
* ``Guest.run(cmd, chroot=True)`` (or ``Guest.python(...)``) runs host programs,
  for instance this very Python interpreter with the installed project
  (pyroute2, plc-manager), inside the guest;
* ``Guest.pyrun(code | module= | script=)`` runs Python forked from a warm
  interpreter in the guest (pyroute2 preloaded): ~0.1 s instead of several
  seconds for a fresh interpreter under TCG.

The kernel is booted through its PVH entry (uncompressed ELF extracted from
the bzImage once), which saves the firmware and decompression time.  An Oops
panics the guest (``oops=panic``): the next use raises :class:`GuestDied` with
the console tail; :meth:`Guest.death_report` lists the console's problem lines
up to the death.  The pytest fixtures fail the test and boot a fresh guest for
the next one.

The kernel log is read with a cursor (:meth:`Guest.read_kernel_log`): a reader
started at boot copies every ``/dev/kmsg`` record to a file in the guest, and
each read returns the records past the last one, by sequence number, so every
line is seen exactly once and records lost to a ring-buffer overrun are named.

Commands travel over a virtio-serial port (binary clean, no tty line
discipline) driven by a tiny shell agent; the kernel console (ttyS0) is logged
separately, so printk output never mixes with command output.  (A second 8250
UART was tried first: bulk output through it makes the RT kernel disable its
IRQ, "irq 3: nobody cared", and the channel stalls.)  Every wait has a hard timeout; QEMU is killed
when the guest stops answering.

    with Guest(workdir="/tmp/work") as g:
        rc, out = g.run("insmod /tmp/work/hello.ko")
        g.check_kernel_log()
"""

from __future__ import annotations

import base64
import atexit
import collections
import contextlib
import math
import os
import re
import secrets
import select
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
import weakref
from typing import Iterable, List, NamedTuple, Optional, Sequence

from .initramfs import CpioWriter, ModuleIndex
from .kernel import KernelImage, find_busybox, find_kernel, find_qemu, pvh_vmlinux

__all__ = [
    "Guest", "GuestError", "GuestBootError", "GuestDied", "GuestTimeout",
    "GuestCommandTimeout", "CommandFailed", "KernelLogError", "CommandResult",
    "KERNEL_LOG_PATTERNS", "kernel_log_problems", "KernelLogRead",
]

# Lines of the kernel log that mean something went wrong in the kernel.
KERNEL_LOG_PATTERNS = (
    r"WARNING:", r"BUG:", r"Oops", r"scheduling while atomic",
    r"sleeping function called from invalid context", r"Call Trace",
    r"general protection fault", r"Kernel panic", r"detected stalls?\b",
    r"blocked for more than \d+ seconds", r"UBSAN:", r"kernel BUG at", r"soft lockup",
    r"hard LOCKUP", r"kthread starved", r"stack-protector:", r"KASAN:", r"KFENCE:",
)
_KLOG_RE = re.compile("|".join(KERNEL_LOG_PATTERNS))

# modules needed for the 9p shares (dependencies are added from .modinfo)
BASE_MODULES = ("virtio_pci", "virtio_console", "9pnet_virtio", "9p")

_MARK = "@@IEC2KMOD"
_KLOG_FILE = "/run/iec2kmod-kmsg"        # in the guest: every /dev/kmsg record
_KLOG_SYNC = _MARK + "-KLOG-"


# what the fork server imports once (a missing one is reported in its ready
# message, not fatal); plc_manager's cli imports the others lazily
PRELOAD = ("pyroute2", "plc_manager.cli", "plc_manager.ops", "plc_manager.netlink",
           "plc_manager.values", "plc_manager.kmod", "plc_manager.project")


class GuestError(RuntimeError):
    """Base class of guest failures."""


class GuestBootError(GuestError):
    """The guest did not come up."""


class GuestDied(GuestError):
    """QEMU exited (kernel panic, poweroff, crash) while the guest was in use."""


class GuestTimeout(GuestError):
    """The guest stopped answering; QEMU was killed."""


class GuestCommandTimeout(GuestError):
    """A command ran longer than its timeout and was killed in the guest (the
    guest itself is still usable)."""

    def __init__(self, msg: str, output: str) -> None:
        super().__init__(msg)
        self.output = output


class CommandFailed(GuestError):
    def __init__(self, cmd: str, result: "CommandResult") -> None:
        super().__init__(f"guest command failed (exit {result.exit_code}): {cmd}\n"
                         f"{result.output.rstrip()}")
        self.result = result


class KernelLogError(GuestError):
    def __init__(self, lines: List[str], context: str) -> None:
        super().__init__("kernel log has problems:\n  " + "\n  ".join(lines)
                         + ("\n--- context ---\n" + context if context else ""))
        self.lines = lines


class KernelLogRead(NamedTuple):
    """New kernel log lines from :meth:`Guest.read_kernel_log`."""
    lines: List[str]          # "[    12.345678] text", one per line of each record
    lost: List[str]           # a description of each run of records lost before reading
    last_ts: float            # timestamp of the last record read so far (0.0: none)

    @property
    def text(self) -> str:
        return "".join(l + "\n" for l in self.lines)


class CommandResult(NamedTuple):
    exit_code: int
    output: str

    @property
    def ok(self) -> bool:
        return self.exit_code == 0


def kernel_log_problems(text: str, allow: Iterable[str] = ()) -> List[str]:
    """Lines of *text* matching :data:`KERNEL_LOG_PATTERNS`, minus those
    matching any regex in *allow*."""
    allow_re = [re.compile(a) for a in allow]
    return [l for l in text.splitlines()
            if _KLOG_RE.search(l) and not any(a.search(l) for a in allow_re)]


_INIT = r"""#!/bin/busybox sh
/bin/busybox mkdir -p /bin /sbin /usr/bin /usr/sbin /proc /sys /dev /tmp /run /host /mnt/work
/bin/busybox --install -s
export PATH=/sbin:/bin:/usr/sbin:/usr/bin
. /etc/iec2kmod-guest.conf
fail() {
    echo "@@IEC2KMOD-INIT-FAIL $*" >/dev/console
    poweroff -f
}
mount -t proc proc /proc || fail "mount proc"
mount -t sysfs sysfs /sys || fail "mount sysfs"
mount -t devtmpfs devtmpfs /dev || fail "mount devtmpfs"
mkdir -p /dev/pts /dev/shm
mount -t devpts devpts /dev/pts
mount -t tmpfs tmpfs /dev/shm
mount -t tracefs tracefs /sys/kernel/tracing 2>/dev/null
mount -t debugfs debugfs /sys/kernel/debug 2>/dev/null
for m in $MODULES; do
    insmod /lib/modules/$m.ko || fail "insmod $m.ko"
done
mount -t 9p -o trans=virtio,version=9p2000.L,ro,msize=$MSIZE,cache=$HOSTCACHE hostroot /host \
    || fail "mount 9p hostroot"
mount -t 9p -o trans=virtio,version=9p2000.L,msize=$MSIZE,cache=none work /mnt/work \
    || fail "mount 9p work"
mkdir -p "$WORKDIR" && mount --bind /mnt/work "$WORKDIR" || fail "bind work dir"
# the chroot: host root read-only, with the guest's own proc/sys/dev/tmp/run
mount -t proc proc /host/proc || fail "mount /host/proc"
mount -t sysfs sysfs /host/sys || fail "mount /host/sys"
mount --rbind /dev /host/dev || fail "bind /host/dev"
mount -t tracefs tracefs /host/sys/kernel/tracing 2>/dev/null
mount -t debugfs debugfs /host/sys/kernel/debug 2>/dev/null
# host paths under /tmp or /run that the chroot needs (a virtualenv, a CI
# checkout): kept visible, read-only, through the new tmpfs
mkdir -p /mnt/hosttmp /mnt/hostrun
mount --bind /host/tmp /mnt/hosttmp && mount --bind /host/run /mnt/hostrun
mount -t tmpfs -o mode=1777 tmpfs /host/tmp || fail "mount /host/tmp"
mount -t tmpfs -o mode=755 tmpfs /host/run || fail "mount /host/run"
for p in $KEEP; do
    case "$p" in
    /tmp/*) src="/mnt/hosttmp${p#/tmp}" ;;
    /run/*) src="/mnt/hostrun${p#/run}" ;;
    *) continue ;;
    esac
    mkdir -p "/host$p" && mount --bind "$src" "/host$p" || fail "keep $p"
done
mkdir -p "/host$WORKDIR" && mount --bind /mnt/work "/host$WORKDIR" || fail "bind /host$WORKDIR"
hostname iec2kmod-guest
# Every kernel log record, with its sequence number, appended to $KLOG for
# Guest.read_kernel_log().  cat ends when the ring buffer overran it (EPIPE);
# the loop reopens /dev/kmsg and the host drops the records it already has
# and reports the sequence numbers it never saw.
(while :; do cat /dev/kmsg; sleep 0.2; done) </dev/null >>"$KLOG" 2>/dev/null &
for p in /sys/class/virtio-ports/*; do
    n=$(cat $p/name 2>/dev/null)
    case "$n" in iec2kmod.*) ln -s ${p##*/} /dev/iec2kmod-${n#iec2kmod.} ;; esac
done
[ -c /dev/iec2kmod-ctl ] || fail "virtio port iec2kmod.ctl not found"
[ -c /dev/iec2kmod-py ] || fail "virtio port iec2kmod.py not found"
exec /bin/sh /agent <>/dev/iec2kmod-ctl >&0 2>&0
"""

# The command loop.  One request per line:
#   TOKEN TIMEOUT MODE KIND PAYLOAD
# MODE is "sh" (busybox, initramfs root) or "chroot" (host root); KIND is
# "b64" (PAYLOAD = base64 of the command) or "file" (PAYLOAD = path of a file
# holding the command).  Reply: "TOKEN-BEGIN\n" OUTPUT "\nTOKEN-END RC T0 T1\n".
_AGENT = r"""set -f
cd "$WORKDIR"
echo "@@IEC2KMOD-READY $(cut -d' ' -f1 /proc/uptime)"
while IFS= read -r line; do
    set -- $line
    tok=$1 tmo=$2 mode=$3 kind=$4 payload=$5
    [ -n "$payload" ] || continue
    if [ "$kind" = file ]; then
        cmd=$(cat "$payload")
    else
        cmd=$(echo "$payload" | base64 -d)
    fi
    printf '%s-BEGIN\n' "$tok"
    t0=$(cut -d' ' -f1 /proc/uptime)
    if [ "$mode" = chroot ]; then
        timeout -s KILL "$tmo" chroot /host /usr/bin/env -i $CHROOT_ENV /bin/sh -c "cd \"\$1\" 2>/dev/null; $cmd" sh "$WORKDIR" </dev/null 2>&1
    else
        timeout -s KILL "$tmo" /bin/sh -c "$cmd" </dev/null 2>&1
    fi
    rc=$?
    t1=$(cut -d' ' -f1 /proc/uptime)
    printf '\n%s-END %d %s %s\n' "$tok" "$rc" "$t0" "$t1"
done
echo "@@IEC2KMOD-AGENT-EXIT"
"""


def _qemu_path_arg(p: str) -> str:
    return p.replace(",", ",,")


_LIVE: "weakref.WeakSet[Guest]" = weakref.WeakSet()


@atexit.register
def _kill_all_guests() -> None:
    for g in list(_LIVE):
        with contextlib.suppress(Exception):
            g.kill()


def _qemu_preexec() -> None:
    """In the QEMU child: own session (no terminal signals), and die with the
    thread that started it (PR_SET_PDEATHSIG), so no QEMU outlives its user."""
    os.setsid()
    try:
        import ctypes
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGKILL, 0, 0, 0)     # PR_SET_PDEATHSIG
    except Exception:
        pass


def _keep_paths(python_exe: str):
    """Host paths under /tmp or /run that the guest's chroot must still see
    although it mounts its own tmpfs there: the Python installation in use
    and the checkout the project is imported from."""
    import iec2kmod
    out = set()
    for p in (sys.prefix, os.path.dirname(os.path.dirname(os.path.abspath(python_exe))),
              os.path.dirname(os.path.dirname(os.path.realpath(python_exe))),
              os.path.dirname(os.path.dirname(os.path.realpath(iec2kmod.__file__)))):
        for top in ("/tmp/", "/run/"):
            if p.startswith(top):
                first = p[len(top):].split("/", 1)[0]
                if first and not any(c.isspace() or c in "'\"\\$`" for c in first):
                    out.add(top + first)
    return out


class Guest:
    """One running PREEMPT_RT guest.  See the module docstring.

    Parameters: *workdir* — host directory shared read-write (created if
    missing); *memory* MiB; *smp* vCPUs; *icount* — deterministic virtual time
    (``-icount shift=0,sleep=off``, forces one vCPU) for timing measurements;
    *append* — extra kernel command line; *host_cache* — 9p cache mode of the
    read-only host root (``"loose"``: fast, but host files created or changed
    after boot may look stale in the guest outside the work directory;
    ``"none"``: always current, slower); *extra_modules* — more kernel modules
    from the image to insert at boot (dependencies resolved);
    *console_log* — path of the kernel console log file; *pvh* — boot the
    uncompressed kernel through its PVH entry (faster; falls back to the
    bzImage when the kernel has no PVH note); *preload* — modules the guest's
    Python fork server (:meth:`pyrun`) imports once at its start; the
    default, :data:`PRELOAD`, is pyroute2 and plc_manager's modules: the
    guest writes no bytecode, so a module not preloaded is compiled again
    by every pyrun that imports it (about 1 s per ``plc-manager`` call);
    *parallel* — a host file that receives the bytes of an ISA parallel port
    (LPT1: I/O base 0x378, IRQ 7, ``-device isa-parallel`` on a ``file``
    chardev): QEMU writes the data register to it on each rising STROBE of
    the control register (with INIT and SELECT set), and raises IRQ 7 on a
    control write with STROBE low when the previous control value had the
    interrupt enable bit (hw/char/parallel.c); no parallel port without it.
    """

    def __init__(self, workdir: str, *, memory: int = 1024, smp: int = 2,
                 icount: bool = False, append: str = "", host_cache: str = "loose",
                 extra_modules: Sequence[str] = (), console_log: Optional[str] = None,
                 boot_timeout: float = 180.0, kernel: Optional[KernelImage] = None,
                 python: Optional[str] = None, qemu_args: Sequence[str] = (),
                 pvh: bool = True, preload: Sequence[str] = PRELOAD,
                 parallel: Optional[str] = None) -> None:
        self.workdir = os.path.realpath(workdir)
        if any(c.isspace() for c in self.workdir):
            raise GuestError(f"work directory path must not contain whitespace: {self.workdir!r}")
        os.makedirs(self.workdir, exist_ok=True)
        self.memory = memory
        self.smp = 1 if icount else smp
        self.icount = icount
        self.append = append
        if host_cache not in ("loose", "none", "fscache", "mmap"):
            raise GuestError(f"host_cache must be loose, none, fscache or mmap, not {host_cache!r}")
        self.host_cache = host_cache
        self.extra_modules = tuple(extra_modules)
        self.boot_timeout = boot_timeout
        self.python_exe = python or sys.executable
        self.qemu_args = list(qemu_args)
        self.parallel = os.path.realpath(parallel) if parallel else None
        self.kernel = kernel
        self.pvh = pvh
        self.preload = tuple(preload)
        self._rundir = tempfile.mkdtemp(prefix="iec2kmod-vm-")
        self.console_log = console_log or os.path.join(self._rundir, "console.log")
        self._proc: Optional[subprocess.Popen] = None
        self._sock: Optional[socket.socket] = None
        self._pysock: Optional[socket.socket] = None
        self._pybuf = b""
        self._pyserver: Optional[dict] = None
        self._pylock = threading.Lock()
        self._rbuf = b""
        self._console_tail: collections.deque = collections.deque(maxlen=400)
        self._console_thread: Optional[threading.Thread] = None
        self._lock = threading.Lock()
        self._seq = 0
        self._tokbase = secrets.token_hex(4)
        self._dead_reason: Optional[str] = None
        self.boot_seconds: Optional[float] = None       # host wall time to READY
        self.guest_uptime_at_ready: Optional[float] = None
        self.baseline: Optional[float] = None          # log timestamp at the start of a test
        # the kernel log cursor (read_kernel_log): byte offset in the guest's
        # record file, last sequence number read, its timestamp; the console
        # log's size when the last read began (console_problems scans from it)
        self._klog_off = 0
        self._klog_seq = -1
        self._klog_ts = 0.0
        self._klog_syncs = 0
        self._klog_reads = 0
        self._console_bytes = 0
        self._console_mark = 0
        self.qemu_cmdline: List[str] = []

    # ------------------------------------------------------------ boot ----
    def _build_initramfs(self, kernel: KernelImage) -> str:
        idx = ModuleIndex(kernel.moddir)
        order = idx.load_order(BASE_MODULES + self.extra_modules)
        env = {
            "PATH": ":".join(dict.fromkeys([
                os.path.dirname(self.python_exe), "/usr/local/sbin", "/usr/local/bin",
                "/usr/sbin", "/usr/bin", "/sbin", "/bin"])),
            # LANGUAGE=C: gettext looks for no catalogue (argparse's 45
            # lookups stat the 9p root: ~0.3 s of every plc-manager call)
            "HOME": "/root", "LANG": "C.UTF-8", "LANGUAGE": "C", "TERM": "dumb",
            "PYTHONDONTWRITEBYTECODE": "1", "PYTHONUNBUFFERED": "1",
        }
        # the host's PYTHONPATH (the host's root is the guest's chroot): a
        # worktree's plc_manager is the one its tests run in the guest
        if os.environ.get("PYTHONPATH"):
            env["PYTHONPATH"] = os.environ["PYTHONPATH"]
        for k, v in env.items():
            if any(c.isspace() or c in "'\"\\$`" for c in v):
                raise GuestError(f"cannot pass {k}={v!r} into the guest (whitespace/quotes)")
        keep = " ".join(sorted(_keep_paths(self.python_exe)))
        conf = (f"WORKDIR='{self.workdir}'\nKEEP='{keep}'\n"
                f"MODULES='{' '.join(order)}'\n"
                f"MSIZE=512000\nHOSTCACHE={self.host_cache}\nKLOG={_KLOG_FILE}\n"
                f"CHROOT_ENV='{' '.join(f'{k}={v}' for k, v in env.items())}'\n"
                f"export WORKDIR CHROOT_ENV\n")
        w = CpioWriter()
        for d in ("bin", "sbin", "usr", "usr/bin", "usr/sbin", "etc", "dev", "proc", "sys",
                  "tmp", "run", "host", "mnt", "mnt/work", "lib", "lib/modules", "root"):
            w.add_dir(d)
        w.add_chardev("dev/console", 5, 1)
        w.add_chardev("dev/null", 1, 3, 0o666)
        w.add_host_file("bin/busybox", find_busybox(), 0o755)
        w.add_symlink("bin/sh", "busybox")
        w.add_file("init", _INIT.encode(), 0o755)
        w.add_file("agent", _AGENT.encode(), 0o755)
        w.add_file("etc/iec2kmod-guest.conf", conf.encode())
        for m in order:
            w.add_host_file(f"lib/modules/{m}.ko", idx.path(m), 0o644)
        path = os.path.join(self._rundir, "initrd.cpio")
        with open(path, "wb") as f:
            f.write(w.finish())
        return path

    def start(self) -> "Guest":
        """Boot the guest and wait until its command agent answers."""
        if self._proc is not None:
            raise GuestError("guest already started")
        kernel = self.kernel or find_kernel()
        self.kernel = kernel
        qemu = find_qemu()
        initrd = self._build_initramfs(kernel)
        kimage = (pvh_vmlinux(kernel) if self.pvh else None) or kernel.vmlinuz
        sockpath = os.path.join(self._rundir, "ctl.sock")
        pysockpath = os.path.join(self._rundir, "py.sock")
        append = ("console=ttyS0 panic=-1 oops=panic loglevel=5 printk.time=1 "
                  "printk.devkmsg=on no_timer_check mitigations=off cryptomgr.notests " + self.append).strip()
        # Note: oops=panic makes an Oops end the guest at once (clear failure)
        # instead of leaving a half-dead kernel; WARNs do not panic.
        cmd = [qemu, "-accel", "tcg", "-nodefaults", "-no-user-config", "-no-reboot",
               "-display", "none", "-monitor", "none",
               "-m", str(self.memory), "-smp", str(self.smp),
               "-kernel", kimage, "-initrd", initrd, "-append", append,
               "-chardev", "stdio,id=con,signal=off", "-serial", "chardev:con",
               "-device", "virtio-serial-pci,id=vser",
               "-chardev", f"socket,id=ctl,path={_qemu_path_arg(sockpath)},server=on,wait=on",
               "-device", "virtserialport,bus=vser.0,chardev=ctl,name=iec2kmod.ctl",
               "-chardev", f"socket,id=py,path={_qemu_path_arg(pysockpath)},server=on,wait=on",
               "-device", "virtserialport,bus=vser.0,chardev=py,name=iec2kmod.py",
               "-virtfs", "local,path=/,mount_tag=hostroot,security_model=none,"
                          "readonly=on,multidevs=remap",
               "-virtfs", f"local,path={_qemu_path_arg(self.workdir)},mount_tag=work,"
                          "security_model=none,multidevs=remap"]
        if self.icount:
            cmd += ["-icount", "shift=0,sleep=off"]
        if self.parallel:
            cmd += ["-chardev", f"file,id=lpt0,path={_qemu_path_arg(self.parallel)}",
                    "-device", "isa-parallel,chardev=lpt0,iobase=0x378,irq=7"]
        cmd += self.qemu_args
        self.qemu_cmdline = cmd
        t0 = time.monotonic()
        logf = open(self.console_log, "wb")
        self._proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                      stderr=subprocess.STDOUT, preexec_fn=_qemu_preexec)
        _LIVE.add(self)
        self._console_thread = threading.Thread(target=self._pump_console, args=(logf,),
                                                name="qemu-console", daemon=True)
        self._console_thread.start()
        try:
            self._sock = self._connect(sockpath, t0 + 20)
            self._pysock = self._connect(pysockpath, t0 + 20)
            line = self._read_until_line(_MARK + "-READY", t0 + self.boot_timeout, boot=True)
            self.guest_uptime_at_ready = float(line.split()[1])
        except GuestError as e:
            self._dead_reason = str(e)
            self.kill()
            raise
        self.boot_seconds = time.monotonic() - t0
        return self

    def _connect(self, sockpath: str, deadline: float) -> socket.socket:
        while True:
            if self._proc.poll() is not None:
                self._wait_console()
                raise GuestBootError(self._died_message("QEMU exited before the guest started"))
            if os.path.exists(sockpath):
                s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
                try:
                    s.connect(sockpath)
                    s.setblocking(False)
                    return s
                except OSError:
                    s.close()
            if time.monotonic() > deadline:
                raise GuestBootError(self._died_message(
                    "QEMU did not open its control socket within 20 s"))
            time.sleep(0.02)

    def _pump_console(self, logf) -> None:
        pending = b""
        try:
            while True:
                chunk = self._proc.stdout.read1(65536) if self._proc else b""
                if not chunk:
                    break
                logf.write(chunk)
                logf.flush()
                self._console_bytes += len(chunk)
                pending += chunk
                *lines, pending = pending.split(b"\n")
                for l in lines:
                    self._console_tail.append(l.decode("utf-8", "replace").rstrip("\r"))
        except (OSError, ValueError):
            pass
        finally:
            if pending:
                self._console_tail.append(pending.decode("utf-8", "replace"))
            logf.close()

    def _wait_console(self) -> None:
        if self._console_thread:
            self._console_thread.join(timeout=2)

    def console_tail(self, n: int = 40) -> str:
        """The last *n* lines of the kernel console (ttyS0)."""
        return "\n".join(list(self._console_tail)[-n:])

    def _died_message(self, what: str) -> str:
        rc = self._proc.poll() if self._proc else None
        parts = [what + (f" (QEMU exit status {rc})" if rc is not None else "")]
        fails = [l for l in self._console_tail if "@@IEC2KMOD-INIT-FAIL" in l]
        if fails:
            parts.append("guest init failed: " + fails[-1].split("INIT-FAIL", 1)[1].strip())
        # a panic's reason can be more than 30 lines above the end of its trace
        bad = self.console_problems()
        if bad:
            parts.append("kernel console since the last kernel log check:\n  "
                         + "\n  ".join(bad))
        parts.append(f"last console lines ({self.console_log}):\n" + self.console_tail(30))
        return "\n".join(parts)

    # ----------------------------------------------------------- channel ----
    @property
    def alive(self) -> bool:
        return (self._proc is not None and self._proc.poll() is None
                and self._sock is not None and self._dead_reason is None)

    def _ensure_alive(self) -> None:
        if self._proc is None:
            raise GuestError("guest not started (call start())")
        if self._dead_reason:
            raise GuestDied(self._dead_reason)
        if self._proc.poll() is not None:
            self._wait_console()
            self._dead_reason = self._died_message("the guest is gone")
            raise GuestDied(self._dead_reason)

    def _recv(self, deadline: float, boot: bool = False) -> None:
        """Read more bytes from the control channel into the buffer, or raise."""
        while True:
            now = time.monotonic()
            if now > deadline:
                if boot:
                    raise GuestBootError(self._died_message(
                        f"the guest did not come up within {self.boot_timeout:.0f} s"))
                raise TimeoutError
            r, _, _ = select.select([self._sock], [], [], min(0.25, deadline - now))
            if r:
                try:
                    data = self._sock.recv(65536)
                except BlockingIOError:
                    continue
                except OSError:
                    data = b""
                if data:
                    self._rbuf += data
                    return
                # EOF: QEMU closed the socket -> it is exiting
                try:
                    self._proc.wait(timeout=5)
                except subprocess.TimeoutExpired:
                    pass
            if self._proc.poll() is not None or (r and not data):
                self._wait_console()
                msg = self._died_message("the guest died" if not boot else
                                         "the guest died while booting")
                self._dead_reason = msg
                raise (GuestBootError if boot else GuestDied)(msg)
            if boot and any("@@IEC2KMOD-INIT-FAIL" in l for l in self._console_tail):
                raise GuestBootError(self._died_message("guest init failed"))

    def _read_until_line(self, prefix: str, deadline: float, boot: bool = False) -> str:
        pat = prefix.encode()
        while True:
            i = self._rbuf.find(pat)
            if i >= 0:
                j = self._rbuf.find(b"\n", i)
                if j >= 0:
                    line = self._rbuf[i:j].decode("utf-8", "replace")
                    self._rbuf = self._rbuf[j + 1:]
                    return line
            self._recv(deadline, boot=boot)

    def _send(self, data: bytes) -> None:
        view = memoryview(data)
        deadline = time.monotonic() + 30
        while view:
            try:
                n = self._sock.send(view)
                view = view[n:]
            except BlockingIOError:
                if time.monotonic() > deadline:
                    raise GuestTimeout(self._hang("the guest does not accept input"))
                select.select([], [self._sock], [], 0.25)
            except OSError as e:
                self._ensure_alive()
                raise GuestDied(self._died_message(f"control channel broken: {e}"))

    def _hang(self, what: str) -> str:
        msg = self._died_message(what + "; QEMU killed")
        self._dead_reason = msg
        self.kill()
        return msg

    # ----------------------------------------------------------- commands ----
    def run(self, cmd: str, timeout: float = 60.0, *, chroot: bool = False,
            check: bool = False, env: Optional[dict] = None, cwd: Optional[str] = None,
            grace: float = 30.0) -> CommandResult:
        """Run shell command *cmd* in the guest; returns ``(exit_code, output)``
        (stdout and stderr together, exactly as printed).

        *chroot=False* runs busybox sh in the initramfs (insmod, rmmod, dmesg
        ...); *chroot=True* runs ``/bin/sh`` of the host root (host programs,
        the host's Python).  The work directory is at its host path in both and
        is the default cwd.  The command is killed in the guest after *timeout*
        seconds (:class:`GuestCommandTimeout`); if the guest does not answer
        within *timeout* + *grace* seconds it is declared hung, QEMU is killed
        and :class:`GuestTimeout` is raised.  *check* raises
        :class:`CommandFailed` on a non-zero exit.
        """
        prefix = ""
        if env:
            prefix += "".join(f"export {k}={shlex.quote(str(v))}; " for k, v in env.items())
        if cwd:
            prefix += f"cd {shlex.quote(cwd)} || exit 125; "
        full = prefix + cmd
        with self._lock:
            self._ensure_alive()
            self._seq += 1
            tok = f"{_MARK}-{self._tokbase}-{self._seq}"
            tmo = max(1, int(math.ceil(timeout)))
            cmdfile = None
            b64 = base64.b64encode(full.encode()).decode()
            if len(b64) <= 1500:
                kind, payload = "b64", b64
            else:
                d = os.path.join(self.workdir, ".guest-cmd")
                os.makedirs(d, exist_ok=True)
                cmdfile = os.path.join(d, f"{self._seq}.sh")
                with open(cmdfile, "w") as f:
                    f.write(full)
                kind, payload = "file", cmdfile
            mode = "chroot" if chroot else "sh"
            try:
                self._rbuf = b""
                self._send(f"{tok} {tmo} {mode} {kind} {payload}\n".encode())
                deadline = time.monotonic() + timeout + grace
                try:
                    self._read_until_line(tok + "-BEGIN", deadline)
                    endpat = f"\n{tok}-END ".encode()
                    while True:
                        i = self._rbuf.find(endpat)
                        if i >= 0 and self._rbuf.find(b"\n", i + 1) >= 0:
                            break
                        self._recv(deadline)
                except TimeoutError:
                    partial = self._rbuf.decode("utf-8", "replace")
                    raise GuestTimeout(self._hang(
                        f"the guest did not finish {cmd!r} within {timeout + grace:.0f} s "
                        f"(output so far: {partial[-2000:]!r})")) from None
                out = self._rbuf[:i]
                j = self._rbuf.find(b"\n", i + 1)
                tail = self._rbuf[i + len(endpat):j].decode().split()
                self._rbuf = self._rbuf[j + 1:]
            finally:
                if cmdfile:
                    try:
                        os.unlink(cmdfile)
                    except OSError:
                        pass
        rc = int(tail[0])
        output = out.decode("utf-8", "replace")
        if rc == 137 and len(tail) >= 3 and float(tail[2]) - float(tail[1]) >= tmo - 0.5:
            raise GuestCommandTimeout(
                f"guest command killed after {tmo} s timeout: {cmd}\n{output[-2000:]}", output)
        res = CommandResult(rc, output)
        if check and rc != 0:
            raise CommandFailed(cmd, res)
        return res

    def check_call(self, cmd: str, timeout: float = 60.0, **kw) -> str:
        """``run(..., check=True)``; returns the output."""
        return self.run(cmd, timeout, check=True, **kw).output

    def run_host(self, cmd: str, timeout: float = 60.0, **kw) -> CommandResult:
        """``run(cmd, chroot=True)``: a command of the host root file system."""
        return self.run(cmd, timeout, chroot=True, **kw)

    def python(self, code: str, *args: str, timeout: float = 120.0, **kw) -> CommandResult:
        """Run *code* with the host's Python interpreter (``sys.executable``, so
        with this project installed) inside the guest's chroot."""
        cmd = " ".join(shlex.quote(a) for a in (self.python_exe, "-c", code) + args)
        return self.run(cmd, timeout, chroot=True, **kw)

    # -------------------------------------------------- warm Python server ----
    def start_pyserver(self, preload: Optional[Sequence[str]] = None,
                       timeout: float = 300.0) -> dict:
        """Start the guest's Python fork server (see :mod:`iec2kmod.testing.vm.pyserver`)
        with *preload* (default: the constructor's) imported once; :meth:`pyrun`
        starts it on first use.  Returns its ready message (``preloaded``,
        ``failed`` modules)."""
        preload = self.preload if preload is None else tuple(preload)
        with self._pylock:
            if self._pyserver is not None:
                return self._pyserver
            self._ensure_alive()
            src = os.path.join(os.path.dirname(os.path.abspath(__file__)), "pyserver.py")
            boot = (f"import runpy, sys; sys.argv = ['pyserver', '/dev/iec2kmod-py', "
                    f"'--preload', {','.join(preload)!r}]; "
                    f"runpy.run_path({src!r}, run_name='__main__')")
            cmd = (f"{shlex.quote(self.python_exe)} -c {shlex.quote(boot)} "
                   "</dev/null >/tmp/.iec2kmod-pyserver.log 2>&1 & echo $!")
            self._pybuf = b""
            pid = self.check_call(cmd, 30, chroot=True).strip()
            try:
                msg = self._py_read(0, time.monotonic() + timeout)
            except TimeoutError:
                log = self.run("cat /host/tmp/.iec2kmod-pyserver.log", 30).output
                self.run(f"kill -9 {pid}", 10)
                raise GuestError(f"the guest's Python server did not start within "
                                 f"{timeout:.0f} s; its log:\n{log}") from None
            self._pyserver = msg
            return msg

    def _py_read(self, want_id: int, deadline: float) -> dict:
        """Next frame with id *want_id* from the Python channel."""
        import json, struct
        while True:
            i = self._pybuf.find(b"IK")
            if i >= 0 and len(self._pybuf) >= i + 6:
                (n,) = struct.unpack(">I", self._pybuf[i + 2:i + 6])
                if len(self._pybuf) >= i + 6 + n:
                    msg = json.loads(self._pybuf[i + 6:i + 6 + n])
                    self._pybuf = self._pybuf[i + 6 + n:]
                    if msg.get("id") == want_id:
                        return msg
                    continue
            self._ensure_alive()
            now = time.monotonic()
            if now > deadline:
                raise TimeoutError
            r, _, _ = select.select([self._pysock], [], [], min(0.25, deadline - now))
            if r:
                try:
                    data = self._pysock.recv(1 << 20)
                except BlockingIOError:
                    continue
                except OSError:
                    data = b""
                if not data:
                    time.sleep(0.1)       # QEMU going away; _ensure_alive reports it
                self._pybuf += data

    def pyrun(self, code: Optional[str] = None, *, module: Optional[str] = None,
              script: Optional[str] = None, argv: Sequence[str] = (),
              cwd: Optional[str] = None, env: Optional[dict] = None,
              timeout: float = 120.0, grace: float = 30.0,
              check: bool = False) -> CommandResult:
        """Run Python in the guest's chroot, forked from a warm interpreter
        (the fork server; started on first use with the *preload* modules
        imported).
        Exactly one of *code* (like ``python -c``), *module* (``python -m``) or
        *script* (a console script such as ``"plc-manager"``) with *argv*.
        Much faster than :meth:`python` (a fork instead of a fresh interpreter
        under TCG); use :meth:`python` when a pristine interpreter matters.
        Returns ``(exit_code, output)``; raises like :meth:`run`."""
        kinds = [(k, v) for k, v in (("code", code), ("module", module), ("script", script))
                 if v is not None]
        if len(kinds) != 1:
            raise ValueError("pyrun: give exactly one of code, module, script")
        self.start_pyserver()
        import json, struct
        with self._pylock:
            self._ensure_alive()
            self._seq += 1
            rid = self._seq
            req = {"id": rid, "kind": kinds[0][0], "target": kinds[0][1], "argv": list(argv),
                   "cwd": cwd or self.workdir, "env": {k: str(v) for k, v in (env or {}).items()},
                   "timeout": timeout}
            data = json.dumps(req).encode()
            frame = b"IK" + struct.pack(">I", len(data)) + data
            self._sendall(self._pysock, frame)
            try:
                msg = self._py_read(rid, time.monotonic() + timeout + grace)
            except TimeoutError:
                info, self._pyserver = self._pyserver or {}, None
                pid = info.get("pid")
                state = "in an unknown state"
                if pid:
                    alive = self.run(f"kill -0 {pid} 2>/dev/null && echo alive", 30).output
                    state = "stuck (killed now)" if "alive" in alive else "dead"
                    self.run(f"kill -9 {pid} 2>/dev/null", 10)
                log = self.run("tail -n 30 /host/tmp/.iec2kmod-pyserver.log", 30).output
                raise GuestError(
                    f"the guest's Python server did not answer within {timeout + grace:.0f} s "
                    f"and is {state}; it restarts on the next pyrun. Its log:\n{log}") from None
        out = base64.b64decode(msg.get("out", "")).decode("utf-8", "replace")
        if msg.get("timed_out"):
            raise GuestCommandTimeout(
                f"guest Python killed after {timeout:.0f} s timeout: {kinds[0][1]!r}\n"
                f"{out[-2000:]}", out)
        res = CommandResult(int(msg["rc"]), out)
        if check and res.exit_code != 0:
            raise CommandFailed(f"{kinds[0][0]} {kinds[0][1]!r} {' '.join(argv)}", res)
        return res

    def _sendall(self, sock: socket.socket, data: bytes) -> None:
        view = memoryview(data)
        deadline = time.monotonic() + 30
        while view:
            try:
                view = view[sock.send(view):]
            except BlockingIOError:
                if time.monotonic() > deadline:
                    raise GuestTimeout(self._hang("the guest does not accept input"))
                select.select([], [sock], [], 0.25)
            except OSError as e:
                self._ensure_alive()
                raise GuestDied(self._died_message(f"guest channel broken: {e}"))

    # ----------------------------------------------------- module helpers ----
    def insmod(self, ko_path: str, *params: str, timeout: float = 60.0) -> str:
        """``insmod`` a module by its host path (must be in the work directory
        or elsewhere on the host file system); raises :class:`CommandFailed`."""
        return self.check_call(" ".join(shlex.quote(a) for a in ("insmod", ko_path) + params),
                               timeout)

    def rmmod(self, name: str, timeout: float = 60.0) -> str:
        return self.check_call(f"rmmod {shlex.quote(name)}", timeout)

    def loaded_modules(self) -> List[str]:
        out = self.check_call("cat /proc/modules")
        return [l.split()[0] for l in out.splitlines() if l.strip()]

    # -------------------------------------------------------- kernel log ----
    def dmesg(self, since: Optional[float] = None) -> str:
        """The kernel log (``dmesg``); with *since*, only lines whose timestamp
        is later than that (a value from :meth:`log_mark`)."""
        out = self.check_call("dmesg", timeout=60)
        out = "".join(l for l in out.splitlines(True) if _KLOG_SYNC not in l)
        if since is None:
            return out
        keep = []
        cur = None
        for line in out.splitlines():
            m = re.match(r"\[\s*(\d+\.\d+)\]", line)
            if m:
                cur = float(m.group(1))
            if cur is not None and cur > since:
                keep.append(line)
        return "\n".join(keep) + ("\n" if keep else "")

    def log_mark(self) -> float:
        """A position in the kernel log: pass it as *since* to :meth:`dmesg`
        or :meth:`check_kernel_log` to look only at later messages."""
        out = self.check_call("dmesg | tail -n 1")
        m = re.match(r"\[\s*(\d+\.\d+)\]", out)
        return float(m.group(1)) if m else 0.0

    def read_kernel_log(self, timeout: float = 60.0) -> KernelLogRead:
        """The kernel log lines logged since the previous call (from boot on
        the first call), each line exactly once over the guest's life.

        A reader started at boot copies every ``/dev/kmsg`` record, with its
        sequence number, to a file in the guest; this call writes a marker
        record to ``/dev/kmsg``, waits until the reader has copied it (so
        everything logged before the call is included) and returns the
        records past the cursor.  Sequence numbers make the cursor exact: no
        record is returned twice, and records the ring buffer overwrote before
        the reader got them are listed in ``lost`` (a problem for
        :meth:`check_kernel_log`).  Raises :class:`GuestError` if the reader
        does not deliver, :class:`GuestDied` if the guest is gone."""
        self._klog_syncs += 1
        marker = f"{_KLOG_SYNC}{self._tokbase}-{self._klog_syncs}@"
        console_mark = self._console_bytes
        off = self._klog_off + 1
        cmd = (f"echo '<7>{marker}' >/dev/kmsg || exit 90; i=0; "
               f"until tail -c +{off} {_KLOG_FILE} | grep -qF ';{marker}'; do "
               f"i=$((i+1)); [ $i -gt 400 ] && exit 91; sleep 0.05; done; "
               f"tail -c +{off} {_KLOG_FILE}")
        res = self.run(cmd, timeout)
        if res.exit_code != 0:
            raise GuestError(
                "the guest's kernel log reader did not deliver a marker record within 20 s "
                f"(exit {res.exit_code}; is the 'cat /dev/kmsg' loop started by the guest's "
                f"init still running?): {res.output[-1000:]}")
        self._console_mark = console_mark
        self._klog_reads += 1
        return self._consume_kmsg(res.output)

    def _consume_kmsg(self, data: str) -> KernelLogRead:
        """Advance the cursor over the complete records in *data* (the
        reader's file from the cursor's byte offset on)."""
        lines: List[str] = []
        lost: List[str] = []
        end = data.rfind("\n") + 1             # a record still being written waits
        for rec in data[:end].split("\n")[:-1]:
            if rec.startswith(" ") or ";" not in rec:
                continue                         # " KEY=value" dictionary lines
            head, msg = rec.split(";", 1)
            fields = head.split(",")
            try:
                seq, usec = int(fields[1]), int(fields[2])
            except (IndexError, ValueError):
                lines.append(f"[unparsed kernel log record] {rec}")
                continue
            if seq <= self._klog_seq:
                continue                         # copied again after a reader restart
            if seq > self._klog_seq + 1:
                lost.append(f"kernel log records {self._klog_seq + 1}..{seq - 1} were lost "
                            "(the ring buffer overran before they were read)")
            self._klog_seq = seq
            stamp = f"{usec // 1000000}.{usec % 1000000:06d}"
            self._klog_ts = float(stamp)
            if msg.startswith(_KLOG_SYNC):
                continue
            msg = re.sub(r"\\x([0-9a-fA-F]{2})", lambda m: chr(int(m.group(1), 16)), msg)
            lines += [f"[{stamp:>12}] {l}" for l in msg.split("\n")]
        self._klog_off += len(data[:end].encode("utf-8", "surrogateescape"))
        return KernelLogRead(lines, lost, self._klog_ts)

    @property
    def klog_reads(self) -> int:
        """How many :meth:`read_kernel_log` calls have returned (0: the log
        since boot is still unread)."""
        return self._klog_reads

    @property
    def klog_last_ts(self) -> float:
        """Timestamp of the last kernel log record :meth:`read_kernel_log`
        returned (a *since* for :meth:`dmesg`)."""
        return self._klog_ts

    def check_kernel_log(self, since: Optional[float] = None,
                         allow: Iterable[str] = ()) -> None:
        """Raise :class:`KernelLogError` listing every kernel log line with
        ``WARNING:``, ``BUG:``, ``Oops``, ``scheduling while atomic``,
        ``sleeping function called from invalid context``, ``Call Trace``,
        panics, stalls, hung tasks (:data:`KERNEL_LOG_PATTERNS`).

        Without *since* it checks the lines :meth:`read_kernel_log` returns,
        i.e. everything logged since the previous check, and consumes them
        (also when it raises): every line is checked once, and a test that
        provokes a WARN on purpose checks it with ``pytest.raises`` or passes
        *allow* (regexes of lines to tolerate).  Lost records are always a
        problem.  With *since* (a :meth:`log_mark`) it checks the ``dmesg``
        lines after that mark and consumes nothing."""
        if since is None:
            r = self.read_kernel_log()
            log, lost = r.text, r.lost
        else:
            log, lost = self.dmesg(since), []
        bad = lost + kernel_log_problems(log, allow)
        if bad:
            lines = log.splitlines()
            first = next((i for i, l in enumerate(lines) if l in bad), 0)
            raise KernelLogError(bad, "\n".join(lines[max(0, first - 5):first + 40]))

    # ------------------------------------------------------- after death ----
    @property
    def dead_reason(self) -> Optional[str]:
        """Why the guest is unusable, once a call has reported it (raised
        :class:`GuestDied`, :class:`GuestTimeout` ...); None while nobody has
        noticed, even if QEMU has already exited."""
        return self._dead_reason

    def console_problems(self, allow: Iterable[str] = ()) -> List[str]:
        """Console (ttyS0) lines matching :data:`KERNEL_LOG_PATTERNS`, from
        where the last :meth:`read_kernel_log` began to the end: what a dead
        guest logged after its last check.  The console carries messages of
        level warning and above (``loglevel=5``), which all those patterns
        are; a line may also have been returned by that last read."""
        if self._proc is not None and self._proc.poll() is not None:
            self._wait_console()
        try:
            with open(self.console_log, "rb") as f:
                f.seek(self._console_mark)
                text = f.read().decode("utf-8", "replace")
        except OSError as e:
            return [f"the console log {self.console_log} cannot be read: {e}"]
        return kernel_log_problems(text.replace("\r", ""), allow)

    def death_report(self) -> str:
        """What to say about a guest that is no longer alive: how it ended,
        the console's problem lines since the last kernel log check, the
        console tail."""
        if self._proc is None:
            return "the guest was never started"
        rc = self._proc.poll()
        how = (self._dead_reason.splitlines()[0] if self._dead_reason else
               "QEMU exited" if rc is not None else "the guest stopped answering")
        if rc is not None:
            how += f" (QEMU exit status {rc})"
        bad = self.console_problems()
        parts = [how]
        if bad:
            parts.append("kernel console since the last kernel log check:\n  "
                         + "\n  ".join(bad))
        else:
            parts.append("no WARNING/BUG/Oops/panic line on the console since the last "
                         "kernel log check")
        parts.append(f"last console lines ({self.console_log}):\n" + self.console_tail(30))
        return "\n".join(parts)

    # ------------------------------------------------------------ shutdown ----
    def close(self, timeout: float = 15.0) -> None:
        """``poweroff -f`` the guest; kill QEMU if it has not exited after
        *timeout* seconds.  Idempotent."""
        if self._proc is None:
            self._cleanup()
            return
        if self._proc.poll() is None and self._sock is not None and not self._dead_reason:
            try:
                with self._lock:
                    tok = f"{_MARK}-{self._tokbase}-off"
                    b64 = base64.b64encode(b"sync; poweroff -f").decode()
                    self._sock.setblocking(True)
                    self._sock.settimeout(2)
                    self._sock.sendall(f"{tok} 10 sh b64 {b64}\n".encode())
            except OSError:
                pass
            try:
                self._proc.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                pass
        self.kill()

    def kill(self) -> None:
        """Kill QEMU at once (no clean shutdown)."""
        p = self._proc
        if p is not None and p.poll() is None:
            try:
                os.killpg(p.pid, signal.SIGKILL)
            except OSError:
                p.kill()
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                pass
        self._cleanup()

    def _cleanup(self) -> None:
        for attr in ("_sock", "_pysock"):
            sk = getattr(self, attr)
            if sk is not None:
                with contextlib.suppress(OSError):
                    sk.close()
                setattr(self, attr, None)
        if self._proc is not None and self._proc.stdout:
            self._wait_console()
        # The run directory goes; a default console log inside it stays only
        # when the guest died or hung, since error messages point at it.
        keep_log = (self._dead_reason is not None
                    and self.console_log.startswith(self._rundir + os.sep))
        if keep_log:
            for fn in ("initrd.cpio", "ctl.sock", "py.sock"):
                with contextlib.suppress(OSError):
                    os.unlink(os.path.join(self._rundir, fn))
        else:
            shutil.rmtree(self._rundir, ignore_errors=True)

    def __enter__(self) -> "Guest":
        if self._proc is None:
            self.start()
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __del__(self) -> None:
        try:
            if self._proc is not None and self._proc.poll() is None:
                self.kill()
        except Exception:
            pass
