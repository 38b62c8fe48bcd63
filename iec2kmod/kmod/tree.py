"""Writing the kbuild tree of a Compilation (`iec2kmod gen PROJECT -o OUT`):

    OUT/Makefile               builds every module (config first, then the
                               others with its Module.symvers)
    OUT/manifest.json          what the manager needs: modules, load order,
                               resources, tasks, GFT slots, variables
    OUT/runtime/               the runtime C and headers, copied
    OUT/include/               the project header and the image header
    OUT/<module>/Kbuild        one directory per module

What goes into which module is decided by kmod/split.py (the
Compilation's ``modules``); this module renders and writes."""

from __future__ import annotations

import re
import shutil
import struct
from pathlib import Path

from jinja2 import Environment, FileSystemLoader, StrictUndefined

from .. import __version__
from ..checks.types import EnumT, StringT, concrete
from ..codegen import cnames as N
from ..codegen.body import copy_value
from ..codegen.expr import Frame
from ..codegen.plan import unbound_pointer_check
from ..codegen.pou import InitEmitter
from ..execmodel import LOOP_BUDGET
from .manifest import manifest_digest, manifest_of, manifest_text
from .split import _code, _global_c_names, _globals_by_c, _sha, interface_description

RUNTIME_HEADERS = ("iec_platform.h", "iec_types.h", "iec_fault.h", "iec_int.h", "iec_conv.h",
                   "iec_time.h", "iec_string.h", "iec_std_fb.h", "iec_real.h", "iec_gen.h")
FP_FLAGS = "-mhard-float -msse -msse2 -fno-math-errno"


def _env():
    from ..resources import templates_root
    ROOT = templates_root()
    return Environment(loader=FileSystemLoader([str(ROOT / "kernel"), str(ROOT / "c")]),
                       undefined=StrictUndefined, keep_trailing_newline=True,
                       trim_blocks=True, lstrip_blocks=True)


def generate_tree(what, out: Path, selective=None) -> dict:
    """Writes the kbuild tree of *what* (a Compilation, or a checked
    project with *selective* as for compilation.selective_plan); returns
    the manifest.  The cyclic garbage collector is off meanwhile: the
    generator allocates as it walks the checked project's millions of
    objects and makes no garbage cycles, and the collector's rescans of
    them were a third of the time of `gen`."""
    import gc
    from ..compilation import Compilation
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        return write_tree(Compilation.of(what, selective), Path(out))
    finally:
        if was_enabled:
            gc.enable()


