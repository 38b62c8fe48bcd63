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
none where the parent itself is computed exactly on literals."""

from __future__ import annotations

from .. import ast
from . import stdlib
from .types import BOOL, LiteralT, common, concrete

COMPARE = ("=", "<>", "<", ">", "<=", ">=")


def settle(e, want=None) -> None:
    """Sets ``sig`` on the standard calls of checked expression *e*, whose
    context computes it in type *want* (None: no context)."""
    if isinstance(e, ast.BinOp):
        if e.fn is not None:
            _settle_call(e, e.fn, [e.left, e.right], want)
            return
        if e.op in COMPARE:
            c = common(e.left.type, e.right.type)
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
                    settle(i)


def _settle_call(e, fn, args, want) -> None:
    ctx = e.type if e.type is not None and not isinstance(e.type, LiteralT) else want
    if ctx is not None and isinstance(ctx, LiteralT):
        ctx = None
    res, ptypes = stdlib.call_types(fn, ctx)
    e.sig = (res, ptypes)
    exact = isinstance(res, LiteralT)
    for a, pt in zip(args, ptypes):
        if a is not None:
            settle(a, None if exact else concrete(pt))
