"""Pass 'configure': configurations, resources and program instances, their
connections, VAR_EXTERNAL matched against globals, access paths and
VAR_CONFIG.

``ConfigChecker`` walks each configuration; two parts of it are mixed in,
each in its file, on the state it sets up: the tasks (checks/tasks.py
``TaskChecks``: INTERVAL, PRIORITY, SINGLE, the watchdog pragma) and the
rules of located variables (checks/located.py ``LocatedRules``: an address
is accessed by one variable of one resource)."""

from __future__ import annotations

from .. import ast
from .body import BodyChecker
from . import fold
from .consts import ConstError, same_value
from .eno import fb_eno
from .located import LocatedRules, check_address_type
from .symbols import Binding, ConfigInfo, Each, POUInfo, ProgramInstance, ResourceInfo
from .tasks import TaskChecks
from .types import ERROR, ArrayT, ErrorT, FBType, StructT, SubrangeT, assignable, identical


class _Scope:
    """The globals in scope, innermost first, looked up through the layers
    instead of copied: a copy of every global per program instance made the
    configure pass quadratic (10,000 instances and 130,000 globals: 41 s)."""

    __slots__ = ("names", "outer")

    def __init__(self, names, outer=None):
        self.names = names
        self.outer = outer

    def get(self, key):
        s = self
        while s is not None:
            v = s.names.get(key)
            if v is not None:
                return v
            s = s.outer
        return None