def write_tree(comp, out: Path) -> dict:
    """Writes the kbuild tree of Compilation *comp*; returns the manifest."""
    from ..resources import templates_root
    ROOT = templates_root()
    env = _env()
    project, sel, plan, gen, mp = comp.project, comp.selective, comp.plan, comp.gen, comp.modules
    cfg = project.configurations[0]

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
    prog_modules = []
    for pm in mp.programs:
        pou, deps, fpu = pm.pou, pm.deps, pm.uses_fpu
        prefix = N.pou_prefix(pou)
        sel_token = None
        if sel is not None:
            from ..codegen.selective import token_define
            sel_token = token_define([_code(t) for t in [gen.header] +
                                      [gen.bodies[p.key][1] for p in deps]])
        body = env.get_template("program_body.c.j2").render(
            type=pou.name, header=gen.header_name, bodies=[gen.bodies[p.key][0] for p in deps],
            prefix=prefix, uses_fpu=fpu, version=__version__, sel_token=sel_token,
            frame_rows=pm.frame_rows, frame_need=pm.frame_need,
            call=f"{prefix}_run(self, ctx, true)" if pm.selective else f"{prefix}_body(self, ctx)")
        # the code only: comments name the sources and change with any edit
        build_id = _sha(*[_code(t) for t in [body, gen.header] +
                          [gen.bodies[p.key][1] for p in deps]])[:8]
        mod = pm.name(build_id)
        main = env.get_template("program_main.c.j2").render(
            type=pou.name, type_upper=pou.name.upper(), build_id=build_id, config=cfg.name,
            header=gen.header_name, prefix=prefix, iface_hash=pm.iface_hash, uses_fpu=fpu,
            version=__version__, source_hash=mp.source_hash)
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
        prog_modules.append({"name": mod, "kind": "program", "program_type": pou.name,
                             "slot": pm.slot, "build_id": build_id,
                             "interface_hash": pm.iface_hash, "uses_fpu": fpu, "dir": mod,
                             "interface": interface_description(pou)})

    # ------------------------------------------------- configuration module
    image_members = []
    for g in mp.config_globals:
        image_members.append(N.declare(g.var.type, g.c_name))
    for c_name, t in plan.directs.values():
        image_members.append(N.declare(t, c_name))
    image_h = env.get_template("image.h.j2").render(config=cfg.name, version=__version__,
                                                    members=image_members)
    (out / "include" / "iec_image.h").write_text(image_h)
    ie = InitEmitter(project)
    f = Frame(ie.body_emitter())
    init = []
    for g in mp.config_globals:
        init += ie.lines(f"iec2kmod_image.{g.c_name}", g.var.type, g.var.init, f)
    cfg_enums: dict = {}
    cfg_vars = [{"path": N.c_string(e.path.encode()), "member": e.c_lvalue, "kind": e.kind,
                 "writable": int(e.writable), "event": event,
                 "checks": _desc_checks(e, cfg_enums)} for e, event in mp.config_vars]
    slots = [{"name": pm.pou.name.upper(), "hash": pm.iface_hash} for pm in mp.programs]
    main = env.get_template("config_main.c.j2").render(
        config=cfg.name, config_lower=cfg.name.lower(), version=__version__,
        source_hash=mp.source_hash, iface_hash=mp.iface_hash, header=gen.header_name,
        image_header="iec_image.h", slots=slots, vars=cfg_vars, nevents=len(mp.single_events),
        enum_sets=_enum_sets(cfg_enums),
        init_decls=f.decls, needs_i=any("for (i = 0;" in ln for ln in init), init=f.pre + init)
    runtime = ["iec_config_rt.c", "iec_ctl.c", "iec_ctl_nl.c", "iec_ctl_sysfs.c", "iec_vars.c"] + \
        _runtime_used([main, image_h], False)
    _write_module(out, mp.config_module, {"main.c": main},
                  ["main.o"] + [f[:-2] + ".o" for f in runtime], [], runtime=runtime)

    # ------------------------------------------------- resource modules
    res_modules = []
    for rm in mp.resources:
        text = _resource_source(env, comp, rm)
        runtime = _runtime_used([text, gen.header], False)
        # REAL-scaled I/O: iec_io_real.c, the module's one FPU object, runs
        # between kernel_fpu_begin() and kernel_fpu_end() (iec_io.c)
        io = _io_of(project.configurations[0], plan, rm.resource)
        fp = ["iec_io_real.c"] if io and io["phys"] else []
        _write_module(out, rm.name, {"main.c": text},
                      ["main.o"] + [f[:-2] + ".o" for f in runtime + fp],
                      [f[:-2] + ".o" for f in fp], runtime=runtime + fp)
        res_modules.append({"name": rm.name, "kind": "resource", "resource": rm.resource.name,
                            "dir": rm.name, "cpu": rm.cpu, **({"uses_fpu": True} if fp else {})})

    manifest = manifest_of(cfg, plan, mp.config_module, prog_modules, res_modules,
                           mp.source_hash, mp.iface_hash)
    manifest["digest"] = manifest_digest(manifest)
    (out / "manifest.json").write_text(manifest_text(manifest))
    modules = [mp.config_module] + [m["name"] for m in prog_modules] + \
        [m["name"] for m in res_modules]
    (out / "Makefile").write_text(_top_makefile())
    (out / "Kbuild").write_text(
        "# SPDX-License-Identifier: GPL-2.0-only OR MIT\n"
        f"# Every module of configuration {cfg.name}; generated by iec2kmod {__version__}.\n"
        + "".join(f"obj-m += {m}/\n" for m in modules))
    return manifest


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


