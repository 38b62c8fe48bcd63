"""`iec2kmod sim`: run a configuration on the host.

The same generated POU C as in the kernel modules, linked with a user-space
scheduler (kmod_templates/sim/sim_main.c) that has a simulated clock: every
periodic task at its INTERVAL, event tasks on the rising edge of their
SINGLE variable, in priority order, deterministically.  Inputs come from a
CSV trace (time, variable, value); outputs go to CSV and VCD."""

from __future__ import annotations

import csv
import hashlib
import os
import shutil
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

from jinja2 import Environment, FileSystemLoader, StrictUndefined

from . import __version__
from .checks.types import Elementary, EnumT, SubrangeT, concrete
from .codegen import generate, source_list
from .codegen import cnames as N
from .codegen.body import copy_value
from .codegen.plan import PlanEmitter, build_plan, unbound_pointer_check
from .codegen.pou import frame_max, frame_need
from .literals import LiteralError, classify, parse_duration
from .located import addresses_of, name_index


# the same per-cycle loop budget as the kernel's tasks, so that a long loop
# faults in the simulation exactly when it would in the kernel
from .kmod import DEFAULT_LOOP_BUDGET as LOOP_BUDGET  # noqa: E402


class SimError(Exception):
    """A usage error of `sim` (bad trace, unknown variable): exit 2."""


class InternalError(Exception):
    """The generated C did not compile: a bug of ours."""


@dataclass
class SimResult:
    names: list                      # watched IEC paths
    changes: list                    # (t_ns, index into names, value)
    faults: list = field(default_factory=list)   # (t_ns, task, fault, pou, file, line)
    cycles: dict = field(default_factory=dict)   # task -> cycles run
    selective: dict = field(default_factory=dict)  # task -> (blocks evaluated, skipped)
    end_ns: int = 0
    stderr: str = ""                             # the simulator's stderr (sanitizer reports)

    def values_at(self, t_ns=None):
        """Last value of every watched variable at time t (default: the end)."""
        out = {}
        for t, i, v in self.changes:
            if t_ns is not None and t > t_ns:
                break
            out[self.names[i]] = v
        return out


def runtime_dir() -> Path:
    from kmod_templates import ROOT
    return ROOT / "runtime"


def sim_dir() -> Path:
    from kmod_templates import ROOT
    return ROOT / "sim"


def render_sim(project, selective=None):
    """Generated sources of the simulator: {file name: text}, plan.
    *selective*: a codegen.selective.SelectivePlan, or None (plain)."""
    gen = generate(project, selective=selective)
    plan = build_plan(project)
    pe = PlanEmitter(project, plan)
    f, init = pe.global_inits()
    for ip in plan.instances:
        init.append(f"{N.pou_prefix(ip.pou)}_init(&{ip.c_name});")
        for member, t, value in ip.config_inits:   # VAR_CONFIG
            init += pe.ie.lines(f"{ip.c_name}.{member}", t, value, f)
        for b in ip.bindings:
            init += b.lines(ip.c_name, lambda g: g.c_name)
        if selective is not None and selective.has_layout(ip.pou) and \
                not selective.instance_selective(program_instance(project, ip)):
            init.append(f"{ip.c_name}.sel.plain = 1;")
    tasks = []
    for tp in plan.tasks:
        body = []
        for ip in tp.instances:
            cf, lines = pe.connection_inputs(ip)
            block = cf.pre + lines
            if selective is not None and selective.has_layout(ip.pou):
                block.append(f"{N.pou_prefix(ip.pou)}_run(&{ip.c_name}, ctx, true);")
            else:
                block.append(f"{N.pou_prefix(ip.pou)}_body(&{ip.c_name}, ctx);")
            block.append("if (ctx->fault != IEC_FAULT_NONE)")
            block.append("\treturn;")
            block += pe.connection_outputs(ip)
            body.append(f"/* {ip.path} : {ip.pou.name} */")
            if cf.decls:
                body += ["{"] + ["\t" + d for d in cf.decls + block] + ["}"]
            else:
                body += block
        if not body:
            body = ["(void)ctx;"]
        implicit = project.configurations[0].resources[0].node.name is None
        size = frame_max(sorted({frame_need(ip.pou) for ip in tp.instances}) + ["16U"])
        tasks.append({"index": tp.index, "frame_size": size,
                      "name": tp.name if implicit else f"{tp.resource}.{tp.name}",
                      "interval": tp.interval_ns or 0, "priority": tp.priority,
                      "loop_budget": LOOP_BUDGET, "watchdog_ns": tp.watchdog_ns,
                      "watchdog_overruns": tp.watchdog_overruns,
                      "single": f"&{tp.single.c_name}" if tp.single else "NULL", "body": body})
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


