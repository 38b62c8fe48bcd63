# SPDX-License-Identifier: MIT
"""`plc-manager serve`: OPC UA and Modbus TCP servers on the running
configuration (long-running; SIGTERM or SIGINT stops it cleanly).

The address space and the Modbus map come from the running build's
manifest alone (the copy plc-manager saved at load, or --project DIR):
its variables, tasks, access paths (VAR_ACCESS) and the addresses of
named located variables.  A poller reads the tasks' status at the fastest
task's rate (not faster than --period-min) and the variables clients
subscribe to, each task's at its own rate when it ended a cycle, stamped
with that cycle's end, and updates the OPC UA nodes that changed; a Read
and every Modbus request read the kernel themselves."""

from __future__ import annotations

import asyncio
import logging
import signal
import sys
import time
from pathlib import Path
from typing import Optional
from urllib.parse import urlparse

from ..errors import PLCError, UsageError

log = logging.getLogger("plc_manager.serve")


def _hostport(text: str, default_port: int):
    if text.startswith("opc.tcp://"):
        try:
            u = urlparse(text)
            return u.hostname or "0.0.0.0", u.port or default_port
        except ValueError:
            raise UsageError(f"{text}: not opc.tcp://HOST:PORT") from None
    host, _, port = text.rpartition(":")
    if not host:
        host, port = text, str(default_port)
    try:
        return host.strip("[]"), int(port)
    except ValueError:
        raise UsageError(f"{text}: not HOST:PORT") from None


def load_model(project: Optional[str]):
    from .. import ops
    from ..project import Project
    from .model import Model
    c = ops.connect("serve")
    st = c.status()
    if project:
        p = Project.open(project)
        if p.configuration.lower() != st.configuration.lower():
            c.close()
            raise UsageError(f"{project} is configuration {p.configuration}, the running one "
                             f"is {st.configuration}")
        manifest = p.m
    else:
        s = ops.running_state(st)
        if s is None:
            c.close()
            raise UsageError("the running configuration was not loaded by plc-manager (or "
                             "was swapped since by hand): give its build with --project DIR")
        manifest = s.manifest
    try:
        return c, Model.from_manifest(manifest)
    except BaseException:
        c.close()
        raise


