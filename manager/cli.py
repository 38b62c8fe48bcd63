# SPDX-License-Identifier: MIT
"""plc-manager: load, hot-swap and stop iec2kmod configurations; status and
live variables.

    plc-manager load DIR [--no-start]      insert a built project, start its tasks
    plc-manager swap NEW [--restart]       hot code change (a rebuilt program-type
                                           module, its directory, or a rebuilt project);
                                           --restart: then restart the tasks stopped on
                                           a fault that run the swapped program types
    plc-manager swap --prepare NEW         its slow half: check, insert staged
    plc-manager swap --publish | --unstage its quick half, or drop what is staged
    plc-manager stop [--keep-loaded] [--resource R]
    plc-manager start [--resource R]
    plc-manager status [--json]
    plc-manager read VAR... [--json]
    plc-manager write VAR VALUE            IEC literal: TRUE, 42, 16#FF, 1.5, T#20ms, 'text'
    plc-manager force VAR VALUE            held at every cycle boundary until unforce
    plc-manager unforce VAR... | --all
    plc-manager watch VAR... [--interval S] [--count N] [--json]
    plc-manager vars [PATTERN] [--json]    the variables of the running configuration

Exit status 0 on success; 1 with one line on stderr when something is
refused or fails (nothing is changed by refused input); 2 for command-line
usage errors.  Netlink commands need CAP_NET_ADMIN, loading and removing
modules CAP_SYS_MODULE: run as root.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import fnmatch
import json
import os
import sys
import time
from typing import List, Optional, Sequence

from .errors import PLCError, UsageError

PROG = "plc-manager"


# ---------------------------------------------------------------------------
# formatting

def table(headers: Sequence[str], rows: Sequence[Sequence[object]],
          right: Sequence[int] = ()) -> str:
    cells = [[str(h) for h in headers]] + [[str(c) for c in r] for r in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(headers))]
    out = []
    for r in cells:
        line = []
        for i, c in enumerate(r):
            line.append(c.rjust(widths[i]) if i in right else c.ljust(widths[i]))
        out.append("  ".join(line).rstrip())
    return "\n".join(out)


def fmt_ns(ns: Optional[int]) -> str:
    if ns is None:
        return "-"
    a = abs(ns)
    if a < 1_000:
        return f"{ns} ns"
    if a < 1_000_000:
        return f"{ns / 1e3:.1f} us"
    if a < 1_000_000_000:
        return f"{ns / 1e6:.2f} ms"
    return f"{ns / 1e9:.3f} s"


def fmt_period(ns: int) -> str:
    if not ns:
        return "event"
    for unit, n in (("s", 10**9), ("ms", 10**6), ("us", 10**3)):
        if ns >= n and ns % n == 0:
            return f"{ns // n} {unit}"
    return fmt_ns(ns)


def fmt_us(ns: int) -> str:
    return f"{ns / 1000:.1f}"


def fmt_since(since_ns: int, now_ns: int) -> str:
    if not since_ns:
        return "-"
    t = _dt.datetime.fromtimestamp(since_ns / 1e9)
    age = max(0, (now_ns - since_ns) / 1e9)
    ago = f"{age:.0f} s ago" if age < 120 else f"{age / 60:.0f} min ago" if age < 7200 \
        else f"{age / 3600:.0f} h ago"
    return f"{t:%Y-%m-%d %H:%M:%S} ({ago})"


def fmt_time(ns: Optional[int]) -> str:
    """A CLOCK_REALTIME time of the kernel, to the millisecond."""
    if not ns:
        return "-"
    return _dt.datetime.fromtimestamp(ns / 1e9).strftime("%Y-%m-%d %H:%M:%S.%f")[:-3]


def status_text(st) -> str:
    out = [f"configuration {st.configuration}  module {st.module}  sources {st.source_hash}  "
           f"interface {st.interface_hash}  forced variables {st.forced}", ""]
    out.append(table(["RESOURCE", "CPU", "MODULE", "TASKS"],
                     [[r.name, r.cpu if r.cpu >= 0 else "any", r.module, len(r.tasks)]
                      for r in st.resources]) if st.resources else "no resource registered")
    rows, faults, long, sel = [], [], [], []
    for t in st.tasks():
        if t.sel_evaluated is not None:
            total = t.sel_evaluated + (t.sel_skipped or 0)
            sel.append([t.path, t.sel_evaluated, t.sel_skipped or 0,
                        f"{100.0 * (t.sel_skipped or 0) / total:.1f}" if total else "-"])
        ran = t.cycles > 0
        rows.append([t.path, t.state, fmt_period(t.interval_ns), t.priority, t.last_cpu,
                     t.cycles,
                     f"{fmt_us(t.exec_min_ns)}/{fmt_us(t.exec_avg_ns)}/{fmt_us(t.exec_max_ns)}"
                     if ran else "-",
                     f"{fmt_us(t.latency_avg_ns)}/{fmt_us(t.latency_max_ns)}" if ran else "-",
                     t.overruns, t.faults, max(t.starts - 1, 0),
                     fmt_time(t.started_ns) if t.starts > 1 else "-"])
        if t.fault:
            when = f" at {fmt_time(t.fault_ns)}" if t.fault_ns else ""
            from .ops import fault_text
            what = f"{fault_text(t)}{when}"
            if t.state == "fault":
                faults.append(f"  {t.path}: stopped on a fault: {what}")
            else:
                faults.append(f"  {t.path}: last fault: {what}; restarted at "
                              f"{fmt_time(t.started_ns)}")
        if (t.in_cycle_ns or 0) >= 100_000_000:
            long.append(f"  {t.path}: inside one cycle for {t.in_cycle_ns // 1_000_000} ms")
    if rows:
        out += ["", table(["TASK", "STATE", "PERIOD", "PRIO", "CPU", "CYCLES",
                           "EXEC us min/avg/max", "JITTER us avg/max", "OVERRUNS", "FAULTS",
                           "RESTARTS", "LAST RESTART"],
                          rows, right=(3, 4, 5, 8, 9, 10))]
    if sel:
        out += ["", table(["TASK", "BLOCKS EVALUATED", "SKIPPED", "SKIPPED %"], sel,
                          right=(1, 2, 3))]
    if faults:
        out += ["", "faults (the last one of each task since the load):"] + faults
    if long:
        out += ["", "tasks inside a long cycle (stop and unload wait for them, with a bound):"] + long
    io = io_bindings(st)
    if io:
        out += ["", "I/O (LAST: the sample last read from or written to the device; "
                "/sys/module/<module>/iec_io):",
                table(["RESOURCE", "ADDRESS", "VARIABLE", "CHANNEL", "DIR", "SAFE", "LAST RAW",
                       "LAST VALUE"],
                      [[b.resource, b.address, b.variable, b.where, "in" if b.input else "out",
                        b.safe_text, "-" if b.last is None else b.last, b.value or "-"]
                       for b in io], right=(6,))]
    irqs = io_interrupts(st)
    if irqs:
        out += ["", "interrupts (COUNT: taken since the load; /sys/module/<module>/iec_io):",
                table(["RESOURCE", "ADDRESS", "VARIABLE", "SOURCE", "IRQ", "WAKES", "COUNT"],
                      [[q.resource, q.address, q.variable, q.where, q.irq,
                        ",".join(q.tasks) or "-", "-" if q.count is None else q.count]
                       for q in irqs], right=(4, 6))]
    out += ["", table(["SLOT", "PROGRAM TYPE", "MODULE", "BUILD", "SINCE"],
                      [[s.index, s.type_name, s.module or "(empty)", s.build_id or "-",
                        fmt_since(s.since_ns, st.now_ns)] for s in st.slots])]
    return "\n".join(out)


def io_bindings(st) -> list:
    """The running configuration's I/O bindings with their last values
    (manager/io.py), from the state saved at load; [] without."""
    from . import io
    from .ops import running_state
    s = running_state(st)
    return io.bindings(s.data.get("io") or {}) if s is not None else []


def io_interrupts(st) -> list:
    """The running configuration's interrupt sources with their counts
    (manager/io.py), from the state saved at load; [] without."""
    from . import io
    from .ops import running_state
    s = running_state(st)
    return io.interrupts(s.data.get("irqs") or {}) if s is not None else []


def status_json(st) -> dict:
    return {
        "configuration": st.configuration, "module": st.module, "abi": st.abi,
        "source_hash": st.source_hash, "interface_hash": st.interface_hash,
        "now_ns": st.now_ns, "forced": st.forced,
        "resources": [{"name": r.name, "module": r.module, "cpu": r.cpu,
                       "tasks": [dict(t.__dict__, path=t.path) for t in r.tasks]}
                      for r in st.resources],
        "slots": [dict(s.__dict__) for s in st.slots],
        "io": [dict(b.__dict__, where=b.where, last_value=b.value) for b in io_bindings(st)],
        "interrupts": [dict(q.__dict__, where=q.where) for q in io_interrupts(st)],
    }


def _var_rows(items):
    from . import values
    return [[t.path, t.shown, values.text(t, v), "forced" if raw.forced else ""]
            for t, raw, v in items]


def _var_json(items):
    from . import values
    return [{"path": t.path, "type": t.shown, "kind": t.kind,
             "value": values.json_value(t, v), "text": values.text(t, v),
             "forced": raw.forced, "writable": raw.writable} for t, raw, v in items]


# ---------------------------------------------------------------------------
# commands

def _say(msg: str) -> None:
    print(msg, flush=True)


def cmd_load(a) -> int:
    from . import ops
    rep = ops.load(a.dir, start=not a.no_start, progress=_quiet if a.json else _say)
    if a.json:
        print(json.dumps({"configuration": rep.configuration,
                          "modules": [{"name": n, "insert_ms": ms} for n, ms in rep.modules],
                          "start_ms": rep.start_ms, "total_ms": rep.total_ms,
                          "phases": rep.phases}))
    return 0


def cmd_swap(a) -> int:
    from . import ops
    say = _quiet if a.json else _say
    if sum(map(bool, (a.prepare, a.publish, a.unstage))) > 1:
        raise UsageError("swap: --prepare, --publish and --unstage exclude each other")
    if (a.new is None) != bool(a.publish or a.unstage):
        raise UsageError("swap: NEW is needed, except with --publish and --unstage"
                         if a.new is None else
                         "swap: --publish and --unstage take no NEW (what is staged)")
    if a.restart and (a.prepare or a.unstage):
        raise UsageError("swap: --restart goes with a swap that publishes (not --prepare "
                         "or --unstage)")
    if a.unstage:
        ops.unstage(progress=say)
        return 0
    rep = ops.publish(restart=a.restart, progress=say) if a.publish else \
        ops.swap(a.new, restart=a.restart, progress=say, prepare_only=a.prepare)
    if a.json:
        print(json.dumps({"check_ms": rep.check_ms, "prepare_ms": rep.prepare_ms,
                          "published": rep.published, "total_ms": rep.total_ms,
                          "phases": rep.phases,
                          "steps": [s.__dict__ for s in rep.steps],
                          "restarted": rep.restarted}))
    elif rep.steps and rep.published:
        _say(f"swap done in {rep.total_ms:.1f} ms (checks {rep.check_ms:.1f} ms)")
    return 0


def cmd_stop(a) -> int:
    from . import ops
    ops.stop(keep_loaded=a.keep_loaded, resource=a.resource, progress=_say)
    return 0


def cmd_start(a) -> int:
    from . import ops
    ops.start(resource=a.resource, progress=_say)
    return 0


def cmd_status(a) -> int:
    from . import ops
    with ops.connect() as c:
        st = c.status()
    print(json.dumps(status_json(st), indent=1) if a.json else status_text(st))
    return 0


def _variables(a):
    from . import ops
    c = ops.connect()
    try:
        return c, ops.Variables(c, c.status(), a.project)
    except BaseException:
        c.close()
        raise


def cmd_read(a) -> int:
    c, vs = _variables(a)
    with c:
        items = vs.read(a.vars)
    if a.json:
        print(json.dumps(_var_json(items)))
    else:
        print(table(["VARIABLE", "TYPE", "VALUE", ""], _var_rows(items)))
    return 0


def cmd_write(a) -> int:
    from . import values
    c, vs = _variables(a)
    with c:
        (t,) = vs.write([(a.var, a.value)])
        ((_, _, v),) = vs.read([t.path])
    print(f"{t.path} := {values.text(t, v)}")
    return 0


def cmd_force(a) -> int:
    from . import values
    c, vs = _variables(a)
    with c:
        (t,) = vs.force([(a.var, a.value)])
        v = values.decode(t, values.encode(t, values.parse(t, a.value)))
    print(f"{t.path} forced to {values.text(t, v)}")
    return 0


def cmd_unforce(a) -> int:
    c, vs = _variables(a)
    with c:
        if a.all:
            c.var_unforce(everything=True)
            print("every variable unforced")
            return 0
        if not a.vars:
            raise PLCError("unforce: name variables, or --all")
        types = vs.unforce(a.vars)
    print("unforced " + ", ".join(t.path for t in types))
    return 0


def cmd_watch(a) -> int:
    c, vs = _variables(a)
    tty = sys.stdout.isatty() and not a.json
    n = 0
    with c:
        for name in a.vars:
            vs.get(name)                     # unknown names fail before the first frame
        try:
            while a.count is None or n < a.count:
                items = vs.read(a.vars)
                now = _dt.datetime.now().strftime("%H:%M:%S.%f")[:-3]
                if a.json:
                    print(json.dumps({"time": now, "variables": _var_json(items)}), flush=True)
                else:
                    text = f"{now}  every {a.interval:g} s  (Ctrl-C ends)\n" + \
                        table(["VARIABLE", "TYPE", "VALUE", ""], _var_rows(items))
                    if tty:
                        sys.stdout.write("\x1b[H\x1b[2J" + text + "\n")
                        sys.stdout.flush()
                    else:
                        print(text + "\n", flush=True)
                n += 1
                if a.count is None or n < a.count:
                    time.sleep(a.interval)
        except KeyboardInterrupt:
            pass
    return 0


def cmd_vars(a) -> int:
    c, vs = _variables(a)
    with c:
        types = sorted(vs.types.values(), key=lambda t: t.path)
    if a.pattern:
        types = [t for t in types if fnmatch.fnmatch(t.path.lower(), a.pattern.lower())]
    if a.json:
        print(json.dumps([{"path": t.path, "type": t.shown, "kind": t.kind, "size": t.size,
                           "writable": t.writable} for t in types]))
    else:
        print(table(["VARIABLE", "TYPE", "ACCESS"],
                    [[t.path, t.shown, "read-write" if t.writable else "read-only"]
                     for t in types]))
    return 0


def _quiet(_msg: str) -> None:
    pass


def cmd_shell(a) -> int:
    """Resident mode: reads commands from standard input, one per line (a
    plc-manager command line without `plc-manager`, shell quoting), and runs
    each in this process.  Python, pyroute2 and the manager are loaded once
    (seconds in a slow guest), so a `swap --publish` sent here takes only its
    own time.  After each command a line `= N` (its exit status);
    `quit` or the end of the input ends the shell (exit 0)."""
    import shlex
    from . import netlink, ops  # noqa: F401  (loaded now, not by the first command)
    netlink._classes()
    for line in sys.stdin:
        try:
            words = shlex.split(line, comments=True)
        except ValueError as e:
            print(f"{PROG}: {e}", file=sys.stderr, flush=True)
            print("= 2", flush=True)
            continue
        if not words:
            continue
        if words[0] in ("quit", "exit"):
            break
        if words[0] == "shell":
            print(f"{PROG}: already in the shell", file=sys.stderr, flush=True)
            rc = 2
        else:
            try:
                rc = main(words)
            except SystemExit as e:         # argparse: usage error or --help
                rc = e.code if isinstance(e.code, int) else 2
        sys.stderr.flush()
        print(f"= {rc}", flush=True)
    return 0


# ---------------------------------------------------------------------------

def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog=PROG, description="Load, hot-swap and stop iec2kmod "
                                "PLC configurations; status and live variables.")
    p.add_argument("--project", metavar="DIR",
                   help="manifest of the running configuration (default: the one saved at load)")
    sub = p.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True

    s = sub.add_parser("load", help="insert a built project's modules and start its tasks")
    s.add_argument("dir", help="project directory (iec2kmod gen + build)")
    s.add_argument("--no-start", action="store_true", help="leave the tasks stopped")
    s.add_argument("--json", action="store_true", help="timings as JSON")
    s.set_defaults(func=cmd_load)

    s = sub.add_parser("swap", help="hot code change of program types")
    s.add_argument("new", nargs="?", help="a rebuilt program-type module (.ko or its "
                                          "directory) or a rebuilt project directory")
    s.add_argument("--prepare", action="store_true",
                   help="only check and insert the new builds, staged in their slots (the "
                        "slow half); the tasks run the old ones until --publish")
    s.add_argument("--publish", action="store_true",
                   help="publish what --prepare staged (the quick half), remove the old "
                        "modules")
    s.add_argument("--unstage", action="store_true",
                   help="drop what --prepare staged, unpublished")
    s.add_argument("--restart", action="store_true",
                   help="then restart the tasks of the swapped program types that are "
                        "stopped on a fault (their state is kept)")
    s.add_argument("--json", action="store_true", help="timings as JSON")
    s.set_defaults(func=cmd_swap)

    s = sub.add_parser("stop", help="stop the tasks and remove the modules")
    s.add_argument("--keep-loaded", action="store_true", help="only stop the tasks")
    s.add_argument("--resource", metavar="R", help="stop the tasks of one resource only")
    s.set_defaults(func=cmd_stop)

    s = sub.add_parser("start", help="start the tasks")
    s.add_argument("--resource", metavar="R", help="start the tasks of one resource only")
    s.set_defaults(func=cmd_start)

    s = sub.add_parser("status", help="configuration, resources, tasks, GFT slots")
    s.add_argument("--json", action="store_true")
    s.set_defaults(func=cmd_status)

    s = sub.add_parser("read", help="read variables")
    s.add_argument("vars", nargs="+", metavar="VAR")
    s.add_argument("--json", action="store_true")
    s.set_defaults(func=cmd_read)

    s = sub.add_parser("write", help="write a variable (IEC literal)")
    s.add_argument("var", metavar="VAR")
    s.add_argument("value", metavar="VALUE")
    s.set_defaults(func=cmd_write)

    s = sub.add_parser("force", help="force a variable (held at every cycle boundary)")
    s.add_argument("var", metavar="VAR")
    s.add_argument("value", metavar="VALUE")
    s.set_defaults(func=cmd_force)

    s = sub.add_parser("unforce", help="release forced variables")
    s.add_argument("vars", nargs="*", metavar="VAR")
    s.add_argument("--all", action="store_true", help="every forced variable")
    s.set_defaults(func=cmd_unforce)

    s = sub.add_parser("watch", help="live table of variables")
    s.add_argument("vars", nargs="+", metavar="VAR")
    s.add_argument("--interval", type=float, default=0.5, metavar="S")
    s.add_argument("--count", type=int, metavar="N", help="refresh N times, then exit")
    s.add_argument("--json", action="store_true", help="one JSON line per refresh")
    s.set_defaults(func=cmd_watch)

    s = sub.add_parser("shell", help="resident mode: run commands read from standard "
                                     "input, one per line, in this process")
    s.set_defaults(func=cmd_shell)

    s = sub.add_parser("vars", help="list the variables")
    s.add_argument("pattern", nargs="?", help="glob, e.g. 'main.c1.*'")
    s.add_argument("--json", action="store_true")
    s.set_defaults(func=cmd_vars)

    s = sub.add_parser("io-daemon", help="reference daemon of a user I/O device: maps "
                                         "/dev/iec_io_*, answers each cycle's outputs "
                                         "with inputs (loopback rules)")
    from .iodaemon import add_arguments as _io_args, run as _io_run
    _io_args(s)
    s.set_defaults(func=_io_run)

    from .serve import add_parsers as _serve_parsers
    _serve_parsers(sub)
    return p


def main(argv: Optional[List[str]] = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except PLCError as e:
        print(f"{PROG}: {e}", file=sys.stderr, flush=True)
        return e.exit_code
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0
    except OSError as e:
        print(f"{PROG}: {e.filename + ': ' if e.filename else ''}{e.strerror or e}",
              file=sys.stderr, flush=True)
        return 1
    except Exception as e:          # a bug: say so in one line, details on request
        if isinstance(e, ModuleNotFoundError) and (e.name or "").startswith("pyroute2"):
            print(f"{PROG}: pyroute2 is not installed: pip install 'iec2kmod[manager]'",
                  file=sys.stderr, flush=True)
            return 1
        if os.environ.get("PLC_MANAGER_DEBUG"):
            raise
        print(f"{PROG}: internal error: {e.__class__.__name__}: {e} "
              f"(PLC_MANAGER_DEBUG=1 shows where)", file=sys.stderr, flush=True)
        return 70


if __name__ == "__main__":
    sys.exit(main())
