"""`iec2kmod verify`: the command.

Exit status: 0 every property proved; 1 source errors, or a construct that
cannot be encoded (an error naming it); 2 usage or I/O errors; 3 a property
violated (its counterexample written and replayed); 4 no violation up to
--depth cycles but not every property proved (or unknown: --timeout);
5 vacuous: the assumptions allow no run longer than K cycles, and no
property is violated in the runs they allow; 70 internal error.  With
several checks the status is the first of 3, 5, 4, 0 that one of them
has.  Each verdict is printed as soon as it is decided."""

from __future__ import annotations

import re
import sys
from pathlib import Path

EXIT_PROVED, EXIT_SOURCE, EXIT_USAGE, EXIT_VIOLATED, EXIT_BOUNDED, EXIT_VACUOUS, \
    EXIT_INTERNAL = 0, 1, 2, 3, 4, 5, 70


def cex_paths(cex_dir, name):
    """The CSV and VCD files of property *name*'s counterexample in
    *cex_dir* (both engines name them so)."""
    stem = "cex_" + re.sub(r"[^A-Za-z0-9_]+", "_", name).strip("_")
    return cex_dir / f"{stem}.csv", cex_dir / f"{stem}.vcd"


def _fmt_time(ns):
    if ns % 1_000_000_000 == 0:
        return f"{ns // 1_000_000_000} s"
    if ns % 1_000_000 == 0:
        return f"{ns // 1_000_000} ms"
    return f"{ns / 1e6:g} ms"


def sim_command(files, csv_path, cycle, sym):
    """The `iec2kmod sim` command that replays a counterexample to the end
    of step `cycle`: step K runs at (K-1) * step, and sim's --duration
    includes the cycles released at that instant."""
    import shlex
    end = (cycle - 1) * sym.period
    dur = f"{end // 1_000_000}ms" if end % 1_000_000 == 0 else f"{end}ns"
    return " ".join(["iec2kmod", "sim", *map(shlex.quote, map(str, files)), "--inputs",
                     shlex.quote(str(csv_path)), "--duration", dur])


