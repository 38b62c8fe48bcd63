"""`iec2kmod export --st PROJECT.xml [-o OUT.st]`: the textual project of a
PLCopen XML project, so a user can leave the graphical editor."""

from __future__ import annotations

import sys
from pathlib import Path


def run_export_st(args) -> int:
    from ..cli import EXIT_OK, EXIT_SOURCE, EXIT_USAGE, print_diagnostics
    from ..diagnostics import Diagnostics
    from ..parse.frontend import InputError, collect_files
    from .reader import is_xml, to_text
    files = collect_files(args.files)
    xml = [f for f in files if is_xml(f)]
    if len(xml) != 1 or len(files) != 1:
        print("iec2kmod: error: export --st takes one PLCopen XML project (a .xml file or a "
              "directory holding plc.xml)", file=sys.stderr)
        return EXIT_USAGE
    if args.property or args.instance:
        print("iec2kmod: error: --property and --instance apply to --uppaal", file=sys.stderr)
        return EXIT_USAGE
    try:
        text, items = to_text(xml[0])
    except OSError as exc:
        raise InputError(f"{xml[0]}: {exc.strerror or exc}") from None
    diags = Diagnostics()
    diags.items = list(items)
    print_diagnostics(diags)
    if diags.errors:
        print(f"{len(diags.errors)} error(s), {len(diags.warnings)} warning(s)", file=sys.stderr)
        return EXIT_SOURCE
    head = f"(* Textual form of {Path(xml[0]).name}, written by iec2kmod export --st *)\n\n"
    if args.output:
        try:
            Path(args.output).write_text(head + text)
        except OSError as exc:
            raise InputError(f"{args.output}: {exc.strerror or exc}") from None
        print(f"wrote {args.output}")
    else:
        sys.stdout.write(head + text)
    return EXIT_OK
