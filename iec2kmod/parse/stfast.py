"""Pass 1, fast path: the common Structured Text statements parsed by hand.

textX (Arpeggio) spends about 0.4 ms on a line such as
``a := (a + b * 2) - (c - d) / 2 + e MOD 3;``: a dozen nested rules and
failed attempts per operand.  Code generated from ladder diagrams and
expression-dense programs are mostly such lines, so this pass parses the
statements it knows in a single pass over the text, and leaves everything
else to the grammar:

- ``target := expression;`` where the target is a variable path without
  index (``a``, ``s.m``, ``w.3``);
- ``IF ... THEN ... ELSIF ... ELSE ... END_IF`` over such statements;
- ``RETURN;``, ``EXIT;`` and the empty statement ``;``;
- expressions of binary operators, unary operators, parentheses, variable
  paths without index and literals (no call, index, ``**`` or direct
  address).

How it stays the grammar's exact equal:

- It only ever *accepts* text; it never reports an error.  Anything it does
  not know, or does not like, raises Unsupported, and that statement is
  parsed by textX with the rest of the file.
- The tokens are the grammar's own compiled expressions (SIMPLE_OPERAND,
  VAR_PATH, LITERAL, BINARY_OP, UNARY_OP, Comment), taken from the metamodel,
  and it makes the grammar's choices in the grammar's order (PEG: the first
  alternative that matches wins); the nodes are built by the same functions
  as the object processors' (parser.climb, parser.simple_node, ...).
- A POU body is cut between top-level statements (the ``;`` outside any
  IF/CASE/FOR/WHILE/REPEAT, comments and strings); a piece this pass parses
  is blanked out of the text textX sees (newlines kept, so every position is
  the real one), and its statements are put back into the POU's body by
  position.  The ST body is a plain sequence of statements, so the pieces
  parse the same apart as together.
- If textX does not give back an ST body for a POU this pass took pieces of,
  or reports any error, the file is parsed again by textX alone, so every
  diagnostic is the grammar's.
- tests/unit/test_fast_builder.py compares the result with textX's alone on
  every project file, snippets, fuzzed and mutated files, and random
  programs of the differential campaign.
"""

from __future__ import annotations

import re

from .. import ast
from .lexical import SKIP_ALL
from .literals import LiteralError, classify

# tokens of an ST body that matter for cutting it between statements;
# comments, strings and pragmas are skipped whole
BODY_TOKENS = re.compile(
    SKIP_ALL + "|"
    r"(;)|\b(IF|CASE|FOR|WHILE|REPEAT|END_IF|END_CASE|END_FOR|END_WHILE|END_REPEAT|"
    r"END_VAR|VAR\w*|PROGRAM|FUNCTION_BLOCK|FUNCTION|END_PROGRAM|END_FUNCTION_BLOCK|"
    r"END_FUNCTION|TYPE|END_TYPE|CONFIGURATION|END_CONFIGURATION|ACTION|METHOD|USING)\b",
    re.S | re.I)
OPENS = {"IF", "CASE", "FOR", "WHILE", "REPEAT"}
CLOSES = {"END_IF", "END_CASE", "END_FOR", "END_WHILE", "END_REPEAT"}
POU_END = {"END_PROGRAM", "END_FUNCTION_BLOCK", "END_FUNCTION"}
_POU_START = {"PROGRAM": "END_PROGRAM", "FUNCTION_BLOCK": "END_FUNCTION_BLOCK",
              "FUNCTION": "END_FUNCTION"}
_SKIPPED = {"TYPE": "END_TYPE", "CONFIGURATION": "END_CONFIGURATION"}


def body_tokens(text: str):
    """(start, end, upper-case keyword or '', is ';') of BODY_TOKENS."""
    return [(m.start(), m.end(), (m.group(2) or "").upper(), bool(m.group(1)))
            for m in BODY_TOKENS.finditer(text) if m.group(1) or m.group(2)]


def statement_pieces(text: str):
    """The ST bodies of the POUs of a file, cut between top-level
    statements: [(POU start, [(piece start, piece end)])].  A POU whose
    shape the scan does not understand (no VAR block, an ACTION, METHOD or
    USING inside, unbalanced keywords) is left out."""
    toks = body_tokens(text)
    out = []
    k = 0
    while k < len(toks):
        word = toks[k][2]
        if word in _SKIPPED:
            end = _SKIPPED[word]
            while k < len(toks) and toks[k][2] != end:
                k += 1
            k += 1
            continue
        if word not in _POU_START:
            k += 1
            continue
        head, end_word = toks[k], _POU_START[word]
        j = k + 1
        while j < len(toks) and toks[j][2] not in POU_END:
            j += 1
        if j == len(toks) or toks[j][2] != end_word:
            return out  # a file the scan does not follow: what it found so far
        pieces = _pieces(toks[k + 1:j], toks[j][0])
        if pieces:
            out.append((head[0], pieces))
        k = j + 1
    return out


