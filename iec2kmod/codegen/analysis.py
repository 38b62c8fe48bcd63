"""Small facts about ST statement lists that let the emitter leave out
checks it can prove unnecessary (FOR loops with constant bounds)."""

from __future__ import annotations

from .. import ast
from ..checks import stdlib

# attributes that point out of the tree (types, symbols, resolved targets)
_SKIP = {"pos", "type", "const", "symbol", "target", "bound", "src", "values", "var_pos",
         "cr_in", "cr_out", "label_pos"}


def _slots(obj):
    for cls in type(obj).__mro__:
        for name in getattr(cls, "__slots__", ()):
            if name not in _SKIP:
                yield name


def walk(node):
    """Every expression, argument and statement under node (lists too)."""
    stack = [node]
    while stack:
        n = stack.pop()
        if isinstance(n, (list, tuple)):
            stack.extend(n)
            continue
        if not isinstance(n, (ast.Expr, ast.Node, ast.Arg)):
            continue
        yield n
        for name in _slots(n):
            v = getattr(n, name, None)
            if isinstance(v, (list, tuple, ast.Expr, ast.Node, ast.Arg)):
                stack.append(v)


def has_loop(stmts) -> bool:
    return any(isinstance(n, (ast.For, ast.While, ast.Repeat)) for n in walk(stmts))


def has_return(stmts) -> bool:
    return any(isinstance(n, ast.Return) for n in walk(stmts))


def modifies(stmts, var) -> bool:
    """May the statements change variable ``var`` (a checks.symbols.Var)?
    Assignments to it (or to a part of it), a FOR over it, and passing it
    to a call as an output or VAR_IN_OUT count; so does anything unknown."""
    key = var.name.upper()
    for n in walk(stmts):
        if isinstance(n, ast.Assign) and getattr(n.target, "symbol", None) is var:
            return True
        if isinstance(n, ast.For) and n.var.upper() == key:
            return True
        if isinstance(n, ast.Call):
            target = n.target
            for a in n.args:
                v = a.value
                if not (isinstance(v, ast.Ref) and v.symbol is var):
                    continue
                if a.kind == "out":
                    return True
                if isinstance(target, stdlib.StdFunc):
                    continue
                bound = n.bound or {}
                param = next((k for k, b in bound.items() if b is a), None)
                pou = getattr(getattr(target, "type", None), "pou", None) or target
                p = pou.var(param) if param and hasattr(pou, "var") else None
                if p is None or p.section != "VAR_INPUT":
                    return True
    return False
