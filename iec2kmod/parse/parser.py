"""Pass 1: parse.  textX grammar -> model, expressions rebuilt into
precedence trees (iec2kmod.ast), syntax errors turned into diagnostics."""

from __future__ import annotations

import gc
import re
import sys
from contextlib import contextmanager
from functools import lru_cache
from pathlib import Path

from arpeggio import EndOfFile, Terminal
from textx import metamodel_from_file, metamodel_from_str
from textx.const import MULT_ASSIGN_ERROR
from textx.exceptions import TextXSyntaxError, TextXSemanticError

from .. import ast
from ..diagnostics import Diagnostics, SourceFile
from . import lexical
from .lexical import pragmas
from .literals import LiteralError, classify

# Arpeggio descends about 16 Python frames per parenthesis, 28 per nested
# call and 10 per nested IF; Python 3.11 keeps pure-Python frames off the C
# stack, so this allows about 570 nested parentheses, 320 nested calls and
# 900 nested statements (no less than before the Operand fast path).
RECURSION_LIMIT = 9200

GRAMMAR = Path(__file__).resolve().parent / "grammar" / "iec61131.tx"

# Binary operator precedence, lowest first (IEC 61131-3 ed.3 table 71);
# ** and the unary operators are handled by the grammar itself.
PRECEDENCE = {"OR": 1, "XOR": 2, "AND": 3, "&": 3, "=": 4, "<>": 4,
              "<": 5, ">": 5, "<=": 5, ">=": 5, "+": 6, "-": 6,
              "*": 7, "/": 7, "MOD": 7}


class _Ctx:
    """Per-parse state shared with the object processors."""

    src: SourceFile | None = None
    diags: Diagnostics | None = None


_ctx = _Ctx()


def _pos(obj):
    return obj._tx_position


def _expression(obj):
    return climb(obj.operands, obj.ops)


def climb(operands, ops):
    """The precedence tree of a flat operand/operator sequence (the
    Expression rule's, and iec2kmod.parse.stfast's)."""
    if not ops:
        return operands[0]
    # precedence climbing over the flat sequence
    ops = [op.upper() if op[0].isalpha() else op for op in ops]
    it = iter(range(len(ops)))
    out_vals = [operands[0]]
    out_ops: list[str] = []
    for i in it:
        op = ops[i]
        prec = PRECEDENCE[op]
        while out_ops and PRECEDENCE[out_ops[-1]] >= prec:
            _reduce(out_vals, out_ops)
        out_ops.append(op)
        out_vals.append(operands[i + 1])
    while out_ops:
        _reduce(out_vals, out_ops)
    return out_vals[0]


def _reduce(vals, ops):
    right = vals.pop()
    left = vals.pop()
    op = ops.pop()
    if op == "&":
        op = "AND"
    vals.append(ast.BinOp(left.pos, op, left, right))


def _unary(obj):
    operands = obj.operands
    node = operands[0]
    for rhs in operands[1:]:
        node = ast.BinOp(node.pos, "**", node, rhs)
    for op in reversed(obj.ops):
        node = ast.UnOp(_pos(obj), "NOT" if op[0] in "nN" else op, node)
    return node


def _exponent(obj):
    node = obj.operand
    for op in reversed(obj.ops):
        node = ast.UnOp(_pos(obj), "NOT" if op[0] in "nN" else op, node)
    return node


def _paren(obj):
    return obj.expr


def _literal(obj):
    text = obj.text
    pos = _pos(obj)
    try:
        kind, value, type_name = classify(text)
    except (LiteralError, ValueError) as exc:
        _ctx.diags.error(_ctx.src, pos, f"invalid literal {text}: {exc}")
        kind, value, type_name = "int", 0, None
    return ast.Lit(pos, text, kind, value, type_name)


def _path_accessors(path, pos, out):
    """Member and bit accessors of a '.a.b.3' path starting at offset pos."""
    for part in path.split("."):
        if part:
            if part[0].isdigit():
                out.append(("bit", int(part), pos))
            else:
                out.append(("member", part, pos))
        pos += len(part) + 1


def _path_ref(path, pos):
    """The Ref of a VAR_PATH token 'a.b.3' at offset pos."""
    name, _, rest = path.partition(".")
    accessors = []
    if rest:
        _path_accessors(rest, pos + len(name) + 1, accessors)
    return ast.Ref(pos, name, accessors)


path_ref = _path_ref  # for iec2kmod.parse.stfast


def _signed_number(obj):
    """An IL operand such as -7 or -2.5: a literal with its sign."""
    text = obj.text
    pos = _pos(obj)
    kind, value, _ = classify(text[1:])
    return ast.Lit(pos, text, kind, -value if text[0] == "-" else value)


def _variable(obj):
    ref = _path_ref(obj.name, _pos(obj))
    accessors = ref.accessors
    for idx in obj.indexes:
        accessors.append(("index", list(idx.indexes), _pos(idx)))
        if idx.members:
            _path_accessors(idx.members[1:], idx._tx_position_end - len(idx.members) + 1,
                            accessors)
    return ref


def _args(call_args):
    out = []
    for a in call_args.args:
        cls = a.__class__.__name__
        if cls == "Positional":
            out.append(ast.Arg(_pos(a), "pos", None, a.value))
        elif cls == "FormalInput":
            out.append(ast.Arg(_pos(a), "in", a.name, a.value))
        else:
            words = a.name.split()
            out.append(ast.Arg(_pos(a), "out", words[-1], a.target, len(words) > 1))
    return out


