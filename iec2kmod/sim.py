"""`iec2kmod sim`: run a configuration on the host.

The same generated POU C as in the kernel modules, linked with a user-space
scheduler (kmod_templates/sim/sim_main.c) that has a simulated clock: every
periodic task at its INTERVAL, event tasks on the rising edge of their
SINGLE variable, in priority order, deterministically.  Inputs come from a
CSV trace (time, variable, value); outputs go to CSV and VCD."""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
from pathlib import Path

from jinja2 import Environment, FileSystemLoader, StrictUndefined

from . import __version__
from .checks.types import concrete
from .codegen import source_list
from .codegen import cnames as N
from .codegen.body import copy_value
from .codegen.plan import unbound_pointer_check
from .codegen.pou import frame_max, frame_need
from .compilation import Compilation, CompileError
from .execmodel import LOOP_BUDGET
from . import traces
from .traces import TraceError, format_value, read_trace, watch_indexes, write_csv, write_vcd
from .traces import Trace as SimResult
from .located import addresses_of

# the trace functions are traces.py's; sim.<name> stays for its callers
__all__ = ["run", "build", "render_sim", "SimError", "InternalError", "SimResult",
           "format_value", "parse_time", "read_trace", "write_csv", "write_vcd"]


class SimError(Exception):
    """A usage error of `sim` (bad trace, unknown variable): exit 2."""


class InternalError(Exception):
    """The generated C did not compile: a bug of ours."""


def parse_time(text: str) -> int:
    """traces.parse_time; a text that is not a time is a SimError."""
    try:
        return traces.parse_time(text)
    except TraceError as exc:
        raise SimError(str(exc)) from None


def runtime_dir() -> Path:
    from .resources import templates_root
    return templates_root() / "runtime"


def sim_dir() -> Path:
    from .resources import templates_root
    return templates_root() / "sim"


def render_sim(what, selective=None):
    """Generated sources of the simulator: ({file name: text}, plan).
    *what*: a Compilation (or a checked project and *selective* as for
    compilation.selective_plan)."""
    comp = Compilation.of(what, selective)
    project, plan, gen, selective = comp.project, comp.plan, comp.gen, comp.selective
    pe = comp.emitter
    f, init = pe.global_inits()
    for ip in plan.instances:
        init.append(f"{N.pou_prefix(ip.pou)}_init(&{ip.c_name});")
        for member, t, value in ip.config_inits:   # VAR_CONFIG
            init += pe.ie.lines(f"{ip.c_name}.{member}", t, value, f)
        for b in ip.bindings:
            init += b.lines(ip.c_name, lambda g: g.c_name)
        if selective is not None and selective.has_layout(ip.pou) and \
                not selective.instance_selective(ip.inst):
            init.append(f"{ip.c_name}.sel.plain = 1;")

    def call(ip):
        if selective is not None and selective.has_layout(ip.pou):
            run = f"{N.pou_prefix(ip.pou)}_run(&{ip.c_name}, ctx, true);"
        else:
            run = f"{N.pou_prefix(ip.pou)}_body(&{ip.c_name}, ctx);"
        return [run, "if (ctx->fault != IEC_FAULT_NONE)", "\treturn;"]

    tasks = []
    implicit = project.configurations[0].resources[0].node.name is None
    for tp in plan.tasks:
        size = frame_max(sorted({frame_need(ip.pou) for ip in tp.instances}) + ["16U"])
        tasks.append({"index": tp.index, "frame_size": size,
                      "name": tp.name if implicit else f"{tp.resource}.{tp.name}",
                      "interval": tp.interval_ns or 0, "priority": tp.priority,
                      "loop_budget": LOOP_BUDGET, "watchdog_ns": tp.watchdog_ns,
                      "watchdog_overruns": tp.watchdog_overruns,
                      "single": f"&{tp.single.c_name}" if tp.single else "NULL",
                      "body": pe.task_run(tp, call)})
    vars_ = [{"path": N.c_string(e.path.encode()), "addr": f"&{e.c_lvalue}", "kind": e.kind,
              "size": e.size} for e in plan.table]
    pou_files = [{"pou": N.c_string(p.name.encode()), "path": N.c_string(p.src.path.encode())}
                 for p in project.pous.values()]
    env = Environment(loader=FileSystemLoader(str(sim_dir())), undefined=StrictUndefined,
                      keep_trailing_newline=True, trim_blocks=True, lstrip_blocks=True)
    sel_token = sel_owned = None
    if selective is not None:
        from .codegen.selective import token_define
        sel_token = token_define([gen.bodies[k][1] for k in gen.order])
        flags = ["1" if e.owner not in ("global", "direct") else "0" for e in plan.table]
        sel_owned = [", ".join(flags[k:k + 16]) + "," for k in range(0, len(flags), 16)] or \
            ["0,"]
    text = env.get_template("sim_project.c.j2").render(
        sel_token=sel_token, sel_owned=sel_owned,
        config=plan.config, version=__version__, header=gen.header_name,
        bodies=[gen.bodies[k][0] for k in gen.order],
        globals=[N.declare(g.var.type, g.c_name) for g in plan.globals],
        directs=[N.declare(t, c) for c, t in plan.directs.values()],
        instances=[f"{N.pou_struct(ip.pou)} {ip.c_name}" for ip in plan.instances],
        sources=source_list(project),
        init_decls=f.decls, needs_i=any("for (i = 0;" in ln for ln in init),
        init=f.pre + init, tasks=tasks, vars=vars_, pou_files=pou_files,
        unbound_check=unbound_pointer_check(plan.instances),
        # directly represented variables are part of a task's image too: a
        # faulting cycle publishes none of them (the kernel copies nothing out)
        backup=[N.declare(g.var.type, g.c_name) for g in plan.globals] +
        [N.declare(t, c) for c, t in plan.directs.values()],
        save=[copy_value(f"sim_backup.{g.c_name}", g.c_name, g.var.type) for g in plan.globals] +
        [copy_value(f"sim_backup.{c}", c, t) for c, t in plan.directs.values()],
        restore=[copy_value(g.c_name, f"sim_backup.{g.c_name}", g.var.type)
                 for g in plan.globals] +
        [copy_value(c, f"sim_backup.{c}", t) for c, t in plan.directs.values()])
    files = {gen.header_name: gen.header, "sim_project.c": text}
    for key in gen.order:
        name, body = gen.bodies[key]
        files[name] = body
    return files, plan


