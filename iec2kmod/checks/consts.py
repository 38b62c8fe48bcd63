"""Pass 'declare', constants: the value of a constant expression and the
check of an initial value against its type.

A constant expression (literals, enumeration values, named constants,
arithmetic, folded by checks/fold.py's rules) sizes arrays and strings,
bounds subranges, numbers enumerations and gives CASE labels and FOR steps
their value; a named constant is looked up in the scope of the POU or the
configuration being checked (``ConstScope``).  An initial value is such an
expression (folded to a literal when it names a constant) or an array or
structure initializer, checked against the declared type; its value is the
one the assignment of the same expression to the variable stores
(``assigned``, checks/settle.py's rules: ``r : LREAL := 7 / 2`` is 3.5), a
program input's constant connection's too (checks/config.py).

``Constants`` is mixed into checks.declare.Declarer, whose ``error``,
``warning``, ``lookup_type`` and ``enum_values`` it uses; its own state is
the scope of the constants in view."""

from __future__ import annotations

import copy
from contextlib import contextmanager

from .. import ast
from . import fold
from .expr import _literal_bits
from .types import (ELEMENTARY, ERROR, ArrayT, Elementary, EnumT, ErrorT, FBType, LiteralT,
                    StringT, StructT, SubrangeT, assignable, not_bit_value)


class ConstError(Exception):
    pass


class ConstScope:
    """Names visible to a constant expression (Constants.scope_of) and the
    constants it used (so they count as used)."""

    __slots__ = ("entries", "outer", "used")

    def __init__(self, entries, outer):
        self.entries = entries
        self.outer = outer
        self.used: set = set()