def simple_is_literal(text):
    """Whether a SIMPLE_OPERAND token is a LITERAL (a VAR_PATH has no '#'
    and no reserved word)."""
    return "#" in text or not (text[0].isalpha() or text[0] == "_") or \
        text.upper() in ("TRUE", "FALSE")


def _simple(obj):
    """A SIMPLE_OPERAND token: the Ref or Lit the full Unary rule makes."""
    text = obj.text
    if simple_is_literal(text):
        return _literal(obj)
    return _path_ref(text, _pos(obj))


def _call_or_variable(obj):
    var = obj.var
    if obj.call is None:
        return var
    if var.accessors:
        _ctx.diags.error(_ctx.src, var.pos, f"'{var!r}' cannot be called")
    return ast.Call(var.pos, var.name, _args(obj.call))


def _keyword_call(obj):
    return ast.Call(_pos(obj), obj.name.upper(), _args(obj.call))


def _direct(obj):
    return ast.Direct(_pos(obj), obj.address.upper())


def _call_args(obj):
    obj.arglist = _args(obj)
    return None


def _il_call_args(obj):
    obj.arglist = _args(obj.list)
    return None


@lru_cache(maxsize=1)
def metamodel():
    mm = metamodel_from_file(str(GRAMMAR), ignore_case=True, autokwd=True,
                             memoization=False, skipws=True)
    mm.register_obj_processors({
        "Expression": _expression,
        "Unary": _unary,
        "Exponent": _exponent,
        "Paren": _paren,
        "Literal": _literal,
        "ILSignedNumber": _signed_number,
        "Simple": _simple,
        "Variable": _variable,
        "CallOrVariable": _call_or_variable,
        "DirectVariable": _direct,
        "KeywordCall": _keyword_call,
        "CallArgs": _call_args,
        "ILCallArgs": _il_call_args,
    })
    return mm


# --------------------------------------------------------------------------
# Lean model builder.
#
# textX's generic builder (model_from_str) walks the parse tree computing a
# line/column for every node, registers every named object for reference
# resolution, resolves references (this grammar has none), checks the whole
# model for postponed objects and walks it once more to call the object
# processors.  The builder below does the same construction in one pass over
# the parse tree of the parser textX generates from the grammar, from the
# metamodel's own information: class rules carry their class (_tx_class),
# assignment rules their attribute (_attr_name) and kind (rule name
# __asgn_plain/optional/zeroormore/oneormore/list), and each class its
# attributes (_tx_attrs).  Object processors run in the same order as
# textX's (children first) and replace values the same way.
# tests/unit/test_fast_builder.py checks it against model_from_str.


class FastBuilder:
    """Builds the textX model of a parse tree, as model_from_str does."""

    def __init__(self, mm):
        from textx.const import (MULT_ONEORMORE, MULT_ZEROORMORE, RULE_ABSTRACT,
                                 RULE_MATCH)
        from textx.lang import BASE_TYPE_NAMES, python_type
        self._mm = mm
        self._procs = mm._obj_processors
        self._many = (MULT_ONEORMORE, MULT_ZEROORMORE)
        self._abstract = RULE_ABSTRACT
        self._match = RULE_MATCH
        self._base_types = BASE_TYPE_NAMES
        self._python_type = python_type
        self._classes = set(mm)  # the metamodel's classes
        self._handlers = {}      # id(grammar rule) -> function(node) -> value
        self.parser = None       # the parser of the current parse (for errors)

    # -- dispatch
    def build(self, node):
        """The model value of one parse-tree node."""
        try:
            return self._handlers[id(node.rule)](node)
        except KeyError:
            pass
        rule = node.rule
        if isinstance(node, Terminal):
            handler = self._terminal
            if isinstance(rule, EndOfFile):  # a fresh rule object each time
                return handler(node)
        elif rule._tx_class._tx_type == self._abstract:
            handler = self._abstract_value
        elif rule._tx_class._tx_type == self._match:
            handler = self._match_value
        else:
            handler = self._class_handler(rule._tx_class)
        self._handlers[id(rule)] = handler
        return handler(node)

    # -- rule kinds (the cases of textX's process_node)
    def _terminal(self, node):
        proc = self._procs.get(node.rule_name)
        return node.value if proc is None else proc(node.value)

    def _abstract_value(self, node):
        if len(node) > 1:
            for n in node:
                if not isinstance(n, Terminal):
                    return self.build(n)
            return "".join(str(n) for n in node)
        return self.build(node[0])

    def _match_value(self, nt):
        if isinstance(nt, Terminal):
            value = nt.value
        elif len(nt) > 1:
            value = "".join(str(self._match_value(n)) for n in nt)
        else:
            value = self._match_value(nt[0])
        proc = self._procs.get(nt.rule_name)
        return value if proc is None else proc(value)

    def _value_processor(self, attr_cls):
        """The object processing textX applies (call_obj_processors) to a
        value of an attribute declared with class attr_cls, as a function
        value -> replacement or None; None when there is nothing to call."""
        if attr_cls._tx_type == self._match:
            return None
        procs = self._procs
        grammar_proc = procs.get(attr_cls.__name__)
        if attr_cls._tx_type != self._abstract and grammar_proc is None:
            return None  # values are always instances of attr_cls itself
        classes = self._classes
        own_procs = {}

        def process(value):
            cls = value.__class__
            try:
                own = own_procs[cls]
            except KeyError:
                own = None
                if cls in classes and cls._tx_fqn != attr_cls._tx_fqn:
                    own = procs.get(cls.__name__)
                own_procs[cls] = own
            current = own(value) if own is not None else None
            grammar = grammar_proc(value) if grammar_proc is not None else None
            return current if current is not None else grammar

        return process

    def _class_handler(self, mclass):
        build = self.build
        many = self._many
        lists = []
        defaults = {}
        for attr in mclass._tx_attrs.values():
            if attr.mult in many:
                lists.append(attr.name)
            elif attr.cls.__name__ in self._base_types:
                if self._mm.auto_init_attributes:
                    defaults[attr.name] = self._python_type(attr.cls.__name__)()
                else:
                    defaults[attr.name] = False if attr.bool_assignment else None
            else:
                defaults[attr.name] = None
        # id(child rule) -> (attribute, op, is_list, processor), or None
        # for children that are not assignments (keywords, separators, ...)
        assigns = {}
        new = mclass.__new__

        def assignment(rule):
            if not rule.rule_name.startswith("__asgn"):
                info = None
            else:
                name = rule._attr_name
                metaattr = mclass._tx_attrs[name]
                info = (name, rule.rule_name.split("_")[-1], metaattr.mult in many,
                        self._value_processor(metaattr.cls))
            if not isinstance(rule, EndOfFile):
                assigns[id(rule)] = info
            return info

        def instance(node):
            inst = new(mclass)
            d = inst.__dict__
            d.update(defaults)
            for name in lists:
                d[name] = []
            d["_tx_position"] = node.position
            d["_tx_position_end"] = node.position_end
            for n in node:
                try:
                    info = assigns[id(n.rule)]
                except KeyError:
                    info = assignment(n.rule)
                if info is None:
                    continue
                name, op, is_list, proc = info
                if op == "plain":
                    if not is_list:
                        old = d[name]
                        if old and not isinstance(old, list):
                            raise TextXSemanticError(
                                message=f"Multiple assignments to attribute {name} at "
                                        f"{self.parser.pos_to_linecol(n.position)}",
                                err_type=MULT_ASSIGN_ERROR)
                    value = build(n[0])
                    if proc is not None:
                        r = proc(value)
                        if r is not None:
                            value = r
                    if is_list:
                        d[name].append(value)
                    else:
                        d[name] = value
                elif op == "optional":
                    d[name] = True
                else:
                    out = d[name]
                    for m in n:
                        if m.rule_name != "sep":
                            value = build(m)
                            if proc is not None:
                                r = proc(value)
                                if r is not None:
                                    value = r
                            out.append(value)
            return inst
        return instance

    def model(self, parse_tree):
        """The model of a whole parse (the tree returned by parser.parse):
        the root and the object processor of its own class."""
        root = self.build(parse_tree[0])
        if root.__class__ in self._classes:
            proc = self._procs.get(root.__class__.__name__)
            if proc is not None:
                r = proc(root)
                if r is not None:
                    root = r
        return root