def program_instance(project, ip):
    """The checked model's ProgramInstance of an InstancePlan."""
    from .codegen.plan import _qual
    for r in project.configurations[0].resources:
        for inst in r.programs:
            if r.name == ip.resource and _qual(r, inst.name) == ip.path:
                return inst
    raise KeyError(ip.path)


def selective_plan(project, selective):
    """A SelectivePlan for ``--selective[=mode]`` (None or False: plain)."""
    if not selective:
        return None
    from .codegen.selective import SelectivePlan
    if isinstance(selective, SelectivePlan):
        return selective
    return SelectivePlan(project, "all" if selective is True else selective)


def build(project, build_dir: Path, sanitize: bool = False, selective=None) -> Path:
    """Compiles the simulator; returns the executable (cached by content).
    *selective*: None, True/'all' or 'marked' (``--selective``)."""
    files, plan = render_sim(project, selective_plan(project, selective))
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


def parse_time(text: str) -> int:
    """T#1.5s, TIME#100ms, 250ms, 1.5s, or a number of seconds."""
    s = text.strip()
    try:
        if "#" in s:
            kind, value, _ = classify(s)
            if kind != "time":
                raise ValueError
            return value
        for unit in ("ms", "us", "ns", "s", "m", "h", "d"):
            if s.lower().endswith(unit) and s[:-len(unit)].replace(".", "", 1).isdigit():
                return parse_duration(s)
        return round(float(s) * 1e9)
    except (LiteralError, ValueError):
        raise SimError(f"'{text}' is not a time (write T#100ms, 100ms or 0.1)") from None


def value_for(entry, text: str):
    """(kind, value) of an IEC literal for a variable of the table."""
    s = text.strip()
    try:
        t = concrete(entry.type)
        if isinstance(t, EnumT):
            name = s.split("#")[-1].upper()
            if name not in t.values:
                raise ValueError(f"'{s}' is not a value of {t.name}")
            return "i", t.values[name][1]
        sign = 1
        if s[:1] in "+-" and "#" not in s:
            sign, s = (-1 if s[0] == "-" else 1), s[1:].strip()
        kind, value, _ = classify(s)
        if sign < 0 and kind in ("int", "real"):
            value = -value
    except (LiteralError, ValueError, IndexError) as exc:
        raise SimError(f"invalid value '{text}' for {entry.path}: {exc}") from None
    if entry.kind == "f":
        if kind not in ("int", "real"):
            raise SimError(f"{entry.path} is REAL: '{text}' is not a number")
        return "f", float(value)
    if entry.kind in ("s", "w"):
        raise SimError(f"{entry.path}: string inputs are not supported by the simulator")
    if kind == "bool" or (entry.kind == "b" and kind == "int" and value in (0, 1)):
        return "i", int(value)
    if kind in ("int", "time", "date", "tod", "dt"):
        if entry.kind == "b":
            raise SimError(f"{entry.path} is BOOL: '{text}' is not TRUE/FALSE")
        rng = _int_range(entry.type) if kind == "int" else None
        if rng is not None and not rng[0] <= int(value) <= rng[1]:
            # as plc-manager write refuses it: never wrapped silently
            raise SimError(f"invalid value '{text}' for {entry.path}: out of range "
                           f"{rng[0]}..{rng[1]}")
        return "i", int(value)
    raise SimError(f"invalid value '{text}' for {entry.path}")


def _int_range(t):
    """(low, high) of an integer, bit string or subrange type; None otherwise."""
    t = concrete(t)
    if isinstance(t, SubrangeT):
        return t.low, t.high
    return t.range if isinstance(t, Elementary) else None


