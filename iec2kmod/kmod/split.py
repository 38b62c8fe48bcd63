"""The split of a configuration into kernel modules, as data: decided
here, written by kmod/tree.py.

    one configuration module   the process image (the configuration's
                               globals and the directly represented
                               variables), the variable table's entries
                               that live there, the program-type slots
    one module per program     the type's code (the POUs it needs,
      type                     dependencies first) and its interface hash;
                               named by a hash of that code (the build id,
                               computed by the writer from the C it renders)
    one module per resource    its globals, its program instances, its
                               tasks, the table entries that live there

Loaded in that order: a resource module depends on the configuration module
and every program module."""

from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass, field

from ..checks.types import ArrayT, EnumT, FBType, StringT, StructT, concrete
from ..codegen import pou_order, source_names, uses_real
from ..codegen import cnames as N
from ..codegen.pou import callees, frame_need, pou_struct


@dataclass
class ProgramModule:
    """A program type's module."""
    pou: object                  # POUInfo
    slot: int
    stem: str                    # the module name before its build id
    iface_hash: str
    deps: list                   # [POUInfo] the POUs of the module, dependencies first
    uses_fpu: bool
    frame_rows: list             # per task: the row of the type's frame areas, -1 none
    frame_need: object           # the largest frame a body of the type needs
    selective: bool              # instances run through <prefix>_run (--selective)

    def name(self, build_id: str) -> str:
        return _modname(self.stem, f"_{build_id}")


@dataclass
class ResourceModule:
    resource: object             # the checked Resource
    name: str
    cpu: int                     # -1: not pinned
    globals: list                # [GlobalPlan] the resource's globals
    instances: list              # [InstancePlan] its program instances
    tasks: list                  # [TaskPlan] its tasks
    vars: list = field(default_factory=list)   # [(TableEntry, C lvalue, event number)]


@dataclass
class ModulePlan:
    config: str                  # configuration name
    config_module: str           # its module's name
    source_hash: str
    iface_hash: str              # of the whole configuration (slots and globals)
    single_events: dict          # id(SINGLE variable) -> event number
    config_globals: list         # [GlobalPlan] the configuration's own globals
    config_vars: list            # [(TableEntry, event number)] entries in the process image
    programs: list               # [ProgramModule] by slot
    resources: list              # [ResourceModule]

    @property
    def slot_of(self) -> dict:
        return {m.pou.key: m.slot for m in self.programs}


def plan_modules(comp) -> ModulePlan:
    """The module split of a Compilation."""
    project, plan, sel = comp.project, comp.plan, comp.selective
    cfg = project.configurations[0]
    cname = _ident(cfg.name)
    sources = sorted((name, u.src.text) for u, name in source_names(project))
    source_hash = _sha(*[p + "\0" + t for p, t in sources])[:16]
    used_types, seen_types = [], set()
    for r in cfg.resources:
        for inst in r.programs:
            if inst.pou.key not in seen_types:
                seen_types.add(inst.pou.key)
                used_types.append(inst.pou)
    programs = []
    for i, pou in enumerate(used_types):
        programs.append(ProgramModule(
            pou=pou, slot=i, stem=f"{cname}_p_{_ident(pou.name)}",
            iface_hash=interface_hash(pou, project, sel), deps=_deps(pou, project),
            uses_fpu=uses_real(pou, project), frame_rows=_frame_rows(plan, pou),
            frame_need=frame_need(pou), selective=sel is not None and sel.has_layout(pou)))
    single_events = {}
    for tp in plan.tasks:
        if tp.single is not None and id(tp.single.var) not in single_events:
            single_events[id(tp.single.var)] = len(single_events)
    resources = [ResourceModule(r, _modname(f"{cname}_r_{_ident(r.name)}"), _cpu_of(r.processor),
                                [g for g in plan.globals if g.resource == r.name],
                                [ip for ip in plan.instances if ip.resource == r.name],
                                [t for t in plan.tasks if t.resource == r.name])
                 for r in cfg.resources]
    res_by_name = {m.resource.name: m for m in resources}
    config_vars = []
    by_c = _globals_by_c(plan)
    res_of = {}
    for ip in plan.instances:
        res_of.setdefault(ip.path, ip.resource)
    for e in plan.table:
        event = 0
        if e.owner in ("global", "direct"):
            g = by_c.get(e.c_lvalue.split("[")[0].split(".")[0])
            if g is not None and g.resource is not None:
                ev = single_events[id(g.var)] + 1 if id(g.var) in single_events and \
                    e.c_lvalue == g.c_name else 0
                res_by_name[g.resource].vars.append((e, f"res_image.{e.c_lvalue}", ev))
                continue
            if g is not None and id(g.var) in single_events and e.c_lvalue == g.c_name:
                event = single_events[id(g.var)] + 1
            config_vars.append((e, event))
        else:
            res_by_name[res_of[e.owner]].vars.append((e, e.c_lvalue, 0))
    iface = _sha(*[f"{m.pou.name.upper()}={m.iface_hash}" for m in programs],
                 *[f"{g.path}:{getattr(g.var.type, 'name', '?')}" for g in plan.globals])[:16]
    return ModulePlan(cfg.name, _modname(cname, "_config"), source_hash, iface, single_events,
                      [g for g in plan.globals if g.resource is None], config_vars, programs,
                      resources)


