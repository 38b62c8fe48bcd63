"""Pass 'emit': the checked project to C.

    project header   <config>_types.h: string types, enumeration constants,
                     user structures, FB/PROGRAM instance structs and their
                     init functions, in dependency order
    one body per POU pou_<name>.c: FUNCTION as a C function, FUNCTION_BLOCK
                     and PROGRAM as <prefix>_body(self, ctx)

The same C is compiled into kernel modules and, for `iec2kmod sim`, into a
user-space library.  Output is deterministic: same input, same bytes."""

from __future__ import annotations

import hashlib
import os
import re
from dataclasses import dataclass, field

from jinja2 import Environment, FileSystemLoader, StrictUndefined

from .. import __version__
from ..checks import stdlib
from ..checks.types import ArrayT, EnumT, FBType, StringT, StructT, concrete
from . import cnames as N
from .expr import CodegenError
from .pou import function_signature, pou_body, pou_init, pou_struct


_STRING_STRUCT = re.compile(r"struct iec_(w?)string_(\d+)\b")


@dataclass
class GeneratedC:
    header_name: str
    header: str
    bodies: dict = field(default_factory=dict)     # POU key -> (file name, text)
    order: list = field(default_factory=list)      # POU keys, dependencies first
    uses_real: set = field(default_factory=set)    # POU keys that use REAL/LREAL


def _env():
    from ..resources import templates_root
    ROOT = templates_root()
    return Environment(loader=FileSystemLoader(str(ROOT / "c")), undefined=StrictUndefined,
                       keep_trailing_newline=True, trim_blocks=True, lstrip_blocks=True,
                       autoescape=False)


def _walk_types(t, seen, order, strings):
    """Collects the types a declaration needs, dependencies first."""
    t = concrete(t)
    if isinstance(t, StringT):
        strings.add((t.wide, t.length))
        return
    if isinstance(t, ArrayT):
        _walk_types(t.elem, seen, order, strings)
        return
    if isinstance(t, (StructT, EnumT)):
        if id(t) in seen:
            return
        seen.add(id(t))
        if isinstance(t, StructT):
            for _, ft, _ in t.fields.values():
                _walk_types(ft, seen, order, strings)
        order.append(t)


def pou_order(project):
    """User POUs with every dependency (FB types, called functions) first."""
    order, state = [], {}

    def visit(pou):
        if state.get(pou.key):
            return
        state[pou.key] = 1
        deps = set(pou.calls)
        for v in pou.vars.values():
            if isinstance(v.type, FBType) and not v.type.pou.standard:
                deps.add(v.type.pou.key)
        for d in sorted(deps):
            if d in project.pous:
                visit(project.pous[d])
        order.append(pou)

    for pou in project.pous.values():
        visit(pou)
    return order


def uses_real(pou, project, memo=None) -> bool:
    """Does a POU (or anything it calls or contains) compute with REAL/LREAL?"""
    from ..checks.types import cat
    memo = {} if memo is None else memo
    if pou.key in memo:
        return memo[pou.key]
    memo[pou.key] = False
    r = pou.uses_real or any(cat(v.type) == "real" or _has_real(v.type)
                             for v in pou.vars.values())
    for d in pou.calls:
        if d in project.pous and uses_real(project.pous[d], project, memo):
            r = True
    memo[pou.key] = r
    return r


def _has_real(t):
    from ..checks.types import cat
    t = concrete(t)
    if isinstance(t, ArrayT):
        return _has_real(t.elem)
    if isinstance(t, StructT):
        return any(_has_real(ft) for _, ft, _ in t.fields.values())
    if isinstance(t, FBType) and not t.pou.standard:
        return any(cat(v.type) == "real" or _has_real(v.type) for v in t.pou.vars.values())
    return cat(t) == "real"


def source_names(project):
    """[(unit, name)]: each source's path relative to the directory that
    holds all of them (``traffic_light.st``), so that what generated files
    say they come from (comments, the source hash) does not depend on where
    the project lies on the build machine."""
    paths = [os.path.abspath(u.src.path) for u in project.units]
    base = os.path.commonpath([os.path.dirname(p) for p in paths]) if paths else ""
    return [(u, os.path.relpath(p, base).replace(os.sep, "/"))
            for u, p in zip(project.units, paths)]


def source_list(project):
    return [{"path": name, "sha": hashlib.sha256(unit.src.text.encode()).hexdigest()[:16]}
            for unit, name in source_names(project)]