def _pieces(inside, end):
    cuts = statement_cuts(inside)
    return list(zip(cuts, cuts[1:] + [end])) if cuts else None


def statement_cuts(inside):
    """Where the ST body of a POU starts (after its leading VAR blocks) and
    where its top-level statements end, from the body_tokens() between its
    header and its END keyword; None for a POU without VAR block, or with
    anything else than statements in its body, or with unbalanced
    IF/CASE/FOR/WHILE/REPEAT."""
    body_start = None
    in_decl = False
    first_body = len(inside)
    for n, t in enumerate(inside):
        if t[2].startswith("VAR") and not in_decl:
            in_decl = True
        elif t[2] == "END_VAR":
            in_decl = False
            body_start = t[1]
        elif not in_decl:
            first_body = n
            break
    if body_start is None:
        return None
    depth = 0
    cuts = [body_start]
    for a, b, word, semi in inside[first_body:]:
        if word in OPENS:
            depth += 1
        elif word in CLOSES:
            depth -= 1
        elif semi and depth == 0:
            cuts.append(b)
        if depth < 0 or word.startswith("VAR") or word in _NOT_IN_BODY:
            return None
    return cuts if depth == 0 else None


_NOT_IN_BODY = {"END_VAR", "ACTION", "METHOD", "USING", "PROGRAM", "FUNCTION", "FUNCTION_BLOCK",
                "TYPE", "CONFIGURATION"}


class Unsupported(Exception):
    """Not a statement this pass parses: textX will."""


_WORD = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


