"""Pass 'plan modules' + 'write tree': `iec2kmod gen PROJECT -o OUT`.

Writes a kbuild tree:

    OUT/Makefile               builds every module (config first, then the
                               others with its Module.symvers)
    OUT/manifest.json          what the manager needs: modules, load order,
                               resources, tasks, GFT slots, variables
    OUT/runtime/               the runtime C and headers, copied
    OUT/include/               the project header and the image header
    OUT/<module>/Kbuild        one directory per module
"""

from __future__ import annotations

import hashlib
import json
import re
import shutil
from pathlib import Path

from jinja2 import Environment, FileSystemLoader, StrictUndefined

from .. import __version__
from ..checks.types import ArrayT, FBType, StringT, StructT, EnumT, concrete
from ..codegen import generate, pou_order, source_names, uses_real
from ..codegen import cnames as N
from ..codegen.expr import Frame, Raw
from ..codegen.body import BodyEmitter, copy_value
from ..codegen.plan import PlanEmitter, build_plan, unbound_pointer_check
from ..codegen.pou import InitEmitter, callees, frame_need, pou_struct

RUNTIME_HEADERS = ("iec_platform.h", "iec_types.h", "iec_fault.h", "iec_int.h", "iec_conv.h",
                   "iec_time.h", "iec_string.h", "iec_std_fb.h", "iec_real.h", "iec_gen.h")
FP_FLAGS = "-mhard-float -msse -msse2 -fno-math-errno"
DEFAULT_LOOP_BUDGET = 1_000_000


def _env():
    from kmod_templates import ROOT
    return Environment(loader=FileSystemLoader([str(ROOT / "kernel"), str(ROOT / "c")]),
                       undefined=StrictUndefined, keep_trailing_newline=True,
                       trim_blocks=True, lstrip_blocks=True)


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
            out.append(f"standard {pou.name}")
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


def generate_tree(project, out: Path, *args, **kwargs) -> dict:
    """Writes the kbuild tree; returns the manifest.  The cyclic garbage
    collector is off meanwhile: the generator allocates as it walks the
    checked project's millions of objects and makes no garbage cycles, and
    the collector's rescans of them were a third of the time of `gen`."""
    import gc
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        return _generate_tree(project, out, *args, **kwargs)
    finally:
        if was_enabled:
            gc.enable()