@lru_cache(maxsize=1)
def fast_builder() -> FastBuilder:
    return FastBuilder(metamodel())


def fast_model_from_str(text: str, file_name: str | None = None):
    """The model of ``text``, like metamodel().model_from_str but built by
    FastBuilder; raises the same TextXSyntaxError on syntax errors."""
    builder = fast_builder()
    parser = metamodel()._parser_blueprint.clone()
    builder.parser = parser
    try:
        tree = parser.parse(text, file_name=file_name)
        return builder.model(tree)
    finally:
        builder.parser = None


# Fast-path tokens of the grammar (see SIMPLE_OPERAND in the grammar): they
# only shortcut what other rules would match, so they are never named in
# "expected ..." messages, and syntax errors are found again with them
# switched off, which gives exactly the errors of the grammar without them.
FAST_PATHS = ("SIMPLE_OPERAND",)
_NEVER = re.compile(r"(?!)")


# ... and the hand-written statement parser (iec2kmod/parse/stfast.py), on or off
# with them
_ST_FAST = [True]


@contextmanager
def fast_paths(enabled: bool):
    """Switches the grammar's fast-path tokens and iec2kmod.parse.stfast on or off
    (process-wide, for the parses inside the ``with`` block)."""
    statement_parser()  # takes the tokens' expressions while they are on
    rules = [metamodel()[name]._tx_peg_rule for name in FAST_PATHS]
    saved = [r.regex for r in rules]
    saved_st = _ST_FAST[0]
    if not enabled:
        for r in rules:
            r.regex = _NEVER
        _ST_FAST[0] = False
    try:
        yield
    finally:
        for r, regex in zip(rules, saved):
            r.regex = regex
        _ST_FAST[0] = saved_st


@lru_cache(maxsize=1)
def statement_parser():
    from .stfast import StatementParser
    return StatementParser(metamodel())


def _model(src: SourceFile, reference: bool):
    def build():
        if reference:
            return metamodel().model_from_str(src.text, file_name=src.path)
        return fast_model_from_str(src.text, file_name=src.path)
    try:
        return build()
    except TextXSyntaxError:
        pass
    # The error (its position and expected tokens) of the grammar without
    # the fast paths, which may try more at the place of the error.
    with fast_paths(False):
        return build()


def _warn_pragmas(src: SourceFile, diags: Diagnostics) -> None:
    """A warning at every pragma no pass reads (see lexical.PRAGMAS)."""
    for p in pragmas(src.text):
        if p.kind is None:
            diags.warning(src, p.start, "pragma ignored")


def _syntax_message(err, text: str, offset: int, end: str = "end of file") -> str:
    """'expected ..., found ...' of a syntax error at offset of text."""
    what = _describe_expected(err, end)
    token = re.match(r"\w+|\S", text[offset:])
    what += f", found '{token.group(0)}'" if token else f", found {end}"
    return what + _unsupported_hint(text, offset)


