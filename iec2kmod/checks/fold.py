"""The constant folder: the value of an expression made of literals and
operators.

The checker folds every expression it types, bottom-up, and sets
``Expr.const`` on each literal and each operator whose operands have a
value (``node``); ``Declarer.const_value`` folds constant expressions that
name constants and enumeration values (array bounds, CASE labels, INTERVAL,
initial values) by the same rules and sets ``const`` on what it folds; the
interpreter's initial values (interp/model.py) apply the same operators
and then the variable's type.  The back ends read ``const``: none folds by
itself.

The rules are IEC arithmetic on exact values: integer division truncates
toward zero, MOD takes the dividend's sign, ``**`` is computed in floating
point; AND, OR, XOR and NOT are bitwise (logical on BOOL)."""

from __future__ import annotations

import math
import struct

from .. import ast
from .types import Elementary, LiteralT

# literal kinds with a numeric value (a string, an enumeration value: none)
NUMERIC = ("int", "real", "bool", "time", "date", "tod", "dt")
ARITH_OPS = ("+", "-", "*", "/", "MOD", "**")
LOGIC_OPS = ("AND", "OR", "XOR")


def unary(op: str, v):
    """-v, +v or NOT v (logical on BOOL, bitwise, not masked, on an integer)."""
    if op == "-":
        return -v
    if op == "+":
        return v
    if isinstance(v, bool):
        return not v
    return ~v


def binary(op: str, a, b):
    """a op b for an arithmetic or logic operator; raises ZeroDivisionError."""
    if op == "+":
        return a + b
    if op == "-":
        return a - b
    if op == "*":
        return a * b
    if op == "/":
        if isinstance(a, int) and isinstance(b, int):
            q = abs(a) // abs(b)
            return q if (a >= 0) == (b >= 0) else -q
        return a / b
    if op == "MOD":
        r = abs(a) % abs(b)
        return r if a >= 0 else -r
    if op == "**":
        return float(a) ** b
    if op == "AND":
        return a & b
    if op == "OR":
        return a | b
    if op == "XOR":
        return a ^ b
    raise ValueError(f"not a folded operator: {op}")


def literal(e):
    """The value of a numeric literal, else None."""
    if isinstance(e, ast.Lit) and e.kind in NUMERIC:
        return e.value
    return None


def node(e):
    """The value of e from its operands' ``const`` (already folded), or
    None: a literal, -x, +x, NOT x, and x op y for the arithmetic and logic
    operators.  An operation that has no value (a division by zero, an
    overflow, a type the checker refuses) gives None."""
    if isinstance(e, ast.Lit):
        return literal(e)
    try:
        if isinstance(e, ast.UnOp):
            v = e.operand.const
            return None if v is None else unary(e.op, v)
        if isinstance(e, ast.BinOp) and (e.op in ARITH_OPS or e.op in LOGIC_OPS):
            a, b = e.left.const, e.right.const
            if a is None or b is None:
                return None
            v = binary(e.op, a, b)
            return v if isinstance(v, (int, float)) else None
    except (ArithmeticError, TypeError, ValueError):
        return None
    return None


def int_arith(e) -> bool:
    """e is made of integer literals, signs and + - * only: the expressions
    whose value the checker uses for subrange and index bounds and an
    untyped literal's value (a wider rule would change which programs are
    accepted and the type an untyped expression takes)."""
    if isinstance(e, ast.Lit):
        return e.kind == "int"
    if isinstance(e, ast.UnOp):
        return e.op in ("-", "+") and int_arith(e.operand)
    if isinstance(e, ast.BinOp):
        return e.op in ("+", "-", "*") and int_arith(e.left) and int_arith(e.right)
    return False


# ------------------------------------------------------- settled values
# The value of a constant expression as a statement computes it once the
# checker has typed and settled it (checks/settle.py: ``sig`` on every
# operator): an initial value is the value the assignment of the same
# expression to the variable stores (checks/consts.py).  Each operator is
# computed in the types of its sig, as the back ends compute it: integers
# wrap to their type, a REAL is rounded to binary32, TIME * REAL rounds half
# to even; a sig left untyped (a LiteralT) is exact.

_F32 = struct.Struct("<f")


def _f32(x: float) -> float:
    if x != x or x in (math.inf, -math.inf):
        return x
    try:
        return _F32.unpack(_F32.pack(x))[0]
    except OverflowError:
        return math.inf if x > 0 else -math.inf


def convert(v, t):
    """Value *v* as type *t* holds it (an implicit conversion: a literal or
    a widening); None for a type no constant has."""
    base = getattr(t, "base", None)
    if isinstance(t, LiteralT) or t is None:
        return v
    if not isinstance(base, Elementary):
        return None
    if base.cat == "real":
        v = float(v)
        return _f32(v) if base.bits == 32 else v
    if base.cat == "bool":
        return bool(v)
    if isinstance(v, float):
        return None
    v = int(v)
    if base.cat in ("sint", "uint", "bit"):
        bits = base.bits
        v &= (1 << bits) - 1
        return v - (1 << bits) if base.cat == "sint" and v >> (bits - 1) else v
    if base.cat in ("time", "date", "tod", "dt"):
        v &= (1 << 64) - 1
        return v - (1 << 64) if v >> 63 else v
    return None


def settled(e):
    """The value of settled constant expression *e* in its own type (its
    ``type``), or None where it has none (a division by zero, an operator
    this folder does not compute: the caller keeps the exact fold)."""
    try:
        return _settled(e)
    except (ArithmeticError, TypeError, ValueError):
        return None


def _settled(e):
    if isinstance(e, ast.Lit):
        v = literal(e)
        if v is None:
            return None
        return v if isinstance(e.type, LiteralT) or e.type is None else convert(v, e.type)
    if isinstance(e, ast.UnOp):
        v = _settled(e.operand)
        if v is None:
            return None
        t = e.type
        if e.op == "NOT" and not isinstance(v, bool):
            v = convert(v, t)       # its bits in the result's bit string
        r = unary(e.op, v)
        return r if isinstance(t, LiteralT) else convert(r, t)
    if not isinstance(e, ast.BinOp):
        return None
    a, b = _settled(e.left), _settled(e.right)
    if a is None or b is None:
        return None
    if e.op in LOGIC_OPS:
        return convert(binary(e.op, convert(a, e.type), convert(b, e.type)), e.type)
    sig = getattr(e, "sig", None)
    fn = getattr(e, "fn", None)
    if sig is None or fn is None:
        return None
    res, (pa, pb) = sig[0], sig[1]
    a, b = convert(a, pa), convert(b, pb)
    fam = fn.family
    if fam in ("MUL_TIME", "DIV_TIME"):
        if isinstance(b, float):
            q = a * b if fam == "MUL_TIME" else a / b
            v = round(q)        # half to even, as the back ends
            return max(-(1 << 63), min((1 << 63) - 1, v))
        return convert(binary("*" if fam == "MUL_TIME" else "/", a, b), res)
    if fam in ("ADD_TIME", "SUB_TIME"):
        return convert(binary(e.op, a, b), res)
    if fam not in ("ADD", "SUB", "MUL", "DIV", "MOD", "EXPT"):
        return None
    if isinstance(res, LiteralT):
        return binary(e.op, a, b)
    base = res.base
    if base.cat == "real":
        if e.op == "**":
            v = math.pow(float(a), float(b))
        else:
            v = binary(e.op, float(a), float(b))
        return convert(v, res)
    return convert(binary(e.op, a, b), res)