def _resource_source(env, comp, rm):
    project, plan, sel, gen, mp = comp.project, comp.plan, comp.selective, comp.gen, comp.modules
    cfg = project.configurations[0]
    r = rm.resource
    slot_of = mp.slot_of
    single_events = mp.single_events
    res_globals, instances = rm.globals, rm.instances
    ie = InitEmitter(project)
    f = Frame(ie.body_emitter())
    init = []
    for g in res_globals:
        init += ie.lines(f"res_image.{g.c_name}", g.var.type, g.var.init, f)
    for ip in instances:
        init.append(f"{N.pou_prefix(ip.pou)}_init(&{ip.c_name});")
        for member, t, value in ip.config_inits:   # VAR_CONFIG
            init += ie.lines(f"{ip.c_name}.{member}", t, value, f)
        if sel is not None and sel.has_layout(ip.pou) and not sel.instance_selective(ip.inst):
            init.append(f"{ip.c_name}.sel.plain = 1;")
    tasks = []
    pe = comp.emitter
    by_c = _globals_by_c(plan)
    c_of = _global_c_names(plan)
    io = _io_of(cfg, plan, r)
    if io:
        pos = {tp.name.upper(): i for i, tp in enumerate(rm.tasks)}
        for q in io["irqs"]:
            q["tasks"] = [pos[n.upper()] for n in q["tasks"]]
    for tp in rm.tasks:
        used: dict[str, tuple] = {}   # global C name -> (read, write)

        def use(name, read, write):
            a, b = used.get(name, (False, False))
            used[name] = (a or read, b or write)

        for ip in tp.instances:
            inst = ip.inst
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
        # a program runs in its type's module (which decides between the
        # plain and the selective body), on the task's copy of the image;
        # connections' fault sites name the configuration
        run = pe.task_run(
            tp, lambda ip: [f"if (iec2kmod_run_program({slot_of[ip.pou.key]}, &{ip.c_name}, ctx))",
                            "\treturn;"],
            image=lambda c, n=tp.index: f"task{n}_image.{c}", owner=pe.ie.body_emitter().pou)
        io_in = [i for i, b in enumerate(io["binds"] if io else []) if b["input"] and
                 used.get(b["c_name"], (False, False))[0]]
        io_out = [i for i, b in enumerate(io["binds"] if io else []) if not b["input"] and
                  used.get(b["c_name"], (False, False))[1]]
        # the devices each direction uses, each once: a cycle asks only
        # these for their whole-cycle hooks (iec_io.c, struct iec_io_set)
        io_devs = {d: sorted({io["binds"][i]["dev"] for i in idx})
                   for d, idx in (("in", io_in), ("out", io_out))}
        tasks.append({"index": tp.index, "name": tp.name, "interval": tp.interval_ns or 0,
                      "io_in": io_in, "io_out": io_out,
                      "io_in_devs": io_devs["in"], "io_out_devs": io_devs["out"],
                      "priority": tp.priority,
                      "single_event": single_events[id(tp.single.var)] if tp.single else -1,
                      "loop_budget": LOOP_BUDGET, "image": image,
                      "watchdog_ns": tp.watchdog_ns, "watchdog_overruns": tp.watchdog_overruns,
                      "copy_in": copy_in, "copy_out": copy_out, "events": events, "run": run,
                      "slots": sorted({slot_of[ip.pou.key] for ip in tp.instances})})
        for ip in tp.instances:
            for b in ip.bindings:
                init += b.lines(ip.c_name, lambda g, n=tp.index: f"task{n}_image.{g.c_name}")
    _user_owner_tasks(io, tasks)
    # an instance variable belongs to the task that runs its instance (1 + index in tasks[]):
    # the manager writes it between two cycles of that task
    task_no = {t["name"].upper(): n + 1 for n, t in enumerate(tasks)}
    task_of = {ip.path: task_no.get((ip.task or "").upper(), 0) for ip in instances}
    enums: dict = {}
    vars_out = [{"path": N.c_string(e.path.encode()), "lvalue": lv, "kind": e.kind,
                 "writable": int(e.writable), "event": ev, "task": task_of.get(e.owner, 0),
                 "checks": _desc_checks(e, enums)}
                for e, lv, ev in rm.vars]
    return env.get_template("resource_main.c.j2").render(
        resource=r.name, resource_lower=r.name.lower(), config=cfg.name, version=__version__,
        header=gen.header_name, image_header="iec_image.h",
        res_globals=[N.declare(g.var.type, g.c_name) for g in res_globals],
        instances=[f"{N.pou_struct(ip.pou)} {ip.c_name}" for ip in instances], tasks=tasks,
        vars=vars_out, enum_sets=_enum_sets(enums), cpu=rm.cpu, init_decls=f.decls,
        needs_i=any("for (i = 0;" in ln for ln in init), init=f.pre + init,
        source_hash=mp.source_hash, iface_hash=mp.iface_hash,
        unbound_check=unbound_pointer_check(instances), io=io)