def _describe_expected(err, end: str = "end of file") -> str:
    rules = getattr(err, "expected_rules", None) or []
    names = []
    for r in rules:
        name = getattr(r, "rule_name", "") or ""
        to_match = getattr(r, "to_match", None)
        if isinstance(to_match, str) and r.__class__.__name__ == "StrMatch":
            label = f"'{to_match}'"
        elif name in ("Comment", "KEYWORD_FUNCTION") or name in FAST_PATHS:
            continue
        elif name == "EOF":
            label = end
        elif name in _TOKEN_NAMES:
            label = _TOKEN_NAMES[name]
        elif name:
            label = name
        else:
            continue
        if label not in names:
            names.append(label)
    if not names:
        return "syntax error"
    if len(names) > 8:
        names = names[:8] + ["..."]
    if len(names) == 1:
        return f"expected {names[0]}"
    return "expected " + ", ".join(names[:-1]) + " or " + names[-1]


_TOKEN_NAMES = {
    "ID": "identifier", "ANY_NAME": "name", "VAR_PATH": "identifier",
    "TYPE_NAME": "type name", "MEMBER_PATH": "'.'", "INPUT_NAME": "identifier",
    "OUTPUT_NAME": "identifier", "INTEGER": "integer",
    "LITERAL": "literal", "DIRECT_ADDRESS": "direct address",
    "BINARY_OP": "operator", "UNARY_OP": "unary operator",
    "IL_OP": "IL operator", "IL_CALL_OP": "CAL", "EOL": "end of line",
    "IL_SIGNED_NUMBER": "number",
}


def parse_source(src: SourceFile, diags: Diagnostics, reference: bool = False):
    """Parses one source file; returns the model or None (errors in diags).

    The model is built by FastBuilder; ``reference=True`` builds it with
    textX's own model_from_str instead (the reference the tests compare
    the fast path with)."""
    # The parse allocates millions of objects and almost no garbage cycles:
    # the cyclic collector would only rescan the growing parse tree over and
    # over (about a fifth of the parse time).
    gc_was_enabled = gc.isenabled()
    gc.disable()
    try:
        return _parse_source(src, diags, reference)
    finally:
        if gc_was_enabled:
            gc.enable()


def _parse_source(src: SourceFile, diags: Diagnostics, reference: bool):
    unit = _parse_unit(src, diags, reference)
    if unit is not None:
        lexical.attach(unit)
    return unit


def _parse_unit(src: SourceFile, diags: Diagnostics, reference: bool):
    _ctx.src = src
    _ctx.diags = diags
    _warn_pragmas(src, diags)
    if sys.getrecursionlimit() < RECURSION_LIMIT:
        sys.setrecursionlimit(RECURSION_LIMIT)
    if not reference and _ST_FAST[0]:
        unit = _parse_with_fast_statements(src, diags)
        if unit is not None:
            return unit
        _ctx.src = src
        _ctx.diags = diags
    try:
        model = _model(src, reference)
    except TextXSyntaxError as err:
        line, col = err.line or 1, err.col or 1
        offset = min(src.offset(line, col), len(src.text))
        spec = _access_specifier(src.text, offset)
        if spec is not None:
            diags.error(src, *spec)
            return None
        diags.error(src, offset, _syntax_message(err, src.text, offset))
        return None
    except TextXSemanticError as err:
        diags.error(src, None, str(err.message), line=err.line or 1, col=err.col or 1)
        return None
    except RecursionError:
        diags.error(src, _deepest_nesting(src.text),
                    "nested too deeply for the parser (simplify this expression or statement)")
        return None
    finally:
        _ctx.src = None
    if not hasattr(model, "elements"):  # an empty file
        return ast.SourceUnit(0, src=src, types=[], pous=[], configurations=[])
    try:
        return to_ast(model, src, diags)
    except RecursionError:
        diags.error(src, _deepest_nesting(src.text),
                    "nested too deeply for the parser (simplify this expression or statement)")
        return None


# ed.3 syntax outside the language iec2kmod compiles: a syntax error on a
# line that uses it says so (the grammar does not know the words)
_ED3_WORDS = re.compile(
    r"\b(CLASS|END_CLASS|METHOD|END_METHOD|INTERFACE|END_INTERFACE|NAMESPACE|"
    r"END_NAMESPACE|EXTENDS|IMPLEMENTS|PROPERTY|END_PROPERTY|REF_TO)\b|"
    r"\b(THIS|SUPER|\w+)\s*\^|\b(REF)\s*\(|ARRAY\s*\[\s*(\*)", re.I)
# forms of other dialects that real code uses, named in a syntax error on
# their line
_DIALECT_FORMS = [(re.compile(rx, re.I | re.M), what) for rx, what in (
    (r"\bPOINTER\s+TO\b", "POINTER TO, a CODESYS pointer type"),
    (r"\bREFERENCE\s+TO\b", "REFERENCE TO, a CODESYS reference type"),
    (r"\.\s*%[XBWDL]\d", "a partial access (.%X0, .%B1 ...), IEC 61131-3 ed.3"),
    (r"/\*", "a /* */ comment, IEC 61131-3 ed.3 (ed.2 comments are (* *))"),
    (r"^\s*VAR_GLOBAL\b", "VAR_GLOBAL outside a CONFIGURATION, a CODESYS/TwinCAT global "
                          "variable list (ed.2 declares global variables in a CONFIGURATION "
                          "or RESOURCE)"),
    (r":\s*[\w\[\]. ]+?\s+AT\s+%", "a location after the type, a form of some editors "
                                "(ed.2 writes name AT %MW0 : UINT)"),
)]
# an access or inheritance specifier after the POU keyword (ed.3 6.6.5,
# CODESYS): FUNCTION_BLOCK PUBLIC name
_ACCESS_SPECIFIER = re.compile(
    r"\b(?:FUNCTION_BLOCK|FUNCTION|PROGRAM)\s+"
    r"(PUBLIC|PRIVATE|INTERNAL|PROTECTED|FINAL|ABSTRACT)\b", re.I)