def _generate_tree(project, out: Path, selective=None) -> dict:
    """Writes the kbuild tree; returns the manifest.  *selective*: a
    codegen.selective.SelectivePlan (``gen --selective``) or None."""
    from kmod_templates import ROOT
    env = _env()
    sel = selective
    gen = generate(project, selective=sel)
    plan = build_plan(project)
    cfg = project.configurations[0]
    cname = _ident(cfg.name)
    sources = sorted((name, u.src.text) for u, name in source_names(project))
    source_hash = _sha(*[p + "\0" + t for p, t in sources])[:16]

    out.mkdir(parents=True, exist_ok=True)
    (out / "runtime").mkdir(exist_ok=True)
    (out / "include").mkdir(exist_ok=True)
    for f in list((ROOT / "runtime").glob("*.[ch]")) + list((ROOT / "kernel").glob("*.[ch]")):
        shutil.copyfile(f, out / "runtime" / f.name)
    (out / "include" / gen.header_name).write_text(gen.header)
    for key in gen.order:
        name, text = gen.bodies[key]
        (out / "include" / name).write_text(text)

    # ------------------------------------------------- program types
    used_types, seen_types = [], set()
    for r in cfg.resources:
        for inst in r.programs:
            if inst.pou.key not in seen_types:
                seen_types.add(inst.pou.key)
                used_types.append(inst.pou)
    slots = []
    prog_modules = []
    for i, pou in enumerate(used_types):
        ihash = interface_hash(pou, project, sel)
        deps = _deps(pou, project)
        fpu = uses_real(pou, project)
        prefix = N.pou_prefix(pou)
        sel_token = None
        if sel is not None:
            from ..codegen.selective import token_define
            sel_token = token_define([_code(t) for t in [gen.header] +
                                      [gen.bodies[p.key][1] for p in deps]])
        body = env.get_template("program_body.c.j2").render(
            type=pou.name, header=gen.header_name, bodies=[gen.bodies[p.key][0] for p in deps],
            prefix=prefix, uses_fpu=fpu, version=__version__, sel_token=sel_token,
            frame_rows=_frame_rows(plan, pou), frame_need=frame_need(pou),
            call=f"{prefix}_run(self, ctx, true)" if sel is not None and sel.has_layout(pou)
            else f"{prefix}_body(self, ctx)")
        # the code only: comments name the sources and change with any edit
        build_id = _sha(*[_code(t) for t in [body, gen.header] +
                          [gen.bodies[p.key][1] for p in deps]])[:8]
        mod = _modname(f"{cname}_p_{_ident(pou.name)}", f"_{build_id}")
        main = env.get_template("program_main.c.j2").render(
            type=pou.name, type_upper=pou.name.upper(), build_id=build_id, config=cfg.name,
            header=gen.header_name, prefix=prefix, iface_hash=ihash, uses_fpu=fpu,
            version=__version__, source_hash=source_hash)
        # The FPU flags exactly where the body runs between kernel_fpu_begin()
        # and kernel_fpu_end() (.uses_fpu, iec2kmod_run_program): with them
        # gcc copies and zeroes structures through %xmm registers, which
        # outside such a section are the interrupted user process's
        fp_objs = ["body.o"] if fpu else []
        fp_runtime = [f for f in ("iec_math.c", "iec_real.c") if (ROOT / "runtime" / f).exists()]
        runtime = _runtime_used([main, body, gen.header] + [gen.bodies[p.key][1] for p in deps],
                                fpu)
        if fpu:
            fp_objs += [f[:-2] + ".o" for f in fp_runtime]
            runtime += fp_runtime
        _write_module(out, mod, {"main.c": main, "body.c": body},
                      ["main.o", "body.o"] + [f[:-2] + ".o" for f in runtime], fp_objs,
                      runtime=runtime)
        slots.append({"name": pou.name.upper(), "hash": ihash})
        prog_modules.append({"name": mod, "kind": "program", "program_type": pou.name,
                             "slot": i, "build_id": build_id, "interface_hash": ihash,
                             "uses_fpu": fpu, "dir": mod,
                             "interface": interface_description(pou)})

    # ------------------------------------------------- configuration module
    image_members = []
    single_events = {}
    for tp in plan.tasks:
        if tp.single is not None and id(tp.single.var) not in single_events:
            single_events[id(tp.single.var)] = len(single_events)
    cfg_globals = [g for g in plan.globals if g.resource is None]
    for g in cfg_globals:
        image_members.append(N.declare(g.var.type, g.c_name))
    for c_name, t in plan.directs.values():
        image_members.append(N.declare(t, c_name))
    image_h = env.get_template("image.h.j2").render(config=cfg.name, version=__version__,
                                                    members=image_members)
    (out / "include" / "iec_image.h").write_text(image_h)
    ie = InitEmitter(project)
    f = Frame(ie.body_emitter())
    init = []
    for g in cfg_globals:
        init += ie.lines(f"iec2kmod_image.{g.c_name}", g.var.type, g.var.init, f)
    cfg_vars = []
    cfg_enums: dict = {}
    res_vars: dict[str, list] = {r.name: [] for r in cfg.resources}
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
                res_vars[g.resource].append((e, f"res_image.{e.c_lvalue}", ev))
                continue
            if g is not None and id(g.var) in single_events and e.c_lvalue == g.c_name:
                event = single_events[id(g.var)] + 1
            cfg_vars.append({"path": N.c_string(e.path.encode()), "member": e.c_lvalue,
                             "kind": e.kind, "writable": int(e.writable), "event": event,
                             "checks": _desc_checks(e, cfg_enums)})
        else:
            res_vars[res_of[e.owner]].append((e, e.c_lvalue, 0))
    iface_hash = _sha(*[f"{s['name']}={s['hash']}" for s in slots],
                      *[f"{g.path}:{getattr(g.var.type, 'name', '?')}"
                        for g in plan.globals])[:16]
    config_mod = _modname(cname, "_config")
    main = env.get_template("config_main.c.j2").render(
        config=cfg.name, config_lower=cfg.name.lower(), version=__version__,
        source_hash=source_hash, iface_hash=iface_hash, header=gen.header_name,
        image_header="iec_image.h", slots=slots, vars=cfg_vars, nevents=len(single_events),
        enum_sets=_enum_sets(cfg_enums),
        init_decls=f.decls, needs_i=any("for (i = 0;" in ln for ln in init), init=f.pre + init)
    runtime = ["iec_config_rt.c", "iec_ctl.c", "iec_vars.c"] + _runtime_used([main, image_h], False)
    _write_module(out, config_mod, {"main.c": main},
                  ["main.o"] + [f[:-2] + ".o" for f in runtime], [], runtime=runtime)

    # ------------------------------------------------- resource modules
    res_modules = []
    slot_of = {p.key: i for i, p in enumerate(used_types)}
    for r in cfg.resources:
        mod = _modname(f"{cname}_r_{_ident(r.name)}")
        text = _resource_source(env, project, plan, r, gen, cfg, slot_of, single_events,
                                res_vars[r.name], source_hash, iface_hash, sel)
        runtime = _runtime_used([text, gen.header], False)
        _write_module(out, mod, {"main.c": text}, ["main.o"] + [f[:-2] + ".o" for f in runtime],
                      [], runtime=runtime)
        res_modules.append({"name": mod, "kind": "resource", "resource": r.name, "dir": mod,
                            "cpu": _cpu_of(r.processor)})

    manifest = _manifest(cfg, plan, config_mod, prog_modules, res_modules, source_hash,
                         iface_hash, single_events)
    manifest["digest"] = manifest_digest(manifest)
    (out / "manifest.json").write_text(_manifest_text(manifest))
    modules = [config_mod] + [m["name"] for m in prog_modules] + [m["name"] for m in res_modules]
    (out / "Makefile").write_text(_top_makefile())
    (out / "Kbuild").write_text(
        "# SPDX-License-Identifier: GPL-2.0-only OR MIT\n"
        f"# Every module of configuration {cfg.name}; generated by iec2kmod {__version__}.\n"
        + "".join(f"obj-m += {m}/\n" for m in modules))
    return manifest