RUNTIME_SOURCES = ("iec_string.c", "iec_std_fb.c", "iec_math.c", "iec_real.c")
CFLAGS = ["-std=gnu11", "-O1", "-Wall", "-Wextra", "-Werror", "-Wdeclaration-after-statement"]
# The sanitized build (``sim --sanitize``).  gcc's "undefined" group leaves out
# float-cast-overflow, so a REAL -> integer C cast of an out-of-range value
# would go unreported; it is added.  float-divide-by-zero is NOT added: REAL
# division by 0.0 is defined behaviour here (IEEE 754: +-Inf or NaN, no
# fault, kmod_templates/runtime/iec_real.h), the sanitizer would report it.
# -fno-sanitize-recover=all: the first report ends the run (a failure).
SANITIZE_FLAGS = ["-fsanitize=undefined,address,float-cast-overflow",
                  "-fno-sanitize-recover=all", "-g"]


def _compiler():
    cc = os.environ.get("CC", "gcc")
    if shutil.which(cc) is None:
        raise SimError(f"no C compiler '{cc}' found: install gcc (apt-get install gcc)")
    return cc


def _flags(sanitize):
    flags = list(CFLAGS)
    if sanitize:
        flags += SANITIZE_FLAGS
    return flags


def runtime_objects(build_dir: Path, sanitize: bool = False) -> list:
    """The runtime library and the scheduler compiled once per content and
    flags (most of a simulator's compile time); cached beside the builds."""
    cc = _compiler()
    flags = _flags(sanitize)
    h = hashlib.sha256(" ".join([cc, *flags]).encode())
    for src in sorted(list(runtime_dir().glob("*")) + list(sim_dir().glob("*"))):
        if src.is_file():
            h.update(src.name.encode() + src.read_bytes())
    out = build_dir / ("rt-" + h.hexdigest()[:20])
    srcs = [sim_dir() / "sim_main.c"]
    srcs += [runtime_dir() / s for s in RUNTIME_SOURCES if (runtime_dir() / s).exists()]
    objs = [out / (s.stem + ".o") for s in srcs]
    if all(o.exists() for o in objs):
        return objs
    out.mkdir(parents=True, exist_ok=True)
    for src, obj in zip(srcs, objs):
        if obj.exists():
            continue
        tmp = obj.with_suffix(f".{os.getpid()}.tmp")
        cmd = [cc, *flags, "-I", str(runtime_dir()), "-I", str(sim_dir()), "-c", str(src),
               "-o", str(tmp)]
        p = subprocess.run(cmd, capture_output=True, text=True)
        if p.returncode != 0:
            raise InternalError(f"the runtime did not compile ({src.name}): {p.stderr[:2000]}")
        os.replace(tmp, obj)
    return objs