def _access_specifier(text: str, offset: int):
    """(offset, message) for a syntax error at or just after an access
    specifier (FUNCTION_BLOCK PUBLIC name), else None."""
    start = text.rfind("\n", 0, max(text.rfind("\n", 0, offset), 0)) + 1
    end = text.find("\n", offset)
    for m in _ACCESS_SPECIFIER.finditer(text, start, end if end >= 0 else len(text)):
        word = m.group(1).upper()
        return m.start(1), (f"access specifier {word} after {m.group(0).split()[0].upper()}: "
                            "an IEC 61131-3 ed.3 / CODESYS object-oriented form, which "
                            f"iec2kmod does not support; remove {word} (an ed.2 POU is "
                            "visible to the whole project)")
    return None


def _unsupported_hint(text: str, offset: int) -> str:
    """A note for a syntax error on a line (or after the line) that uses
    IEC 61131-3 ed.3 object orientation or references, or at a '*)' out of
    any comment (a nested comment)."""
    if text.startswith("*)", offset):
        return " (a '*)' outside a comment: nested comments are not supported)"
    start = text.rfind("\n", 0, max(text.rfind("\n", 0, offset), 0)) + 1
    end = text.find("\n", offset)
    line = text[start:end if end >= 0 else len(text)]
    line = re.sub(r"\(\*.*?\*\)|//.*|'[^']*'|\"[^\"]*\"", " ", line)
    here = text[text.rfind("\n", 0, offset) + 1:offset]
    if re.match(r"\s*\(\*", here) and "*)" in here[here.index("(*") + 2:]:
        # (*DBG: return (void *)&x;*): the comment ended at the first '*)'
        return (" (the comment opened on this line was ended by the '*)' inside it: "
                "'*)' ends a comment wherever it stands, and comments do not nest)")
    for rx, what in _DIALECT_FORMS:
        if rx.search(line):
            return f" (this line uses {what}, which iec2kmod does not support)"
    m = _ED3_WORDS.search(line)
    if not m:
        return ""
    if m.group(1):
        word = m.group(1).upper()
        what = f"{word}, IEC 61131-3 ed.3 " + ("references" if word == "REF_TO" else
                                              "object orientation")
    elif m.group(2):
        what = "'^', an ed.3 dereference"
    elif m.group(3):
        what = "REF(), an ed.3 reference"
    else:
        what = "ARRAY[*], an ed.3 array of variable length"
    return f" (this line uses {what}, which iec2kmod does not support)"


def _parse_with_fast_statements(src: SourceFile, diags: Diagnostics):
    """The unit of src with iec2kmod.parse.stfast taking the statements it knows
    and textX the rest; None when stfast takes nothing or textX does not
    agree (see the module docstring of stfast): then textX parses it all."""
    from .stfast import fast_statements
    got = fast_statements(src.text, statement_parser())
    if got is None:
        return None
    text, taken = got
    local = Diagnostics()
    _ctx.src = src
    _ctx.diags = local
    try:
        model = fast_model_from_str(text, file_name=src.path)
        if not hasattr(model, "elements"):
            return None
        unit = to_ast(model, src, local)
    except (TextXSyntaxError, TextXSemanticError, RecursionError):
        return None
    finally:
        _ctx.src = None
    if local.errors:
        return None
    pous = {p.pos: p for p in unit.pous}
    for pos, stmts in taken.items():
        pou = pous.get(pos)
        if pou is None or pou.language != "ST":
            return None
        pou.body = sorted(pou.body + stmts, key=lambda s: s.pos)
    diags.items += local.items
    return unit


def _deepest_nesting(text: str) -> int:
    """Offset of the first parenthesis at the deepest nesting level."""
    depth = best = 0
    where = 0
    for i, ch in enumerate(text):
        if ch in "([":
            depth += 1
            if depth > best:
                best, where = depth, i
        elif ch in ")]":
            depth -= 1
    return where


# --------------------------------------------------------------------------
# One expression on its own: verify properties and assumptions, and paths
# like sim --watch's.  The grammar's Expression rule is the root of a second
# metamodel made from the same grammar (same tokens, same object
# processors), so positions are those of the expression's own text.

_EXPRESSION_ROOT = "ExpressionText:\n    value=Expression\n;\n\n"


@lru_cache(maxsize=1)
def expression_metamodel():
    mm = metamodel_from_str(_EXPRESSION_ROOT + GRAMMAR.read_text(), ignore_case=True,
                            autokwd=True, memoization=False, skipws=True)
    mm.register_obj_processors(metamodel()._obj_processors)
    return mm