def manifest_digest(manifest: dict) -> str:
    """The manifest's own checksum, so that plc-manager refuses a manifest
    edited by hand: sha256 of its canonical JSON without "digest" and
    "kernel_release" (`iec2kmod build` adds that one).  plc-manager has the
    same function (manager/project.py; a unit test compares them)."""
    body = {k: v for k, v in manifest.items() if k not in ("digest", "kernel_release")}
    return hashlib.sha256(json.dumps(body, sort_keys=True,
                                     separators=(",", ":")).encode()).hexdigest()[:32]


# Calls into the runtime's out-of-line parts: iec_string.c (every STRING and
# WSTRING function and conversion has str or char in its name) and
# iec_std_fb.c (the standard function blocks' bodies; their _init functions
# are inline).  A module links only the parts its C calls (a 10-line program
# carried 42 KB of runtime it never called); a call this misses is an
# undefined symbol that fails the build (modpost), never a wrong module.
_CALLS_STRING_RT = re.compile(r"\b(?:iec_\w*(?:str|char)\w*|IEC_W?STR\w*)\s*\(")
_CALLS_STD_FB = re.compile(r"\biec_fb_(\w+)\s*\(")


def _runtime_used(texts, fpu: bool) -> list[str]:
    """The runtime sources (iec_string.c, iec_std_fb.c) that C texts call;
    REAL code (iec_real.c formats into strings) needs iec_string.c."""
    strings = fpu or any(_CALLS_STRING_RT.search(t) for t in texts)
    fbs = any(not m.group(1).endswith("_init") for t in texts
              for m in _CALLS_STD_FB.finditer(t))
    return (["iec_string.c"] if strings else []) + (["iec_std_fb.c"] if fbs else [])


def _cpu_of(processor):
    """RESOURCE r ON CPU1 pins the resource's tasks to CPU 1; other
    processor names leave them unpinned."""
    if processor and processor.upper().startswith("CPU") and processor[3:].isdigit():
        return int(processor[3:])
    return -1


