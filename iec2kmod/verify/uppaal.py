"""`iec2kmod export --uppaal`: the configuration as a network of UPPAAL
timed automata (XML, UPPAAL 4.1+), with its properties as queries.

The network (seed 004 for the program logic, seed 002 for the timers):

  * one automaton `Task` for the configuration's periodic task: location
    `wait` (invariant c <= PERIOD, the clock c counting milliseconds), and a
    chain of committed locations for one scan: the scan edge (guard
    c == PERIOD, or the first scan at time 0) chooses every input with
    `select` -- any value of its type --, copies the connected inputs in;
    then the program bodies, instruction by instruction: IL (seed 004)
    one edge per instruction with the current result in one variable per
    nesting level of parentheses (cr0, cr1, ...), jumps and RET as edges
    to their targets; ST statements as edges with guards (IF, CASE),
    unrolled FOR loops, RETURN as an edge to the end of the POU; function
    block instances inlined; then the outputs copied out, back to `wait`;
  * one automaton per TON / TOF / TP instance, after seed 002: locations
    Init, Work, Tout (and On for TOF) and a clock x; the program calls the
    timer by synchronising on its channel (its IN and PT set on the
    calling edge), and the timer's edge sets Q by comparing x with PT;
  * R_TRIG, F_TRIG, SR, RS, CTU, CTD, CTUD as updates on the calling edge;
  * variables: BOOL as bool, enumerations and integers of at most 16 bits
    as bounded ints, every arithmetic result wrapped into its type by the
    functions wrap_s8/wrap_u8/wrap_s16/wrap_u16 of the declarations; TIME
    as an int counting milliseconds (the model's time unit);
  * each property P as the query  A[] (Task.wait imply (P)): in `wait`
    the scan's copy-out is done and the inputs it selected are still in
    their variables -- the point where `iec2kmod verify` checks properties
    and assumptions (the state after step K with the inputs step K read;
    the initial state, before the first scan, is not checked by either).

Here: the automata and their locations, the Exporter's types, variables
and the network, the timers' templates, the XML; the bodies are
uppaal_body.py's (the mixin BodyExport).

What cannot be exported is refused with an error naming the construct (the
model is exact or not written): REAL, 32/64-bit integers, strings, arrays
and structures accessed with a variable index, user FUNCTIONs, times that
are not whole milliseconds, a timer's ET (a clock), several tasks, event
tasks.  A property that reads something not exported is left out with a
warning."""

from __future__ import annotations

from xml.sax.saxutils import escape

from .. import ast
from ..checks.types import BOOL, Elementary, EnumT, SubrangeT, concrete
from ..interp.values import base_of
from .terms import Frame, Refuse
from .uppaal_body import BodyExport, ident

MS = 1_000_000


class Loc:
    __slots__ = ("id", "name", "committed", "invariant")

    def __init__(self, n, name=None, committed=True, invariant=None):
        self.id = n
        self.name = name
        self.committed = committed
        self.invariant = invariant


class Automaton:
    def __init__(self, name):
        self.name = name
        self.locs = []
        self.edges = []        # (src, dst, select, guard, sync, update)
        self.init = None
        self.params = ""
        self.decl = ""

    def loc(self, name=None, committed=True, invariant=None):
        lo = Loc(len(self.locs), name, committed, invariant)
        self.locs.append(lo)
        return lo

    def edge(self, src, dst, guard=None, sync=None, update=None, select=None):
        self.edges.append((src, dst, select, guard, sync, update))


