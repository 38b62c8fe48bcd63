"""Compiler diagnostics: ``file:line:col: severity: message`` plus the source
line and a caret, like gcc.  Every pass reports through a :class:`Diagnostics`
collector; nothing in the front end raises for a source error."""

from __future__ import annotations

import bisect
from dataclasses import dataclass, field


class SourceFile:
    """A source text with fast offset -> (line, column) conversion."""

    __slots__ = ("path", "text", "_starts")

    def __init__(self, path: str, text: str):
        self.path = path
        self.text = text
        starts = [0]
        find = text.find
        pos = find("\n")
        while pos >= 0:
            starts.append(pos + 1)
            pos = find("\n", pos + 1)
        self._starts = starts

    def linecol(self, offset: int) -> tuple[int, int]:
        """1-based line and column of a character offset."""
        line = bisect.bisect_right(self._starts, offset) - 1
        return line + 1, offset - self._starts[line] + 1

    def offset(self, line: int, col: int) -> int:
        """Character offset of a 1-based line and column."""
        line = min(max(line, 1), len(self._starts))
        return self._starts[line - 1] + col - 1

    def line_text(self, line: int) -> str:
        if line < 1 or line > len(self._starts):
            return ""
        start = self._starts[line - 1]
        end = self.text.find("\n", start)
        return self.text[start:] if end < 0 else self.text[start:end]


@dataclass(frozen=True, order=True)
class Diagnostic:
    path: str
    line: int
    col: int
    severity: str  # "error" | "warning" | "note"
    message: str
    source_line: str = field(default="", compare=False)

    def format(self) -> str:
        head = f"{self.path}:{self.line}:{self.col}: {self.severity}: {self.message}"
        if not self.source_line:
            return head
        src = self.source_line.rstrip("\r").replace("\t", " ")
        caret = " " * max(self.col - 1, 0) + "^"
        return f"{head}\n{src}\n{caret}"


# The warnings --strict makes errors: each begins with one of these words.
# A write to an input inside its POU is refused by the rule IEC 61131-3 tools
# check but compiled by CODESYS, TwinCAT and MatIEC (OSCAT relies on it).
INPUT_WRITE_RULE = "write to"
STRICT_RULES = (INPUT_WRITE_RULE,)


class Diagnostics:
    """Collects diagnostics from every pass."""

    def make_strict(self) -> None:
        """--strict: the warnings of STRICT_RULES become errors."""
        self.items = [Diagnostic(d.path, d.line, d.col, "error", d.message, d.source_line)
                      if d.severity == "warning" and d.message.startswith(STRICT_RULES) else d
                      for d in self.items]

    def __init__(self):
        self.items: list[Diagnostic] = []
        self._seen: set = set()

    def add(self, src: SourceFile | None, offset: int | None, severity: str,
            message: str, line: int | None = None, col: int | None = None) -> None:
        if src is None:
            diag = Diagnostic("<input>", line or 0, col or 0, severity, message)
        else:
            if line is None:
                line, col = src.linecol(offset or 0)
            diag = Diagnostic(src.path, line, col, severity, message, src.line_text(line))
        key = (diag.path, diag.line, diag.col, diag.severity, diag.message)
        if key not in self._seen:
            self._seen.add(key)
            self.items.append(diag)

    def error(self, src, offset, message, **kw):
        self.add(src, offset, "error", message, **kw)

    def warning(self, src, offset, message, **kw):
        self.add(src, offset, "warning", message, **kw)

    @property
    def errors(self) -> list[Diagnostic]:
        return [d for d in self.items if d.severity == "error"]

    @property
    def warnings(self) -> list[Diagnostic]:
        return [d for d in self.items if d.severity == "warning"]

    def sorted(self) -> list[Diagnostic]:
        return sorted(self.items)

    def __bool__(self):
        return bool(self.items)
