"""Small helpers for the front-end tests."""

from __future__ import annotations

from iec2kmod import ast
from iec2kmod.checks import check_project
from iec2kmod.diagnostics import Diagnostics, SourceFile
from iec2kmod.parse.parser import parse_source


def parse(text: str, path: str = "t.st"):
    """(unit, diagnostics) of one source text; unit is None on syntax errors."""
    diags = Diagnostics()
    unit = parse_source(SourceFile(path, text), diags)
    return unit, diags


def parse_ok(text: str):
    unit, diags = parse(text)
    assert unit is not None and not diags.errors, [d.format() for d in diags.items]
    return unit


def body(text: str, decls: str = ""):
    """The statements of a PROGRAM whose body is ``text``."""
    unit = parse_ok(f"PROGRAM p\n{decls}\n{text}\nEND_PROGRAM\n")
    return unit.pous[0].body


def expr(text: str):
    """The expression ``text`` as parsed on the right of an assignment."""
    stmt = body(f"x := {text};")[0]
    assert isinstance(stmt, ast.Assign)
    return stmt.value


def check(text: str, path: str = "t.st"):
    """All diagnostics of a one-file project, as 'line:col: severity: message'."""
    src = SourceFile(path, text)
    diags = Diagnostics()
    unit = parse_source(src, diags)
    if unit is not None and not diags.errors:
        check_project([unit], diags)
    return [f"{d.line}:{d.col}: {d.severity}: {d.message}" for d in diags.sorted()]


def errors(text: str):
    return [d for d in check(text) if ": error: " in d]