def std_eno_type(pou):
    """(struct, functions) of a standard FB whose instances keep their ENO
    (checks/stdlib.keeping_eno): the runtime's struct in member fb, ENO
    beside it (TRUE initially); the call runs the runtime's body on fb, and
    sets eno itself (codegen/body.py)."""
    p, base = N.pou_prefix(pou), N.pou_prefix(stdlib.FUNCTION_BLOCKS[pou.key])
    struct = "\n".join([f"/* {pou.name} keeping the ENO of its last call (an instance's ENO is "
                        "read) */",
                        f"struct {p} {{", f"\tstruct {base} fb;", "\tiec_bool eno;", "};"])
    funcs = "\n".join([f"static inline void {p}_init(struct {p} *self)", "{",
                       f"\t{base}_init(&self->fb);", "\tself->eno = 1;", "}", "",
                       f"static inline void {p}(struct {p} *self, struct iec_ctx *ctx)", "{",
                       f"\t{base}(&self->fb, ctx);", "}"])
    return struct, funcs


def generate(project, name: str | None = None, selective=None) -> GeneratedC:
    """C for every user POU of the project; *selective* is a
    selective.SelectivePlan (None: plain code) whose rule 8 questions are
    answered (iec2kmod.compilation makes it so)."""
    if selective is not None and not selective.settled:
        raise ValueError("a selective plan whose idempotence questions are not answered "
                         "(make it with iec2kmod.compilation.selective_plan)")
    env = _env()
    cfg = project.configurations[0].name if project.configurations else (name or "project")
    guard = f"IEC_{cfg.upper()}_TYPES"
    order = pou_order(project)
    seen, types, strings = set(), [], set()
    for t in project.types.values():
        if not isinstance(t, dict):
            _walk_types(t, seen, types, strings)
    for pou in order:
        for v in pou.vars.values():
            _walk_types(v.type, seen, types, strings)
    for c in project.configurations:
        for g in list(c.globals.values()) + [g for r in c.resources for g in r.globals.values()]:
            _walk_types(g.type, seen, types, strings)

    enums, structs = [], []
    for t in types:
        if isinstance(t, EnumT):
            base = N.enum_base(t)
            enums.append({"name": t.name, "ctype": base.c_type,
                          "consts": [(N.enum_const(t, n), v) for n, v in t.values.values()]})
        else:
            lines = [f"struct t_{t.name.lower()} {{"]
            for fname, ft, _ in t.fields.values():
                lines.append(f"\t{N.declare(ft, N.var(fname))};")
            lines.append("};")
            structs.append("\n".join(lines))
    inits = []
    for t in project.std_fbs.values():
        if t.pou.keeps_eno:
            # before every struct: those of the POUs hold such instances
            struct, init = std_eno_type(t.pou)
            structs.insert(0, struct)
            inits.append(init)
    for pou in order:
        if pou.kind == "FUNCTION":
            continue
        structs.append("\n".join(pou_struct(pou, selective)))
        inits.append("\n".join(pou_init(project, pou)))
    memo = {}
    tpl = env.get_template("pou.c.j2")
    bodies = {}
    names = {id(u.src): name for u, name in source_names(project)}
    for pou in order:
        text = tpl.render(kind=pou.kind, name=pou.name, version=__version__,
                          path=names.get(id(pou.src), pou.src.path), line=pou.src.linecol(pou.node.pos)[0],
                          functions=["\n".join(pou_body(project, pou, selective))])
        bodies[pou.key] = (f"pou_{pou.name.lower()}.c", text)
    # string temporaries of the bodies (CONCAT results ...) need their types too
    for text in [b[1] for b in bodies.values()] + inits:
        for m in _STRING_STRUCT.finditer(text):
            strings.add((m.group(1) == "w", int(m.group(2))))
    header = env.get_template("project.h.j2").render(
        guard=guard, config=cfg, version=__version__, sources=source_list(project),
        string_lengths=sorted(n for w, n in strings if not w and n != 254),
        wstring_lengths=sorted(n for w, n in strings if w and n != 254),
        enums=enums, structs=structs, inits=inits, selective=selective is not None)
    out = GeneratedC(f"{guard.lower()}.h", header, order=[p.key for p in order])
    out.bodies = bodies
    for pou in order:
        if uses_real(pou, project, memo):
            out.uses_real.add(pou.key)
    return out


__all__ = ["generate", "GeneratedC", "CodegenError", "pou_order", "function_signature"]
