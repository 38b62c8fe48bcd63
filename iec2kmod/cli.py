"""iec2kmod command line.

    iec2kmod check FILE|DIR...     parse and check, gcc-style diagnostics

Exit status: 0 clean (warnings allowed), 1 source errors, 2 usage or I/O
errors, 70 internal error (a bug of ours, reported in one line).

`iec2kmod verify`: 0 every property proved, 1 source errors or a construct
that cannot be encoded, 2 usage, 3 a property violated (counterexample
written), 4 no violation up to --depth cycles but not every property
proved (or unknown: --timeout), 5 vacuous (the assumptions allow no run
longer than K cycles), 70 internal error.
"""

from __future__ import annotations

import argparse
import sys

EXIT_OK, EXIT_SOURCE, EXIT_USAGE, EXIT_INTERNAL = 0, 1, 2, 70


SELECTIVE_HELP = ("selective execution (seed 001): skip the function block and program "
                  "instances whose inputs did not change; 'all' (default) every block the "
                  "rules of iec2kmod/codegen/selective.py allow except those marked "
                  "{selective off}, 'marked' only those marked {selective on}")


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        self.print_usage(sys.stderr)
        print(f"iec2kmod: error: {message}", file=sys.stderr)
        sys.exit(EXIT_USAGE)


