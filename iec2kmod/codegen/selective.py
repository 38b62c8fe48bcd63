"""Pass 'selective': which blocks may be skipped, and the C that skips them.

Selective execution (seed 001, Milik): a block is evaluated again only when
something in its argument set changed since its last evaluation,
Y_n = lambda(X, Q, Y_n-1).  Here a *block* is a call of a user
FUNCTION_BLOCK instance and a program instance.  Off unless asked for:
``iec2kmod gen|sim --selective`` (every block the rules allow) or
``--selective=marked`` (only the POUs and instances marked with a pragma).

Pragmas (IEC 61131-3 ``{...}``), each in front of what it applies to:

    {selective off} FUNCTION_BLOCK Valve ...      no instance of Valve is skipped
    {selective on}  FUNCTION_BLOCK Valve ...      (--selective=marked) Valve's are
    VAR {selective off} v1 : Valve; END_VAR       this instance is always evaluated
    {selective off} PROGRAM line1 WITH fast : Main;   this program instance too

A pragma that precedes nothing of that kind is a warning; without
``--selective`` the pragmas change nothing (the output is the plain one).

Rules (``BlockInfo.reason`` says which one keeps a POU type out):

1. A block may be skipped only if its type is deterministic in what the
   analysis can see.  Never skipped: a POU that contains, at any depth (its
   own variables of any section, arrays and structures of instances, the
   function blocks and functions it calls), a standard timer (TON, TOF,
   TP: they read the task's clock, so the result depends on time) or an
   SFC body (its steps' T and timed action qualifiers read the clock); a POU
   whose VAR_EXTERNALs inside arrays of FB instances would have to be
   compared element by element (not done: "cannot see").  Functions have
   no state and no VAR_EXTERNAL: they are part of the caller's evaluation.
2. The argument set of a block is: its VAR_INPUTs (for a program: what its
   connections wrote), every VAR_EXTERNAL at any depth of the instance (the
   global, through the pointer the instance holds), for a function block
   its VAR_IN_OUTs (the pointer and what it points to), and its own state.
   The state is only changed by the block's own evaluations: from outside
   an instance only its inputs can be written (the front end refuses
   assignments to outputs, and internal variables are not visible), and
   the inputs are compared.  What the manager or a trace writes into
   instance variables bumps the task's epoch (``ctx->sel_epoch``), which
   invalidates every block of that task.
3. Change detection.  The inputs, externals and in-outs are compared, byte
   for byte (iec_sel_ne: a REAL's -0.0 and 0.0 differ, so do two NaNs with
   different bits), with a copy taken when the last evaluation started
   (the last-input comparison: the stores into an instance are the
   caller's statements, the globals are copied in by the task, written by
   other tasks and by the manager; comparing at the call is the one point
   every writer passes).  A skip needs: the block's token equals the
   module's ``IEC_SEL_TOKEN`` (set by an evaluation that settled, below),
   the task's epoch is the one the block last saw, nothing in the argument
   set differs, and the loop budget left is larger than what the last
   evaluation used.
4. Settling.  An evaluation settles (the next call may skip) when it
   changed nothing it could read again: its written state (the members the
   body may write: outputs, internals, inputs it assigns, edge memories;
   nested instances called selectively report instead, through
   ``ctx->sel_changed``), the externals and the in-outs' targets are as
   they were when it started, no nested evaluation reported a change, and
   it was not the first evaluation after an epoch change.  Then running it
   again would read the same values and, being deterministic, write the
   same values: skipping it is invisible.  A counter (``n := n + 1``) never
   settles and is evaluated every time.  A nested call whose inputs
   changed reports a change to its caller (the caller's state is the
   nested instance).
5. Faults.  A block is skipped only after an evaluation that ended without
   fault, on the same arguments: it would run without fault again.  The
   loop budget is the one thing outside the argument set that an
   evaluation consumes: the budget used by the last evaluation is charged
   when the block is skipped, and a block is evaluated (and faults exactly
   where plain execution faults) when the budget left is not larger than
   that.  A fault leaves the token cleared: the block is evaluated next
   time.
6. Hot swap.  The selective state (token, epoch, budget used, copies)
   is part of the instance, so it stays in the resource module across a
   swap, and it is part of the interface hash (a plain and a selective
   build do not swap into each other).  ``IEC_SEL_TOKEN`` is derived from
   the code of the program-type module: a new algorithm has a new token,
   and every block is evaluated once by the new code before it can be
   skipped again.
7. A call of an instance of a selective type that is not selective (the
   instance is marked off, or it is a VAR_TEMP, fresh at every call) runs
   the body as plain code and clears the instance's token.

Generated C: a struct ``<prefix>_sel`` member ``sel`` at the end of the
instance struct, and ``<prefix>_run(self, ctx)`` beside ``<prefix>_body``
in the POU's file; selective calls call ``_run``.  The counters
``ctx->sel_evaluated`` and ``ctx->sel_skipped`` count blocks per task."""