class StatementParser:
    """Recursive descent over the grammar's tokens; see the module docstring."""

    def __init__(self, mm):
        from . import parser
        self._p = parser
        rx = {name: mm[name]._tx_peg_rule.regex
              for name in ("SIMPLE_OPERAND", "VAR_PATH", "LITERAL", "BINARY_OP", "UNARY_OP",
                           "Comment")}
        self._simple = rx["SIMPLE_OPERAND"].match
        self._var_path = rx["VAR_PATH"].match
        self._literal = rx["LITERAL"].match
        self._binary = rx["BINARY_OP"].match
        self._unary = rx["UNARY_OP"].match
        # Arpeggio skips its whitespace, then comments each followed by
        # whitespace, before every token
        self._blank = re.compile(r"[\t\n\r ]*(?:(?:" + rx["Comment"].pattern + r")[\t\n\r ]*)*",
                                 rx["Comment"].flags).match
        self.text = ""

    def piece(self, text: str, start: int, end: int):
        """The statements of text[start:end] (one piece of a body), or
        Unsupported."""
        self.text = text
        self.end = end
        out = self._statements(start, ())
        if self.pos != end:
            raise Unsupported
        return out

    # -- helpers
    def _skip(self, pos):
        return self._blank(self.text, pos).end()

    def _word(self, pos):
        m = _WORD.match(self.text, pos)
        return m.group().upper() if m else ""

    def _expect_word(self, word, pos):
        pos = self._skip(pos)
        if self._word(pos) != word:
            raise Unsupported
        return pos + len(word)

    # -- statements
    def _statements(self, pos, stop):
        out = []
        text = self.text
        while True:
            pos = self._skip(pos)
            if pos >= self.end:  # (the blanks after a piece are the next piece's)
                if stop:
                    raise Unsupported  # a piece ends inside an IF: never from a good cut
                pos = self.end
                break
            if text[pos] == ";":
                out.append(ast.Empty(pos))
                pos += 1
                continue
            word = self._word(pos)
            if word in stop:
                break
            if word == "IF":
                node, pos = self._if(pos)
                out.append(node)
                continue
            if word in ("RETURN", "EXIT"):     # kw='RETURN' ';'
                q = self._skip(pos + len(word))
                if q >= self.end or text[q] != ";":
                    raise Unsupported
                out.append(ast.Return(pos) if word == "RETURN" else ast.Exit(pos))
                pos = q + 1
                continue
            if word == "CONTINUE":              # kw='CONTINUE' ';', not reserved
                q = self._skip(pos + len(word))
                if q < self.end and text[q] == ";":
                    out.append(ast.Continue(pos))
                    pos = q + 1
                    continue
            m = self._var_path(text, pos)
            if not m:
                raise Unsupported
            q = self._skip(m.end())
            if not text.startswith(":=", q):
                raise Unsupported   # an index, a call, or not a statement
            value, q = self._expression(q + 2)
            q = self._skip(q)
            if q >= self.end or text[q] != ";":
                raise Unsupported
            out.append(ast.Assign(pos, target=self._p.path_ref(m.group(), pos), value=value))
            pos = q + 1
        self.pos = pos
        return out

    def _if(self, pos):
        start = pos
        cond, pos = self._expression(pos + 2)
        pos = self._expect_word("THEN", pos)
        then = self._statements(pos, ("ELSIF", "ELSE", "END_IF"))
        branches = [(cond, then)]
        pos = self.pos
        else_ = None
        while True:
            word = self._word(pos)
            if word == "ELSIF":
                cond, pos = self._expression(pos + 5)
                pos = self._expect_word("THEN", pos)
                branches.append((cond, self._statements(pos, ("ELSIF", "ELSE", "END_IF"))))
                pos = self.pos
            elif word == "ELSE":
                else_ = self._statements(pos + 4, ("END_IF",)) or None
                pos = self.pos
                if self._word(pos) != "END_IF":
                    raise Unsupported
            elif word == "END_IF":
                break
            else:
                raise Unsupported
        pos += 6
        q = self._skip(pos)
        if q < self.end and self.text[q] == ";":  # 'END_IF' ';'?
            pos = q + 1
        return ast.If(start, branches=branches, else_=else_), pos

    # -- expressions
    def _expression(self, pos):
        """Expression: operands=Operand (ops=BINARY_OP operands=Operand)*"""
        operand, pos = self._operand(pos)
        operands = [operand]
        ops = []
        while True:
            q = self._skip(pos)
            m = self._binary(self.text, q)
            if not m:
                break
            ops.append(m.group())
            operand, pos = self._operand(m.end())
            operands.append(operand)
        return self._p.climb(operands, ops), pos

    def _operand(self, pos):
        """Operand: Simple | Unary"""
        text = self.text
        pos = self._skip(pos)
        m = self._simple(text, pos)
        if m:
            return self._simple_node(m.group(), pos), m.end()
        ops = []
        q = pos
        while True:
            m = self._unary(text, q)
            if not m:
                break
            ops.append(m.group())
            q = self._skip(m.end())
        node, q = self._primary(q)
        if text.startswith("**", self._skip(q)):
            raise Unsupported
        for op in reversed(ops):
            node = ast.UnOp(pos, "NOT" if op[0] in "nN" else op, node)
        return node, q

    def _primary(self, pos):
        """Primary: KeywordCall | CallOrVariable | Literal | Paren | DirectVariable,
        without calls, indexes and direct variables"""
        text = self.text
        if text.startswith("(", pos):
            node, q = self._expression(pos + 1)
            q = self._skip(q)
            if not text.startswith(")", q):
                raise Unsupported
            return node, q + 1
        m = self._var_path(text, pos)
        if m:
            after = self._skip(m.end())
            if after < len(text) and text[after] in "[(":
                raise Unsupported  # an index or a call (or a keyword function)
            return self._p.path_ref(m.group(), pos), m.end()
        m = self._literal(text, pos)
        if m:
            return self._literal_node(m.group(), pos), m.end()
        raise Unsupported

    def _simple_node(self, text, pos):
        if self._p.simple_is_literal(text):
            return self._literal_node(text, pos)
        return self._p.path_ref(text, pos)

    def _literal_node(self, text, pos):
        try:
            kind, value, type_name = classify(text)
        except (LiteralError, ValueError):
            raise Unsupported from None  # textX reports it
        return ast.Lit(pos, text, kind, value, type_name)


def fast_statements(text: str, parser: StatementParser):
    """(text for textX, {POU start: [statements]}) or None when this pass
    takes nothing: the pieces it parsed are blanked in the returned text."""
    taken = {}
    spans = []
    for pou, pieces in statement_pieces(text):
        got = []
        for a, b in pieces:
            try:
                got += parser.piece(text, a, b)
            except (Unsupported, RecursionError):
                continue
            spans.append((a, b))
        if got:
            taken[pou] = got
    if not spans:
        return None
    out = []
    last = 0
    for a, b in spans:
        out.append(text[last:a])
        out.append(_blank(text[a:b]))
        last = b
    out.append(text[last:])
    return "".join(out), taken


def _blank(piece: str) -> str:
    """A piece taken out of textX's text, its length and newlines kept: a
    comment, which Arpeggio skips with one regular-expression match where
    it would step over blanks one character at a time."""
    blank = re.sub(r"[^\n]", " ", piece)
    core = blank.strip("\n")
    if len(core) < 4 or "\n" in core[:2] + core[-2:]:
        return blank
    a = len(blank) - len(blank.lstrip("\n"))
    return blank[:a] + "(*" + core[2:-2] + "*)" + blank[a + len(core):]