def _resource_source(env, project, plan, r, gen, cfg, slot_of, single_events, vars_,
                     source_hash, iface_hash, sel=None):
    res_globals = [g for g in plan.globals if g.resource == r.name]
    instances = [ip for ip in plan.instances if ip.resource == r.name]
    ie = InitEmitter(project)
    f = Frame(ie.body_emitter())
    init = []
    for g in res_globals:
        init += ie.lines(f"res_image.{g.c_name}", g.var.type, g.var.init, f)
    inst_of = _instances_by_name(cfg)
    for ip in instances:
        init.append(f"{N.pou_prefix(ip.pou)}_init(&{ip.c_name});")
        for member, t, value in ip.config_inits:   # VAR_CONFIG
            init += ie.lines(f"{ip.c_name}.{member}", t, value, f)
        if sel is not None and sel.has_layout(ip.pou) and \
                not sel.instance_selective(inst_of[(ip.resource, ip.path.split(".")[-1])]):
            init.append(f"{ip.c_name}.sel.plain = 1;")
    tasks = []
    pe = PlanEmitter(project, plan)
    by_c = _globals_by_c(plan)
    c_of = _global_c_names(plan)
    for tp in [t for t in plan.tasks if t.resource == r.name]:
        used: dict[str, tuple] = {}   # global C name -> (read, write)

        def use(name, read, write):
            a, b = used.get(name, (False, False))
            used[name] = (a or read, b or write)

        for ip in tp.instances:
            inst = inst_of[(ip.resource, ip.path.split(".")[-1])]
            for b in inst.bindings:
                if b.in_program:
                    continue
                pointer = b.steps[-1]
                use(c_of[id(b.target)], True, pointer.assigned and not b.target.constant)
            for param, value in inst.inputs:
                if hasattr(value, "symbol") and value.symbol is not None and \
                        id(value.symbol) in c_of:
                    use(c_of[id(value.symbol)], True, False)
                elif getattr(value, "address", None):
                    use(plan.directs[value.address][0], True, False)
            for param, target in inst.outputs:
                if getattr(target, "address", None):
                    use(plan.directs[target.address][0], False, True)
                else:
                    use(c_of[id(target.symbol)], False, True)
        image, copy_in, copy_out, events = [], [], [], []
        for name, (rd, wr) in used.items():
            g = by_c.get(name)
            t = g.var.type if g is not None else next(
                t for c, t in plan.directs.values() if c == name)
            src = f"res_image.{name}" if g is not None and g.resource else \
                f"iec2kmod_image.{name}"
            image.append(N.declare(t, name))
            copy_in.append(copy_value(f"task{tp.index}_image.{name}", src, t))
            if wr:
                if g is not None and id(g.var) in single_events:
                    ev = single_events[id(g.var)]
                    copy_out.append(f"if (!{src} && task{tp.index}_image.{name})")
                    copy_out.append(f"\tevents[nevents++] = {ev};")
                    events.append(ev)
                copy_out.append(copy_value(src, f"task{tp.index}_image.{name}", t))
        run = []
        for ip in tp.instances:
            cf, lines = _connection_inputs(pe, ip, tp)
            run.append(f"/* {ip.path} : {ip.pou.name} */")
            block = cf.pre + lines
            block.append(f"if (iec2kmod_run_program({slot_of[ip.pou.key]}, &{ip.c_name}, ctx))")
            block.append("\treturn;")
            for gname, member, t in ip.outputs:
                block.append(copy_value(f"task{tp.index}_image.{gname}", f"{ip.c_name}.{member}", t))
            run += (["{"] + ["\t" + d for d in cf.decls + block] + ["}"]) if cf.decls else block
        if not run:
            run = ["(void)ctx;"]
        tasks.append({"index": tp.index, "name": tp.name, "interval": tp.interval_ns or 0,
                      "priority": tp.priority,
                      "single_event": single_events[id(tp.single.var)] if tp.single else -1,
                      "loop_budget": DEFAULT_LOOP_BUDGET, "image": image,
                      "watchdog_ns": tp.watchdog_ns, "watchdog_overruns": tp.watchdog_overruns,
                      "copy_in": copy_in, "copy_out": copy_out, "events": events, "run": run,
                      "slots": sorted({slot_of[ip.pou.key] for ip in tp.instances})})
        for ip in tp.instances:
            for b in ip.bindings:
                init += b.lines(ip.c_name, lambda g, n=tp.index: f"task{n}_image.{g.c_name}")
    # an instance variable belongs to the task that runs its instance (1 + index in tasks[]):
    # the manager writes it between two cycles of that task
    task_no = {t["name"].upper(): n + 1 for n, t in enumerate(tasks)}
    task_of = {ip.path: task_no.get((ip.task or "").upper(), 0) for ip in instances}
    enums: dict = {}
    vars_out = [{"path": N.c_string(e.path.encode()), "lvalue": lv, "kind": e.kind,
                 "writable": int(e.writable), "event": ev, "task": task_of.get(e.owner, 0),
                 "checks": _desc_checks(e, enums)}
                for e, lv, ev in vars_]
    return env.get_template("resource_main.c.j2").render(
        resource=r.name, resource_lower=r.name.lower(), config=cfg.name, version=__version__,
        header=gen.header_name, image_header="iec_image.h",
        res_globals=[N.declare(g.var.type, g.c_name) for g in res_globals],
        instances=[f"{N.pou_struct(ip.pou)} {ip.c_name}" for ip in instances], tasks=tasks,
        vars=vars_out, enum_sets=_enum_sets(enums), cpu=_cpu_of(r.processor), init_decls=f.decls,
        needs_i=any("for (i = 0;" in ln for ln in init), init=f.pre + init,
        source_hash=source_hash, iface_hash=iface_hash,
        unbound_check=unbound_pointer_check(instances))