from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass, field

from .. import ast
from ..checks.symbols import Var
from ..checks.types import ArrayT, FBType, StructT, concrete
from . import analysis
from . import cnames as N

TIMERS = {"TON", "TOF", "TP"}
MODES = ("all", "marked")

_PRAGMA = re.compile(r"'(?:[^'$\n]|\$.)*'|\"(?:[^\"$\n]|\$.)*\"|\(\*.*?\*\)|//[^\n]*|"
                     r"(\{\s*selective\b([^}]*)\})", re.S | re.I)


def is_selective_pragma(text: str) -> bool:
    """Is a ``{...}`` pragma one of this pass's (the parser does not warn)?"""
    return re.match(r"\{\s*selective\b", text, re.I) is not None


@dataclass
class BlockInfo:
    """A FUNCTION_BLOCK or PROGRAM type as a block."""
    pou: object
    reason: str | None = None            # why never skipped; None: may be skipped
    inputs: list = field(default_factory=list)     # [Var] VAR_INPUT
    written: list = field(default_factory=list)    # [(member C name, declaration type or C)]
    exts: list = field(default_factory=list)       # [(pointer C path from self, Var)]
    inouts: list = field(default_factory=list)     # [Var] a FB's VAR_IN_OUT
    loops: bool = False
    layout: bool = False                  # instances carry the selective state

    @property
    def skippable(self):
        return self.reason is None


