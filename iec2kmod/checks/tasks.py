"""Pass 'configure', tasks: a TASK's INTERVAL, PRIORITY and SINGLE checked,
and the {watchdog ...} pragma in front of it read (the limits both engines
and the kernel module apply to a cycle).

``TaskChecks`` is mixed into checks.config.ConfigChecker, whose ``decl``
(constant values), ``error``, ``warning`` and ``watchdogs_used`` it uses."""

from __future__ import annotations

import re

from .. import ast
from ..parse.literals import LiteralError, parse_duration
from .consts import ConstError
from .symbols import TaskInfo
from .types import BOOL

MAX_PRIORITY = 48   # IEC 0 (most urgent) .. 48 -> SCHED_FIFO 49 .. 1


# The watchdog of a task (issue 9): set by a pragma in front of its TASK
# declaration, {watchdog TIME} or {watchdog TIME, N}; TIME is a TIME literal
# or "off", N the number of overrunning cycles in a row that fault the task
# (0 or absent: no such limit).  Without a pragma: WATCHDOG_DEFAULT_NS and
# no overrun limit.
WATCHDOG_DEFAULT_NS = 5_000_000_000
WATCHDOG_MAX_OVERRUNS = 1_000_000


class TaskChecks:
    def task(self, t, r, cfg) -> TaskInfo:
        src = cfg.src
        info = TaskInfo(t.name, t.pos)
        for key, (expr, pos) in t.props.items():
            if key == "INTERVAL":
                try:
                    v = self.decl.const_value(expr, src, "INTERVAL")
                except ConstError:
                    self.error(src, expr.pos, "INTERVAL must be a constant TIME, e.g. T#10ms")
                    continue
                named = r.globals.get(expr.name.upper()) or cfg.globals.get(
                    expr.name.upper()) if isinstance(expr, ast.Ref) else None
                is_time = (isinstance(expr, ast.Lit) and expr.kind == "time") or (
                    named is not None and named.constant and
                    getattr(named.type, "cat", None) == "time")
                if not is_time or v <= 0:
                    self.error(src, expr.pos, "INTERVAL must be a positive TIME literal or "
                                              "TIME constant, e.g. T#10ms")
                    continue
                if v < 50_000:
                    self.error(src, expr.pos, "INTERVAL below 50 us cannot be met by a kernel "
                                              "thread; use at least T#50us")
                    continue
                info.interval_ns = v
            elif key == "PRIORITY":
                try:
                    v = self.decl.const_value(expr, src, "PRIORITY")
                except ConstError:
                    self.error(src, expr.pos, "PRIORITY must be an integer constant")
                    continue
                if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v <= MAX_PRIORITY:
                    self.error(src, expr.pos, f"PRIORITY must be 0 (most urgent) .. "
                                              f"{MAX_PRIORITY}")
                    continue
                info.priority = v
            elif key == "SINGLE":
                if not isinstance(expr, ast.Ref) or expr.accessors:
                    self.error(src, expr.pos, "SINGLE must name a BOOL global variable")
                    continue
                v = r.globals.get(expr.name.upper()) or cfg.globals.get(expr.name.upper())
                if v is None:
                    self.error(src, expr.pos, f"unknown global variable '{expr.name}'")
                    continue
                if v.type is not BOOL:
                    self.error(src, expr.pos, f"SINGLE variable '{expr.name}' must be BOOL, "
                                              f"not {v.type.name}")
                    continue
                v.used = True
                info.single = v
                info.single_name = v.name
        self.watchdog(info, t, src)
        if "PRIORITY" not in t.props:
            self.error(src, t.pos, f"task '{t.name}' needs a PRIORITY")
        if info.interval_ns is None and info.single is None and \
                "INTERVAL" not in t.props and "SINGLE" not in t.props:
            self.error(src, t.pos, f"task '{t.name}' needs an INTERVAL (periodic) or a SINGLE "
                                   "(event) variable")
        if "INTERVAL" in t.props and "SINGLE" in t.props:
            self.error(src, t.pos, f"task '{t.name}' has both INTERVAL and SINGLE: a task is "
                                   "periodic or event-driven")
        return info

    def watchdog(self, info: TaskInfo, t, src) -> None:
        """The {watchdog ...} pragma right in front of the TASK, if any (the
        parser attached it to the Task: parse/lexical.attach)."""
        info.watchdog_ns = WATCHDOG_DEFAULT_NS
        m = next((p for p in t.pragmas or () if p.kind == "watchdog"), None)
        if not m:
            return
        self.watchdogs_used.add((src.path, m.start))
        pos = m.start
        words = [w.strip() for w in m.body.split(",")]
        usage = "write {watchdog T#20ms}, {watchdog T#20ms, 3} or {watchdog off, 3}"
        if len(words) > 2 or not words[0]:
            self.error(src, pos, f"malformed watchdog pragma: {usage}")
            return
        if words[0].lower() == "off":
            ns = 0
        else:
            body = re.match(r"(?:T|TIME)#(.+)\Z", words[0], re.I)
            try:
                ns = parse_duration(body.group(1)) if body else None
            except LiteralError:
                ns = None
            if ns is None:
                self.error(src, pos, f"watchdog time '{words[0]}' is not a TIME literal: "
                                     f"{usage}")
                return
            if ns <= 0:
                self.error(src, pos, "the watchdog time must be positive (or off)")
                return
        n = 0
        if len(words) == 2:
            if not words[1].isdigit() or int(words[1]) > WATCHDOG_MAX_OVERRUNS:
                self.error(src, pos, f"the overrun limit '{words[1]}' is not a number of "
                                     f"cycles 0..{WATCHDOG_MAX_OVERRUNS}: {usage}")
                return
            n = int(words[1])
        if n and not info.interval_ns:
            self.error(src, pos, "an overrun limit needs a periodic task (INTERVAL)")
            return
        info.watchdog_ns, info.watchdog_overruns = ns, n

    def unused_watchdogs(self, units) -> None:
        for unit in units:
            src = unit.src
            for m in unit.pragmas or ():
                if m.kind == "watchdog" and (src.path, m.start) not in self.watchdogs_used:
                    self.warning(src, m.start, "watchdog pragma applies to nothing: put it "
                                                  "right in front of a TASK declaration")
