"""Directly represented variables in a PROGRAM (ed.2 B.1.4: ``variable ::=
direct_variable | symbolic_variable``; ``located_var_decl ::=
[variable_name] location ':' ...``).

iec2kmod reaches an address through the one variable located there (the
process image of iec2kmod.located), so before the checks each PROGRAM's
direct variables become such variables:

* an unnamed located declaration (``AT %IX1.1 : BOOL;``) gets the name of
  its address (``IX1_1__``: two underscores, which no IEC identifier may
  hold, so it cannot meet a user's name);
* ``%QX0.0`` in the body is the program's variable located at that address
  when it declares one, else a variable of the program that the use
  declares, typed by the address's size (X or none: BOOL, B: BYTE, W: WORD,
  D: DWORD, L: LWORD).

Either is then a located variable of the program like a named one: the
rule that one address is accessed by exactly one variable across the
configuration applies (two instances of the program, or two programs using
one address, are an error naming both).  FUNCTIONs and FUNCTION_BLOCKs keep
the refusal of the body checker: they have no process image of their own.
"""

from __future__ import annotations

from .. import ast

_SIZE_TYPE = {"X": "BOOL", "B": "BYTE", "W": "WORD", "D": "DWORD", "L": "LWORD"}
_SKIP = frozenset(("pos", "type", "const", "symbol", "src", "end_pos", "name", "kind",
                   "language", "result"))


def synthetic_name(address: str) -> str:
    """The variable name of a direct address: %IX1.1 -> IX1_1__."""
    return address[1:].replace(".", "_") + "__"


def address_type(address: str) -> str:
    size = address[2] if len(address) > 2 and address[2].isalpha() else "X"
    return _SIZE_TYPE[size]


def _slots(obj):
    for cls in type(obj).__mro__:
        for s in getattr(cls, "__slots__", ()):
            if s not in _SKIP:
                yield s


def _replace(x, repl):
    if isinstance(x, ast.Direct):
        return repl(x)
    if isinstance(x, list):
        x[:] = [_replace(i, repl) for i in x]
        return x
    if type(x) is tuple:
        return tuple(_replace(i, repl) for i in x)
    if isinstance(x, (ast.Node, ast.Expr, ast.Arg)):
        for s in _slots(x):
            v = getattr(x, s, None)
            if v is not None:
                nv = _replace(v, repl)
                if nv is not v:
                    setattr(x, s, nv)
        return x
    return x


def name_direct_variables(units, diags) -> None:
    for unit in units:
        for pou in unit.pous:
            if pou.kind == "PROGRAM":
                _program(pou, diags)
            else:
                _unnamed_refused(pou, diags)


def _unnamed_refused(pou, diags):
    """Names the unnamed located declarations of a FUNCTION or
    FUNCTION_BLOCK, for the declaration check's refusal."""
    for b in pou.blocks or ():
        for d in b.decls:
            if isinstance(d, ast.VarDecl) and not d.names:
                # the body checker refuses a located variable here
                d.names = [(synthetic_name(d.location or "%MX0"), d.pos)]


def _program(pou, diags):
    located = {}
    for b in pou.blocks or ():
        for d in b.decls:
            if not isinstance(d, ast.VarDecl) or not d.location:
                continue
            if not d.names:
                if "*" in d.location:
                    diags.error(pou.src, d.pos, f"unnamed located variable AT {d.location}: "
                                                "an incomplete location needs a name for "
                                                "VAR_CONFIG to complete")
                d.names = [(synthetic_name(d.location), d.pos)]
            if len(d.names) == 1 and "*" not in d.location:
                located.setdefault(d.location, d.names[0][0])
    implicit = []

    def repl(e: ast.Direct):
        a = e.address
        if "*" in a:
            diags.error(pou.src, e.pos, f"{a} in a statement: an incomplete address "
                                        "names no location")
            return e
        name = located.get(a)
        if name is None:
            name = located[a] = synthetic_name(a)
            implicit.append(ast.VarDecl(e.pos, names=[(name, e.pos)], location=a, edge=None,
                                        spec=ast.NamedSpec(e.pos, name=address_type(a)),
                                        init=None))
        return ast.Ref(e.pos, name, [])

    _replace(pou.body, repl)
    if getattr(pou, "sfc", None) is not None:
        _replace(pou.sfc, repl)
    if implicit:
        pou.blocks = list(pou.blocks or []) + [
            ast.VarBlock(implicit[0].pos, kind="VAR", qualifiers=(), decls=implicit)]
