"""The configuration plan: where every global, program instance and task
lives in C, and the variable table that the simulator and the manager use
to read and write variables by IEC name.  Shared by `iec2kmod sim` and the
kernel module generator."""

from __future__ import annotations

from dataclasses import dataclass, field

from .. import ast
from ..checks.symbols import Each, POUInfo, Var
from ..checks.types import (ArrayT, EnumT, FBType, StringT, StructT, SubrangeT,
                            concrete)
from ..execmodel import MAX_TABLE_ELEMENTS, element_path, kind_of
from . import cnames as N
from .body import BodyEmitter, copy_value
from .expr import BindingError, Frame, Raw
from .pou import InitEmitter, pointer_members


@dataclass
class GlobalPlan:
    path: str            # IEC name as the user writes it: 'level' or 'r1.local'
    c_name: str          # C object: g_level, g_r1_local
    var: Var
    resource: str | None


@dataclass
class InstancePlan:
    path: str            # r1.p1
    c_name: str          # inst_r1_p1
    pou: POUInfo
    resource: str
    task: str | None
    inputs: list = field(default_factory=list)    # (member C lvalue, IEC type, value AST)
    outputs: list = field(default_factory=list)   # (global C lvalue, member, IEC type)
    externals: list = field(default_factory=list) # (member, global C name, is array)
    bindings: list = field(default_factory=list)  # [PointerBinding], complete (check_bindings)
    config_inits: list = field(default_factory=list)  # (member path, IEC type, init AST)
    inst: object = None  # the checked model's ProgramInstance (checks/config.py)


@dataclass
class PointerBinding:
    """One pointer member of a program instance, at any depth, and what it
    points to.  ``member`` is its C path from the instance with ``[*]`` for
    every element of an array (``counts`` gives their sizes); the target is a
    global (``target``) or a VAR_GLOBAL member of the program itself
    (``program_member``)."""
    iec_path: str
    member: str
    counts: tuple
    target: GlobalPlan | None
    program_member: str | None
    is_array: bool

    def lines(self, inst_c: str, global_expr) -> list[str]:
        """C statements that set the pointer in instance *inst_c*;
        global_expr(GlobalPlan) is where a global lives for that code."""
        if self.target is not None:
            obj = global_expr(self.target)
        else:
            obj = f"{inst_c}.{self.program_member}"
        value = obj if self.is_array else f"&{obj}"
        return _each_loops(f"{inst_c}.{self.member}", self.counts, f" = {value};")


@dataclass
class TaskPlan:
    name: str
    resource: str
    index: int
    interval_ns: int | None
    priority: int
    single: GlobalPlan | None
    instances: list = field(default_factory=list)
    watchdog_ns: int = 0          # see checks/tasks.py
    watchdog_overruns: int = 0


@dataclass
class TableEntry:
    path: str            # IEC path: level, r1.p1.count, r1.p1.arr[2], r1.p1.t.ET
    c_lvalue: str
    type: object
    kind: str            # b (BOOL) i (signed) u (unsigned, bit strings) f (real) t (time-like)
                         # e (enumeration) s (STRING) w (WSTRING)
    size: int
    writable: bool
    owner: str           # 'global' or the instance path


@dataclass
class Plan:
    config: str
    globals: list
    instances: list
    tasks: list
    table: list
    located: list        # (address, GlobalPlan)
    directs: dict        # address used in a connection -> (C name, IEC type)


def _c_ident(*parts):
    return "_".join(p.lower() for p in parts if p)