STRICT_HELP = ("refuse what the standard's rules forbid but other tools accept with a "
               "warning: a write to a VAR_INPUT inside its POU")


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="iec2kmod", description="IEC 61131-3 to Linux PREEMPT_RT kernel modules")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    c = sub.add_parser("check", help="parse and check a project, print diagnostics")
    c.add_argument("files", nargs="+", metavar="FILE", help="source files or directories")
    c.add_argument("--no-cache", action="store_true", help="ignore the result cache")
    c.add_argument("--timings", action="store_true", help="print the time of each pass")
    c.add_argument("-j", "--jobs", type=int, default=None, help="parallel parser processes")
    c.add_argument("--strict", action="store_true", help=STRICT_HELP)
    gp = sub.add_parser("gen", help="write the kbuild tree of a project's kernel modules")
    gp.add_argument("files", nargs="+", metavar="PROJECT", help="source files or directories")
    gp.add_argument("-o", "--output", required=True, metavar="OUT", help="output directory")
    gp.add_argument("--selective", nargs="?", const="all", choices=("all", "marked"),
                    help=SELECTIVE_HELP)
    gp.add_argument("--strict", action="store_true", help=STRICT_HELP)
    bp = sub.add_parser("build", help="build the kernel modules of a generated tree")
    bp.add_argument("tree", metavar="OUT", help="directory written by `iec2kmod gen`")
    bp.add_argument("--kdir", help="kernel build tree (default: the running kernel's, "
                                   "else Debian's linux-headers-rt-amd64)")
    bp.add_argument("--container", action="store_true",
                    help="build inside the project's container image (docker)")
    bp.add_argument("--sparse", action="store_true",
                    help="also run sparse on every source (make C=1; Debian package "
                         "sparse); a sparse warning fails the build")
    bp.add_argument("-j", "--jobs", type=int, default=0, help="make -j (default: cores)")
    s = sub.add_parser("sim", help="run a configuration on the host with a simulated clock")
    s.add_argument("files", nargs="+", metavar="PROJECT", help="source files or directories")
    g = s.add_mutually_exclusive_group(required=True)
    g.add_argument("--cycles", type=int, help="cycles of the fastest periodic task")
    g.add_argument("--duration", help="simulated time, e.g. 10s or T#500ms")
    s.add_argument("--inputs", metavar="TRACE.csv", help="input events: time,variable,value")
    s.add_argument("--csv", metavar="OUT.csv", help="write watched values as CSV")
    s.add_argument("--vcd", metavar="OUT.vcd", help="write watched values as VCD (GTKWave)")
    s.add_argument("--watch", metavar="A,B,C", help="variables to record (default: globals)")
    s.add_argument("--list", action="store_true", help="list the variables and exit")
    s.add_argument("--sanitize", action="store_true",
                   help="build with -fsanitize=undefined,address,float-cast-overflow "
                        "(the first report ends the run)")
    s.add_argument("--engine", choices=("c", "interp", "vm"), default="c",
                   help="c: compile the generated C and run it (default); interp: run the "
                        "reference interpreter (no C compiler needed; 'vm' is an alias)")
    s.add_argument("--selective", nargs="?", const="all", choices=("all", "marked"),
                   help=SELECTIVE_HELP + " (C engine)")
    s.add_argument("--strict", action="store_true", help=STRICT_HELP)
    v = sub.add_parser("verify", help="prove properties of a configuration for every input "
                                      "sequence (bounded model checking and k-induction)")
    v.add_argument("files", nargs="+", metavar="PROJECT", help="source files or directories")
    v.add_argument("--property", "-p", action="append", default=[], metavar="EXPR",
                   help="an ST boolean expression over the configuration's variables, "
                        "checked after every cycle (repeatable; {verify NAME: EXPR} pragmas "
                        "in the sources are checked too)")
    v.add_argument("--assume", action="append", default=[], metavar="EXPR",
                   help="a constraint on the inputs of every step, evaluated where the properties "
                        "are: after the step, with the inputs it read (repeatable)")
    v.add_argument("--depth", type=int, default=20, metavar="N",
                   help="cycles of bounded model checking and of induction (default 20)")
    v.add_argument("--instance", metavar="PATH",
                   help="resolve --property/--assume names in this program instance")
    v.add_argument("--cex-dir", default=".", metavar="DIR",
                   help="where counterexamples are written (default: .)")
    v.add_argument("--unroll", type=int, default=16, metavar="N",
                   help="iterations a WHILE/REPEAT loop or a FOR loop with variable bounds is "
                        "unrolled (default 16); a run that needs more is reported undecided")
    v.add_argument("--timeout", type=float, default=None, metavar="SECONDS",
                   help="time limit of the whole verification: the checks not decided by "
                        "then are reported 'unknown (timeout)', the others are kept "
                        "(default: none; one solver query is limited to 120 s)")
    v.add_argument("--engine", choices=("z3", "explicit"), default="z3",
                   help="z3: bounded model checking and k-induction (default); explicit: "
                        "breadth-first exploration of every reachable state over the reference "
                        "interpreter with every input valuation at every step (small finite "
                        "configurations; the referee of the z3 engine)")
    v.add_argument("--max-states", type=int, default=200000, metavar="N",
                   help="explicit engine: states explored before answering 'too large' "
                        "(default 200000)")
    v.add_argument("--max-inputs", type=int, default=4096, metavar="N",
                   help="explicit engine: input valuations per step before answering 'too "
                        "large' (default 4096)")
    x = sub.add_parser("export", help="write a model of a configuration for another tool")
    x.add_argument("files", nargs="+", metavar="PROJECT", help="source files or directories")
    xf = x.add_mutually_exclusive_group(required=True)
    xf.add_argument("--uppaal", action="store_true",
                    help="a network of UPPAAL timed automata (XML) with the properties as "
                         "queries")
    xf.add_argument("--st", action="store_true",
                    help="the equivalent textual project (ST, IL, textual SFC) of a PLCopen "
                         "XML project; -o FILE or standard output")
    x.add_argument("-o", "--output", metavar="OUT",
                   help="the model (MODEL.xml, required with --uppaal) or the text (--st)")
    x.add_argument("--property", "-p", action="append", default=[], metavar="EXPR",
                   help="also export this property as a query (repeatable)")
    x.add_argument("--instance", metavar="PATH",
                   help="resolve --property names in this program instance")
    return p


def print_diagnostics(diags, stream=None) -> None:
    stream = stream if stream is not None else sys.stderr     # the current one (tests capture it)
    for d in diags.sorted():
        print(d.format(), file=stream)