class SelectivePlan:
    """The decisions of the pass for one project."""

    def __init__(self, project, mode="all"):
        if mode not in MODES:
            raise ValueError(f"selective mode {mode!r}")
        self.project = project
        self.mode = mode
        self.warnings = []                # (src, offset, message)
        self.pou_mark = {}                # POU key -> True/False
        self.var_mark = {}                # id(Var) -> True/False
        self.inst_mark = {}               # id(ProgramInstance) -> True/False
        self._read_pragmas()
        self.blocks = {}
        for pou in project.pous.values():
            if pou.kind in ("FUNCTION_BLOCK", "PROGRAM"):
                self.blocks[pou.key] = self._analyse(pou)
        for b in self.blocks.values():
            b.layout = b.skippable and self._type_wanted(b.pou)
        for b in self.blocks.values():
            if b.layout:
                b.written = self._written(b.pou)

    # ------------------------------------------------------------ pragmas
    def _read_pragmas(self):
        """Each ``{selective on|off}`` applies to the POU, FB instance
        declaration or program instance that follows it in its file."""
        targets = {}                      # path -> [(offset, kind, obj)]
        for pou in self.project.pous.values():
            if pou.node is None or pou.src is None:
                continue
            targets.setdefault(pou.src.path, []).append((pou.node.pos, "pou", pou))
            for v in pou.vars.values():
                if v.pos is not None and v.src is not None:
                    targets.setdefault(v.src.path, []).append((v.pos, "var", v))
        for cfg in self.project.configurations:
            for r in cfg.resources:
                for inst in r.programs:
                    pos = getattr(inst.node, "pos", None)
                    if pos is not None:
                        targets.setdefault(cfg.src.path, []).append((pos, "inst", inst))
        for unit in self.project.units:
            src = unit.src
            if "{" not in src.text:
                continue
            mine = sorted(targets.get(src.path, []), key=lambda t: t[0])
            for m in _PRAGMA.finditer(src.text):
                if not m.group(1):
                    continue
                word = m.group(2).strip().lower()
                if word in ("", "on"):
                    on = True
                elif word == "off":
                    on = False
                else:
                    self.warnings.append((src, m.start(1), "unknown selective pragma: write "
                                          "{selective on} or {selective off}"))
                    continue
                after = [t for t in mine if t[0] >= m.end(1)]
                if not after or not _only_space_between(src.text, m.end(1), after[0][0]):
                    self.warnings.append((src, m.start(1), "selective pragma applies to "
                                          "nothing: put it in front of a POU, a function "
                                          "block instance or a program instance"))
                    continue
                _, kind, obj = after[0]
                # several names in one declaration share the pragma
                same = [t for t in after if t[0] == after[0][0]]
                if kind == "pou":
                    self.pou_mark[obj.key] = on
                elif kind == "var":
                    for _, _, v in same:
                        if not isinstance(v.type, FBType) or v.type.pou.standard:
                            self.warnings.append((src, m.start(1), f"selective pragma on "
                                                  f"'{v.name}', which is not an instance of a "
                                                  "user function block"))
                        self.var_mark[id(v)] = on
                else:
                    self.inst_mark[id(obj)] = on

    def _type_wanted(self, pou):
        mark = self.pou_mark.get(pou.key)
        if self.mode == "all":
            return mark is not False
        if mark is not None:
            return mark
        # an instance marked on asks for its type's layout
        if any(on and isinstance(v.type, FBType) and v.type.pou is pou
               for p in self.project.pous.values() for v in p.vars.values()
               for on in [self.var_mark.get(id(v))] if on):
            return True
        return any(self.inst_mark.get(id(inst)) and inst.pou is pou
                   for c in self.project.configurations for r in c.resources
                   for inst in r.programs)

    # ----------------------------------------------------------- analysis
    def _closure(self, pou):
        """Every POU a POU uses (calls, FB types of its variables), itself
        included, and the standard FB types met on the way."""
        seen, std, stack = {}, set(), [pou]
        while stack:
            p = stack.pop()
            if p.key in seen:
                continue
            seen[p.key] = p
            for d in p.calls:
                if d in self.project.pous:
                    stack.append(self.project.pous[d])
            for v in p.vars.values():
                for fbp in _fb_types(v.type):
                    if fbp.standard:
                        std.add(fbp.name.upper())
                    else:
                        stack.append(fbp)
        return list(seen.values()), std

    def _analyse(self, pou) -> BlockInfo:
        b = BlockInfo(pou)
        closure, std = self._closure(pou)
        timers = sorted(std & TIMERS)
        if timers:
            b.reason = f"depends on time (contains {', '.join(timers)})"
        sfc = [p.name for p in closure if getattr(p, "sfc", None) is not None]
        if sfc and b.reason is None:
            b.reason = f"depends on time (SFC steps' T in {', '.join(sorted(sfc))})"
        b.loops = any(_has_loop(p) for p in closure)
        b.inputs = [v for v in pou.vars.values() if v.section == "VAR_INPUT"]
        if pou.kind == "FUNCTION_BLOCK":
            b.inouts = [v for v in pou.vars.values() if v.section == "VAR_IN_OUT"]
        for c, v, counts in _pointers(pou):
            if counts:
                b.reason = b.reason or (f"VAR_EXTERNAL {v.name} inside an array of function "
                                        "block instances")
            b.exts.append((c, v))
        return b

    def _written(self, pou) -> list:
        """The members of an instance of pou that its body may write."""
        stmts = pou.node.body if pou.node is not None else []
        il = getattr(pou.node, "language", "ST") == "IL"
        out = []
        for v in pou.vars.values():
            if v.section in ("VAR_EXTERNAL", "VAR_IN_OUT", "VAR_TEMP"):
                continue
            if v.section == "VAR_INPUT" and not il and not writes(stmts, v):
                continue
            if v.section == "VAR" and self.call_kind(pou, v) == "sel" and \
                    not writes(stmts, v):
                continue      # reports its changes itself (ctx->sel_changed)
            out.append((N.var(v.name), v.type))
        for v in pou.inputs:
            if v.edge:
                n = v.name.lower()
                out.append((f"h_{n}", "iec_bool"))
                out.append((f"h_{n}_prev", "iec_bool"))
        return out

    # ---------------------------------------------------------- decisions
    def block(self, pou):
        return self.blocks.get(pou.key)

    def has_layout(self, pou) -> bool:
        b = self.blocks.get(pou.key) if not pou.standard else None
        return bool(b and b.layout)

    def call_kind(self, caller, inst: Var):
        """A call of FB instance *inst* in POU *caller*: 'sel' (may be
        skipped), 'plain' (evaluated; clears the instance's token) or None
        (not a selective type)."""
        t = inst.type
        if not isinstance(t, FBType) or not self.has_layout(t.pou):
            return None
        if inst.section == "VAR_TEMP":
            return "plain"
        mark = self.var_mark.get(id(inst))
        if mark is False:
            return "plain"
        if self.mode == "marked" and not mark and not self.pou_mark.get(t.pou.key):
            return "plain"
        return "sel"

    def instance_selective(self, inst) -> bool:
        """A program instance (ProgramInstance of the checked model)."""
        if not self.has_layout(inst.pou):
            return False
        mark = self.inst_mark.get(id(inst))
        if mark is False:
            return False
        return self.mode == "all" or bool(mark) or bool(self.pou_mark.get(inst.pou.key))

    def report(self):
        """One line per POU type: may it be skipped, and why not."""
        out = []
        for key in sorted(self.blocks):
            b = self.blocks[key]
            what = "selective" if b.layout else (f"always evaluated: {b.reason}" if b.reason
                                                 else "always evaluated: not marked")
            out.append(f"{b.pou.kind.lower()} {b.pou.name}: {what}")
        return out

    # ---------------------------------------------------------------- C
    def struct_lines(self, pou) -> list[str]:
        """``struct <prefix>_sel``: the selective state of an instance."""
        b = self.blocks[pou.key]
        name = f"{N.pou_struct(pou)}_sel"
        lines = [f"/* selective execution state of {pou.name} (iec2kmod/codegen/selective.py) */",
                 f"{name} {{", "\tiec_u32 tok;\t\t/* IEC_SEL_TOKEN: settled */",
                 "\tiec_u32 epoch;\t\t/* ctx->sel_epoch of the last evaluation */"]
        if b.loops:
            lines.append("\tiec_u32 cost;\t\t/* loop budget used by the last evaluation */")
        if pou.kind == "PROGRAM":
            lines.append("\tiec_u8 plain;\t\t/* this instance is always evaluated */")
        for v in b.inputs:
            lines.append(f"\t{N.declare(v.type, 'i_' + v.name.lower())};")
        for k, (_, v) in enumerate(b.exts):
            lines.append(f"\t{N.declare(v.type, f'e{k}')};")
        for v in b.inouts:
            lines.append(f"\t{_pointer_decl(v, 'p_' + v.name.lower())};")
            lines.append(f"\t{N.declare(v.type, 'd_' + v.name.lower())};")
        for member, t in b.written:
            decl = f"{t} w_{member}" if isinstance(t, str) else N.declare(t, f"w_{member}")
            lines.append(f"\t{decl};")
        lines.append("};")
        return lines

    def run_function(self, pou) -> list[str]:
        """``<prefix>_run(self, ctx)``: skip, or evaluate and settle."""
        b = self.blocks[pou.key]
        prefix = N.pou_prefix(pou)
        s = "self->sel"

        def ne(a, b_, size):
            return f"iec_sel_ne({a}, {b_}, sizeof({size}))"

        in_ne = [ne(f"&self->{N.var(v.name)}", f"&{s}.i_{v.name.lower()}",
                    f"{s}.i_{v.name.lower()}") for v in b.inputs]
        ext_ne = [ne(f"self->{c}", f"&{s}.e{k}", f"{s}.e{k}") for k, (c, _) in enumerate(b.exts)]
        io_ptr_ne = [f"self->{N.var(v.name)} != {s}.p_{v.name.lower()}" for v in b.inouts]
        io_ne = [ne(f"self->{N.var(v.name)}", f"&{s}.d_{v.name.lower()}",
                    f"{s}.d_{v.name.lower()}") for v in b.inouts]
        w_ne = [ne(f"&self->{m}", f"&{s}.w_{m}", f"{s}.w_{m}") for m, _ in b.written]
        out = [f"IEC_POU_SCOPE void {prefix}_run({N.pou_struct(pou)} *self, "
               "struct iec_ctx *ctx)", "{",
               "\tbool sel_changed;", "\tbool sel_saved;", "\tbool sel_settle;"]
        if b.loops:
            out.append("\tiec_u32 sel_budget;")
        out.append("")
        if pou.kind == "PROGRAM":
            out += ["\tif (self->sel.plain) {",
                    f"\t\t{prefix}_body(self, ctx);",
                    "\t\tself->sel.tok = 0;",
                    "\t\treturn;",
                    "\t}"]
        out.append("\tsel_changed = " + _disjunction(in_ne, "\t\t") + ";")
        cond = ["!sel_changed", f"{s}.tok == IEC_SEL_TOKEN", f"{s}.epoch == ctx->sel_epoch"]
        cond += [f"!({x})" for x in io_ptr_ne] + [f"!{x}" for x in ext_ne + io_ne]
        if b.loops:
            cond.append(f"ctx->loop_budget > {s}.cost")
        out.append("\tif (" + " &&\n\t    ".join(cond) + ") {")
        if b.loops:
            out.append(f"\t\tctx->loop_budget -= {s}.cost;")
        out += ["\t\tctx->sel_skipped++;", "\t\treturn;", "\t}",
                "\tctx->sel_evaluated++;",
                f"\tsel_settle = {s}.epoch == ctx->sel_epoch;",
                f"\t{s}.epoch = ctx->sel_epoch;",
                f"\t{s}.tok = 0;"]
        for v in b.inputs:
            out.append("\t" + _copy(f"{s}.i_{v.name.lower()}", f"self->{N.var(v.name)}", v.type))
        for k, (c, v) in enumerate(b.exts):
            out.append(f"\tiec_memcpy(&{s}.e{k}, self->{c}, sizeof({s}.e{k}));")
        for v in b.inouts:
            n = v.name.lower()
            out.append(f"\t{s}.p_{n} = self->{N.var(v.name)};")
            out.append(f"\tiec_memcpy(&{s}.d_{n}, self->{N.var(v.name)}, sizeof({s}.d_{n}));")
        for m, t in b.written:
            out.append("\t" + _copy(f"{s}.w_{m}", f"self->{m}", t))
        out += ["\tsel_saved = ctx->sel_changed;", "\tctx->sel_changed = false;"]
        if b.loops:
            out.append("\tsel_budget = ctx->loop_budget;")
        out += [f"\t{prefix}_body(self, ctx);",
                "\tif (ctx->fault != IEC_FAULT_NONE)",
                "\t\treturn;"]
        if b.loops:
            out.append(f"\t{s}.cost = sel_budget - ctx->loop_budget;")
        after = ["ctx->sel_changed"] + w_ne + ext_ne + io_ne
        out += ["\tif (" + _disjunction(after, "\t    ") + ")",
                "\t\tsel_changed = true;",
                "\telse if (sel_settle)",
                f"\t\t{s}.tok = IEC_SEL_TOKEN;",
                "\tctx->sel_changed = sel_saved || sel_changed;",
                "}"]
        return out


