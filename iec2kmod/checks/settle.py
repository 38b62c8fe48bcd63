"""The last step of typing an expression: the types its standard calls are
computed in.

The checker types expressions bottom-up; an untyped expression (``1 + 2``,
``ABS(-3)``, ``TRUNC(1.0E10) + 1``: its type a LiteralT) takes the type of
its context, which is only known once the whole expression and the
statement around it are checked (``check_assign`` gives the value of an
assignment its target's type).  ``settle`` walks a checked expression from
its root down and sets, on every arithmetic operator (``BinOp.fn``) and
standard function call, ``sig``: (result type, [parameter types]) by
``stdlib.call_types`` for the context the call sits in.  The back ends
(interp, verify, codegen) read ``sig``; none works a call's type out again.

The context of an operand is the type its parent computes it in: the
parameter type (the parent's result for an untyped operand of an
arithmetic, ABS, MAX, ... call; the operands' common type for a comparison);
none where the parent itself is computed exactly on literals.

The rules for untyped expressions (IEC 61131-3 ed.3: an untyped literal
takes the type its context requires; where none does, the checker's
default), each decided once in checks/ and read by every engine:

  * with a context, a call on untyped literals is computed in the
    context's type (``l := 2147483647 + 1`` into a LINT: 2147483648);
    MUX's inputs in its result's type, K in its own (stdlib.call_types);
  * without one (a comparison of two untyped expressions, an index, a CASE
    selector), ADD, SUB, MUL, DIV, MOD and EXPT are computed exactly on the
    values, any other family in the type that holds its literals' values
    (``own_type``: the narrowest of DINT, LINT, ULINT, LREAL for a real;
    ``MAX(0, 4000000000)`` in LINT); an untyped index or CASE selector is
    used in its own type (``settle_root``); two untyped operands are
    compared in the type that holds both (``3000000000 > 0`` in LINT,
    ``-1 < 16#FFFFFFFFFFFFFFFF`` in LREAL: no integer type holds both), as
    MatIEC compares them (C on the values; LWORD for MAX, LIMIT);
  * a context the family cannot compute in (a bit string, BOOL, MOD into a
    REAL: stdlib.NUMERIC_CONTEXT) is no context: the exact value is
    converted to it as a literal is (``b := 1 + 2`` into a BYTE: 3);
  * each literal argument of a call whose arguments are all untyped keeps
    its own value (``MAX(0, 4000000000)``: 4000000000 is a LINT where the
    call is computed without context: body._literal_arg_type);
  * IL: a current result computed from untyped literals (``LD 2147483647
    ADD 1``) takes the type of the variable it is stored in (``ST x``, x a
    LINT: 2147483648), as the ST assignment ``x := 2147483647 + 1`` and
    MatIEC's IL do, where the ST instructions that read it store into one
    integer or real type (a comparison with a literal after them compares
    in it); read by anything else it keeps the literal's own type
    (il._type_literal_chains);
  * AND, OR, XOR and NOT (IL's too, LDN, STN) on untyped integer literals
    are computed in a bit string, DWORD, LWORD beyond 32 bits
    (types.concrete_bits), as SHL on a literal is: the integer default DINT
    has no bitwise operations; stored into a bit string, they and SHL, SHR,
    ROL, ROR on an untyped literal are computed in it (``l := SHL(1, 40)``
    into an LWORD: 2**40; ``b := NOT 0`` into a BYTE: 255), as MatIEC
    computes them, and a literal the bit string cannot hold is refused
    (expr.check_assign);
  * ABS of an untyped literal is the literal of its absolute value (ABS(-5)
    into a BYTE: 5, computed exactly as 1 + 2 into a BYTE is);
  * an initial value is the value the assignment of the same expression to
    the variable stores: checks/consts.py types a copy of it as that
    statement (the variable's type its context), settles it here and folds
    it in its types (fold.settled); where that differs from the exact fold
    of its literals (``r : LREAL := 7 / 2``: 3.5; ``t : TIME := T#1s * 2``)
    the declaration holds the literal of the value, which every back end
    initialises from; a program input's constant connection (``PROGRAM p
    WITH t : P (r := 7 / 2)``) likewise.  An initial value that names a constant is folded
    exactly; a call in an initial value is refused (a constant expression
    has none; MatIEC refuses any expression there);
  * a computation made of untyped constants only never wraps silently: an
    ADD, SUB, MUL, DIV, MOD or EXPT (operator or call) whose operands are
    untyped and all have a value (``const``: literals and operators on
    them; the folder does not see a named constant in a statement) and
    which its context computes in an integer or bit-string type that
    cannot hold its exact result, or one of its operands, is refused
    (``overflows``): ``s := (100 + 100) / 2`` into
    a SINT would add in SINT (200 wraps to -56: -28 where MatIEC and
    CODESYS give 100), ``200 / 2`` would divide -56; in a statement, an
    initial value, a constant connection and an IL chain typed by its
    store alike (il._chain_overflow).  The exact result is IEC's (integer
    division truncates: no error); a REAL's rounding is no error; an
    expression with a variable is run-time arithmetic and wraps, and so
    does one with a typed literal operand (``SINT#-127 * SINT#19``,
    ``DINT#2147483647 + 8``: computed in the type its author wrote, as
    on variables of that type).  SHL,
    SHR, ROL, ROR and NOT on literals are not checked: shifting drops the
    bits it shifts out by definition (``SHL(1, 40)`` into a DWORD is 0) and
    NOT sets the bits the bit string has (``NOT 0`` into a BYTE: 255); AND,
    OR and XOR cannot leave their operands' bits."""