class Exporter(BodyExport):
    def __init__(self, project):
        from . import build
        from ..diagnostics import Diagnostics
        self.project = project
        self.diags = Diagnostics()
        # the roles of the variables (input, state, constant) from the verifier's
        # encoding; a fresh storage (the encoding ran a cycle in the first one)
        self.out = build(project, [], [], None, self.diags)
        from .model import SymbolicMachine
        self.sym = SymbolicMachine(project)
        sym = self.sym
        self.input_names = [leaf.name for leaf, _, _ in self.out.system.inputs
                            if leaf is not None]
        if len(sym.tasks) != 1:
            raise Refuse(sym.cfg.src, sym.tasks[1].pos,
                         "export: a second task: only one periodic task can be exported")
        if sym.period % MS:
            raise Refuse(sym.cfg.src, sym.task.pos,
                         "export: a task interval that is not a whole number of milliseconds")
        self.period_ms = sym.period // MS
        self.names = {}           # z3 const name (path) -> (ident, leaf)
        self.timers = []          # (instance path, kind, ident prefix)
        self.task = Automaton("Task")
        self.cur = None
        self.temp = 0

    # ---------------------------------------------------------- types
    def utype(self, t, pou=None, pos=None):
        ct = concrete(t)
        b = base_of(ct)
        if isinstance(b, EnumT):
            lo = min(v for _, v in b.values.values())
            hi = max(v for _, v in b.values.values())
            return f"int[{lo},{hi}]"
        if isinstance(b, Elementary):
            if b.cat == "bool":
                return "bool"
            if b.cat in ("sint", "uint", "bit") and b.bits <= 16:
                if isinstance(ct, SubrangeT):
                    return f"int[{ct.low},{ct.high}]"
                lo, hi = b.range
                return f"int[{lo},{hi}]"
            if b.cat == "time" and b.name == "TIME":
                return "int"
            if b.name == "$STATE":
                return None
        self._refuse(pou, pos, f"a variable of type {getattr(ct, 'name', ct)}")

    def wrap(self, t, text):
        b = base_of(concrete(t))
        if isinstance(b, Elementary) and b.cat in ("sint", "uint", "bit"):
            return f"wrap_{'s' if b.cat == 'sint' else 'u'}{b.bits if b.bits > 8 else 8}({text})"
        return text

    def _refuse(self, pou, pos, what):
        src = pou.src if pou is not None else self.sym.cfg.src
        raise Refuse(src, pos if pos is not None else 0, f"export: {what} cannot be exported "
                                                        "to UPPAAL exactly")

    # ------------------------------------------------------ variables
    def declare(self):
        lines = []
        timer_insts = {id(i) for i in self.sym.timers}
        self.timer_paths = {}
        for leaf in self.sym.leaves:
            if leaf.hidden:
                continue
            n = ident(leaf.name)
            self.names[str(leaf.var)] = (n, leaf)
        for inst in self.sym.timers:
            q = str(inst.v["Q"])
            base = q[:-2]
            self.timer_paths[id(inst)] = base
        for leaf in self.sym.leaves:
            if leaf.hidden:
                continue
            n, _ = self.names[str(leaf.var)]
            if leaf.name.endswith(".ET") and any(leaf.name[:-3] == b
                                                for b in self.timer_paths.values()):
                continue        # a timer's ET is its clock
            try:
                ut = self.utype(leaf.type)
            except Refuse:
                if leaf.role == "const" or not self._used(leaf):
                    continue
                raise Refuse(self.sym.cfg.src, 0, f"export: {leaf.name} of type "
                                                  f"{getattr(leaf.type, 'name', '?')} cannot "
                                                  "be exported to UPPAAL exactly")
            init = self.init_text(leaf)
            lines.append(f"{ut} {n} = {init};")
        del timer_insts
        return lines

    def _used(self, leaf):
        return True

    def init_text(self, leaf):
        v = leaf.init
        b = base_of(concrete(leaf.type))
        if isinstance(b, Elementary) and b.cat == "bool":
            return "true" if v else "false"
        if isinstance(b, Elementary) and b.cat == "time":
            return str(self.ms(v))
        return str(int(v))

    def ms(self, ns, pou=None, pos=None):
        if ns % MS:
            self._refuse(pou, pos, f"the time {ns} ns (not whole milliseconds)")
        return ns // MS

    def name_of(self, term, pou, pos):
        key = str(term)
        hit = self.names.get(key)
        if hit is None:
            self._refuse(pou, pos, f"'{key}' (not a variable of the model)")
        return hit[0]

    # ---------------------------------------------------------- network
    def build(self, props):
        from .encode import Encoder
        sym = self.sym
        self.enc = Encoder(sym)
        self.extra = set()
        self.dead = set()
        self.ret_target = None
        self.depth = 0
        decls = self.declare()
        task = self.task
        wait = task.loc("wait", committed=False, invariant=f"c <= {self.period_ms}")
        start = task.loc("start")
        task.init = start
        scan = task.loc("scan")
        inputs = [sym.by_name[n] for n in self.input_names]
        sel, ups = [], []
        for k, leaf in enumerate(inputs):
            ut = self.utype(leaf.type)
            nm = ident(leaf.name)
            if ut == "bool":
                sel.append(f"i{k} : int[0,1]")
                ups.append(f"{nm} = (i{k} == 1)")
            elif ut == "int":
                self._refuse(None, None, f"the TIME input {leaf.name}")
            else:
                sel.append(f"i{k} : {ut}")
                ups.append(f"{nm} = i{k}")
        task.edge(start, scan, select=", ".join(sel) or None, update=", ".join(ups) or None)
        task.edge(wait, scan, guard=f"c == {self.period_ms}", select=", ".join(sel) or None,
                  update=", ".join(["c = 0"] + ups))
        self.cur = scan
        m = sym.machine
        insts = {id(pi): inst for (_, inst), pi in zip(m.instances, sym.programs)}
        for pi in sym.programs:
            if pi.task is not sym.task:
                continue
            inst = insts[id(pi)]
            frame = Frame(inst, pi.pou)
            for param, value in pi.inputs:
                if isinstance(value, ast.Lit):
                    src_text = self._expr(value, frame)
                    vt = value.type
                elif hasattr(value, "address"):
                    src_text = self.name_of(m.directs[value.address], pi.pou, value.pos)
                    vt = param.type
                else:
                    c, k = m.cells[id(value.symbol)]
                    src_text = self.name_of(c[k], pi.pou, value.pos)
                    vt = value.symbol.type
                self.assign(self.name_of(inst.v[param.key], pi.pou, value.pos),
                            self.conv(src_text, vt, param.type))
            self.body(pi.pou, frame)
            for param, target in pi.outputs:
                if hasattr(target, "address"):
                    c, k = m._direct(target.address, param.type)
                else:
                    c, k = m.cells[id(target.symbol)]
                self.assign(self.name_of(c[k], pi.pou, target.pos),
                            self.name_of(inst.v[param.key], pi.pou, target.pos))
        task.edge(self.cur, wait)
        queries = []
        for name, text, expr_text in props:
            queries.append((name, f"A[] (Task.wait imply ({expr_text}))"))
        return decls, queries

    def xml(self, props=()):
        decls, queries = self.build([])
        qs = []
        for name, (pou, inst, e) in props:
            try:
                qs.append((name, f"A[] (Task.wait imply "
                                 f"({self.expr(e, Frame(inst, pou), BOOL)}))"))
            except Refuse as exc:
                self.warnings.append(f"property {name} not exported: {exc.message}")
        crs = max(getattr(self, "_crs", -1), -1)
        g = ["// iec2kmod export --uppaal: " + self.sym.cfg.name,
             f"const int PERIOD = {self.period_ms};   // ms, the model's time unit",
             "clock c;"]
        g += ["int wrap_s8(int v) { v = v % 256; if (v < 0) v = v + 256; "
              "return v >= 128 ? v - 256 : v; }",
              "int wrap_u8(int v) { v = v % 256; if (v < 0) v = v + 256; return v; }",
              "int wrap_s16(int v) { v = v % 65536; if (v < 0) v = v + 65536; "
              "return v >= 32768 ? v - 65536 : v; }",
              "int wrap_u16(int v) { v = v % 65536; if (v < 0) v = v + 65536; return v; }"]
        for k in range(crs + 1):
            g.append(f"int cr{k} = 0;   // IL current result (integer), nesting level {k}")
            g.append(f"bool crb{k} = false;   // IL current result (BOOL), nesting level {k}")
        g += decls + sorted(self.extra)
        for base, kind in self.timers:
            g.append(f"chan {base}_call;")
        return render(self, "\n".join(g), qs)