def parse_expression(text: str, origin: tuple[SourceFile, int] | None = None,
                     diags: Diagnostics | None = None, what: str = "expression"):
    """The AST of the ST expression ``text``, or None after an error.

    ``origin`` is (src, offset): where text stands in a source file; the
    positions of the AST and of the diagnostics (into *diags*) are then
    those of src, else those of text itself.  *what* names the expression
    in messages ("property": "in a property: expected ...")."""
    src, base = origin if origin is not None else (SourceFile("<expression>", text), 0)
    own = SourceFile(src.path, text)
    local = Diagnostics()
    mm = expression_metamodel()
    saved_src, saved_diags = _ctx.src, _ctx.diags
    _ctx.src, _ctx.diags = own, local
    if sys.getrecursionlimit() < RECURSION_LIMIT:
        sys.setrecursionlimit(RECURSION_LIMIT)
    expr = None
    try:
        try:
            expr = mm.model_from_str(text).value
        except TextXSyntaxError:
            # the error of the grammar without its fast-path tokens (see
            # FAST_PATHS), as parse_source reports it
            rules = [mm[name]._tx_peg_rule for name in FAST_PATHS]
            saved = [r.regex for r in rules]
            for r in rules:
                r.regex = _NEVER
            try:
                mm.model_from_str(text)
            except TextXSyntaxError as err:
                offset = min(own.offset(err.line or 1, err.col or 1), len(text))
                local.error(own, offset, _syntax_message(err, text, offset,
                                                         f"end of {what}"))
            finally:
                for r, regex in zip(rules, saved):
                    r.regex = regex
    except TextXSemanticError as err:
        local.error(own, None, str(err.message), line=err.line or 1, col=err.col or 1)
    except RecursionError:
        local.error(own, _deepest_nesting(text), "nested too deeply for the parser "
                                                 "(simplify this expression)")
    finally:
        _ctx.src, _ctx.diags = saved_src, saved_diags
    if local.errors or expr is None:
        if diags is not None:
            for e in local.errors or [None]:
                if e is None:
                    diags.error(src, base, f"a {what} must be one expression")
                    continue
                off = min(max(own.offset(e.line, e.col), 0), len(text))
                diags.error(src, base + off, f"in a {what}: {e.message}")
        return None
    if base:
        shift_positions(expr, base)
    return expr


def shift_positions(e, d: int) -> None:
    """Moves the positions of expression e (and its operands) by d."""
    if e is None:
        return
    if isinstance(e, ast.Expr) and e.pos is not None:
        e.pos += d
    if isinstance(e, ast.BinOp):
        shift_positions(e.left, d)
        shift_positions(e.right, d)
    elif isinstance(e, ast.UnOp):
        shift_positions(e.operand, d)
    elif isinstance(e, ast.Ref):
        acc = []
        for k, val, pos in e.accessors:
            if k == "index":
                for x in val:
                    shift_positions(x, d)
            acc.append((k, val, pos + d if pos is not None else pos))
        e.accessors = acc
    elif isinstance(e, ast.Call):
        for a in e.args:
            if a.pos is not None:
                a.pos += d
            shift_positions(a.value, d)


def parse_file(path: str, diags: Diagnostics):
    """Reads and parses one file: (SourceFile, SourceUnit | None)."""
    text = Path(path).read_text(encoding="utf-8", errors="replace")
    src = SourceFile(path, text)
    return src, parse_source(src, diags)


# --------------------------------------------------------------------------
# textX model -> iec2kmod.ast (picklable, independent of the metamodel)


def _cls(obj):
    return obj.__class__.__name__


def _spec(t):
    c = _cls(t)
    pos = _pos(t)
    if c == "NamedType":
        return ast.NamedSpec(pos, name=t.name)
    if c == "StringSpec":
        return ast.StringSpec(pos, wide=t.kind.upper() == "WSTRING", length=t.length)
    if c == "SubrangeSpec":
        return ast.SubrangeSpec(pos, base=t.base, low=t.low, high=t.high)
    if c == "EnumSpec":
        return ast.EnumSpec(pos, base=t.base or None,
                            values=[(v.name, v.value, _pos(v)) for v in t.values])
    if c == "ArraySpec":
        return ast.ArraySpec(pos, ranges=[(r.low, r.high) for r in t.ranges],
                             element=_spec(t.element))
    if c == "StructSpec":
        return ast.StructSpec(pos, members=[
            ast.VarDecl(_pos(m), names=[(m.name, _pos(m))],
                        location=m.location.address.upper() if m.location else None,
                        edge=None, spec=_spec(m.spec), init=_init(m.init))
            for m in t.members])
    raise AssertionError(f"unknown type specification {c}")


def _init(i):
    if i is None or isinstance(i, ast.Expr):
        return i
    c = _cls(i)
    if c == "ArrayInit":
        return ast.ArrayInit(_pos(i), items=[
            (int(it.count.replace("_", "")) if it.count else None, _init(it.value))
            for it in i.items])
    if c == "StructInit":
        return ast.StructInit(_pos(i), fields=[(f.name, _init(f.value), _pos(f))
                                               for f in i.fields])
    raise AssertionError(f"unknown initializer {c}")


def _path(p):
    if p.location:
        return p.location.upper() if isinstance(p.location, str) else p.location.address.upper()
    parts = list(p.parts)
    if p.bit:
        parts.append(p.bit)
    return ".".join(parts)