def read_trace(path: str, plan, addresses=None):
    """Input events from a CSV trace: time,variable,value (header optional);
    a located variable may be named by its address."""
    index = name_index(plan.table, addresses)
    events = []
    try:
        with open(path, newline="") as fh:
            for n, row in enumerate(csv.reader(fh), 1):
                if not row or row[0].strip().startswith("#"):
                    continue
                if n == 1 and row[0].strip().lower() == "time":
                    continue
                if len(row) != 3:
                    raise SimError(f"{path}:{n}: expected time,variable,value")
                i = index.get(row[1].strip().upper())
                if i is None:
                    raise SimError(f"{path}:{n}: unknown variable '{row[1].strip()}'")
                e = plan.table[i]
                if not e.writable:
                    raise SimError(f"{path}:{n}: '{e.path}' cannot be written")
                try:
                    kind, value = value_for(e, row[2])
                    t = parse_time(row[0])
                except SimError as exc:
                    raise SimError(f"{path}:{n}: {exc}") from None
                events.append((t, n, i, kind, value))
    except OSError as exc:
        raise SimError(f"{path}: {exc.strerror}") from None
    events.sort(key=lambda ev: (ev[0], ev[1]))
    return events


def run(project, end_ns: int, watch=None, inputs=None, build_dir=None, sanitize=False,
        timeout=600, selective=None) -> SimResult:
    build_dir = Path(build_dir or (Path(os.environ.get("IEC2KMOD_CACHE") or
                                        Path.home() / ".cache" / "iec2kmod") / "sim"))
    exe, plan = build(project, build_dir, sanitize, selective)
    addresses = addresses_of(project)
    index = name_index(plan.table, addresses)
    if watch:
        idx = []
        for w in watch:
            i = index.get(w.strip().upper())
            if i is None:
                raise SimError(f"unknown variable '{w}' (see `iec2kmod sim --list`)")
            if i not in idx:         # an address and its name are one variable
                idx.append(i)
    else:
        idx = [i for i, e in enumerate(plan.table) if e.owner == "global" or e.owner == "direct"]
    events = read_trace(inputs, plan, addresses) if inputs else []
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


def format_value(entry_type, v):
    if isinstance(v, bool):
        return "TRUE" if v else "FALSE"
    return str(v)


def write_csv(res: SimResult, path):
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["time_ns"] + res.names)
        cur = [""] * len(res.names)
        i = 0
        ch = res.changes
        while i < len(ch):
            t = ch[i][0]
            while i < len(ch) and ch[i][0] == t:
                cur[ch[i][1]] = format_value(None, ch[i][2])
                i += 1
            w.writerow([t] + cur)


def write_vcd(res: SimResult, path, plan=None):
    ids = [_vcd_id(k) for k in range(len(res.names))]
    kinds = {}
    if plan is not None:
        by_path = {e.path: e for e in plan.table}
        kinds = {n: by_path[n] for n in res.names if n in by_path}
    with open(path, "w") as fh:
        fh.write(f"$date iec2kmod sim $end\n$version iec2kmod {__version__} $end\n"
                 "$timescale 1ns $end\n$scope module plc $end\n")
        for n, vid in zip(res.names, ids):
            e = kinds.get(n)
            if e is not None and e.kind == "b":
                fh.write(f"$var wire 1 {vid} {_vcd_name(n)} $end\n")
            elif e is not None and e.kind == "f":
                fh.write(f"$var real 64 {vid} {_vcd_name(n)} $end\n")
            elif e is not None and e.kind in ("s", "w"):
                fh.write(f"$var string 1 {vid} {_vcd_name(n)} $end\n")
            else:
                bits = e.size * 8 if e is not None else 64
                fh.write(f"$var integer {bits} {vid} {_vcd_name(n)} $end\n")
        fh.write("$upscope $end\n$enddefinitions $end\n")
        last_t = None
        for t, i, v in res.changes:
            if t != last_t:
                fh.write(f"#{t}\n")
                last_t = t
            e = kinds.get(res.names[i])
            if isinstance(v, bool):
                fh.write(f"{int(v)}{ids[i]}\n")
            elif isinstance(v, float):
                fh.write(f"r{v!r} {ids[i]}\n")
            elif isinstance(v, str) and (e is None or e.kind != "e"):
                fh.write(f"s{v.replace(' ', '_') or '_'} {ids[i]}\n")
            elif isinstance(v, str):
                fh.write(f"s{v} {ids[i]}\n")
            else:
                bits = e.size * 8 if e is not None else 64
                fh.write(f"b{v & ((1 << bits) - 1):b} {ids[i]}\n")
        fh.write(f"#{res.end_ns}\n")


def _vcd_id(k):
    chars = [chr(c) for c in range(33, 127)]
    out = ""
    k += 1
    while k:
        k, r = divmod(k - 1, len(chars))
        out = chars[r] + out
    return out


def _vcd_name(n):
    return n.replace("[", "(").replace("]", ")").replace(",", "_").replace("%", "")