# Indexes built once per configuration (a lookup inside the loops over
# table entries, instances and connections must not scan: 1,000 instances
# and 13,000 globals made `gen` quadratic, 25 s)

def _instances_by_name(cfg):
    """(resource name, instance name) -> program instance; the first wins."""
    out = {}
    for r in cfg.resources:
        for inst in r.programs:
            out.setdefault((r.name, inst.name), inst)
    return out


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


def _connection_inputs(pe, ip, tp):
    """Program inputs from the task image (globals, process image) or constants."""
    from .. import ast
    be = BodyEmitter(pe.ie.body_emitter().pou)
    f = Frame(be)
    lines = []
    for member, t, value in ip.inputs:
        dst = f"{ip.c_name}.{member}"
        if isinstance(value, ast.Ref) and id(value.symbol) in pe.by_var:
            src = f"task{tp.index}_image.{pe.by_var[id(value.symbol)].c_name}"
            lines += be.assign_code(f, dst, t, Raw(src, value.symbol.type))
        elif isinstance(value, ast.Direct):
            from ..codegen.plan import _direct_c_name
            lines += be.assign_code(f, dst, t, Raw(f"task{tp.index}_image."
                                                   f"{_direct_c_name(value.address)}", t))
        else:
            lines += be.assign_code(f, dst, t, value)
    return f, lines


def _write_module(out, mod, files, objs, fp_objs, runtime):
    d = out / mod
    d.mkdir(exist_ok=True)
    for name, text in files.items():
        (d / name).write_text(text)
    for r in runtime:
        # kbuild compiles sources inside the module directory: a small
        # wrapper includes the shared runtime file
        (d / r).write_text(f'// SPDX-License-Identifier: GPL-2.0-only OR MIT\n'
                           f'#include "../runtime/{r}"\n')
    lines = [
        "# SPDX-License-Identifier: GPL-2.0-only OR MIT",
        f"# Module {mod}: generated by iec2kmod {__version__}.  Do not edit.",
        f"obj-m := {mod}.o",
        f"{mod}-y := {' '.join(objs)}",
        # the kernel's own frame-size warning (2048 bytes) applies: a POU's
        # strings, arrays, structures and FB instances that are not state
        # live in its frame area, not on the stack (iec_fault.h)
        "ccflags-y := -I$(src)/../runtime -I$(src)/../include -std=gnu11",
    ]
    for o in fp_objs:
        lines.append(f"CFLAGS_{o} += {FP_FLAGS}")
    (d / "Kbuild").write_text("\n".join(lines) + "\n")


def _top_makefile():
    return f"""# SPDX-License-Identifier: GPL-2.0-only OR MIT
# Generated by iec2kmod {__version__}.  Builds every module (see Kbuild) in
# one kbuild run against KDIR:
#   make KDIR=/usr/src/linux-headers-6.1.0-56-rt-amd64
# A single module, e.g. a rebuilt program type for a hot swap:
#   make -C $KDIR M=$PWD/<module> KBUILD_EXTRA_SYMBOLS=$PWD/Module.symvers modules
KDIR ?= /lib/modules/$(shell uname -r)/build

all:
\t$(MAKE) -C $(KDIR) M=$(CURDIR) modules

clean:
\t$(MAKE) -C $(KDIR) M=$(CURDIR) clean

.PHONY: all clean
"""


