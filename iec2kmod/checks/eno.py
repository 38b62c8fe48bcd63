"""The implicit ENO output of user and standard function blocks (ed.2
2.5.1.2, ed.3 6.6.1.5) as the checker declares it: when a body uses ENO
without declaring it (declare.declare_eno) and when a caller reads an
instance's ENO (``f.ENO``: checks/expr.py, checks/config.py, access paths
in checks/declare.py).  A module of its own so that declare.py and expr.py,
which both need it, do not import each other."""

from __future__ import annotations

from .. import ast
from . import stdlib
from .symbols import POUInfo, Var
from .types import BOOL, FBType


def _true(pos):
    lit = ast.Lit(pos, "TRUE", "bool", True)
    lit.type = BOOL
    return lit


def implicit_eno(pou: POUInfo):
    """The ENO output (BOOL, initially TRUE) of the user function or
    function block pou, declared when its body uses ENO without declaring
    it (declare_eno) or when a caller reads an instance's ENO (``f.ENO``,
    checks/expr.py): then the instance keeps the ENO of its last call --
    TRUE when it starts, what the body set, FALSE after a call with EN =
    FALSE -- as MatIEC's instances do.  A block whose ENO nothing reads
    gets no member (its layout, and the interface hash, stay as they
    were).  Returns the (existing or new) variable."""
    v = pou.vars.get("ENO")
    if v is None:
        v = _eno_var(pou)
    if v not in pou.outputs:
        pou.outputs.append(v)
    return v


def fb_eno(t: FBType):
    """The ENO of instances of the function block type t, read from
    outside (``f.ENO``): of a user block, implicit_eno; of a standard
    block, t (the project's one FBType of that block) becomes the copy
    that keeps it (stdlib.keeping_eno)."""
    if not t.pou.standard:
        return implicit_eno(t.pou)
    if t.pou.var("ENO") is None:
        t.pou = stdlib.keeping_eno(t.pou)
    return t.pou.var("ENO")


def _eno_var(pou):
    node = pou.node
    v = Var("ENO", BOOL, "VAR_OUTPUT", node.pos, node.src, owner=pou)
    v.init = _true(node.pos)
    pou.vars["ENO"] = v
    return v