class Constants:
    def __init__(self):
        # named constants: the scope a constant expression is evaluated in
        self._const_scope = ConstScope({}, None)
        self._config_scope = ConstScope({}, None)
        self._pou_scopes: dict[str, ConstScope] = {}
        self._const_busy: set = set()
        self._resource_constants: set = set()

    # ------------------------------------------------------- constants
    def const_value(self, expr, src, what="value"):
        """Evaluates a constant expression (literals, enum values, named
        constants, arithmetic) by the folder's rules (checks/fold.py) and
        sets ``const`` on the literals and operators it folds; raises
        ConstError with a message."""
        v = self._const_value(expr, src, what)
        if expr.const is None and isinstance(v, (int, float)) and (
                isinstance(expr, (ast.UnOp, ast.BinOp)) or fold.literal(expr) is not None):
            expr.const = v
        return v

    def _const_value(self, expr, src, what):
        if isinstance(expr, ast.Lit):
            if expr.kind in fold.NUMERIC:
                return fold.literal(expr)
            if expr.kind == "enum":
                t = self.lookup_type(expr.type_name, src, expr.pos, report=False)
                if isinstance(t, EnumT) and t.has(expr.value):
                    return t.values[expr.value.upper()][1]
                raise ConstError(f"unknown enumeration value {expr.text}")
            return expr.value
        if isinstance(expr, ast.UnOp):
            v = self.const_value(expr.operand, src, what)
            if expr.op == "NOT":
                _bit_operand("operator NOT", v)
            return fold.unary(expr.op, v)
        if isinstance(expr, ast.BinOp):
            a = self.const_value(expr.left, src, what)
            b = self.const_value(expr.right, src, what)
            if expr.op in fold.ARITH_OPS:
                try:
                    return fold.binary(expr.op, a, b)
                except ZeroDivisionError:
                    raise ConstError("division by zero in a constant expression") from None
            if expr.op in fold.LOGIC_OPS:
                if isinstance(a, bool) != isinstance(b, bool):
                    raise ConstError(f"operator {expr.op} in a constant expression needs two "
                                     "BOOL or two bit-string values")
                _bit_operand(f"operator {expr.op}", a)
                _bit_operand(f"operator {expr.op}", b)
                return fold.binary(expr.op, a, b)
        if isinstance(expr, ast.Ref) and not expr.accessors:
            key = expr.name.upper()
            found = self._const_scope.entries.get(key)
            if found is not None and found[0] != "var":
                return self.named_constant(key, found, what)
            hits = self.enum_values.get(key, [])
            if len(hits) == 1:
                return hits[0].values[key][1]
            if found is not None:
                raise ConstError(f"{what} must be a constant expression: '{expr.name}' is a "
                                 "variable (a named constant is declared VAR CONSTANT, or "
                                 "VAR_EXTERNAL CONSTANT for the configuration's VAR_GLOBAL "
                                 "CONSTANT, with an initial value)")
        raise ConstError(f"{what} must be a constant expression")

    # ------------------------------------------------- named constants
    # A constant expression may name a constant (ed.3 7.3.2, 6.4.4: array
    # bounds, string lengths, subranges, CASE labels): a VAR CONSTANT of the
    # same POU (or VAR_GLOBAL CONSTANT of the configuration or resource)
    # with a constant initial value, in any order of declaration, or a
    # VAR_EXTERNAL CONSTANT, whose value is the configuration's VAR_GLOBAL
    # CONSTANT of that name: a POU type has one layout for all its
    # instances, so a resource's global cannot give it.
    def named_constant(self, key, found, what):
        kind, init, src, name = found
        scope = self._const_scope
        if kind == "external":
            scope.used.add(key)
            g = self._config_scope.entries.get(key)
            if g is None or g[0] != "const":
                why = ("; a resource's constant of that name cannot give it (a POU type has "
                       "one layout for all its instances)" if key in self._resource_constants
                       else ", which this project does not declare")
                raise ConstError(f"{what}: VAR_EXTERNAL CONSTANT '{name}' takes its value from "
                                 f"the configuration's VAR_GLOBAL CONSTANT {name}{why}")
            _, init, src, name = g
            scope = self._config_scope
        mark = (id(scope), key)
        if mark in self._const_busy:
            raise ConstError(f"constant '{name}' is defined in terms of itself")
        self._const_busy.add(mark)
        saved = self._const_scope
        self._const_scope = scope
        try:
            value = self.const_value(init, src, what)
        finally:
            self._const_scope = saved
            self._const_busy.discard(mark)
        scope.used.add(key)
        return value

    @staticmethod
    def scope_of(blocks, src, outer=None) -> "ConstScope":
        """The names a list of VAR blocks declares, as a ConstScope over
        *outer*'s: 'const' (a CONSTANT with an initial value), 'external'
        (VAR_EXTERNAL CONSTANT) or 'var' (any other variable)."""
        entries = dict(outer.entries) if outer is not None else {}
        for block in blocks:
            if block.kind in ("VAR_ACCESS", "VAR_CONFIG"):
                continue
            constant = "CONSTANT" in block.qualifiers
            for decl in block.decls:
                if constant and block.kind == "VAR_EXTERNAL":
                    kind = "external"
                elif constant and decl.init is not None and \
                        block.kind in ("VAR", "VAR_GLOBAL") and not decl.location:
                    kind = "const"
                else:
                    kind = "var"
                for name, _ in decl.names:
                    entries[name.upper()] = (kind, decl.init, src, name)
        return ConstScope(entries, outer)

    def pou_scope(self, pou) -> "ConstScope":
        scope = self._pou_scopes.get(pou.key)
        if scope is None:
            scope = self.scope_of(pou.node.blocks, pou.node.src)
            self._pou_scopes[pou.key] = scope
        return scope

    @contextmanager
    def constants_of(self, scope):
        """Constant expressions inside name *scope*'s constants."""
        saved = self._const_scope
        self._const_scope = scope
        try:
            yield scope
        finally:
            self._const_scope = saved

    def collect_config_constants(self, units):
        """The configuration's VAR_GLOBAL CONSTANTs, before the POUs are
        declared: their VAR_EXTERNAL CONSTANTs may size arrays."""
        configs = [c for u in units for c in u.configurations]
        if configs:
            self._config_node = configs[0]
            self._config_scope = self.config_scope(configs[0])
            self._resource_constants = {
                key for r in configs[0].resources
                for key, found in self.scope_of(r.blocks, configs[0].src).entries.items()
                if found[0] == "const"}

    def config_scope(self, node) -> "ConstScope":
        """The constants a configuration's own declarations see."""
        if node is getattr(self, "_config_node", None) and self._config_scope.entries:
            return self._config_scope
        return self.scope_of([b for b in node.blocks if b.kind == "VAR_GLOBAL"], node.src)

    @staticmethod
    def mark_used(scope, table):
        for key in scope.used:
            v = table.get(key)
            if v is not None:
                v.used = True

    def const_int(self, expr, src, what):
        try:
            v = self.const_value(expr, src, what)
        except ConstError as exc:
            self.error(src, expr.pos, str(exc))
            return None
        if isinstance(v, bool) or not isinstance(v, int):
            self.error(src, expr.pos, f"{what} must be an integer constant")
            return None
        return v

    # ---------------------------------------------------- initializers
    def check_initializer(self, init, t, src):
        """Checks an initial value for type *t*; returns it, an expression
        that names constants folded to the literal of its value (the code
        generators and the interpreter initialise from literals)."""
        if isinstance(init, ast.ArrayInit):
            if not isinstance(t, ArrayT):
                self.error(src, init.pos, f"an array initializer cannot initialize {t.name}")
                return init
            n = 0
            for i, (count, value) in enumerate(init.items):
                k = count if count is not None else 1
                if count is not None and count < 1:
                    self.error(src, init.pos, "repetition count must be at least 1")
                n += k
                if value is not None:
                    init.items[i] = (count, self.check_initializer(value, t.elem, src))
            if n > t.count:
                self.error(src, init.pos, f"{n} initial values for an array of {t.count} elements")
            return init
        if isinstance(init, ast.StructInit):
            if not isinstance(t, StructT):
                if isinstance(t, FBType):
                    pou = t.pou
                    for i, (fname, fval, fpos) in enumerate(init.fields):
                        v = pou.var(fname)
                        if v is None or v.section not in ("VAR_INPUT", "VAR_OUTPUT", "VAR"):
                            self.error(src, fpos, f"'{t.name}' has no member '{fname}'")
                        else:
                            init.fields[i] = (fname, self.check_initializer(fval, v.type, src),
                                              fpos)
                    return init
                self.error(src, init.pos, f"a structure initializer cannot initialize {t.name}")
                return init
            for i, (fname, fval, fpos) in enumerate(init.fields):
                f = t.fields.get(fname.upper())
                if f is None:
                    self.error(src, fpos, f"structure '{t.name}' has no member '{fname}'")
                    continue
                init.fields[i] = (fname, self.check_initializer(fval, f[1], src), fpos)
            return init
        # an expression: a constant of an assignable type
        typed = self.assigned(init, t, src)
        try:
            v = self.const_value(init, src, "initial value")
        except ConstError as exc:
            if isinstance(init, ast.Ref) and isinstance(t, EnumT) and t.has(init.name) \
                    and not init.accessors:
                return init
            if isinstance(init, ast.Lit) and init.kind in ("string", "wstring"):
                v = init.value
            elif typed is not None and not isinstance(typed[1], LiteralT):
                v = None        # NOT 16#0F AND 16#3C into a BYTE: only its bits are a value
            else:
                self.error(src, init.pos, str(exc))
                return init
        if typed is not None and not isinstance(typed[1], LiteralT) and (
                not same_value(typed[0], v, t) or t.base.cat in ("time", "date", "tod", "dt")):
            # a typed expression (T#1s * 2, REAL#1.0 / 3.0): its value in its
            # type, stored as the assignment stores it
            v = typed[0]
            init = self.folded(v, init, t) or init
            self.check_const_fits(v, init, t, src)
            return init
        bitwise = _bitwise_op(init)
        if bitwise is not None and not isinstance(v, bool):
            base = getattr(t, "base", None)
            if not isinstance(base, Elementary) or base.cat != "bit":
                self.error(src, init.pos, f"cannot initialize {t.name} with a bit-string "
                                          f"expression ({bitwise}), which initializes a bit string "
                                          "(BYTE, WORD, DWORD, LWORD) or a BOOL")
                return init
            v &= base.range[1]            # NOT of a bit string: its bits, not a negative
            init.const = v
        if self.names_constant(init):
            folded = self.folded(v, init, t)
            if folded is None:
                self.error(src, init.pos, "initial value: a named constant of this kind "
                                          f"cannot initialize {t.name}")
                return init
            init = folded
        before = len(self.diags.errors)
        self.check_const_fits(v, init, t, src)
        if typed is not None and not same_value(typed[0], v, t) and \
                len(self.diags.errors) == before:
            # untyped literals (7 / 2 into an LREAL: 3.5, not 3): the exact
            # value fits, the variable holds the assignment's
            init = self.folded(typed[0], init, t) or init
        return init

    def assigned(self, init, t, src):
        """(value, type) of initial value *init* of a variable of type *t*
        as the assignment of the same expression stores it (*init* itself
        untouched: check_initializer replaces it by the literal of that
        value where it differs from the exact fold): typed by the
        statement checker, an untyped one with *t* as its context, settled
        (checks/settle.py) and folded in its types (fold.settled); None for
        a single literal, an expression that names a constant or an
        enumeration value (folded exactly: its value does not depend on a
        context) or one the checker refuses (the errors are this class's)."""
        if not isinstance(init, (ast.UnOp, ast.BinOp)) or not _literals_only(init) or \
                not isinstance(t.base, Elementary):
            return None
        from ..diagnostics import Diagnostics
        from .body import BodyChecker
        from .settle import overflows, settle
        from .symbols import POUInfo
        silent = Diagnostics()
        checker = BodyChecker(self.p, self, silent, POUInfo("PROGRAM", "<initial value>", src=src))
        init = copy.deepcopy(init)      # typed aside: the declaration keeps its own
        vt = checker.expr(init)
        if silent.errors or isinstance(vt, ErrorT):
            return None
        checker.check_assign(vt, t, init, None)     # the statement's rule, its typing
        if silent.errors:
            return None
        vt = init.type if _literal_bits(init) else vt
        settle(init)
        wraps = overflows(init)
        for pos, msg in wraps:      # k : SINT := (100 + 100) / 2: 100 + 100 in SINT
            self.error(src, pos, msg)
        if wraps:
            return None
        v = fold.settled(init)
        if v is None:
            return None
        v = fold.convert(v, t)
        return (v, vt) if v is not None else None

    def names_constant(self, expr) -> bool:
        """Whether a constant expression names a constant of the scope."""
        if isinstance(expr, ast.Ref):
            found = self._const_scope.entries.get(expr.name.upper())
            return not expr.accessors and found is not None and found[0] != "var"
        if isinstance(expr, ast.UnOp):
            return self.names_constant(expr.operand)
        if isinstance(expr, ast.BinOp):
            return self.names_constant(expr.left) or self.names_constant(expr.right)
        return False

    @staticmethod
    def folded(v, expr, t):
        """The literal of value *v* of a constant expression for type *t*
        (None for a value no literal kind carries: a string, an enum)."""
        cat = getattr(getattr(t, "base", None), "cat", None)
        if isinstance(v, bool):
            return ast.Lit(expr.pos, "TRUE" if v else "FALSE", "bool", v)
        if isinstance(v, int):
            if cat in ("time", "date", "tod", "dt"):
                return ast.Lit(expr.pos, str(v), cat, v)
            if isinstance(t, EnumT):
                return None
            return ast.Lit(expr.pos, str(v), "int", v)
        if isinstance(v, float):
            return ast.Lit(expr.pos, repr(v), "real", v)
        return None

    def check_const_fits(self, v, expr, t, src):
        if t is ERROR:
            return
        base = t.base
        lit_kind = getattr(expr, "kind", None) if isinstance(expr, ast.Lit) else None
        if isinstance(t, EnumT):
            if isinstance(expr, ast.Lit) and expr.kind == "enum":
                et = self.lookup_type(expr.type_name, src, expr.pos, report=False)
                if et is not t:
                    self.error(src, expr.pos, f"{expr.text} is not a value of {t.name}")
                return
            if isinstance(expr, ast.Ref) and t.has(expr.name):
                return
            self.error(src, expr.pos, "initial value of an enumeration must be one of its values")
            return
        if isinstance(base, StringT):
            if lit_kind not in ("string", "wstring"):
                self.error(src, expr.pos, f"cannot initialize {t.name} with a non-string value")
            elif (lit_kind == "wstring") != base.wide:
                self.error(src, expr.pos, f"cannot initialize {t.name} with a "
                                          f"{'WSTRING' if lit_kind == 'wstring' else 'STRING'}")
            elif len(v) > base.length:
                self.warning(src, expr.pos, f"initial string of {len(v)} characters is "
                                            f"truncated to {base.length}")
            return
        if not isinstance(base, Elementary):
            self.error(src, expr.pos, f"cannot initialize {t.name} with a single value")
            return
        if isinstance(expr, ast.Lit) and expr.type_name and expr.kind in ("int", "real", "bool"):
            lt = ELEMENTARY.get(expr.type_name.upper())
            if lt is not None and not assignable(lt, base):
                self.error(src, expr.pos, f"cannot initialize {t.name} with {lt.name}")
                return
        if isinstance(v, bool):
            if base.cat not in ("bool", "bit"):
                self.error(src, expr.pos, f"cannot initialize {t.name} with a BOOL")
            return
        if isinstance(v, float):
            if base.cat != "real":
                self.error(src, expr.pos, f"cannot initialize {t.name} with a REAL value")
            return
        if lit_kind in ("time", "date", "tod", "dt"):
            if base.cat != lit_kind:
                self.error(src, expr.pos, f"cannot initialize {t.name} with a {lit_kind.upper()} "
                                          "literal")
            return
        if base.cat in ("time", "date", "tod", "dt"):
            self.error(src, expr.pos, f"cannot initialize {t.name} with an integer")
            return
        if base.cat != "real":
            lo, hi = base.range
            if base.cat == "bool" and v not in (0, 1):
                self.error(src, expr.pos, f"{v} is not a BOOL value")
            elif not lo <= v <= hi:
                self.error(src, expr.pos, f"initial value {v} is out of range for {base.name}")
                return
        if isinstance(t, SubrangeT) and not t.low <= v <= t.high:
            self.error(src, expr.pos, f"initial value {v} is outside the subrange "
                                      f"{t.low}..{t.high}")