def build_plan(project) -> Plan:
    cfg = project.configurations[0]
    globals_: list[GlobalPlan] = []
    by_var: dict[int, GlobalPlan] = {}
    for v in cfg.globals.values():
        g = GlobalPlan(v.name, "g_" + _c_ident(v.name), v, None)
        globals_.append(g)
        by_var[id(v)] = g
    for r in cfg.resources:
        for v in r.globals.values():
            g = GlobalPlan(r.path(v.name), "g_" + _c_ident(r.name, v.name), v, r.name)
            globals_.append(g)
            by_var[id(v)] = g
    instances, tasks = [], []
    directs: dict = {}
    for r in cfg.resources:
        rtasks = {}
        for t in r.tasks.values():
            tp = TaskPlan(t.name, r.name, len(tasks), t.interval_ns, t.priority,
                          by_var.get(id(t.single)) if t.single else None,
                          watchdog_ns=t.watchdog_ns, watchdog_overruns=t.watchdog_overruns)
            tasks.append(tp)
            rtasks[t.name.upper()] = tp
        for inst in r.programs:
            ip = InstancePlan(r.path(inst.name), "inst_" + _c_ident(r.name, inst.name),
                              inst.pou, r.name, inst.task.name if inst.task else None,
                              inst=inst)
            for key, g in inst.externals.items():
                ext = inst.pou.vars[key]
                ip.externals.append((N.var(ext.name), by_var[id(g)].c_name,
                                     isinstance(ext.type, ArrayT)))
            for b in inst.bindings:
                ip.bindings.append(_pointer_binding(ip, b, by_var))
            check_bindings(ip)
            for param, value in inst.inputs:
                ip.inputs.append((N.var(param.name), param.type, value))
                if isinstance(value, ast.Direct):
                    directs[value.address] = (_direct_c_name(value.address), param.type)
            for param, target in inst.outputs:
                if isinstance(target, ast.Ref):
                    ip.outputs.append((by_var[id(target.symbol)].c_name, N.var(param.name),
                                       param.type))
                else:
                    directs[target.address] = (_direct_c_name(target.address), param.type)
                    ip.outputs.append((_direct_c_name(target.address), N.var(param.name),
                                       param.type))
            instances.append(ip)
            if inst.task is not None:
                rtasks[inst.task.name.upper()].instances.append(ip)
    by_inst = {(ip.resource, ip.path): ip for ip in instances}
    for r, inst, chain, init in cfg.config_inits:
        member = N.var(chain[0].name)
        for outer, v in zip(chain, chain[1:]):
            member += "." + N.member(outer.type.pou, v.name)
        by_inst[(r.name, r.path(inst.name))].config_inits.append(
            (member, chain[-1].type, init))
    located = [(g.var.location, g) for g in globals_ if g.var.location]
    table = variable_table(globals_, instances)
    for address, (c_name, t) in sorted(directs.items()):
        table.append(TableEntry(address, c_name, t, kind_of(t), _size(t),
                                address[1] != "Q", "direct"))
    return Plan(cfg.name, globals_, instances, tasks, table, located, directs)


def _pointer_binding(ip, b, by_var) -> PointerBinding:
    member, iec, counts = [], [ip.path], []
    for step in b.steps:
        if isinstance(step, Each):
            member.append("[*]")
            iec.append("[*]")
            counts.append(step.count)
        elif isinstance(step, str):
            member.append("." + N.var(step))
            iec.append("." + step)
        else:
            name = N.temp_proto(step.name) if step.section == "VAR_TEMP" else N.var(step.name)
            member.append(("." if member else "") + name)
            iec.append("." + step.name)
    pointer = b.steps[-1]
    target = None if b.in_program else by_var[id(b.target)]
    return PointerBinding("".join(iec), "".join(member), tuple(counts), target,
                          N.var(b.target.name) if b.in_program else None,
                          isinstance(pointer.type, ArrayT))


def check_bindings(ip: InstancePlan) -> None:
    """Every pointer member of the instance's struct has exactly one binding
    (the wrong state, an instance running with a NULL pointer, cannot be
    generated)."""
    want = {c: counts for c, _, counts in pointer_members(ip.pou)}
    have = [b.member for b in ip.bindings]
    missing = sorted(set(want) - set(have))
    extra = sorted(set(have) - set(want))
    twice = sorted({m for m in have if have.count(m) > 1})
    wrong = sorted(b.member for b in ip.bindings if b.member in want and
                   want[b.member] != b.counts)
    if missing or extra or twice or wrong:
        raise BindingError(f"instance {ip.path}: pointer members without a binding: "
                           f"{missing}, bindings without a pointer member: {extra}, bound "
                           f"twice: {twice}, element counts differ: {wrong}")


def _each_loops(lvalue: str, counts, tail: str) -> list[str]:
    """``lvalue + tail`` for every element where lvalue has ``[*]`` (one
    loop per ``[*]``, b0, b1 ... as indexes, in a block of its own)."""
    if not counts:
        return [lvalue + tail]
    idx = [f"b{k}" for k in range(len(counts))]
    for k in idx:
        lvalue = lvalue.replace("[*]", f"[{k}]", 1)
    lines = ["{", f"\tiec_u32 {', '.join(idx)};"]
    for depth, (k, n) in enumerate(zip(idx, counts)):
        lines.append("\t" * (depth + 1) + f"for ({k} = 0; {k} < {n}; {k}++)")
    lines.append("\t" * (len(counts) + 1) + lvalue + tail)
    lines.append("}")
    return lines


def unbound_pointer_check(instances, inst_c=lambda ip: ip.c_name) -> list[str]:
    """Body of a C function returning the IEC path of the first pointer
    member that is NULL after initialisation, or NULL: the run-time side of
    check_bindings(), derived from the struct layout alone."""
    lines = []
    for ip in instances:
        for member, iec, counts in pointer_members(ip.pou):
            body = _each_loops(f"{inst_c(ip)}.{member}", counts, "")
            test = body[-2] if counts else body[0]
            indent = test[:len(test) - len(test.lstrip("\t"))]
            cond = [f"{indent}if (!{test.strip()})",
                    f"{indent}\treturn {N.c_string(f'{ip.path}.{iec}'.encode())};"]
            if counts:
                body[-2:-1] = cond
            else:
                body = cond
            lines += body
    lines.append("return NULL;")
    return lines


def _direct_c_name(address: str) -> str:
    return "d_" + address[1:].replace(".", "_").replace("*", "x").lower()