# ---------------------------------------------------------------- timers
TIMER = {
    # kind: (locations, edges (src, dst, guard, update)), seed 002's automata
    "TON": (["Init", "Work", "Tout"], [
        ("Init", "Init", "!IN", "Q = false"),
        ("Init", "Tout", "IN && PT <= 0", "Q = true"),
        ("Init", "Work", "IN && PT > 0", "x = 0, Q = false"),
        ("Work", "Init", "!IN", "Q = false"),
        ("Work", "Tout", "IN && x >= PT", "Q = true"),
        ("Work", "Work", "IN && x < PT", "Q = false"),
        ("Tout", "Tout", "IN", "Q = true"),
        ("Tout", "Init", "!IN", "Q = false")]),
    "TOF": (["Init", "On", "Work", "Tout"], [
        ("Init", "On", "IN", "Q = true"),
        ("Init", "Init", "!IN", "Q = false"),
        ("On", "On", "IN", "Q = true"),
        ("On", "Tout", "!IN && PT <= 0", "Q = false"),
        ("On", "Work", "!IN && PT > 0", "x = 0, Q = true"),
        ("Work", "On", "IN", "Q = true"),
        ("Work", "Tout", "!IN && x >= PT", "Q = false"),
        ("Work", "Work", "!IN && x < PT", "Q = true"),
        ("Tout", "On", "IN", "Q = true"),
        ("Tout", "Tout", "!IN", "Q = false")]),
    "TP": (["Init", "Work", "Tout"], [
        ("Init", "Work", "IN && !last && PT > 0", "x = 0, Q = true, last = IN"),
        ("Init", "Tout", "IN && !last && PT <= 0", "Q = false, last = IN"),
        ("Init", "Init", "!(IN && !last)", "Q = false, last = IN"),
        ("Work", "Tout", "x >= PT && IN", "Q = false, last = IN"),
        ("Work", "Init", "x >= PT && !IN", "Q = false, last = IN"),
        ("Work", "Work", "x < PT", "Q = true, last = IN"),
        ("Tout", "Work", "IN && !last && PT > 0", "x = 0, Q = true, last = IN"),
        ("Tout", "Tout", "IN && !last && PT <= 0", "Q = false, last = IN"),
        ("Tout", "Init", "!(IN && !last) && !IN", "Q = false, last = IN"),
        ("Tout", "Tout", "!(IN && !last) && IN", "Q = false, last = IN")]),
}