def cmd_check(args) -> int:
    from .parse.frontend import run
    result = run(args.files, use_cache=not args.no_cache, jobs=args.jobs, strict=args.strict)
    print_diagnostics(result.diags)
    if args.timings:
        for name, secs in result.timings.items():
            print(f"{name:>10}: {secs * 1000:8.1f} ms", file=sys.stderr)
    n_err = len(result.diags.errors)
    n_warn = len(result.diags.warnings)
    if n_err or n_warn:
        print(f"{n_err} error(s), {n_warn} warning(s)", file=sys.stderr)
    return EXIT_SOURCE if n_err else EXIT_OK


def front_end(files, strict=False):
    """Checked project or None (diagnostics printed)."""
    from .parse.frontend import run
    result = run(files, use_cache=False, strict=strict)
    print_diagnostics(result.diags)
    if not result.ok:
        n = len(result.diags.errors)
        print(f"{n} error(s), {len(result.diags.warnings)} warning(s)", file=sys.stderr)
        return None
    if not result.project.configurations:
        print("iec2kmod: error: the project has no CONFIGURATION to run", file=sys.stderr)
        return None
    return result.project


def compile_project(project, mode=None):
    """The Compilation of a checked project (compilation.py) for
    --selective MODE (None: plain); the selective pass's warnings (pragmas)
    are printed like the front end's."""
    from .compilation import Compilation
    comp = Compilation(project, mode)
    if comp.selective is not None:
        from .diagnostics import Diagnostics
        diags = Diagnostics()
        for src, offset, message in comp.selective.warnings:
            diags.warning(src, offset, message)
        print_diagnostics(diags)
    return comp