def _bit_operand(what, v):
    """A value AND, OR, XOR or NOT takes in a constant expression: a BOOL or
    a bit string's (0 .. 16#FFFF_FFFF_FFFF_FFFF), as in a statement."""
    why = not_bit_value(what, [v])
    if why is not None:
        raise ConstError(why)


def same_value(typed, v, t):
    """Whether the exact fold *v* stored into *t* is the assignment's value
    *typed* (-2.9 into a REAL: its binary32 value either way): the
    declaration then keeps its expression, and the generated code its text."""
    if v is None:
        return False
    try:
        return fold.convert(v, t) == typed
    except (ArithmeticError, TypeError, ValueError):
        return False


def _literals_only(e):
    """Constant expression *e* is made of literals and operators only."""
    if isinstance(e, ast.Lit):
        return e.kind in fold.NUMERIC
    if isinstance(e, ast.UnOp):
        return _literals_only(e.operand)
    if isinstance(e, ast.BinOp):
        return _literals_only(e.left) and _literals_only(e.right)
    return False


def _bitwise_op(e):
    """The first AND, OR, XOR or NOT in constant expression *e*, or None."""
    if isinstance(e, ast.UnOp):
        return "NOT" if e.op == "NOT" else _bitwise_op(e.operand)
    if isinstance(e, ast.BinOp):
        if e.op in fold.LOGIC_OPS:
            return e.op
        return _bitwise_op(e.left) or _bitwise_op(e.right)
    return None