def token_of(texts) -> int:
    """IEC_SEL_TOKEN of a module: from the code it runs, never 0."""
    h = hashlib.sha256()
    for t in texts:
        h.update(t.encode())
        h.update(b"\0")
    return int.from_bytes(h.digest()[:4], "big") | 1


def token_define(texts) -> str:
    return f"#define IEC_SEL_TOKEN 0x{token_of(texts):08x}U"


def _disjunction(items, ind):
    if not items:
        return "false"
    return (" ||\n" + ind).join(items)


def _copy(dst, src, t):
    if not isinstance(t, str) and N.is_scalar(t) or t == "iec_bool":
        return f"{dst} = {src};"
    return f"iec_memcpy(&{dst}, &{src}, sizeof({dst}));"


def _pointer_decl(v, name):
    if isinstance(v.type, ArrayT):
        elem, _ = N.array_flat(v.type)
        return f"{N.ctype(elem)} *{name}"
    return f"{N.ctype(v.type)} *{name}"


def _only_space_between(text, a, b):
    between = text[a:b]
    # the declaration may start with its keyword (FUNCTION_BLOCK, PROGRAM) or
    # sit on the next line; comments and other pragmas may come between
    between = re.sub(r"\(\*.*?\*\)|//[^\n]*|\{[^}]*\}", " ", between, flags=re.S)
    return re.fullmatch(r"\s*(?:(?:FUNCTION_BLOCK|PROGRAM|FUNCTION|VAR\w*|RETAIN|"
                        r"NON_RETAIN|CONSTANT)\s+)*", between, re.I) is not None