def _label(kind, text, x=0, y=0):
    return f'<label kind="{kind}" x="{x}" y="{y}">{escape(text)}</label>'


def render(ex, globals_text, queries):
    out = ['<?xml version="1.0" encoding="utf-8"?>',
           "<!DOCTYPE nta PUBLIC '-//Uppaal Team//DTD Flat System 1.1//EN' "
           "'http://www.it.uu.se/research/group/darts/uppaal/flat-1_2.dtd'>",
           "<nta>", f"<declaration>{escape(globals_text)}</declaration>"]
    # the timer templates
    for kind in sorted({k for _, k in ex.timers}):
        locs, edges = TIMER[kind]
        ids = {n: i for i, n in enumerate(locs)}
        out.append(f"<template><name>{kind}</name>")
        out.append("<parameter>chan &amp;call, bool &amp;IN, int &amp;PT, bool &amp;Q"
                   "</parameter>")
        out.append(f"<declaration>{escape('clock x;' + (' bool last = false;' if kind == 'TP' else ''))}"
                   "</declaration>")
        for n, i in ids.items():
            out.append(f'<location id="id{i}" x="{i * 200}" y="0"><name x="{i * 200}" y="-30">'
                       f"{n}</name></location>")
        out.append('<init ref="id0"/>')
        for s, d, g, u in edges:
            out.append(f'<transition><source ref="id{ids[s]}"/><target ref="id{ids[d]}"/>'
                       + _label("guard", g) + _label("synchronisation", "call?")
                       + _label("assignment", u) + "</transition>")
        out.append("</template>")
    # the task
    t = ex.task
    out.append("<template><name>Task</name>")
    for lo in t.locs:
        name = f'<name x="{lo.id * 40}" y="-20">{lo.name}</name>' if lo.name else ""
        inv = _label("invariant", lo.invariant) if lo.invariant else ""
        com = "<committed/>" if lo.committed else ""
        out.append(f'<location id="id{lo.id}" x="{lo.id * 40}" y="0">{name}{inv}{com}'
                   "</location>")
    out.append(f'<init ref="id{t.init.id}"/>')
    for src, dst, sel, g, sync, upd in t.edges:
        lab = ""
        if sel:
            lab += _label("select", sel)
        if g:
            lab += _label("guard", g)
        if sync:
            lab += _label("synchronisation", sync)
        if upd:
            lab += _label("assignment", upd)
        out.append(f'<transition><source ref="id{src.id}"/><target ref="id{dst.id}"/>{lab}'
                   "</transition>")
    out.append("</template>")
    system = []
    names = []
    for base, kind in ex.timers:
        path = base[2:]
        system.append(f"{base}_T = {kind}({base}_call, {base}_IN, {base}_PT, {base}_Q);")
        names.append(f"{base}_T")
        del path
    system.append("system Task" + "".join(f", {n}" for n in names) + ";")
    out.append(f"<system>{escape(chr(10).join(system))}</system>")
    out.append("<queries>")
    for name, q in queries:
        out.append(f"<query><formula>{escape(q)}</formula><comment>{escape(name)}</comment>"
                   "</query>")
    out.append("</queries>")
    out.append("</nta>")
    return "\n".join(out) + "\n"


def export(project, cli_props=(), instance=None):
    """(xml text, warnings) of the project's configuration."""
    from ..diagnostics import Diagnostics
    from .props import Prop, PropChecker, parse_expr, scan_pragmas
    from ..diagnostics import SourceFile
    from . import _scopes
    ex = Exporter(project)
    ex.warnings = []
    diags = Diagnostics()
    props, bad = scan_pragmas(project)
    for n, text in enumerate(cli_props, 1):
        props.append(Prop("property", f"property {n}", text,
                          SourceFile(f"<--property {n}>", text), 0, None))
    checked = []
    for p in props:
        if p.kind != "property":
            ex.warnings.append(f"{p.name}: {{assume}} is not exported (the inputs range over "
                               "their types)")
            continue
        for name, pou, inst in _scopes(ex.sym, p, instance, diags):
            e = parse_expr(p.text, p.src, p.start, diags)
            if e is None:
                continue
            if PropChecker(project, diags, pou, p.src, dict(ex.sym.machine.direct_types)
                           ).check_expr(e):
                checked.append((name, (pou, inst, e)))
    if diags.errors:
        return None, diags
    return ex.xml(checked), ex.warnings