class ConfigChecker(TaskChecks, LocatedRules):
    def __init__(self, project, declarer, diags):
        self.p = project
        self.decl = declarer
        self.diags = diags
        self.watchdogs_used = set()        # (path, offset) of the pragmas read
        # address -> [(owner description, resource name or None, src, pos)]
        self.addresses: dict = {}
        self.reported_externals: set = set()
        # program type key -> (instance name, its place) of the instance
        # that owns the type's located variables
        self.located_owner: dict = {}
        # address -> IEC path of its variable (ConfigInfo.addresses)
        self.paths: dict = {}
        self.completed: set = set()         # upper paths VAR_CONFIG locates

    def error(self, src, pos, msg):
        self.diags.error(src, pos, msg)

    def warning(self, src, pos, msg):
        self.diags.warning(src, pos, msg)

    def check(self, units):
        names = {}
        for unit in units:
            for node in unit.configurations:
                key = node.name.upper()
                if key in names:
                    self.error(node.src, node.pos, f"configuration '{node.name}' is already "
                                                   "defined")
                    continue
                names[key] = node
                self.p.configurations.append(self.configuration(node))
        self.unused_watchdogs(units)
        if len(self.p.configurations) > 1:
            c = self.p.configurations[1]
            self.error(c.src, c.node.pos, "only one configuration per project: iec2kmod runs "
                                          "one configuration at a time")

    # ---------------------------------------------------------------
    def configuration(self, node) -> ConfigInfo:
        scope = self.decl.config_scope(node)
        with self.decl.constants_of(scope):
            cfg = self._configuration(node)
        self.decl.mark_used(scope, cfg.globals)
        return cfg

    def _configuration(self, node) -> ConfigInfo:
        src = node.src
        cfg = ConfigInfo(node.name, node, src)
        for block in node.blocks:
            if block.kind != "VAR_GLOBAL":
                self.error(src, block.pos, f"{block.kind} is not allowed here: a configuration "
                                           "declares VAR_GLOBAL, VAR_ACCESS and VAR_CONFIG")
                continue
            for v in self.decl.declare_block(block, cfg, src, cfg.globals, allow_located=True):
                self.note_address(v, None, src)
                if v.location:
                    self.paths.setdefault(v.location, v.name)
        res_names = {}
        for rnode in node.resources:
            r = self.resource(rnode, cfg)
            key = (r.name or "").upper()
            if key in res_names:
                self.error(src, rnode.pos, f"resource '{r.name}' is already defined")
                continue
            res_names[key] = r
            cfg.resources.append(r)
        for block in node.access:
            if block.kind == "VAR_GLOBAL":
                self.error(src, block.pos, "VAR_GLOBAL must come before the resources")
            elif block.kind == "VAR_ACCESS":
                self.access(block, cfg)
            elif block.kind == "VAR_CONFIG":
                self.var_config(block, cfg)
            else:
                self.error(src, block.pos, f"{block.kind} is not allowed in a configuration")
        self.check_address_rules(src)
        self.check_completed(cfg)
        cfg.addresses = {a: p for a, p in self.paths.items() if not a.endswith("*")}
        # address -> (type, resources declaring or using it), for the I/O map
        cfg.located = {a: (e[0][6], frozenset(e[0][5] | ({e[0][1]} if e[0][1] else set())))
                       for a, e in self.addresses.items() if not a.endswith("*")}
        return cfg

    def resource(self, rnode, cfg) -> ResourceInfo:
        scope = self.decl.scope_of([b for b in rnode.blocks if b.kind == "VAR_GLOBAL"],
                                   cfg.src, outer=self.decl._const_scope)
        with self.decl.constants_of(scope):
            r = self._resource(rnode, cfg)
        self.decl.mark_used(scope, r.globals)
        self.decl._const_scope.used |= {k for k in scope.used if k not in r.globals}
        return r

    def _resource(self, rnode, cfg) -> ResourceInfo:
        src = cfg.src
        r = ResourceInfo(rnode.name or cfg.name, rnode.processor, rnode)
        for block in rnode.blocks:
            if block.kind != "VAR_GLOBAL":
                self.error(src, block.pos, f"{block.kind} is not allowed in a resource")
                continue
            for v in self.decl.declare_block(block, r, src, r.globals, allow_located=True):
                if v.key in cfg.globals:
                    self.warning(src, v.pos, f"resource global '{v.name}' hides the "
                                             "configuration global of the same name")
                self.note_address(v, r.name, src)
                if v.location:
                    self.paths.setdefault(v.location, r.path(v.name))
        for t in rnode.tasks:
            if t.name.upper() in r.tasks:
                self.error(src, t.pos, f"task '{t.name}' is already defined")
                continue
            r.tasks[t.name.upper()] = self.task(t, r, cfg)
        inst_names = set()
        for pc in rnode.programs:
            if pc.name.upper() in inst_names:
                self.error(src, pc.pos, f"program instance '{pc.name}' is already defined")
                continue
            inst_names.add(pc.name.upper())
            inst = self.program_instance(pc, r, cfg)
            if inst is not None:
                r.programs.append(inst)
        return r

    def program_instance(self, pc, r, cfg):
        src = cfg.src
        pou = self.p.pous.get(pc.type.upper())
        task = None
        if pc.task is not None:
            task = r.tasks.get(pc.task.upper())
            if task is None:
                self.error(src, pc.task_pos, f"unknown task '{pc.task}' in resource '{r.name}'")
        if pou is None or pou.kind != "PROGRAM":
            if pou is None:
                self.error(src, pc.type_pos, f"unknown program type '{pc.type}'")
            else:
                self.error(src, pc.type_pos, f"'{pc.type}' is a "
                                             f"{pou.kind.lower().replace('_', ' ')}, not a program")
            return None
        if task is None and pc.task is None:
            self.error(src, pc.pos, f"program instance '{pc.name}' has no task: associate it "
                                    "WITH a TASK so the resource knows when to run it")
        inst = ProgramInstance(pc.name, pou, task, pc)
        seen = set()
        for conn in pc.connections:
            param = pou.var(conn.name)
            if conn.name.upper() in seen:
                self.error(src, conn.pos, f"'{conn.name}' is connected twice")
                continue
            seen.add(conn.name.upper())
            if param is not None and param.section == "VAR_IN_OUT" and conn.direction == "in":
                self.inout_connection(conn, param, r, cfg, inst)
                continue
            want = "VAR_INPUT" if conn.direction == "in" else "VAR_OUTPUT"
            if param is None or param.section != want:
                kind = "input" if conn.direction == "in" else "output"
                self.error(src, conn.pos, f"program '{pou.name}' has no {kind} '{conn.name}'")
                continue
            self.connection(conn, param, r, cfg, inst)
        for v in pou.inouts:
            if v.key not in seen:
                self.error(src, pc.pos, f"VAR_IN_OUT '{v.name}' of program '{pou.name}' must be "
                                        f"connected to a global variable ({v.name} := ...)")
        self.bind_externals(pou, r, cfg, inst, src)
        self.program_located(pou, inst, pc, r, src)
        return inst

    def inout_connection(self, conn, param, r, cfg, inst):
        """A program's VAR_IN_OUT refers to a whole global of its type."""
        src = cfg.src
        value = conn.value
        g = None
        if isinstance(value, ast.Ref) and not value.accessors:
            g = self.visible(r, cfg, value.name)
            if g is None:
                self.error(src, value.pos, f"unknown global variable '{value.name}'")
                return
        if g is None:
            self.error(src, value.pos, f"VAR_IN_OUT '{param.name}' must be connected to a "
                                       "global variable")
            return
        if not _same_type(g.type, param.type):
            self.error(src, value.pos, f"VAR_IN_OUT '{param.name}' is {param.type.name}; "
                                       f"'{g.name}' is {g.type.name}")
            return
        if g.constant:
            self.error(src, value.pos, f"cannot connect VAR_IN_OUT '{param.name}' to "
                                       f"constant '{g.name}'")
            return
        g.used = True
        if param.assigned:
            g.assigned = True
        value.symbol = g
        value.type = g.type
        self.note_global_use(g, r, src, value.pos)
        inst.bindings.append(Binding((param,), g))

    def visible(self, r, cfg, name):
        return r.globals.get(name.upper()) or cfg.globals.get(name.upper())

    def connection(self, conn, param, r, cfg, inst):
        src = cfg.src
        value = conn.value
        if isinstance(value, ast.Direct):
            self.note_direct(value.address, r.name, src, value.pos,
                             f"connection of {inst.name}.{conn.name}", typ=param.type)
            check_address_type(self.decl, src, value.pos, value.address, param.type)
        elif conn.direction == "out":
            if not isinstance(value, ast.Ref) or value.accessors:
                self.error(src, value.pos, "an output must be connected to a global variable "
                                           "or a direct address")
                return
            g = self.visible(r, cfg, value.name)
            if g is None:
                self.error(src, value.pos, f"unknown global variable '{value.name}'")
                return
            if g.constant:
                self.error(src, value.pos, f"cannot connect output to constant '{g.name}'")
            g.used = g.assigned = True
            value.symbol = g
            value.type = g.type
            self.note_global_use(g, r, src, value.pos)
            if not assignable(param.type, g.type):
                self.error(src, value.pos, f"output '{param.name}' is {param.type.name}; "
                                           f"'{g.name}' is {g.type.name}")
        else:
            t = self.connection_value_type(value, r, cfg)
            if t is None:
                return
            if not isinstance(t, ErrorT) and not assignable(t, param.type):
                self.error(src, value.pos, f"input '{param.name}' is {param.type.name}; the "
                                           f"value is {t.name}")
            elif isinstance(value, (ast.UnOp, ast.BinOp)):
                # a constant expression: the value its assignment to the input
                # stores (p (r := 7 / 2), r an LREAL: 3.5), as an initial value
                typed = self.decl.assigned(value, param.type, src)
                if typed is not None and not same_value(typed[0], value.const, param.type):
                    lit = self.decl.folded(typed[0], value, param.type)
                    if lit is not None:
                        lit.type = param.type.base if isinstance(param.type, SubrangeT) \
                            else param.type
                        lit.const = fold.literal(lit)
                        value = conn.value = lit
        (inst.inputs if conn.direction == "in" else inst.outputs).append((param, value))

    def connection_value_type(self, value, r, cfg):
        src = cfg.src
        if isinstance(value, ast.Ref):
            if value.accessors:
                self.error(src, value.pos, "connect a whole global variable")
                return None
            g = self.visible(r, cfg, value.name)
            if g is not None:
                g.used = True
                value.symbol = g
                value.type = g.type
                self.note_global_use(g, r, src, value.pos)
                return g.type
            hits = self.decl.enum_values.get(value.name.upper(), [])
            if len(hits) == 1:
                value.type = hits[0]
                return hits[0]
            self.error(src, value.pos, f"unknown global variable '{value.name}'")
            return None
        try:
            self.decl.const_value(value, src, "connection")
        except ConstError:
            if not (isinstance(value, ast.Lit) and value.kind in ("string", "wstring")):
                self.error(src, value.pos, "an input must be connected to a global variable, a "
                                           "direct address or a constant")
                return None
        fake = POUInfo("PROGRAM", "<connection>", src=src)
        checker = BodyChecker(self.p, self.decl, self.diags, fake)
        t = checker.expr(value)
        checker.settle_roots()
        return t

    # ------------------------------------------------------- externals
    def bind_externals(self, pou, r, cfg, inst, src):
        """VAR_EXTERNAL of the program and of every FB instance inside it, at
        every depth (also in arrays and structures), must match a global of
        the same name and type in scope; each becomes a Binding of the
        instance, so the code generator has the complete list of pointer
        members to set when the instance is initialised."""
        self._bind(pou, _Scope(r.globals, _Scope(cfg.globals)), r, inst, frozenset(), src, ())

    def _bind(self, pou, scope, r, inst, stack, src, steps):
        if pou.key in stack:
            return  # recursion is reported by the call-graph check
        stack = stack | {pou.key}
        for v in pou.vars.values():
            if v.section == "VAR_EXTERNAL":
                g = scope.get(v.key)
                if g is None:
                    if (id(v), r.name) in self.reported_externals:
                        continue
                    self.reported_externals.add((id(v), r.name))
                    self.error(v.src, v.pos, f"VAR_EXTERNAL '{v.name}' has no matching global "
                                             f"variable in resource '{r.name}' (used by "
                                             f"program instance '{inst.name}')")
                    continue
                if not _same_type(g.type, v.type):
                    self.error(v.src, v.pos, f"VAR_EXTERNAL '{v.name}' is {v.type.name} but the "
                                             f"global is {g.type.name}")
                    continue
                if g.constant and not v.constant:
                    self.error(v.src, v.pos, f"global '{g.name}' is CONSTANT: declare the "
                                             "external VAR_EXTERNAL CONSTANT")
                g.used = True
                if v.assigned:
                    g.assigned = True
                if not steps:
                    inst.externals[v.key] = g
                inst.bindings.append(Binding(steps + (v,), g,
                                             in_program=g.section == "VAR_GLOBAL" and
                                             any(g is w for w in inst.pou.vars.values())))
                self.note_global_use(g, r, src, None)
        own = {v.key: v for v in pou.vars.values() if v.section == "VAR_GLOBAL"}
        inner = _Scope(own, scope) if own else scope
        for v in pou.vars.values():
            if v.section in ("VAR_EXTERNAL", "VAR_IN_OUT"):
                continue   # a reference to an instance that is bound where it lives
            for sub, fb in fb_slots(v.type, steps + (v,)):
                self._bind(fb, inner, r, inst, stack, src, sub)

    # ------------------------------------------------ access, VAR_CONFIG
    def access(self, block, cfg):
        src = cfg.src
        names = set()
        for d in block.decls:
            if d.name.upper() in names:
                self.error(src, d.pos, f"access path '{d.name}' is already declared")
                continue
            names.add(d.name.upper())
            t = self.decl.type_of_spec(d.spec, src)
            target = self.resolve_path(d.path, cfg, src, d.pos)
            if target is not None and t is not ERROR and not _same_type(target.type, t):
                self.error(src, d.pos, f"access path '{d.name}' is declared {t.name} but "
                                       f"{d.path} is {target.type.name}")
            if target is not None and d.direction == "READ_WRITE" and target.constant:
                self.error(src, d.pos, f"{d.path} is CONSTANT: its access path must be "
                                       "READ_ONLY")
            cfg.access.append((d.name, d.path, target, d.direction))

    def resolve_path(self, path, cfg, src, pos):
        """A.B.C: configuration global, resource.global, or
        resource.instance.variable (or instance.variable)."""
        if path.startswith("%"):
            for entry in self.addresses.get(path, []):
                if entry[4] is not None:
                    return entry[4]
            self.error(src, pos, f"no variable is located at {path}")
            return None
        parts = path.split(".")
        if len(parts) == 1:
            g = cfg.globals.get(parts[0].upper())
            if g is None:
                self.error(src, pos, f"unknown global variable '{path}'")
            return g
        res = {r.name.upper(): r for r in cfg.resources}
        r = res.get(parts[0].upper())
        rest = parts[1:]
        if r is None:
            if len(cfg.resources) == 1:
                r, rest = cfg.resources[0], parts
            else:
                self.error(src, pos, f"unknown resource '{parts[0]}' in '{path}'")
                return None
        if len(rest) == 1:
            g = r.globals.get(rest[0].upper())
            if g is None:
                self.error(src, pos, f"resource '{r.name}' has no global '{rest[0]}'")
            return g
        inst = next((i for i in r.programs if i.name.upper() == rest[0].upper()), None)
        if inst is None:
            self.error(src, pos, f"resource '{r.name}' has no program instance '{rest[0]}'")
            return None
        pou = inst.pou
        v = fbt = None
        for part in rest[1:]:
            v = pou.var(part) if pou is not None else None
            if v is None and fbt is not None and part.upper() == "ENO":
                v = fb_eno(fbt)
            if v is None:
                self.error(src, pos, f"'{path}': no variable '{part}'")
                return None
            fbt = v.type if isinstance(v.type, FBType) else None
            pou = fbt.pou if fbt is not None else None
        return v

    def var_config(self, block, cfg):
        src = cfg.src
        for d in block.decls:
            target = self.resolve_path(d.path, cfg, src, d.pos)
            if target is None:
                continue
            t = self.decl.type_of_spec(d.spec, src)
            if t is not ERROR and not _same_type(target.type, t):
                self.error(src, d.pos, f"'{d.path}' is {target.type.name}, not {t.name}")
                continue
            if d.location:
                if not (target.location or "").endswith("*"):
                    self.error(src, d.pos, f"'{d.path}' is not declared with an incomplete "
                                           "address AT %I*, %Q* or %M*")
                elif target.location[:2] != d.location[:2]:
                    self.error(src, d.pos, f"{d.location} is not in the area of "
                                           f"{target.location}")
                else:
                    check_address_type(self.decl, src, d.pos, d.location, target.type)
                    self.note_direct(d.location, None, src, d.pos, f"VAR_CONFIG {d.path}",
                                     var=target)
                    chain = self.instance_chain(d.path, cfg)
                    if chain is not None:
                        r, inst, vs = chain
                        path = ".".join([r.path(inst.name)] + [v.name for v in vs])
                        self.completed.add(path.upper())
                        self.paths.setdefault(d.location, path)
            if d.init is not None and t is not ERROR:
                d.init = self.decl.check_initializer(d.init, t, src)
                chain = self.instance_chain(d.path, cfg)
                if chain is None:
                    self.error(src, d.pos, f"'{d.path}' is a global: VAR_CONFIG gives initial "
                                           "values to variables of program instances; write "
                                           "the global's initial value in its VAR_GLOBAL")
                elif target.constant:
                    self.error(src, d.pos, f"'{d.path}' is CONSTANT: VAR_CONFIG cannot change "
                                           "its value")
                else:
                    cfg.config_inits.append((*chain, d.init))

    @staticmethod
    def instance_chain(path, cfg):
        """(resource, program instance, [Var ...]) of a path that resolve_path
        accepted and that names a variable of a program instance; None for a
        global."""
        parts = path.split(".")
        res = {r.name.upper(): r for r in cfg.resources}
        r = res.get(parts[0].upper())
        rest = parts[1:]
        if r is None:
            r, rest = cfg.resources[0], parts
        if len(rest) < 2:
            return None
        inst = next(i for i in r.programs if i.name.upper() == rest[0].upper())
        pou, chain = inst.pou, []
        for part in rest[1:]:
            v = pou.var(part)
            chain.append(v)
            pou = v.type.pou if isinstance(v.type, FBType) else None
        return r, inst, chain


def _same_type(a, b):
    """An external, an IN_OUT connection, an access path or a VAR_CONFIG
    entry refers to the global itself: the types must be identical (a
    STRING[4] external of a STRING[8] global would be a reference of the
    wrong size)."""
    return identical(a, b)


def fb_slots(t, steps):
    """(steps, POU) of every user FB instance inside a value of type t: the
    value itself, the elements of an array, the fields of a structure."""
    if isinstance(t, FBType):
        if not t.pou.standard:
            yield steps, t.pou
    elif isinstance(t, ArrayT):
        count, elem = t.count, t.elem
        while isinstance(elem, ArrayT):
            count *= elem.count
            elem = elem.elem
        yield from fb_slots(elem, steps + (Each(count),))
    elif isinstance(t, StructT):
        for fname, ft, _ in t.fields.values():
            yield from fb_slots(ft, steps + (fname,))