from __future__ import annotations

from .. import ast
from . import fold, stdlib
from .types import BOOL, ELEMENTARY, LREAL, AnyIntResult, Elementary, LiteralT, common, concrete

COMPARE = ("=", "<>", "<", ">", "<=", ">=")
# the integer types an untyped value is computed in where no context decides,
# the narrowest that holds it first
_OWN_INTS = [ELEMENTARY[n] for n in ("DINT", "LINT", "ULINT")]
# the standard functions whose result is one of their (untyped) arguments'
# values, or made of them: computed in a type that holds them all
VALUE_FAMILIES = ("ABS", "MAX", "MIN", "LIMIT", "SEL", "MUX", "MOVE") + stdlib.LITERAL_FAMILIES


def settle(e, want=None) -> None:
    """Sets ``sig`` on the standard calls of checked expression *e*, whose
    context computes it in type *want* (None: no context)."""
    if isinstance(e, ast.BinOp):
        if e.fn is not None:
            _settle_call(e, e.fn, [e.left, e.right], want)
            return
        if e.op in COMPARE:
            c = common(e.left.type, e.right.type)
            if isinstance(c, LiteralT):     # two untyped operands: a type that holds both
                w = widest([own_type(e.left), own_type(e.right)])
            else:
                w = concrete(c) if c is not None else None
            e.sig = (BOOL, [w, w])      # the operands compared in their common type
        else:                           # AND OR XOR
            w = concrete(e.type) if e.type is not None else None
        settle(e.left, w)
        settle(e.right, w)
    elif isinstance(e, ast.UnOp):
        settle(e.operand, concrete(e.type) if e.type is not None else None)
    elif isinstance(e, ast.Call):
        std = isinstance(e.target, stdlib.StdFunc)
        rest = []
        if std:
            args = [a.value for a in e.args
                    if a.kind == "pos" or (a.name or "").upper() not in ("EN", "ENO")]
            _settle_call(e, e.target, args, want)
            rest = [a.value for a in e.args
                    if a.kind != "pos" and (a.name or "").upper() in ("EN", "ENO")]
        else:       # a user POU's inputs are typed by check_assign; outputs are targets
            rest = [a.value for a in e.args]
        for v in rest:
            if v is not None:
                settle(v)
        if e.ref is not None:
            settle(e.ref)
    elif isinstance(e, ast.Ref):
        for kind, val, _ in e.accessors:
            if kind == "index":
                for i in val:
                    settle_root(i)