async def serve(a) -> int:
    from .kernel import Kernel
    from .model import modbus_map
    if not a.opcua and not a.modbus:
        raise UsageError("serve: give --opcua opc.tcp://HOST:PORT and/or --modbus HOST:PORT")
    # the arguments first, then the kernel
    users = {}
    if a.opcua:
        if not a.opcua.startswith("opc.tcp://"):
            raise UsageError(f"--opcua {a.opcua}: an endpoint URL opc.tcp://HOST:PORT")
        _hostport(a.opcua, 4840)
        from .opcua import read_users
        if a.users:
            users = read_users(a.users)
        if not users and not a.allow_anonymous:
            raise UsageError("serve --opcua: no users (--users FILE, written by `plc-manager "
                             "serve-user`) and anonymous access is off (--allow-anonymous)")
    if a.modbus:
        _hostport(a.modbus, 502)
    from concurrent.futures import ThreadPoolExecutor
    t_start = time.monotonic()
    pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="netlink")
    try:
        kernel = Kernel.open(pool, lambda: load_model(a.project))
    except BaseException:
        pool.shutdown()
        raise
    model = kernel.model
    from .. import ops
    kernel.connect = lambda: ops.connect("serve")
    t_model = time.monotonic() - t_start
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    me = asyncio.current_task()
    serving = [False]

    def on_signal():
        stop.set()
        if not serving[0]:          # still starting: give up at once
            me.cancel()

    for sig in (signal.SIGTERM, signal.SIGINT):
        loop.add_signal_handler(sig, on_signal)
    mb = ua = None
    lines = []
    stats = PollStats()
    gone = None
    try:
        if a.modbus:
            from . import modbus
            host, port = _hostport(a.modbus, 502)
            mmap = modbus_map(model, a.writable)
            mb = await modbus.start(kernel, mmap, host, port)
            lines.append(f"modbus tcp://{host}:{port}: {len(mmap.coils)} coils, "
                         f"{len(mmap.discrete)} discrete inputs, {len(mmap.inputs)} input "
                         f"registers, {len(mmap.holding)} holding registers")
            for why in mmap.skipped:
                lines.append(f"  not on Modbus: {why}")
        if a.opcua:
            from .opcua import OpcUaServer
            ua = OpcUaServer(model, kernel, a.opcua, writable_all=a.writable, users=users,
                             allow_anonymous=a.allow_anonymous, security=a.security,
                             cert_dir=Path(a.cert_dir))
            print(f"starting opc ua {a.opcua} ({len(model.order)} variables)", flush=True)
            await ua.start()
            lines.append(f"opc ua {a.opcua}: {len(model.order)} variables, "
                         f"{len(model.access)} access paths, security "
                         f"{'Basic256Sha256 SignAndEncrypt' if a.security == 'encrypt' else 'none or Basic256Sha256'}"
                         f", {len(users)} users{', anonymous read' if a.allow_anonymous else ''}")
        fastest = model.fastest_interval_ns()
        period = max((fastest or 0) / 1e9, a.period_min / 1000.0)
        lines.append(f"serving {model.configuration}: polling every {period * 1000:.0f} ms "
                     f"(started in {time.monotonic() - t_start:.1f} s, the model "
                     f"{t_model:.1f} s)")
        print("\n".join(lines), flush=True)
        serving[0] = True
        gone = await _poll(kernel, model, ua, period, stop, stats, a.gone_after)
    except asyncio.CancelledError:
        print("serve: stopped while starting", flush=True)
    finally:
        if ua is not None:
            await ua.stop()
        if mb is not None:
            await mb.shutdown()
        kernel.close()
    print(f"stopped: {kernel.requests} kernel requests"
          + (f", modbus {mb.plc_context.requests} requests ({mb.plc_context.refused} refused)"
             if mb else "")
          + (f", opc ua {ua.writes} writes ({ua.refused} refused); poller: {stats.text()}"
             if ua else ""), flush=True)
    if gone:
        print(f"serve: {gone}: stopping (exit {EXIT_RELOAD}; start it again to serve what "
              f"runs now)", file=sys.stderr, flush=True)
        return EXIT_RELOAD
    return 0


class PollStats:
    def __init__(self) -> None:
        self.polls = 0
        self.total = 0.0
        self.max = 0.0
        self.late = 0
        self.sampled = 0

    def text(self) -> str:
        if not self.polls:
            return "no polls"
        return (f"{self.polls} polls, {1000 * self.total / self.polls:.1f} ms mean, "
                f"{1000 * self.max:.1f} ms max, {self.late} longer than the period, "
                f"{self.sampled} values sampled")


GONE_AFTER = 30.0     # seconds without an answer from the kernel: the configuration is gone
EXIT_RELOAD = 75      # EX_TEMPFAIL: the configuration changed; start serve again


async def _poll(kernel, model, ua, period: float, stop: asyncio.Event,
                stats: PollStats, gone_after: Optional[float] = None) -> Optional[str]:
    """Each *period* (the fastest task's interval, at least --period-min;
    Modbus only: each second) reads the tasks' status and, for every task
    that ended a cycle since its variables were last sampled and whose
    interval has passed, the variables of it that a client subscribes to
    (globals with the fastest task); a poll that takes longer than the
    period is followed by a pause as long as itself (at most half the
    server's time goes to polling, the clients get the rest).  Variables
    nobody subscribes to are not read (a client's Read asks the kernel
    itself; Modbus requests too).

    When the kernel does not answer, every value says BadServerHalted at
    once.  Returns why it ended other than by *stop*: the kernel runs
    another configuration or another interface (a load, a swap that
    changed the interface: the address space and the map no longer fit),
    or it has not answered for GONE_AFTER seconds (stopped)."""
    failing_since = None
    gone_after = GONE_AFTER if gone_after is None else gone_after
    if ua is None:
        period = max(period, 1.0)
    sampled: dict = {}       # 'res.task' -> (cycles, monotonic time) of its last sample
    while not stop.is_set():
        t0 = time.monotonic()
        try:
            st = await kernel.status()
            if st.configuration.lower() != model.configuration.lower() or \
                    (model.interface_hash and st.interface_hash != model.interface_hash):
                return (f"the kernel runs {st.configuration} (interface {st.interface_hash}), "
                        f"not what is served ({model.configuration}, interface "
                        f"{model.interface_hash})")
            if ua is not None:
                due = set()
                for t in st.tasks():
                    key = t.path.lower()
                    cyc, when = sampled.get(key, (None, -1e9))
                    if t.cycles != cyc and t0 - when >= (t.interval_ns or 0) / 1e9 - period / 2:
                        due.add(key)
                        sampled[key] = (t.cycles, t0)
                paths = [p for p in ua.wanted()
                         if (ua._task_of(p) in due) or (ua._task_of(p) is None and due)]
                stats.sampled += len(paths)
                snap = await kernel.read(paths) if paths else {}
                await ua.update(snap, st)
            if failing_since is not None:
                print("serve: the kernel answers again", file=sys.stderr, flush=True)
            failing_since = None
        except PLCError as e:
            if failing_since is None:
                print(f"serve: cannot read the kernel: {e}", file=sys.stderr, flush=True)
                failing_since = t0
                if ua is not None:
                    await ua.halt()
            elif t0 - failing_since >= gone_after:
                return f"no answer from the kernel for {gone_after:.0f} s: {e}"
        took = time.monotonic() - t0
        stats.polls += 1
        stats.total += took
        stats.max = max(stats.max, took)
        if took > period:
            stats.late += 1
        delay = max(period - took, min(took, 1.0)) if took > period else period - took
        try:
            await asyncio.wait_for(stop.wait(), timeout=delay)
        except asyncio.TimeoutError:
            pass
    return None


