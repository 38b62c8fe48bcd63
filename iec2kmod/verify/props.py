"""Properties and assumptions: ST boolean expressions, from the command line
or from pragmas in the sources.

Pragma syntax (anywhere a comment may stand; the keyword is case-insensitive):

    {verify NAME: EXPR}     a property, checked after every cycle of the task
    {verify: EXPR}          the same, named after its position
    {assume: EXPR}          a constraint on every step's inputs (and state),
                            evaluated where the properties are: on the state
                            after the step, with the inputs the step read

Inside a PROGRAM (between PROGRAM and END_PROGRAM) names are the program's
own variables -- inputs, outputs, internals, FB instances and their
members -- and the property is checked for every instance of the program in
the configuration.  Anywhere else names are configuration paths, the ones
``iec2kmod sim --watch`` takes: globals, ``resource.global``,
``instance.variable``, ``instance.fb.output``, ``%QX0.1``, enumeration
values."""

from __future__ import annotations

import re
from dataclasses import dataclass

from .. import ast
from ..checks.body import BodyChecker
from ..checks.declare import Declarer
from ..checks.symbols import POUInfo, Var
from ..checks.types import BOOL, ERROR, EnumT, ErrorT, FBType, StructT
from ..diagnostics import Diagnostics, SourceFile
from ..parse import lexical
from ..parse.parser import parse_expression

# the text after {verify / {assume: an optional name, a colon, the expression
_PROP_BODY = re.compile(r"\s*(" + lexical.NAME + r")?\s*:(.*)\Z", re.S)


@dataclass
class Prop:
    kind: str            # property | assume
    name: str
    text: str
    src: SourceFile
    start: int           # offset of the expression in src
    program: str | None  # upper POU name when written inside a PROGRAM
    expr: object = None  # checked AST (per scope, filled by check())


def scan_pragmas(project) -> tuple[list, list]:
    """Every {verify}/{assume} pragma of the project's source files, in
    the order they are written: the parser attached each to the POU it is
    written in, or to its file (parse/lexical.attach)."""
    props, bad = [], []
    seen = set()
    for unit in project.units:
        src = unit.src
        if id(src) in seen:
            continue
        seen.add(id(src))
        found = [(p, None) for p in unit.outside or ()]
        for pou in unit.pous:
            found += [(p, pou) for p in pou.pragmas or () if p.kind in ("verify", "assume")]
        for p, pou in sorted(found, key=lambda x: x[0].start):
            m = _PROP_BODY.match(p.body)
            if not m:
                continue     # no colon: not a property (as before the registry)
            kind = p.kind
            start = p.body_start + m.start(2)
            text = m.group(2)
            program = None
            if pou is not None:
                if pou.kind == "PROGRAM":
                    program = pou.name.upper()
                else:
                    bad.append((src, p.start, f"a {{{kind}}} pragma inside a "
                                f"{pou.kind.replace('_', ' ').lower()} (write it in a "
                                "PROGRAM or in the configuration)"))
                    continue
            line, _ = src.linecol(p.start)
            name = m.group(1) or f"{src.path.rsplit('/', 1)[-1]}:{line}"
            props.append(Prop("property" if kind == "verify" else "assume", name, text, src,
                              start, program))
    return props, bad


# ----------------------------------------------------------- parsing
def parse_expr(text: str, src: SourceFile, start: int, diags: Diagnostics):
    """The expression AST of ``text`` (found at offset ``start`` of src),
    its positions those of src; None after a syntax error (in diags)."""
    return parse_expression(text, (src, start), diags, "property")