def settle_root(e) -> None:
    """Settles an expression no context types (a statement's value, an
    index, a CASE selector): an untyped one takes its own type
    (``own_type``), the type the back ends compute and use it in."""
    if isinstance(e.type, LiteralT):
        e.type = own_type(e)
    settle(e)


def own_type(e):
    """The type an untyped expression is computed in where no context
    decides: the narrowest of DINT, LINT and ULINT that holds its value
    (LREAL for a real), its operands' where the checker has no value (a
    standard call on literals, ``MAX(0, 4000000000)``: LINT); a typed
    expression's own type."""
    t = e.type
    if not isinstance(t, LiteralT):
        return t
    v = e.const
    if isinstance(v, (int, float)) and not isinstance(v, bool):
        return value_type(v)
    args = []
    if isinstance(e, ast.BinOp):
        args = [e.left, e.right]
    elif isinstance(e, ast.UnOp):
        args = [e.operand]
    elif isinstance(e, ast.Call) and isinstance(e.target, stdlib.StdFunc) and \
            e.target.family in VALUE_FAMILIES:
        args = [a.value for a in e.args if a.value is not None and (
            a.kind == "pos" or (a.name or "").upper() not in ("EN", "ENO"))]
        if e.target.family == "MUX":
            args = args[1:]         # K selects, its value is not the result's
    own = [own_type(a) for a in args if isinstance(a.type, LiteralT)]
    if t.cat == "real":
        return LREAL
    return widest(own) if own and not isinstance(t, AnyIntResult) else concrete(t)


def value_type(v):
    """The type an untyped literal value is computed in by itself: LREAL
    for a real, else the narrowest of DINT, LINT, ULINT that holds it (LREAL
    where none does)."""
    if isinstance(v, float):
        return LREAL
    return next((t for t in _OWN_INTS if t.range[0] <= v <= t.range[1]), LREAL)


def widest(types):
    """The type that holds values of all *types* (DINT, LINT, ULINT, LREAL:
    own_type's): LREAL for a real or where no integer type holds them all
    (a negative and a ULINT beyond LINT)."""
    if any(t.cat == "real" for t in types):
        return LREAL
    lo = min(t.range[0] for t in types)
    hi = max(t.range[1] for t in types)
    return next((t for t in _OWN_INTS if t.range[0] <= lo and hi <= t.range[1]), LREAL)


def _settle_call(e, fn, args, want) -> None:
    ctx = e.type if e.type is not None and not isinstance(e.type, LiteralT) else want
    if ctx is not None and isinstance(ctx, LiteralT):
        ctx = None
    if ctx is None and isinstance(fn.result, LiteralT) and fn.family in VALUE_FAMILIES and \
            fn.family not in stdlib.LITERAL_FAMILIES:
        ctx = own_type(e)       # MAX(0, 4000000000) alone: in LINT, which holds its values
    res, ptypes = stdlib.call_types(fn, ctx)
    e.sig = (res, ptypes)
    exact = isinstance(res, LiteralT)
    for a, pt in zip(args, ptypes):
        if a is not None:
            settle(a, None if exact else concrete(pt))


# ------------------------------------------------------- literal overflow
# the arithmetic families whose result on constants can leave the type they
# are settled into, and the operator the folder computes each with
_ARITH = {"ADD": "+", "SUB": "-", "MUL": "*", "DIV": "/", "MOD": "MOD", "EXPT": "**"}
_RANGED = ("sint", "uint", "bit")


def overflows(e) -> list:
    """The constant computations of settled expression *e* that would
    wrap, as (position, error message) pairs.  An ADD, SUB, MUL, DIV, MOD or
    EXPT (operator or call) whose operands are all untyped constants
    (``const``: literals and operators on them) and whose sig, the type its
    context gives it, is an integer or bit string type reports, the
    innermost first and its ancestors not again, an operand constant the
    parameter type cannot hold (``200 / 2`` into a SINT: 200) or an exact
    result its result type cannot hold (``(100 + 100) / 2`` into a SINT:
    100 + 100 is 200); the exact result is IEC's (integer division
    truncates: no error).  *e* itself is reported too: the caller leaves
    out a position check_assign already refused (``s := 100 + 100``: 200 is
    out of range for SINT)."""
    out: list = []
    _overflows(e, out)
    return out