def main_serve(a) -> int:
    logging.basicConfig(level=logging.WARNING, format="%(name)s: %(message)s")
    logging.getLogger("asyncua").setLevel(logging.ERROR)
    # pymodbus logs a client that leaves mid-request as an error with a dump
    # of its last frames: the server counts requests and refusals itself
    logging.getLogger("pymodbus").setLevel(logging.CRITICAL)
    return asyncio.run(serve(a))


def main_user(a) -> int:
    from .opcua import add_user
    if a.password_stdin:
        pw = sys.stdin.readline().rstrip("\n")
    else:
        import getpass
        pw = getpass.getpass(f"password of {a.name}: ")
    if len(pw) < 8:
        raise UsageError("a password of at least 8 characters")
    add_user(a.file, a.name, a.role, pw)
    print(f"{a.file}: user {a.name} ({a.role})")
    return 0


def add_parsers(sub) -> None:
    s = sub.add_parser("serve", help="OPC UA and Modbus TCP servers on the running "
                                     "configuration (long-running)")
    s.add_argument("--opcua", metavar="opc.tcp://HOST:PORT", help="OPC UA endpoint")
    s.add_argument("--modbus", metavar="HOST:PORT", help="Modbus TCP address")
    s.add_argument("--project", metavar="DIR", help="the running build (default: the copy "
                                                    "saved at load)")
    s.add_argument("--writable", action="store_true",
                   help="without access paths, clients may write what the kernel lets write "
                        "(default: read-only)")
    s.add_argument("--users", metavar="FILE", help="OPC UA users (plc-manager serve-user)")
    s.add_argument("--allow-anonymous", action="store_true",
                   help="OPC UA anonymous sessions (read-only)")
    s.add_argument("--security", choices=["encrypt", "none"], default="encrypt",
                   help="encrypt: Basic256Sha256 SignAndEncrypt only (default); none: also "
                        "an unencrypted endpoint")
    s.add_argument("--cert-dir", default="/var/lib/plc-manager/opcua", metavar="DIR",
                   help="the server's certificate and key (generated when missing)")
    s.add_argument("--gone-after", type=float, default=GONE_AFTER, metavar="S",
                   help="a kernel that does not answer for so long (a stop; a load takes "
                        "seconds) ends serve with exit 75 (default 30 s); until then values "
                        "say BadServerHalted")
    s.add_argument("--period-min", type=float, default=20.0, metavar="MS",
                   help="the poller's shortest period (default 20 ms)")
    s.set_defaults(func=main_serve)
    s = sub.add_parser("serve-user", help="add or change a user of the OPC UA server")
    s.add_argument("file")
    s.add_argument("name")
    s.add_argument("--role", choices=["read", "write"], default="read")
    s.add_argument("--password-stdin", action="store_true")
    s.set_defaults(func=main_user)