def _fb_types(t, depth=0):
    t = concrete(t)
    if isinstance(t, FBType):
        return [t.pou]
    if isinstance(t, ArrayT):
        return _fb_types(t.elem, depth + 1)
    if isinstance(t, StructT):
        out = []
        for _, ft, _ in t.fields.values():
            out += _fb_types(ft, depth + 1)
        return out
    return []


def _has_loop(pou) -> bool:
    if pou.node is None:
        return False
    body = pou.node.body or []
    if getattr(pou.node, "language", "ST") == "IL":
        return any(isinstance(i, ast.ILInstr) and i.op in ("JMP", "JMPC", "JMPCN")
                   for i in analysis.walk(body))
    return analysis.has_loop(body)


def _pointers(pou, c_prefix="", counts=()):
    """Pointer members bound at initialisation (VAR_EXTERNAL at any depth,
    a program's VAR_IN_OUT): (C path, Var, element counts), as
    pou.pointer_members walks the struct."""
    from .pou import has_fb
    out = []
    for v in pou.vars.values():
        c = f"{c_prefix}{N.var(v.name)}"
        if v.section == "VAR_TEMP":
            if not has_fb(v.type):
                continue
            c = f"{c_prefix}{N.temp_proto(v.name)}"
        if v.section == "VAR_EXTERNAL" or (v.section == "VAR_IN_OUT" and pou.kind == "PROGRAM"):
            out.append((c, v, counts))
        elif v.section != "VAR_IN_OUT":
            out += _pointers_in(v.type, c, counts)
    return out