def _overflows(e, out) -> bool:
    """Appends the wraps under and at *e* to *out*; whether it found one."""
    kids = []
    if isinstance(e, ast.BinOp):
        kids = [e.left, e.right]
    elif isinstance(e, ast.UnOp):
        kids = [e.operand]
    elif isinstance(e, ast.Call):
        kids = [a.value for a in e.args if a.value is not None]
    found = False
    for k in kids:
        found = _overflows(k, out) or found
    if found:
        return True
    fn = getattr(e, "fn", None) if isinstance(e, ast.BinOp) else \
        e.target if isinstance(e, ast.Call) else None
    sig = getattr(e, "sig", None)
    if not isinstance(fn, stdlib.StdFunc) or fn.family not in _ARITH or sig is None:
        return False
    if isinstance(e, ast.Call):
        if any(a.kind != "pos" and (a.name or "").upper() in ("EN", "ENO") for a in e.args):
            return False
        args = [a.value for a in e.args]
    else:
        args = [e.left, e.right]
    vals = [getattr(a, "const", None) for a in args]
    if not args or any(not _number(v) for v in vals):
        return False        # a variable among them: run-time arithmetic, it wraps
    res, ptypes = sig
    if isinstance(res, LiteralT):
        return False        # computed exactly
    if not all(isinstance(getattr(a, "type", None), LiteralT) for a in args):
        return False        # SINT#-127 * SINT#19: computed in the type its author wrote
    for a, v, pt in zip(args, vals, ptypes):
        lo_hi = _range(pt)
        if lo_hi is not None and isinstance(v, int) and not lo_hi[0] <= v <= lo_hi[1]:
            out.append((a.pos, f"{text(a)} is out of range for {pt.name}, the type {text(e)} is "
                               "computed in (the type of its context); write the value or "
                               "convert explicitly"))
            return True
    lo_hi = _range(res)
    if lo_hi is None:
        return False
    v = vals[0]
    try:
        for w in vals[1:]:
            v = fold.binary(_ARITH[fn.family], v, w)
    except (ArithmeticError, ValueError):
        return False        # a division by zero: the checker's own error
    if isinstance(v, float):      # EXPT into an integer type
        if lo_hi[0] <= v <= lo_hi[1]:
            return False
        shown = repr(v)
    elif lo_hi[0] <= v <= lo_hi[1]:
        return False
    else:
        shown = str(v)
    out.append((e.pos, f"{text(e)} is {shown}, out of range for {res.name} (the type of its "
                       "context); write the value or convert explicitly"))
    return True


def _number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _range(t):
    base = getattr(t, "base", t)
    if isinstance(base, Elementary) and base.cat in _RANGED and base.range is not None:
        return base.range
    return None


def text(e) -> str:
    """Expression *e* written back as source (for a message)."""
    if isinstance(e, ast.Lit):
        return f"{e.type_name}#{e.text}" if e.type_name and "#" not in e.text else e.text
    if isinstance(e, ast.UnOp):
        sep = " " if e.op.isalpha() else ""
        return f"{e.op}{sep}{_paren(e.operand)}"
    if isinstance(e, ast.BinOp):
        return f"{_paren(e.left)} {e.op} {_paren(e.right)}"
    if isinstance(e, ast.Call):
        args = ", ".join(text(a.value) if a.kind == "pos" else
                         f"{a.name} {'=>' if a.kind == 'out' else ':='} {text(a.value)}"
                         for a in e.args if a.value is not None)
        return f"{e.name}({args})"
    if isinstance(e, ast.Ref):
        return e.name
    return "this expression"


def _paren(e) -> str:
    return f"({text(e)})" if isinstance(e, ast.BinOp) else text(e)
