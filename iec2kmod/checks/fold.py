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

from .. import ast

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
