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
parser's last step, ``attach``, hangs them on the nodes they apply to,
where the passes that read them find them (no pass scans text for a pragma):

    {watchdog}          Task.pragmas (the TASK right after it)
    {verify} {assume}   POU.pragmas (the POU it is written in), else
                        SourceUnit.outside
    {selective}         POU.pragmas, VarDecl.pragmas or ProgramConfig.pragmas
                        (the POU, variable declaration or program instance
                        right after it), else SourceUnit.unattached

"Right after" is by the positions of the nodes: only blanks (whitespace,
comments, other pragmas, inline C) between, and for the first declaration
of a VAR block its keyword and qualifiers (``{selective off} VAR RETAIN
v : Valve;``); see ``attach``."""

from __future__ import annotations

import re
from bisect import bisect_left
from dataclasses import dataclass
from functools import lru_cache

from .. import ast

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

# what the grammar skips as blanks: whitespace, comments, pragmas, inline C
# (one character or one whole token per step: no backtracking blow-up)
_BLANKS = re.compile(r"(?:\s|" + COMMENT + "|" + INLINE_C + "|" + PRAGMA + ")*", re.S)
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
               "that task: Task.pragmas", "iec2kmod/checks/tasks.py"),
    PragmaKind("selective", "{selective} | {selective on} | {selective off}",
               "right in front of a POU, a variable declaration of a POU or a "
               "program instance (blanks between; in front of a VAR block's "
               "first declaration, the block's keyword and qualifiers too)",
               "that POU, the function block instances of that declaration "
               "(every name of it), or that program instance: POU.pragmas, "
               "VarDecl.pragmas, ProgramConfig.pragmas; in front of none of "
               "them, SourceUnit.unattached (a warning)",
               "iec2kmod/codegen/selective.py"),
    PragmaKind("verify", "{verify NAME: EXPR} | {verify: EXPR}",
               "inside a PROGRAM or outside any POU",
               "the program (its instances) or the configuration: "
               "POU.pragmas or SourceUnit.outside", "iec2kmod/verify/props.py"),
    PragmaKind("assume", "{assume: EXPR}",
               "inside a PROGRAM or outside any POU",
               "the program (its instances) or the configuration: "
               "POU.pragmas or SourceUnit.outside", "iec2kmod/verify/props.py"),
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
    blanks between (whitespace, comments, inline C: as for {selective}),
    or None."""
    best = None
    for p in pragmas(text):
        if p.end > pos:
            break
        best = p
    if best is None or best.kind != kind or not blank(text, best.end, pos):
        return None
    return best


def blank(text: str, a: int, b: int) -> bool:
    """Only what the grammar skips as blanks (whitespace, comments,
    pragmas, inline C) in text[a:b]."""
    return _BLANKS.fullmatch(text, a, b) is not None


def attach(unit) -> None:
    """Hangs the pragmas of a parsed file (ast.SourceUnit, its ``src`` the
    whole file) on its nodes: ``unit.pragmas`` every pragma in order; a
    {watchdog} right in front of a TASK (blanks between) on that Task's
    ``pragmas``; a {verify} or {assume} inside a POU (from its keyword to
    its END keyword) on that POU's ``pragmas``, else on ``unit.outside``;
    a {selective} on what it stands in front of (``_place_selective``):
    the ``pragmas`` of a POU, of a VarDecl of a POU (every name of the
    declaration) or of a ProgramConfig, else on ``unit.unattached``."""
    text = unit.src.text
    found = pragmas(text)
    unit.pragmas = found
    outside = []
    pous = [(pou.pos, pou.end_pos, pou) for pou in unit.pous]
    for _, _, pou in pous:
        pou.pragmas = ()
        for b in pou.blocks:
            for d in b.decls:
                if isinstance(d, ast.VarDecl):
                    d.pragmas = ()
    for cfg in unit.configurations:
        for r in cfg.resources:
            for t in r.tasks:
                p = in_front_of(text, t.pos, "watchdog") if found else None
                t.pragmas = (p,) if p is not None else ()
            for pc in r.programs:
                pc.pragmas = ()
    # in front of a POU first: its pragmas in the order they are written
    unit.unattached = _place_selective(unit, [p for p in found if p.kind == "selective"])
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


def _place_selective(unit, found) -> tuple:
    """Adds each {selective} pragma of found to the ``pragmas`` of the node
    it stands in front of; returns those in front of none.

    The nodes it may apply to, by their positions: a POU (its keyword), a
    variable declaration of a POU (its first name; the names of one
    declaration share it) and a program instance of a resource (its
    PROGRAM keyword).  A pragma applies to the first of them that starts
    at or after its end when only blanks (``blank``) lie between; in front
    of the first declaration of a VAR block, the block's keyword and
    qualifiers may lie between as well (from the keyword on the pragma may
    stand anywhere up to the name).  Whatever else lies between (END_VAR,
    a statement, a type, a POU's name, the rest of a declaration) leaves
    it unattached: the selective pass warns at it."""
    if not found:
        return ()
    text = unit.src.text
    # (position, where the blanks in front of it must start, node)
    targets = []
    for pou in unit.pous:
        if pou.pos is None:
            continue
        targets.append((pou.pos, pou.pos, pou))
        for b in pou.blocks:
            for i, d in enumerate(b.decls):
                if isinstance(d, ast.VarDecl) and d.pos is not None:
                    targets.append((d.pos, b.pos if i == 0 else d.pos, d))
    for cfg in unit.configurations:
        for r in cfg.resources:
            for pc in r.programs:
                if pc.pos is not None:
                    targets.append((pc.pos, pc.pos, pc))
    targets.sort(key=lambda t: t[0])
    starts = [t[0] for t in targets]
    unattached = []
    for p in found:
        k = bisect_left(starts, p.end)
        if k < len(targets):
            pos, anchor, node = targets[k]
            if p.start > anchor or blank(text, p.end, anchor):
                node.pragmas += (p,)
                continue
        unattached.append(p)
    return tuple(unattached)
