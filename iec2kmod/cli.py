"""iec2kmod command line.

    iec2kmod check FILE|DIR...     parse and check, gcc-style diagnostics

Exit status: 0 clean (warnings allowed), 1 source errors, 2 usage or I/O
errors, 70 internal error (a bug of ours, reported in one line).
"""

from __future__ import annotations

import argparse
import sys

EXIT_OK, EXIT_SOURCE, EXIT_USAGE, EXIT_INTERNAL = 0, 1, 2, 70


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        self.print_usage(sys.stderr)
        print(f"iec2kmod: error: {message}", file=sys.stderr)
        sys.exit(EXIT_USAGE)


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="iec2kmod", description="IEC 61131-3 to Linux PREEMPT_RT kernel modules")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    c = sub.add_parser("check", help="parse and check a project, print diagnostics")
    c.add_argument("files", nargs="+", metavar="FILE", help="source files or directories")
    c.add_argument("--no-cache", action="store_true", help="ignore the result cache")
    c.add_argument("--timings", action="store_true", help="print the time of each pass")
    c.add_argument("-j", "--jobs", type=int, default=None, help="parallel parser processes")
    return p


def print_diagnostics(diags, stream=sys.stderr) -> None:
    for d in diags.sorted():
        print(d.format(), file=stream)


def cmd_check(args) -> int:
    from .frontend import run
    result = run(args.files, use_cache=not args.no_cache, jobs=args.jobs)
    print_diagnostics(result.diags)
    if args.timings:
        for name, secs in result.timings.items():
            print(f"{name:>10}: {secs * 1000:8.1f} ms", file=sys.stderr)
    n_err = len(result.diags.errors)
    n_warn = len(result.diags.warnings)
    if n_err or n_warn:
        print(f"{n_err} error(s), {n_warn} warning(s)", file=sys.stderr)
    return EXIT_SOURCE if n_err else EXIT_OK


COMMANDS = {"check": cmd_check}


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    from .frontend import InputError
    try:
        return COMMANDS[args.command](args)
    except InputError as exc:
        print(f"iec2kmod: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        return 130
    except Exception as exc:  # noqa: BLE001 - the one place that catches everything
        where = ""
        tb = exc.__traceback__
        while tb is not None:
            where = f" at {tb.tb_frame.f_code.co_filename.rsplit('/', 1)[-1]}:{tb.tb_lineno}"
            tb = tb.tb_next
        print(f"iec2kmod: internal error: {type(exc).__name__}: {exc}{where}", file=sys.stderr)
        return EXIT_INTERNAL


if __name__ == "__main__":
    sys.exit(main())