# the C enum of iec_io.c for a subdevice kind of the I/O map
_IO_KINDS = {"AI", "AO", "DI", "DO", "DIO"}


def _io_of(cfg, plan, r):
    """The template's view of resource r's I/O map (iec2kmod/iomap.py), or
    None: its devices, and per binding the C lvalue of its located
    variable (a global of the configuration or the resource, or a direct
    address of a program connection)."""
    from ..compilation import CompileError
    from ..iomap import raw_of
    rio = (getattr(cfg, "io", None) or {}).get(r.name.upper())
    if rio is None or not (rio.bindings or rio.interrupts):
        return None
    devs = list(rio.devices.values())
    index = {d.name.upper(): i for i, d in enumerate(devs)}
    by_path = {g.path.upper(): g for g in plan.globals}
    binds = []
    for b in rio.bindings:
        if b.address in plan.directs:
            c_name = plan.directs[b.address][0]
            lvalue = f"iec2kmod_image.{c_name}"
        else:
            g = by_path.get((cfg.addresses.get(b.address) or "").upper())
            if g is None:
                raise CompileError(f"{b.place}: {b.address} is a program's located variable "
                                   f"({cfg.addresses.get(b.address)}): the kernel binds devices "
                                   "to globals and program connections only; declare it in "
                                   "the resource's VAR_GLOBAL")
            c_name = g.c_name
            lvalue = f"res_image.{c_name}" if g.resource else f"iec2kmod_image.{c_name}"
        if b.kind == "USER":
            binds.append(_user_bind(b, index, lvalue, c_name))
            continue
        assert b.kind in _IO_KINDS
        maxdata = 1 if b.scale == "bit" else (1 << b.bits) - 1
        phys = b.scale == "phys"
        if b.safe in (None, "HOLD"):
            safe = 0
        elif phys:      # volts: the sample the kernel writes for them
            safe = raw_of(b.lo, b.hi, b.bits, float(b.safe), b.type)
        else:
            safe = int(b.safe)
        binds.append({"address": b.address, "channel": f"{b.device}.{b.subdevice}.{b.channel}",
                      "dev": index[b.device.upper()], "subdev": b.subdevice, "chan": b.channel,
                      "kind": b.kind, "input": int(b.address[1] == "I"), "range": b.range,
                      "hold": int(b.safe == "HOLD"), "maxdata": maxdata, "safe": safe,
                      "lvalue": lvalue, "c_name": c_name,
                      "signed": int(b.type in ("SINT", "INT", "DINT", "LINT")),
                      "phys": int(phys), "lo": _double_bits(b.lo), "hi": _double_bits(b.hi)})
    irqs = [{"address": q.address, "source": f"{q.device}.{q.source}",
             "dev": index[q.device.upper()], "line": q.irq, "tasks": list(q.tasks)}
            for q in rio.interrupts]
    users = []
    for i, d in enumerate(devs):
        if d.provider != "user":
            continue
        slots = {(b["input"], b["chan"]): b for b in binds if b["dev"] == i}
        users.append({"dev": i, "name": d.name, "node": rio.user_node(d)[len("/dev/"):],
                      "inputs": d.inputs, "outputs": d.outputs, "stale_ms": d.stale_ms,
                      "slots": [(N.c_string(slots[(inp, k)]["address"].encode()),
                                 slots[(inp, k)]["type_code"]) if (inp, k) in slots else
                                ('""', 0)
                                for inp, count in ((1, d.inputs), (0, d.outputs))
                                for k in range(count)]})
    return {"devs": [{"name": d.name, "provider": d.provider, "minor": d.minor,
                      "handle": f"&io_user{i}" if d.provider == "user" else "NULL"}
                     for i, d in enumerate(devs)],
            "binds": binds, "irqs": irqs,
            "comedi": any(d.provider == "comedi" for d in devs), "users": users,
            "phys": any(b["phys"] for b in binds)}