def _manifest(cfg, plan, config_mod, prog_modules, res_modules, source_hash, iface_hash,
              single_events):
    tasks_by_res = {}
    for tp in plan.tasks:
        tasks_by_res.setdefault(tp.resource, []).append({
            "name": tp.name, "interval_ns": tp.interval_ns, "priority": tp.priority,
            "single": tp.single.path if tp.single else None,
            "programs": [ip.path for ip in tp.instances]})
    variables = []
    for e in plan.table:
        variables.append({"path": e.path, "type": getattr(e.type, "name", "?"),
                          "kind": e.kind, "size": e.size, "writable": e.writable,
                          "owner": e.owner, **_value_info(e.type)})
    return {
        "format": 1,
        "generator": f"iec2kmod {__version__}",
        "configuration": cfg.name,
        "source_hash": source_hash,
        "interface_hash": iface_hash,
        "modules": ([{"name": config_mod, "kind": "configuration", "dir": config_mod,
                      "depends": []}] +
                    [dict(m, depends=[config_mod]) for m in prog_modules] +
                    [dict(m, depends=[config_mod] + [p["name"] for p in prog_modules])
                     for m in res_modules]),
        "load_order": [config_mod] + [m["name"] for m in prog_modules] +
                      [m["name"] for m in res_modules],
        "resources": [{"name": m["resource"], "module": m["name"], "cpu": m["cpu"],
                       "tasks": tasks_by_res.get(m["resource"], [])} for m in res_modules],
        "program_types": [{"name": m["program_type"], "slot": m["slot"], "module": m["name"],
                           "build_id": m["build_id"], "interface_hash": m["interface_hash"],
                           "uses_fpu": m["uses_fpu"], "interface": m["interface"]}
                          for m in prog_modules],
        "instances": [{"path": ip.path, "type": ip.pou.name, "resource": ip.resource,
                       "task": ip.task} for ip in plan.instances],
        "variables": variables,
        # a located variable's address names it too (plc-manager read %IW2)
        "addresses": {a: p for a, p in sorted(getattr(cfg, "addresses", {}).items())
                      if p.upper() in {v["path"].upper() for v in variables}},
    }


def _manifest_text(manifest) -> str:
    """The manifest as JSON, indented, with one line per variable (the
    variable table is most of it: 23,000 entries in a plant-sized
    configuration, which json's indenting encoder takes a third of a second
    to write)."""
    parts = []
    for key, value in manifest.items():
        if key == "variables" and value:
            body = ",\n".join("    " + json.dumps(v) for v in value)
            text = f"[\n{body}\n  ]"
        else:
            text = json.dumps(value, indent=2).replace("\n", "\n  ")
        parts.append(f"  {json.dumps(key)}: {text}")
    return "{\n" + ",\n".join(parts) + "\n}\n"


def _c_s64(v: int) -> str:
    return "(-9223372036854775807LL - 1)" if v == -2 ** 63 else f"{v}LL"


def _desc_checks(e, enums: dict) -> str:
    """The designated initializers of what the kernel checks in a value
    written to or forced into the variable of table entry *e* (struct
    iec_var_desc in iec_kmod.h): a STRING's declared capacity, a subrange's
    bounds, an enumeration's values (one static array per value set, named
    in *enums*)."""
    from ..checks.types import SubrangeT
    t = concrete(e.type)
    if isinstance(t, SubrangeT):
        if e.kind == "u":
            return f", .check = IEC_VCHK_RANGE, .range.u = {{ {t.low}ULL, {t.high}ULL }}"
        return (f", .check = IEC_VCHK_RANGE, .range.s = {{ {_c_s64(t.low)}, "
                f"{_c_s64(t.high)} }}")
    if isinstance(t, EnumT):
        bits = N.enum_base(t).bits
        # as the C object holds them, read sign-extended by the kernel
        values = tuple(sorted({v - 2 ** bits if v >= 2 ** (bits - 1) else v
                               for _, v in t.values.values()}))
        name = enums.setdefault(values, f"iec_enum_set{len(enums)}")
        return f", .check = IEC_VCHK_ENUM, .enum_values = {name}, .nenum = {len(values)}"
    if isinstance(t, StringT):
        return f", .cap = {t.length}"
    return ""


def _enum_sets(enums: dict) -> list:
    return [{"name": name, "set": ", ".join(map(_c_s64, values))}
            for values, name in enums.items()]


def _value_info(t):
    """What plc-manager needs to check a value written to a variable: the
    elementary type, a subrange's bounds, an enumeration's values, a
    string's length."""
    from ..checks.types import Elementary, SubrangeT
    t = concrete(t)
    info = {}
    if isinstance(t, SubrangeT):
        info["range"] = [t.low, t.high]
        t = t.elem
    if isinstance(t, EnumT):
        info["base"] = N.enum_base(t).name
        info["enum"] = {name: value for name, value in sorted(t.values.values(),
                                                               key=lambda x: x[1])}
    elif isinstance(t, StringT):
        info["base"] = "WSTRING" if t.wide else "STRING"
        info["length"] = t.length
    elif isinstance(t, Elementary):
        info["base"] = t.name
    return info