def run_verify(args) -> int:
    if getattr(args, "engine", "z3") == "explicit":
        from .explicit import run_cli
        return run_cli(args)
    import time
    from ..cli import front_end, print_diagnostics
    from ..diagnostics import Diagnostics
    from . import Refuse, UsageError, verify
    from .cex import replay, write_trace
    if args.unroll < 1:
        print("iec2kmod: error: --unroll must be at least 1", file=sys.stderr)
        return EXIT_USAGE
    if args.depth < 1:
        print("iec2kmod: error: --depth must be at least 1", file=sys.stderr)
        return EXIT_USAGE
    if args.timeout is not None and args.timeout <= 0:
        print("iec2kmod: error: --timeout must be a positive number of seconds",
              file=sys.stderr)
        return EXIT_USAGE
    project = front_end(args.files)
    if project is None:
        return EXIT_SOURCE
    t_start = time.monotonic()
    deadline = t_start + args.timeout if args.timeout is not None else None
    diags = Diagnostics()
    cex_dir = Path(args.cex_dir)
    st = {"worst": EXIT_PROVED, "faulty": False, "width": 16, "out": None, "error": None,
          "seen": []}

    def worse(code):
        # violated (3) first, then vacuous (5), then undecided (4)
        rank = {EXIT_PROVED: 0, EXIT_BOUNDED: 1, EXIT_VACUOUS: 2, EXIT_VIOLATED: 3}
        if rank[code] > rank[st["worst"]]:
            st["worst"] = code

    def built(out):
        st["out"] = out
        sym = out.sym
        tasks = ", ".join(f"{t.name} every {_fmt_time(t.interval_ns)}" if t.single is None
                          else f"{t.name} on {t.single.name}" for t in sym.tasks)
        step = f"; a step is {_fmt_time(sym.period)}" if len(sym.tasks) > 1 else ""
        print(f"configuration {sym.cfg.name}: task{'s' if len(sym.tasks) > 1 else ''} {tasks}"
              f"{step}; {out.leaves} state variables, {out.inputs} inputs; "
              f"{len(out.props)} properties", flush=True)
        if sym.events:
            print(f"note: the inputs change at the instants of the step "
                  f"({_fmt_time(sym.period)}); an event task triggered by an input between two "
                  "steps is not modelled", flush=True)
        st["width"] = max([len("no runtime error")] + [len(n) for n in out.props])

    def assuming(out):
        if not out.assumptions:
            return "no assumptions"
        return "assuming " + "; ".join(out.assumptions)

    def report(r):
        out = st["out"]
        st["seen"].append(r)
        width = st["width"]
        pad = f"\n{'':{width + 4}}"
        if r.status == "proved":
            text = f"proved (induction over {r.k} cycle{'s' if r.k != 1 else ''}, " \
                   f"{r.seconds:.2f} s; {assuming(out)}"
            if r.runs_to:
                text += f"; they allow runs of {r.runs_to} cycles, longer runs not " \
                        "checked to exist"
            text += ")"
        elif r.status == "vacuous":
            worse(EXIT_VACUOUS)
            n = r.cycle
            text = f"vacuous: the assumptions allow no run longer than {n} " \
                   f"cycle{'s' if n != 1 else ''} ({assuming(out)})"
        elif r.status == "bounded":
            text = f"holds up to {r.cycle} cycles"
            worse(EXIT_BOUNDED)
        elif r.status == "violated":
            worse(EXIT_VIOLATED)
            text = f"violated at cycle {r.cycle}"
            if r.fault is not None:
                text += ": " + _fault_text(r.fault)
            try:
                cex_dir.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                st["error"] = (f"iec2kmod: error: {cex_dir}: {exc.strerror}", EXIT_USAGE)
                raise _Stop() from None
            csv_path, vcd_path = cex_paths(cex_dir, r.name)
            write_trace(out, r, csv_path)
            ok, why = replay(out, r, str(csv_path), str(vcd_path))
            if not ok and r.havoc:
                # the violation reads variables of a task a fault stopped,
                # free in the encoding from that fault on: not a verdict
                worse(EXIT_BOUNDED)
                print(f"  {r.name:<{width}}  holds up to {r.cycle - 1} cycles; cycle {r.cycle} "
                      "undecided: it reads variables of a task stopped by a runtime fault, "
                      f"which the encoding leaves free from the fault on ({', '.join(r.havoc)})",
                      flush=True)
                return
            if not ok:
                st["error"] = (f"iec2kmod: internal error: the counterexample of '{r.name}' "
                               f"does not replay in the interpreter: {why}", EXIT_INTERNAL)
                raise _Stop()
            text += f"{pad}counterexample: {csv_path} (sim --inputs), {vcd_path}"
            text += f"{pad}replay: {sim_command(args.files, csv_path, r.cycle, out.sym)}"
        elif r.timeout:
            text = "unknown (timeout)"
            if r.cycle:
                text += f": holds up to {r.cycle} cycles"
            worse(EXIT_BOUNDED)
        elif r.fault is not None:
            text = f"holds up to {r.cycle} cycles; undecided at cycle {r.cycle + 1}: " \
                   + _fault_text(r.fault, r.fault[0][len("unroll: "):])
            worse(EXIT_BOUNDED)
            st["faulty"] = True
        else:
            text = f"holds up to {r.cycle} cycles; cycle {r.cycle + 1} undecided (solver " \
                   "time limit of one query)"
            worse(EXIT_BOUNDED)
        if r.free:
            text += f"{pad}with any value of: " + "; ".join(r.free)
        if r.name == "no runtime error" and r.status == "violated":
            st["faulty"] = True
        print(f"  {r.name:<{width}}  {text}", flush=True)

    try:
        out = verify(project, args.property, args.assume, depth=args.depth,
                     instance=args.instance, diags=diags, timeout_ms=120_000,
                     unroll=args.unroll, on_built=built, on_result=report, deadline=deadline)
    except Refuse as exc:
        diags.error(exc.src, exc.pos if exc.pos is not None else 0, exc.message)
        out = None
    except UsageError as exc:
        print(f"iec2kmod: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except _Stop:
        msg, code = st["error"]
        print(msg, file=sys.stderr)
        return code
    print_diagnostics(diags, sys.stderr)
    if out is None:
        return EXIT_SOURCE
    if st["faulty"] and any(r.status not in ("violated", "vacuous") for r in out.results[1:]):
        print("note: a runtime error is reachable; the task that faults stops there and the "
              "other tasks go on: the properties were checked on those runs too")
    return st["worst"]


class _Stop(Exception):
    """Ends the run from inside a verdict callback (the message in st)."""


def _fault_text(fault, kind=None):
    k, pou, src, pos = fault
    where = ""
    if src is not None and pos is not None:
        line, col = src.linecol(pos)
        where = f" at {src.path}:{line}:{col}"
    return f"{kind if kind is not None else k} in {pou}{where}"


def run_export(args) -> int:
    """`iec2kmod export --uppaal`: 0 written, 1 source errors or a construct
    that cannot be exported, 2 usage or I/O errors."""
    from ..cli import front_end, print_diagnostics
    from ..diagnostics import Diagnostics
    from . import Refuse, UsageError
    from .clockfb import clock_user
    from .uppaal import export
    project = front_end(args.files)
    if project is None:
        return EXIT_SOURCE
    diags = Diagnostics()
    try:
        if (clock := clock_user(project, "export")) is not None:
            raise Refuse(*clock)
        text, warnings = export(project, args.property, args.instance)
    except UsageError as exc:
        print(f"iec2kmod: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except Refuse as exc:
        diags.error(exc.src, exc.pos if exc.pos is not None else 0, exc.message)
        print_diagnostics(diags, sys.stderr)
        return EXIT_SOURCE
    if text is None:
        print_diagnostics(warnings, sys.stderr)
        return EXIT_SOURCE
    for w in warnings:
        print(f"iec2kmod: warning: {w}", file=sys.stderr)
    try:
        Path(args.output).write_text(text)
    except OSError as exc:
        print(f"iec2kmod: error: {args.output}: {exc.strerror}", file=sys.stderr)
        return EXIT_USAGE
    n = text.count("<query>")
    print(f"wrote {args.output}: UPPAAL network with {text.count('<template>')} templates, "
          f"{n} quer{'y' if n == 1 else 'ies'}")
    return EXIT_PROVED