def _block(b):
    kind = b.kind.upper()
    pos = _pos(b)
    if kind == "VAR_ACCESS":
        decls = [ast.AccessDecl(_pos(d), name=d.name, path=_path(d.path), spec=_spec(d.spec),
                                direction=(d.direction or "READ_WRITE").upper())
                 for d in b.decls]
        return ast.VarBlock(pos, kind=kind, qualifiers=(), decls=decls)
    if kind == "VAR_CONFIG":
        decls = [ast.ConfigDecl(_pos(d), path=_path(d.path),
                                location=d.location.address.upper() if d.location else None,
                                spec=_spec(d.spec), init=_init(d.init))
                 for d in b.decls]
        return ast.VarBlock(pos, kind=kind, qualifiers=(), decls=decls)
    decls = []
    for d in b.decls:
        # names carry their own offsets: find each name in the source
        names = _names_with_pos(d)
        decls.append(ast.VarDecl(_pos(d), names=names,
                                 location=d.location.address.upper() if d.location else None,
                                 edge=d.edge.upper() if d.edge else None,
                                 spec=_spec(d.spec), init=_init(d.init)))
    return ast.VarBlock(pos, kind=kind, qualifiers=tuple(q.upper() for q in b.qualifiers),
                        decls=decls)


_NAME_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def _names_with_pos(d):
    text = _ctx.src.text
    pos = _pos(d)
    out = []
    for name in d.names:
        m = _NAME_RE.search(text, pos)
        while m and m.group(0) != name:
            m = _NAME_RE.search(text, m.end())
        if m is None:
            out.append((name, _pos(d)))
            continue
        out.append((name, m.start()))
        pos = m.end()
    return out


def _body(stmt_list):
    """Statements of a StmtList; an empty list matches nothing (None)."""
    return _stmts(stmt_list.statements) if stmt_list is not None else []


def _stmts(lst):
    return [_stmt(s) for s in lst]


def _stmt(s):
    c = _cls(s)
    pos = _pos(s)
    if c == "AssignOrCall":
        if s.assign:
            return ast.Assign(pos, target=s.target, value=s.value)
        target = s.target
        # t[i](IN := x): an element of an array of FB instances (the checker
        # tells whether what the accessors lead to can be called)
        return ast.CallStmt(pos, call=ast.Call(target.pos, target.name, s.call.arglist,
                                               ref=target if target.accessors else None))
    if c == "IfStmt":
        branches = [(s.cond, _body(s.then))]
        branches += [(e.cond, _body(e.body)) for e in s.elsifs]
        return ast.If(pos, branches=branches,
                      else_=_body(s.else_) if s.else_ else None)
    if c == "CaseStmt":
        elements = [([(lab.low, lab.high) for lab in el.labels], _body(el.body))
                    for el in s.cases]
        return ast.Case(pos, selector=s.selector, elements=elements,
                        else_=_body(s.else_) if s.else_ else None)
    if c == "ForStmt":
        m = _NAME_RE.search(_ctx.src.text, pos + 3)
        return ast.For(pos, var=s.var, var_pos=m.start() if m else pos, start=s.start,
                       end=s.end, step=s.step, body=_body(s.body))
    if c == "WhileStmt":
        return ast.While(pos, cond=s.cond, body=_body(s.body))
    if c == "RepeatStmt":
        return ast.Repeat(pos, body=_body(s.body), cond=s.cond)
    if c == "ExitStmt":
        return ast.Exit(pos)
    if c == "ContinueStmt":
        return ast.Continue(pos)
    if c == "ReturnStmt":
        return ast.Return(pos)
    if c == "EmptyStmt":
        return ast.Empty(pos)
    raise AssertionError(f"unknown statement {c}")


_LABEL_END = re.compile(r":[ \t\r\n]*")


def _il(instrs):
    """Rebuilds the nesting of deferred operations from the flat lines."""
    top: list = []
    stack = [top]
    opened = []
    pending = None  # a label on a line of its own
    text = _ctx.src.text
    for i in instrs:
        pos = _pos(i)
        label = i.label or None
        ipos = pos
        if label:
            m = _LABEL_END.match(text, text.index(":", pos))
            ipos = m.end() if m else pos
        if i.close:
            if len(stack) == 1:
                _ctx.diags.error(_ctx.src, ipos, "')' without a deferred operation to close")
                continue
            stack.pop()
            opened.pop()
            if label:
                _ctx.diags.error(_ctx.src, pos, "a label cannot stand before ')'")
            continue
        op = i.op.upper() if i.op else None
        if op is None and not i.fn:
            if label:  # a label alone on its line marks the next instruction
                pending = (label, pos) if pending is None else pending
                if pending[0] != label:
                    _ctx.diags.error(_ctx.src, pos, f"two labels ('{pending[0]}', '{label}') "
                                                    "for one instruction")
            continue
        if pending is not None:
            if label:
                _ctx.diags.error(_ctx.src, pos, f"two labels ('{pending[0]}', '{label}') for "
                                                "one instruction")
            label, pos = pending
            pending = None
        if op == "&":
            op = "AND"
        elif op == "&N":
            op = "ANDN"
        deferred = bool(i.deferred)
        instr = ast.ILInstr(
            ipos, label=label, label_pos=pos if label else None, op=op,
            operand=i.operand, deferred=deferred,
            nested=[] if deferred else None, fb=i.fb or None, fn=i.fn or None,
            args=i.args.arglist if i.args else None,
            operands=list(i.operands) if i.operands else [])
        stack[-1].append(instr)
        if deferred:
            stack.append(instr.nested)
            opened.append(instr)
    for instr in opened:
        _ctx.diags.error(_ctx.src, instr.pos, f"'{instr.op}(' is never closed with ')'")
    if pending is not None:
        # a label at the very end: the target of a jump to the end of the body
        top.append(ast.ILInstr(pending[1], label=pending[0], label_pos=pending[1], op="NOP",
                               operand=None, deferred=False, nested=None, fb=None, fn=None,
                               args=None, operands=[]))
    return top


