"""`iec2kmod verify`: the command.

Exit status: 0 every property proved; 1 source errors, or a construct that
cannot be encoded (an error naming it); 2 usage or I/O errors; 3 a property
violated (its counterexample written and replayed); 4 no violation up to
--depth cycles but not every property proved; 70 internal error."""

from __future__ import annotations

import re
import sys
from pathlib import Path

EXIT_PROVED, EXIT_SOURCE, EXIT_USAGE, EXIT_VIOLATED, EXIT_BOUNDED, EXIT_INTERNAL = \
    0, 1, 2, 3, 4, 70


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
    project = front_end(args.files)
    if project is None:
        return EXIT_SOURCE
    diags = Diagnostics()
    try:
        out = verify(project, args.property, args.assume, depth=args.depth,
                     instance=args.instance, diags=diags, timeout_ms=int(args.timeout * 1000),
                     unroll=args.unroll)
    except Refuse as exc:
        diags.error(exc.src, exc.pos if exc.pos is not None else 0, exc.message)
        out = None
    except UsageError as exc:
        print(f"iec2kmod: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    print_diagnostics(diags, sys.stderr)
    if out is None:
        return EXIT_SOURCE
    sym = out.sym
    tasks = ", ".join(f"{t.name} every {_fmt_time(t.interval_ns)}" if t.single is None
                      else f"{t.name} on {t.single.name}" for t in sym.tasks)
    step = f"; a step is {_fmt_time(sym.period)}" if len(sym.tasks) > 1 else ""
    print(f"configuration {sym.cfg.name}: task{'s' if len(sym.tasks) > 1 else ''} {tasks}"
          f"{step}; {out.leaves} state variables, {out.inputs} inputs; "
          f"{len(out.props)} properties")
    if sym.events:
        print(f"note: the inputs change at the instants of the step "
              f"({_fmt_time(sym.period)}); an event task triggered by an input between two "
              "steps is not modelled")
    cex_dir = Path(args.cex_dir)
    worst = EXIT_PROVED
    faulty = any(r.status == "violated" for r in out.results[:1])
    width = max(len(r.name) for r in out.results)
    for r in out.results:
        if r.status == "proved":
            text = f"proved (induction over {r.k} cycle{'s' if r.k != 1 else ''}, " \
                   f"{r.seconds:.2f} s)"
        elif r.status == "bounded":
            text = f"holds up to {r.cycle} cycles"
            worst = max(worst, EXIT_BOUNDED) if worst != EXIT_VIOLATED else worst
        elif r.status == "violated":
            worst = EXIT_VIOLATED
            text = f"violated at cycle {r.cycle}"
            if r.fault is not None:
                kind, pou, src, pos = r.fault
                where = ""
                if src is not None and pos is not None:
                    line, col = src.linecol(pos)
                    where = f" at {src.path}:{line}:{col}"
                text += f": {kind} in {pou}{where}"
            try:
                cex_dir.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                print(f"iec2kmod: error: {cex_dir}: {exc.strerror}", file=sys.stderr)
                return EXIT_USAGE
            stem = "cex_" + re.sub(r"[^A-Za-z0-9_]+", "_", r.name).strip("_")
            csv_path, vcd_path = cex_dir / f"{stem}.csv", cex_dir / f"{stem}.vcd"
            write_trace(out, r, csv_path)
            ok, why = replay(out, r, str(csv_path), str(vcd_path))
            if not ok:
                print(f"iec2kmod: internal error: the counterexample of '{r.name}' does not "
                      f"replay in the interpreter: {why}", file=sys.stderr)
                return EXIT_INTERNAL
            text += f"\n{'':{width + 4}}counterexample: {csv_path} (sim --inputs), {vcd_path}"
            text += f"\n{'':{width + 4}}replay: {sim_command(args.files, csv_path, r.cycle, sym)}"
        elif r.fault is not None:
            kind, pou, src, pos = r.fault
            where = ""
            if src is not None and pos is not None:
                line, col = src.linecol(pos)
                where = f" at {src.path}:{line}:{col}"
            text = f"holds up to {r.cycle} cycles; undecided at cycle {r.cycle + 1}: " \
                   f"{kind[len('unroll: '):]} in {pou}{where}"
            worst = max(worst, EXIT_BOUNDED) if worst != EXIT_VIOLATED else worst
            faulty = True
        else:
            text = f"holds up to {r.cycle} cycles; cycle {r.cycle + 1} undecided (solver " \
                   "time limit, see --timeout)"
            worst = max(worst, EXIT_BOUNDED) if worst != EXIT_VIOLATED else worst
        if r.free:
            text += f"\n{'':{width + 4}}with any value of: " + "; ".join(r.free)
        print(f"  {r.name:<{width}}  {text}")
    if faulty and any(r.status != "violated" for r in out.results[1:]):
        print("note: a runtime error (or a loop longer than the unrolling) is reachable; the "
              "other properties were checked on the runs before it")
    return worst


def run_export(args) -> int:
    """`iec2kmod export --uppaal`: 0 written, 1 source errors or a construct
    that cannot be exported, 2 usage or I/O errors."""
    from ..cli import front_end, print_diagnostics
    from ..diagnostics import Diagnostics
    from . import Refuse, UsageError
    from .uppaal import export
    project = front_end(args.files)
    if project is None:
        return EXIT_SOURCE
    diags = Diagnostics()
    try:
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