def cmd_sim(args) -> int:
    from . import sim
    from .compilation import CompileError
    from .traces import TraceError, format_value, write_csv, write_vcd
    project = front_end(args.files, strict=args.strict)
    if project is None:
        return EXIT_SOURCE
    if args.engine == "vm":                  # the interpreter's former name
        args.engine = "interp"
    try:
        if args.engine == "interp" and args.sanitize:
            raise sim.SimError("--sanitize applies to the C engine only")
        if args.engine == "interp" and args.selective:
            raise sim.SimError("--selective applies to the C engine only")
        if args.engine == "interp":
            from . import interp
            try:
                machine = interp.Machine(project)
                table = machine.table()
            except interp.InterpError as exc:
                raise sim.SimError(str(exc)) from None
        else:
            comp = compile_project(project, args.selective)
            table = comp.plan.table
        if args.list:
            for e in table:
                access = "rw" if e.writable else "ro"
                print(f"{e.path:40} {getattr(e.type, 'name', '?'):16} {access}")
            return EXIT_OK
        if args.cycles is not None:
            periods = [t.interval_ns for c in project.configurations for r in c.resources
                       for t in r.tasks.values() if t.interval_ns]
            if not periods:
                raise sim.SimError("--cycles needs a periodic task; use --duration")
            if args.cycles < 1:
                raise sim.SimError("--cycles must be at least 1")
            end = min(periods) * (args.cycles - 1)
        else:
            end = sim.parse_time(args.duration)
        watch = [w for w in args.watch.split(",") if w.strip()] if args.watch else None
        if args.engine == "interp":
            try:
                res = interp.run(project, end, watch=watch, inputs=args.inputs, machine=machine)
            except interp.InterpError as exc:
                raise sim.SimError(str(exc)) from None
        else:
            res = sim.run(comp, end, watch=watch, inputs=args.inputs, sanitize=args.sanitize)
    except (sim.SimError, TraceError, CompileError) as exc:
        print(f"iec2kmod: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except sim.InternalError as exc:
        print(f"iec2kmod: internal error: {exc}", file=sys.stderr)
        return EXIT_INTERNAL
    for t, task, fault, pou, file, line in res.faults:
        if pou == "?" and not line:          # a fault of the task, not of a statement
            print(f"iec2kmod: runtime error: {fault} (task {task}, t={t / 1e9:.6f} s); the "
                  f"task is stopped", file=sys.stderr)
            continue
        if str(file).lower().endswith(".xml"):      # the XML's line (issue 28)
            from .plcopen import remap_location
            file, line = remap_location(file, line)
        print(f"{file}:{line}: runtime error: {fault} in {pou} (task {task}, "
              f"t={t / 1e9:.6f} s); the task is stopped", file=sys.stderr)
    if args.csv:
        write_csv(res, args.csv)
    if args.vcd:
        write_vcd(res, args.vcd, table)
    final = res.values_at()
    width = max((len(n) for n in res.names), default=10)
    print(f"simulated {res.end_ns / 1e9:g} s; cycles: " +
          ", ".join(f"{k} {v}" for k, v in res.cycles.items()))
    if getattr(args, "selective", None):
        print("selective blocks: " + (", ".join(
            f"{k} {ev} evaluated {sk} skipped" for k, (ev, sk) in res.selective.items())
            or "none"))
    for n in res.names:
        v = final.get(n, "")
        print(f"  {n:<{width}}  {format_value(None, v)}")
    return EXIT_SOURCE if res.faults else EXIT_OK


def cmd_gen(args) -> int:
    from pathlib import Path
    from .compilation import CompileError
    from .kmod import generate_tree
    project = front_end(args.files, strict=args.strict)
    if project is None:
        return EXIT_SOURCE
    out = Path(args.output)
    if out.exists() and not out.is_dir():
        print(f"iec2kmod: error: {out} exists and is not a directory", file=sys.stderr)
        return EXIT_USAGE
    try:
        comp = compile_project(project, args.selective)
        manifest = generate_tree(comp, out)
    except CompileError as exc:
        print(f"iec2kmod: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    print(f"wrote {out}: {len(manifest['modules'])} modules "
          f"({', '.join(m['name'] for m in manifest['modules'])})")
    return EXIT_OK


def cmd_build(args) -> int:
    from .kmod.build import BuildError, build_tree
    try:
        result = build_tree(args.tree, kdir=args.kdir, container=args.container,
                            jobs=args.jobs, sparse=args.sparse)
    except BuildError as exc:
        print(f"iec2kmod: error: {exc}", file=sys.stderr)
        return exc.exit_code
    for line in result.messages:
        print(line)
    return EXIT_OK


def cmd_export(args) -> int:
    if args.st:
        from .plcopen.export import run_export_st
        return run_export_st(args)
    if not args.output:
        print("iec2kmod: error: export --uppaal needs -o MODEL.xml", file=sys.stderr)
        return EXIT_USAGE
    from .verify.cli import run_export
    return run_export(args)


def cmd_verify(args) -> int:
    from .verify.cli import run_verify
    return run_verify(args)


COMMANDS = {"export": cmd_export, "verify": cmd_verify, "check": cmd_check, "sim": cmd_sim, "gen": cmd_gen, "build": cmd_build}


# the third-party modules of the optional features: (distribution, extra of
# pyproject.toml); check, gen, build and sim need none of them
OPTIONAL_MODULES = {"z3": ("z3-solver", "verify"), "docker": ("docker", "container"),
                    "requests": ("requests", "container"), "lxml": ("lxml", "plcopen")}


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    from .parse.frontend import InputError
    try:
        return COMMANDS[args.command](args)
    except InputError as exc:
        print(f"iec2kmod: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        return 130
    except Exception as exc:  # noqa: BLE001 - the one place that catches everything
        extra = OPTIONAL_MODULES.get((getattr(exc, "name", None) or "").split(".")[0])
        if isinstance(exc, ModuleNotFoundError) and extra is not None:
            print(f"iec2kmod: error: `{args.command}` needs {extra[0]}, which is not "
                  f"installed: pip install 'iec2kmod[{extra[1]}]'", file=sys.stderr)
            return EXIT_USAGE
        where = ""
        tb = exc.__traceback__
        while tb is not None:
            where = f" at {tb.tb_frame.f_code.co_filename.rsplit('/', 1)[-1]}:{tb.tb_lineno}"
            tb = tb.tb_next
        print(f"iec2kmod: internal error: {type(exc).__name__}: {exc}{where}", file=sys.stderr)
        return EXIT_INTERNAL


if __name__ == "__main__":
    sys.exit(main())