def _ident(s: str) -> str:
    return "".join(c if c.isalnum() else "_" for c in s.lower())


# the kernel's MODULE_NAME_LEN (64 - sizeof(unsigned long)) less the NUL:
# modpost refuses a longer name ("module name is too long")
MODULE_NAME_MAX = 55


def _modname(stem: str, suffix: str = "") -> str:
    """iec_<stem><suffix>, the stem shortened and made unique by a hash of
    it when the whole would not fit the kernel's limit on module names
    (long configuration and POU names are valid IEC)."""
    name = f"iec_{stem}{suffix}"
    if len(name) <= MODULE_NAME_MAX:
        return name
    keep = MODULE_NAME_MAX - len("iec_") - len(suffix) - 9
    return f"iec_{stem[:keep].rstrip('_')}_{_sha(stem)[:8]}{suffix}"


def _sha(*texts) -> str:
    h = hashlib.sha256()
    for t in texts:
        h.update(t.encode() if isinstance(t, str) else t)
        h.update(b"\0")
    return h.hexdigest()


_C_COMMENT = re.compile(r"/\*.*?\*/|//[^\n]*", re.S)


def _code(text: str) -> str:
    """C text without comments (a build id must not depend on them)."""
    return _C_COMMENT.sub("", text)


def _type_defs(t, out, seen, project, sel=None):
    """Struct text of every type an instance's layout depends on."""
    t = concrete(t)
    if isinstance(t, ArrayT):
        out.append(f"array {t.name}")
        _type_defs(t.elem, out, seen, project, sel)
    elif isinstance(t, StringT):
        out.append(f"string {t.name}")
    elif isinstance(t, EnumT):
        out.append(f"enum {t.name} {sorted(t.values.values(), key=lambda x: x[1])} "
                   f"{N.enum_base(t).name}")
    elif isinstance(t, StructT):
        if id(t) in seen:
            return
        seen.add(id(t))
        for fname, ft, _ in t.fields.values():
            out.append(f"field {t.name}.{fname}")
            _type_defs(ft, out, seen, project, sel)
    elif isinstance(t, FBType):
        pou = t.pou
        if id(pou) in seen:
            return
        seen.add(id(pou))
        if pou.standard:
            # an instance that keeps its ENO is larger (codegen.std_eno_type)
            out.append(f"standard {pou.name}" + (" ENO" if pou.keeps_eno else ""))
            return
        out.append("\n".join(pou_struct(pou, sel)))
        for v in pou.vars.values():
            _type_defs(v.type, out, seen, project, sel)
    else:
        out.append(f"elementary {t.name}")


def interface_hash(pou, project, sel=None) -> str:
    """Hash of a program type's interface: the layout of its instance state
    (every variable, nested FB instance and type, and with --selective the
    selective execution state).  Algorithms may change across a hot swap;
    this may not."""
    parts = ["abi 1", "\n".join(pou_struct(pou, sel))]
    seen = set()
    for v in pou.vars.values():
        parts.append(f"{v.section} {v.name} {getattr(v.type, 'name', '?')}")
        _type_defs(v.type, parts, seen, project, sel)
    return _sha(*parts)[:16]


def interface_description(pou):
    return [{"name": v.name, "section": v.section, "type": getattr(v.type, "name", "?")}
            for v in pou.vars.values()]


def _deps(pou, project):
    """The POUs a program type's module must contain, dependencies first."""
    order = pou_order(project)
    need = set()

    def visit(p):
        if p.key in need:
            return
        need.add(p.key)
        # the same POUs whose frame needs the body's adds up (codegen.pou)
        for c in callees(project, p):
            visit(c)

    visit(pou)
    return [p for p in order if p.key in need]


def _frame_rows(plan, pou) -> list[int]:
    """For each task of the configuration, the row of the program type's
    frame areas it uses, -1 if it runs no instance of the type."""
    rows, n = [], 0
    for tp in plan.tasks:
        if any(ip.pou is pou for ip in tp.instances):
            rows.append(n)
            n += 1
        else:
            rows.append(-1)
    return rows


def _cpu_of(processor):
    """RESOURCE r ON CPU1 pins the resource's tasks to CPU 1; other
    processor names leave them unpinned."""
    if processor and processor.upper().startswith("CPU") and processor[3:].isdigit():
        return int(processor[3:])
    return -1



# Indexes built once per configuration (a lookup inside the loops over
# table entries, instances and connections must not scan: 1,000 instances
# and 13,000 globals made `gen` quadratic, 25 s)

def _global_c_names(plan):
    """id(variable) -> C name of the global; the first wins."""
    out = {}
    for g in plan.globals:
        out.setdefault(id(g.var), g.c_name)
    return out


def _globals_by_c(plan):
    """C name -> GlobalPlan; the first wins."""
    out = {}
    for g in plan.globals:
        out.setdefault(g.c_name, g)
    return out
