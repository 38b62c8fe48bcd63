"""The lexical rules every scan of source text shares, and the registry of
pragmas.

Strings, comments and pragmas are skipped whole by every pass that looks at
raw text (cutting files and bodies, finding POU spans, finding pragmas); the
patterns below are the one copy of how they look.  They match what the
grammar's ``Comment`` rule skips (grammar/iec61131.tx):

    (* ... *)   // ...   {{ inline C, MatIEC }}   { pragma }

A pragma is ``{`` up to the next ``}``; its first word is its kind.  The
kinds iec2kmod reads are listed in PRAGMAS (syntax, where it may stand,
what it attaches to, who reads it); any other pragma, and MatIEC's ``{{ }}``
inline C, is ignored with a warning by the parser.  ``pragmas(text)`` gives
every pragma of a text once, in order, with its kind and offsets; the
parser's last step, ``attach``, hangs them on the nodes they apply to (a
{watchdog} on its Task, a {verify} or {assume} on its POU or the file),
where the passes that read them find them."""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import lru_cache

# -- tokens skipped whole
STRING = r"'(?:[^'$\n]|\$.)*'|\"(?:[^\"$\n]|\$.)*\""     # 'single' and "double" strings
COMMENT = r"\(\*.*?\*\)|//[^\n]*"                         # (* block *) and // line
INLINE_C = r"\{\{(?:[^}]|\}(?!\}))*\}\}"                  # MatIEC {{ inline C }}
PRAGMA = r"\{[^}]*\}"                                     # { pragma }
NAME = r"[A-Za-z_][A-Za-z0-9_]*"

# Prefix of a scanner's alternation: strings and comments, which no pragma
# or keyword starts inside of (compile with re.S).
SKIP = STRING + "|" + COMMENT
# ... and pragmas and inline C skipped as well (the grammar's blanks).
SKIP_ALL = SKIP + "|" + INLINE_C + "|" + PRAGMA

# every pragma (group 1), strings and comments skipped
_SCAN = re.compile(SKIP + "|(" + INLINE_C + "|" + PRAGMA + ")", re.S)
_KIND = re.compile(r"\{\s*(" + NAME + r")\b", re.I)


@dataclass(frozen=True)
class PragmaKind:
    name: str         # the first word, lower case
    syntax: str       # how it is written
    where: str        # where it may stand
    attaches_to: str  # what it applies to
    reader: str       # the module that reads it


PRAGMAS = {k.name: k for k in (
    PragmaKind("watchdog", "{watchdog TIME} | {watchdog TIME, N} | {watchdog off, N}",
               "right in front of a TASK declaration (blanks between)",
               "that task", "iec2kmod/checks/tasks.py"),
    PragmaKind("selective", "{selective} | {selective on} | {selective off}",
               "right in front of a POU, a variable declaration or a program "
               "instance (blanks between)",
               "that POU, the function block instances of that declaration, "
               "or that program instance", "iec2kmod/codegen/selective.py"),
    PragmaKind("verify", "{verify NAME: EXPR} | {verify: EXPR}",
               "inside a PROGRAM or outside any POU",
               "the program (its instances) or the configuration",
               "iec2kmod/verify/props.py"),
    PragmaKind("assume", "{assume: EXPR}",
               "inside a PROGRAM or outside any POU",
               "the program (its instances) or the configuration",
               "iec2kmod/verify/props.py"),
)}


@dataclass(frozen=True)
class Pragma:
    start: int        # offset of '{'
    end: int          # offset after '}'
    text: str         # the whole pragma, braces included
    kind: str | None  # a PRAGMAS key, or None (unknown, or {{ inline C }})

    @property
    def body(self) -> str:
        """The text after the kind's word, up to the closing brace."""
        m = _KIND.match(self.text)
        return self.text[m.end():-1] if m else self.text[1:-1]

    @property
    def body_start(self) -> int:
        m = _KIND.match(self.text)
        return self.start + (m.end() if m else 1)


@lru_cache(maxsize=32)
def pragmas(text: str) -> tuple[Pragma, ...]:
    """Every pragma and inline C block of text, in order."""
    if "{" not in text:
        return ()
    out = []
    for m in _SCAN.finditer(text):
        p = m.group(1)
        if not p:
            continue
        kind = None
        if not p.startswith("{{"):
            k = _KIND.match(p)
            if k and k.group(1).lower() in PRAGMAS:
                kind = k.group(1).lower()
        out.append(Pragma(m.start(1), m.end(1), p, kind))
    return tuple(out)


def of_kind(text: str, kind: str) -> list[Pragma]:
    return [p for p in pragmas(text) if p.kind == kind]


def in_front_of(text: str, pos: int, kind: str) -> Pragma | None:
    """The pragma of that kind that ends right before pos, with only
    blanks between, or None."""
    best = None
    for p in pragmas(text):
        if p.end > pos:
            break
        best = p
    if best is None or best.kind != kind or text[best.end:pos].strip():
        return None
    return best


def attach(unit) -> None:
    """Hangs the pragmas of a parsed file (ast.SourceUnit, its ``src`` the
    whole file) on its nodes: ``unit.pragmas`` every pragma in order; a
    {watchdog} right in front of a TASK (blanks between) on that Task's
    ``pragmas``; a {verify} or {assume} inside a POU (from its keyword to
    its END keyword) on that POU's ``pragmas``, else on ``unit.outside``.
    A {selective} is matched to its declaration by codegen/selective.py
    from ``unit.pragmas``."""
    text = unit.src.text
    found = pragmas(text)
    unit.pragmas = found
    outside = []
    pous = [(pou.pos, pou.end_pos, pou) for pou in unit.pous]
    for _, _, pou in pous:
        pou.pragmas = ()
    for cfg in unit.configurations:
        for r in cfg.resources:
            for t in r.tasks:
                p = in_front_of(text, t.pos, "watchdog") if found else None
                t.pragmas = (p,) if p is not None else ()
    for p in found:
        if p.kind not in ("verify", "assume"):
            continue
        inside = [pou for a, b, pou in pous
                  if a is not None and b is not None and a <= p.start < b]
        if inside:
            inside[-1].pragmas += (p,)
        else:
            outside.append(p)
    unit.outside = tuple(outside)