def _user_owner_tasks(io, tasks):
    """A user device is exchanged by one task (its cycle is the device's
    cycle, iec_io_user.c): records it, or refuses two naming both."""
    from ..compilation import CompileError
    for u in (io or {}).get("users", []):
        users = {}
        for t in tasks:
            for i in t["io_in"] + t["io_out"]:
                b = io["binds"][i]
                if b["dev"] == u["dev"]:
                    users.setdefault(t["name"], b)
        if len(users) > 1:
            (t1, b1), (t2, b2) = list(users.items())[:2]
            raise CompileError(f"{b2['place']}: user device '{u['name']}' is exchanged by "
                               f"task {t1} ({b1['address']}, {b1['place']}) and task {t2} "
                               f"({b2['address']}): a user device serves one task; declare "
                               "one device per task")
        owner = next((t for t in tasks if t["name"] in users), None)
        u["interval"] = owner["interval"] if owner else 0
        # a task that writes none of its outputs publishes at its cycles' start
        u["publish_in"] = "false" if owner and any(
            io["binds"][i]["dev"] == u["dev"] for i in owner["io_out"]) else "true"


def _user_bind(b, index, lvalue, c_name):
    """A binding of the user provider (iec_io_user.c): a 32-bit slot.  The
    variable's bits reach the provider unclamped (maxdata U32_MAX, read as
    unsigned); the provider sign-extends and saturates by the slot's type."""
    from ..iomap import USER_TYPES
    if b.safe in (None, "HOLD"):
        safe = 0
    elif b.type == "REAL":
        safe = struct.unpack("<I", struct.pack("<f", float(b.safe)))[0]
    else:
        safe = int(b.safe) & 0xFFFFFFFF
    inp = int(b.address[1] == "I")
    return {"address": b.address, "channel": f"{b.device}.{b.channel}",
            "dev": index[b.device.upper()], "subdev": 0, "chan": b.channel,
            # the kind only tells the direction: the user provider reads no other
            "kind": "DI" if inp else "DO", "input": inp, "range": 0,
            "hold": int(b.safe == "HOLD"), "maxdata": 1 if b.type == "BOOL" else 0xFFFFFFFF,
            "safe": safe, "lvalue": lvalue, "c_name": c_name, "signed": 0, "phys": 0,
            "type_code": USER_TYPES[b.type], "place": b.place}


def _double_bits(x: float) -> str:
    """A double as the C literal of its IEEE bits (a non-FP object holds
    no floating-point constant: iec_io_real.h)."""
    import struct
    return f"0x{struct.unpack('<Q', struct.pack('<d', float(x)))[0]:016x}ULL"


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