_STEP_NAME = re.compile(r"(?:INITIAL_STEP|STEP)\s+", re.I)
_NAME_AT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def _step_names(steps):
    """[(name, pos)] of a FROM/TO step list."""
    text = _ctx.src.text
    out = []
    pos = _pos(steps)
    for name in steps.names:
        m = _NAME_AT.search(text, pos)
        while m and m.group(0).upper() != name.upper():
            m = _NAME_AT.search(text, m.end())
        p = m.start() if m else _pos(steps)
        out.append((name, p))
        pos = m.end() if m else pos
    return out


def _sfc(body):
    """The SFC elements of a body (textual SFC, ed.2 2.6)."""
    text = _ctx.src.text
    sfc = ast.SFC(_pos(body), steps=[], transitions=[], actions=[])
    for e in body.elements:
        c = _cls(e)
        pos = _pos(e)
        if c == "SFCStep":
            m = _STEP_NAME.match(text, pos)
            assocs = []
            for a in e.assocs:
                qpos = None
                if a.qualifier:
                    m2 = re.compile(r"\(\s*").search(text, _pos(a))
                    qpos = m2.end() if m2 else _pos(a)
                assocs.append(ast.ActionAssoc(_pos(a), action=a.action,
                                              qualifier=a.qualifier.upper() if a.qualifier
                                              else None, qual_pos=qpos, args=list(a.args),
                                              time=None, indicators=[]))
            sfc.steps.append(ast.Step(m.end() if m else pos, name=e.name,
                                      initial=bool(e.initial), assocs=assocs))
        elif c == "SFCTransition":
            il = None
            if e.il is not None:
                il = _il([i.instruction for i in e.il.instructions])
            sfc.transitions.append(ast.Transition(
                pos, name=e.name or None,
                priority=int(e.priority.replace("_", "")) if e.priority else None,
                sources=_step_names(e.sources), targets=_step_names(e.targets),
                cond=e.cond, il=il, index=len(sfc.transitions)))
        else:
            b = e.body
            if b is not None and b.il is not None:
                language, stmts = "IL", _il(b.il.instructions)
            else:
                language, stmts = "ST", _body(b.st) if b is not None else []
            m = re.compile(r"ACTION\s+", re.I).match(text, pos)
            sfc.actions.append(ast.Action(m.end() if m else pos, name=e.name,
                                          language=language, body=stmts))
    return sfc


def _pou(e, kind, src):
    body = e.body
    sfc = None
    if body is not None and body.sfc is not None:
        language, stmts = "SFC", []
        sfc = _sfc(body.sfc)
    elif body is None or (body.il is None and body.st is None):
        language, stmts = "ST", []
    elif body.il is not None:
        language, stmts = "IL", _il(body.il.instructions)
    else:
        language, stmts = "ST", _body(body.st)
    return ast.POU(_pos(e), kind=kind, name=e.name,
                   result=_spec(e.result) if kind == "FUNCTION" else None,
                   blocks=[_block(b) for b in e.blocks], body=stmts, language=language,
                   src=src, end_pos=e._tx_position_end, sfc=sfc)


def _resource_body(body, name, processor, blocks, pos):
    tasks = [ast.Task(_pos(t), name=t.name,
                      props={p.key.upper(): (p.value, _pos(p)) for p in t.props})
             for t in body.tasks]
    programs = []
    text = _ctx.src.text
    for p in body.programs:
        task_pos = type_pos = _pos(p)
        if p.task:
            m = re.compile(r"\bWITH\s+", re.I).search(text, _pos(p))
            task_pos = m.end() if m else _pos(p)
        m = re.compile(r":\s*", re.I).search(text, task_pos)
        type_pos = m.end() if m else _pos(p)
        conns = [ast.Connection(_pos(c), name=c.name, direction="in" if c.input else "out",
                                value=c.value if c.input else c.target)
                 for c in p.connections]
        programs.append(ast.ProgramConfig(_pos(p), name=p.name,
                                          retain=p.retain.upper() if p.retain else None,
                                          task=p.task or None, task_pos=task_pos,
                                          type=p.type, type_pos=type_pos, connections=conns))
    return ast.Resource(pos, name=name, processor=processor, blocks=blocks, tasks=tasks,
                        programs=programs)


def _configuration(e, src):
    if e.single is not None:
        resources = [_resource_body(e.single, None, None, [], _pos(e.single))]
    else:
        resources = [_resource_body(r.body, r.name, r.processor, [_block(b) for b in r.blocks],
                                    _pos(r))
                     for r in e.resources]
    blocks = [_block(b) for b in e.blocks]
    access = [_block(b) for b in e.access]
    return ast.Configuration(_pos(e), name=e.name, blocks=blocks, resources=resources,
                             access=access, src=src)


def to_ast(model, src: SourceFile, diags: Diagnostics) -> ast.SourceUnit:
    unit = ast.SourceUnit(0, src=src, types=[], pous=[], configurations=[])
    _ctx.src = src
    _ctx.diags = diags
    try:
        for e in model.elements:
            c = _cls(e)
            if c == "DataTypeDecl":
                unit.types += [ast.TypeDef(_pos(t), name=t.name, spec=_spec(t.spec),
                                           init=_init(t.init), src=src) for t in e.types]
            elif c == "FunctionDecl":
                unit.pous.append(_pou(e, "FUNCTION", src))
            elif c == "FunctionBlockDecl":
                unit.pous.append(_pou(e, "FUNCTION_BLOCK", src))
            elif c == "ProgramDecl":
                unit.pous.append(_pou(e, "PROGRAM", src))
            else:
                unit.configurations.append(_configuration(e, src))
    finally:
        _ctx.src = None
    return unit