def _size(t) -> int:
    t = concrete(t)
    if isinstance(t, SubrangeT):
        t = t.elem
    if isinstance(t, EnumT):
        return N.enum_base(t).bits // 8
    if isinstance(t, StringT):
        return 0
    return max(1, t.bits // 8)


def _expand(path, lvalue, t, writable, owner, out, budget):
    """Table entries of a variable and, for arrays/structs/FBs, its parts."""
    if len(out) >= budget:
        return
    k = kind_of(t)
    if k is not None:
        out.append(TableEntry(path, lvalue, t, k, _size(t), writable, owner))
        return
    t = concrete(t)
    if isinstance(t, ArrayT):
        elem, count = N.array_flat(t)
        # list the flat elements with their IEC indexes
        cur = t
        dims = []
        while isinstance(cur, ArrayT):
            dims += cur.dims
            cur = cur.elem
        for n in range(min(count, MAX_TABLE_ELEMENTS)):
            _expand(element_path(path, dims, n), f"{lvalue}[{n}]", elem, writable, owner, out,
                    budget)
        return
    if isinstance(t, StructT):
        for fname, ft, _ in t.fields.values():
            _expand(f"{path}.{fname}", f"{lvalue}.{N.var(fname)}", ft, writable, owner, out,
                    budget)
        return
    if isinstance(t, FBType):
        pou = t.pou
        for v in pou.vars.values():
            if v.section in ("VAR_INPUT", "VAR_OUTPUT") or (not pou.standard and
                                                             v.section == "VAR"):
                _expand(f"{path}.{v.name}", f"{lvalue}.{N.member(pou, v.name)}", v.type,
                        writable and v.section != "VAR_OUTPUT" and v.step is None, owner, out,
                        budget)


def variable_table(globals_, instances) -> list[TableEntry]:
    out: list[TableEntry] = []
    for g in globals_:
        _expand(g.path, g.c_name, g.var.type, not g.var.constant, "global", out,
                len(out) + 4096)
    for ip in instances:
        for v in ip.pou.vars.values():
            if v.section in ("VAR_EXTERNAL", "VAR_IN_OUT", "VAR_TEMP"):
                continue
            # an SFC step changes only by its transitions: read-only
            _expand(f"{ip.path}.{v.name}", f"{ip.c_name}.{N.var(v.name)}", v.type,
                    not v.constant and v.step is None, ip.path, out, len(out) + 4096)
    return out


class PlanEmitter:
    """C statements for globals' initial values and program connections."""

    def __init__(self, project, plan):
        self.project = project
        self.plan = plan
        self.ie = InitEmitter(project, POUInfo("PROGRAM", "<configuration>"))
        self.by_var = {id(g.var): g for g in plan.globals}

    def global_inits(self):
        f = Frame(self.ie.body_emitter())
        lines = []
        for g in self.plan.globals:
            lines += self.ie.lines(g.c_name, g.var.type, g.var.init, f)
        return f, lines

    def connection_inputs(self, ip: InstancePlan, image=lambda c_name: c_name, owner=None):
        """Statements copying connected values into a program instance:
        (Frame, lines).  *image*(C name) is where a global or a directly
        represented variable is read (the simulator: the object itself; a
        kernel task: its copy in the task's image); *owner* the POUInfo the
        statements' fault sites name (default: the program's)."""
        be = BodyEmitter(owner or POUInfo("PROGRAM", ip.pou.name, src=ip.pou.src))
        f = Frame(be)
        lines = []
        for member, t, value in ip.inputs:
            dst = f"{ip.c_name}.{member}"
            if isinstance(value, ast.Ref) and id(value.symbol) in self.by_var:
                src = image(self.by_var[id(value.symbol)].c_name)
                lines += be.assign_code(f, dst, t, Raw(src, value.symbol.type))
            elif isinstance(value, ast.Direct):
                lines += be.assign_code(f, dst, t, Raw(image(_direct_c_name(value.address)), t))
            else:
                lines += be.assign_code(f, dst, t, value)
        return f, lines

    @staticmethod
    def connection_outputs(ip: InstancePlan, image=lambda c_name: c_name):
        return [copy_value(image(gname), f"{ip.c_name}.{member}", t)
                for gname, member, t in ip.outputs]

    def task_run(self, tp: TaskPlan, call, image=lambda c_name: c_name, owner=None):
        """The body of task *tp*'s run function: for each program instance,
        in order, its connected inputs copied in, *call*(ip) (the lines
        that run it and return on a fault), its outputs copied out;
        *image* and *owner* as for connection_inputs."""
        body = []
        for ip in tp.instances:
            cf, lines = self.connection_inputs(ip, image, owner)
            block = cf.pre + lines + call(ip) + self.connection_outputs(ip, image)
            body.append(f"/* {ip.path} : {ip.pou.name} */")
            body += (["{"] + ["\t" + d for d in cf.decls + block] + ["}"]) if cf.decls else block
        return body or ["(void)ctx;"]