def _pointers_in(t, c, counts):
    if isinstance(t, FBType):
        return [] if t.pou.standard else _pointers(t.pou, c + ".", counts)
    if isinstance(t, ArrayT):
        elem, count = N.array_flat(t)
        return _pointers_in(elem, c + "[*]", counts + (count,))
    if isinstance(t, StructT):
        out = []
        for fname, ft, _ in t.fields.values():
            out += _pointers_in(ft, f"{c}.{N.var(fname)}", counts)
        return out
    return []


_IL_STORES = {"ST", "STN", "S", "R"}


def writes(stmts, var) -> bool:
    """May the statements (ST or IL) write variable *var* or a part of it
    other than by calling it: an assignment, a FOR over it, an IL store,
    passing it (or a part) to a call as an output or VAR_IN_OUT."""
    key = var.name.upper()
    for n in analysis.walk(stmts):
        if isinstance(n, ast.Assign) and getattr(n.target, "symbol", None) is var:
            return True
        if isinstance(n, ast.For) and n.var.upper() == key:
            return True
        if isinstance(n, ast.ILInstr) and n.op in _IL_STORES and \
                getattr(n.operand, "symbol", None) is var:
            return True
        if isinstance(n, ast.Call):
            target = n.target
            bound = n.bound or {}
            for a in n.args:
                v = a.value
                if not (isinstance(v, ast.Ref) and v.symbol is var):
                    continue
                if a.kind == "out":
                    return True
                param = next((k for k, b in bound.items() if b is a), None)
                ref = getattr(n, "ref", None)     # t[i](...): an element's FB
                pou = ref.type.pou if ref is not None else \
                    getattr(getattr(target, "type", None), "pou", None) or target
                p = pou.var(param) if param and hasattr(pou, "var") else None
                if p is None:
                    if hasattr(pou, "var"):        # a user POU: unknown binding
                        return True
                    continue                       # a standard function's input
                if p.section != "VAR_INPUT":
                    return True
    return False