# ---------------------------------------------------------- checking
class PropChecker(BodyChecker):
    """Type checks a property in a scope: a PROGRAM's variables, or the
    configuration's paths.  Members of function block and program instances
    may be read whatever their section (as `sim --watch` reads them)."""

    def __init__(self, project, diags, scope_pou, src, directs):
        decl = Declarer(project, diags)
        for t in project.types.values():
            if isinstance(t, EnumT):
                for k in t.values:
                    decl.enum_values.setdefault(k, []).append(t)
        super().__init__(project, decl, diags, scope_pou)
        self.src = src
        self.directs = directs

    def member(self, t, name, pos):
        if isinstance(t, FBType):
            v = t.pou.var(name)
            if v is None or v.section in ("VAR_TEMP", "RESULT") or (
                    t.pou.standard and name.startswith("$")):
                self.error(pos, f"{t.name} has no variable '{name}'")
                return ERROR, None
            return v.type, None
        return super().member(t, name, pos)

    def _expr(self, e):
        if isinstance(e, ast.Direct):
            t = self.directs.get(e.address.upper()) or self.directs.get(e.address)
            if t is None:
                self.error(e.pos, f"{e.address} is not connected in the configuration")
                return ERROR
            return t
        if isinstance(e, ast.Call) and e.target is None and self.pou.var(e.name) is not None \
                and isinstance(self.pou.var(e.name).type, FBType):
            self.error(e.pos, "a property cannot call a function block")
            return ERROR
        return super()._expr(e)

    def check_expr(self, e):
        t = self.expr(e)
        self.settle_roots()
        if isinstance(t, ErrorT):
            return False
        if t.base is not BOOL:
            self.error(e.pos, f"a property must be BOOL, not {t.name}")
            return False
        return True


def config_scope(sym):
    """A pseudo POU whose variables are the configuration's paths: globals
    (references), resources (named ones) and program instances."""
    m = sym.machine
    cfg = sym.cfg
    scope = POUInfo("PROGRAM", cfg.name)
    scope.src = cfg.src
    from ..interp.model import Instance
    inst = Instance(scope)
    named = any(r.node.name for r in cfg.resources)

    def add(pou, holder, name, t, section, cell=None, value=None):
        v = Var(name, t, section, owner=pou)
        pou.vars[v.key] = v
        if section == "VAR_IN_OUT":
            holder.r[v.key] = cell
        else:
            holder.v[v.key] = value
        return v

    for g in cfg.globals.values():
        add(scope, inst, g.name, g.type, "VAR_IN_OUT", cell=(m.globals, g.key))
    insts = {path: i for path, i in m.instances}
    for r in cfg.resources:
        if r.node.name:
            rp = POUInfo("FUNCTION_BLOCK", r.name)
            rp.src = cfg.src
            ri = Instance(rp)
            for g in r.globals.values():
                add(rp, ri, g.name, g.type, "VAR_IN_OUT", cell=(m.res_globals[r.name], g.key))
            for pi in r.programs:
                add(rp, ri, pi.name, FBType(pi.pou.name, pi.pou), "VAR",
                    value=insts[f"{r.name}.{pi.name}"])
            add(scope, inst, r.name, FBType(r.name, rp), "VAR", value=ri)
        else:
            for g in r.globals.values():
                add(scope, inst, g.name, g.type, "VAR_IN_OUT",
                    cell=(m.res_globals[r.name], g.key))
            for pi in r.programs:
                add(scope, inst, pi.name, FBType(pi.pou.name, pi.pou), "VAR",
                    value=insts[pi.name])
    del named
    return scope, inst


def instance_of_path(sym, path):
    """(POUInfo, Instance) of a program instance path (``crossing`` or
    ``plc.crossing``), or None."""
    for p, inst in sym.machine.instances:
        if p.upper() == path.upper() or p.upper().split(".")[-1] == path.upper():
            return inst.pou, inst
    return None


_ = (StructT, BOOL)


def collect(project, cli_props, cli_assumes, diags):
    """Every property and assumption of a check: the {verify}/{assume}
    pragmas of the sources, then --property and --assume (errors of the
    pragmas into *diags*).  Both engines start from this list."""
    props, bad = scan_pragmas(project)
    for src, pos, msg in bad:
        diags.error(src, pos, msg)
    for n, text in enumerate(cli_props, 1):
        props.append(Prop("property", f"property {n}", text,
                          SourceFile(f"<--property {n}>", text), 0, None))
    for n, text in enumerate(cli_assumes, 1):
        props.append(Prop("assume", f"assume {n}", text,
                          SourceFile(f"<--assume {n}>", text), 0, None))
    return props