def build(what, build_dir: Path, sanitize: bool = False, selective=None):
    """Compiles the simulator of *what* (a Compilation, or a checked project
    and *selective*: None, True/'all' or 'marked'); returns (executable,
    plan), the executable cached by content."""
    files, plan = render_sim(what, selective)
    objs = runtime_objects(build_dir, sanitize)
    h = hashlib.sha256(__version__.encode() + (b"san" if sanitize else b""))
    for name in sorted(files):
        h.update(name.encode() + files[name].encode())
    for obj in objs:
        h.update(str(obj).encode())
    key = h.hexdigest()[:20]
    out = build_dir / key
    exe = out / "sim"
    if exe.exists():
        return exe, plan
    out.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        (out / name).write_text(text)
    cc = _compiler()
    tmp = f"{exe}.{os.getpid()}.tmp"
    cmd = [cc, *_flags(sanitize), "-I", str(out), "-I", str(runtime_dir()), "-I", str(sim_dir()),
           str(out / "sim_project.c"), *map(str, objs), "-o", tmp, "-lm"]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        first = next((ln for ln in p.stderr.splitlines() if "error" in ln), p.stderr[:200])
        raise InternalError(f"the generated C did not compile ({out}): {first}")
    os.replace(tmp, exe)
    return exe, plan


def run(what, end_ns: int, watch=None, inputs=None, build_dir=None, sanitize=False,
        timeout=600, selective=None) -> SimResult:
    """Runs the simulator of *what* (a Compilation, or a checked project
    and *selective* as for build) from 0 to end_ns of simulated time."""
    build_dir = Path(build_dir or (Path(os.environ.get("IEC2KMOD_CACHE") or
                                        Path.home() / ".cache" / "iec2kmod") / "sim"))
    try:
        exe, plan = build(what, build_dir, sanitize, selective)
    except CompileError as exc:
        raise SimError(str(exc)) from None
    # a located variable may be named by its address (iec2kmod/located.py)
    addresses = addresses_of(getattr(what, "project", what))
    try:
        idx = watch_indexes(plan.table, addresses, watch)
    except TraceError as exc:
        raise SimError(str(exc)) from None
    try:
        events = read_trace(inputs, plan.table, addresses) if inputs else []
    except TraceError as exc:
        raise SimError(str(exc)) from None
    ev_path = exe.parent / f"events.{os.getpid()}.txt"
    with open(ev_path, "w") as fh:
        for t, _, i, kind, value in events:
            fh.write(f"{t} {i} {kind} {value!r}\n" if kind == "f" else f"{t} {i} {kind} {value}\n")
    try:
        p = subprocess.run([str(exe), str(end_ns), str(ev_path), *map(str, idx)],
                           capture_output=True, text=True, timeout=timeout)
    finally:
        ev_path.unlink(missing_ok=True)
    if p.returncode != 0:
        raise InternalError(f"the simulator failed ({p.returncode}): {p.stderr.strip()[:2000]}")
    names = [plan.table[i].path for i in idx]
    pos = {i: k for k, i in enumerate(idx)}
    res = SimResult(names, [], end_ns=end_ns, stderr=p.stderr)
    for line in p.stdout.splitlines():
        tag, _, rest = line.partition(" ")
        if tag == "v":
            t, i, v = rest.split(" ", 2)
            e = plan.table[int(i)]
            res.changes.append((int(t), pos[int(i)], _decode(e, v)))
        elif tag == "f":
            t, task, info = rest.split(" ", 2)
            fault, pou, file, ln = info.rsplit("|", 3)
            res.faults.append((int(t), task, fault, pou, file, int(ln)))
        elif tag == "n":
            task, n = rest.rsplit(" ", 1)
            res.cycles[task] = int(n)
        elif tag == "s":
            task, ev, sk = rest.rsplit(" ", 2)
            res.selective[task] = (int(ev), int(sk))
    return res


def _decode(entry, text):
    if entry.kind == "f":
        return float(text)
    if entry.kind == "s":
        return bytes.fromhex(text[1:]).decode("latin-1")
    if entry.kind == "w":
        h = text[1:]
        return "".join(chr(int(h[k:k + 4], 16)) for k in range(0, len(h), 4))
    if entry.kind == "b":
        return bool(int(text))
    if entry.kind == "e":
        t = concrete(entry.type)
        v = int(text)
        for name, val in t.values.values():
            if val == v:
                return name
        return v
    return int(text)
