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

The parser places them (parse/lexical.attach, by the positions of the
nodes): a pragma in front of a POU is in ``ast.POU.pragmas``, in front of
a variable declaration (or of the VAR keyword of its block) in
``ast.VarDecl.pragmas`` (every name of the declaration shares it), in
front of a program instance in ``ast.ProgramConfig.pragmas``; this pass
reads those (``_read_pragmas``) and scans no text.  A pragma that precedes
nothing of that kind is in ``ast.SourceUnit.unattached`` and is a warning
at its file:line:col; without ``--selective`` the pragmas change nothing
(the output is the plain one).

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
   every writer passes: flags set by the writers would need every store
   into a global, through a VAR_IN_OUT pointer or by the manager to know
   the blocks that read it).  The comparisons are unrolled word loads, the
   inputs one span.  A skip needs: the block's token equals the
   module's ``IEC_SEL_TOKEN`` (set by an evaluation that settled, below),
   the task's epoch is the one the block last saw, nothing in the argument
   set differs, and the loop budget left is larger than what the last
   evaluation used.
4. Settling.  An evaluation settles (the next call may skip) when it
   changed nothing it could read again: its written state (the members the
   body may write: outputs, internals, inputs it assigns, edge memories;
   not the outputs and internals whose value at the start an ST body
   never reads: on every path it assigns them as a whole, without reading
   them, before anything else mentions them (definite assignment through
   IF and CASE branches with an ELSE; a mention in a condition, a loop, a
   call or an index counts as a read); an input the body assigns stays,
   since the caller's next call stores over it; nested instances called
   selectively report instead, through ``ctx->sel_changed``), the
   externals and in-outs' targets that anything in it writes are as they
   were when it started, no nested evaluation
   reported a change, and it was not the first evaluation after an epoch
   change.  Then running it again would read the same values and, being
   deterministic, write the same values: skipping it is invisible.  A
   counter (``n := n + 1``) never settles and is evaluated every time.
   Only a *full* evaluation checks this (it copies the written state first
   and compares it after): the first one after a skip, or one on arguments
   equal to the last evaluation's.  A block whose arguments keep changing
   gets *fast* evaluations, which copy only the arguments and count as a
   change, so that a block changing every cycle pays little more than
   plain execution; once its arguments stop changing, the next evaluation
   is a full one.  What a nested block reports to its caller: that its
   state may have changed (it was evaluated: its outputs are state the caller
   may write: any evaluation counts), or, when the caller provably reads
   nothing of it from before the call (SelectivePlan.feedback), only that
   it ended unsettled.  A block evaluated fast IEC_SEL_BUSY_AFTER times in
   a row is then evaluated plainly (no comparison, no copy) for the next
   IEC_SEL_BUSY task cycles (``ctx->sel_cycle``) before it is checked
   again; each time it goes on changing after such a period, the next one
   is twice as long (up to IEC_SEL_BUSY << IEC_SEL_BUSY_LEVELS), and a full
   evaluation starts over from IEC_SEL_BUSY.  A plain run counts in
   ``ctx->sel_plain`` (evaluations too, reported with sel_evaluated), and
   a full evaluation of an enclosing block that saw that count move during
   its body does not settle: a plain run is a change.
5. Faults.  A block is skipped only after an evaluation that ended without
   fault, on the same arguments: it would run without fault again.  The
   loop budget is the one thing outside the argument set that an
   evaluation consumes: the budget used by the last evaluation is charged
   when the block is skipped, and a block is evaluated (and faults exactly
   where plain execution faults) when the budget left is not larger than
   that.  A fault leaves the token unset (0, or IEC_SEL_PENDING: even,
   never a module's odd IEC_SEL_TOKEN): the block is evaluated next time.
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
8. Settling without a confirm run (iec2kmod/verify/idempotent.py).  For
   each selective type this pass asks (``SelectivePlan.questions``), and
   the driver answers with z3 (iec2kmod/compilation.py, before any code
   is generated: ``SelectivePlan.settle``), about two evaluations on the
   same arguments X (inputs, externals, in-out targets: a skip needs them
   equal to the shadows), from any state S: S1 = f(X, S), S2 = f(X, S1).
   The type is *idempotent* when an evaluation without fault leaves a
   fixpoint: the second evaluation does not fault, S2 = S1 (every
   variable of the instance, nested instances and hidden memories
   included) and it leaves X as it found it.  An idempotent block settles
   after any evaluation without fault that is not the first after an
   epoch change and does not start a busy period: no written state, no
   copy, no confirm run; the nested blocks are part of f, so neither
   their reports nor their plain runs matter (its busy counting is by
   consecutive task cycles).  Combinational logic and latches (SR, RS, a
   seal-in) are idempotent; an edge detector (R_TRIG's Q falls on the
   second evaluation), a counter, a state read before it is written in
   the same body (one cycle's output feeding the next), or a second
   evaluation that may fault are not.  A type without nested user blocks
   that is not idempotent has its comparison narrowed instead: written
   state members (rule 4) are left out greedily, one at a time, as long
   as z3 proves "no fault and the remaining members unchanged by the
   evaluation ==> the next evaluation faults not and changes nothing";
   rule 4's full evaluation then compares only those.  A proof is accepted
   only as unsat within z3's resource limit (RLIMIT: deterministic, unlike
   a time limit, so the generated code does not depend on the machine;
   at most MAX_CHECKS checks per type); refused (the confirm run and rule 4's
   whole written state stay): whatever the encoder cannot encode, a loop
   at any depth (the budget charged on a skip is the last evaluation's),
   REAL/LREAL or STRING state (one NaN in the SMT theory, many in the
   machine), directly represented variables, writes to a VAR_EXTERNAL or
   through a VAR_IN_OUT, an in-out beside a body that writes its own
   inputs, and externals or in-outs holding FB instances (the model gives
   every argument storage of its own, so overlapping arguments must not
   matter).  ``BlockInfo.idempotent`` and ``idem_note`` (why not) show in
   ``SelectivePlan.report``.

Generated C: a struct ``<prefix>_sel`` member ``sel`` at the end of the
instance struct, and ``<prefix>_run(self, ctx, fb)`` beside
``<prefix>_body`` in the POU's file; selective calls call ``_run``, which
returns false when nothing can have faulted: it skipped the block, or
(a leaf type) it evaluated it and checked for a fault itself; the caller
checks for a fault only after true.  ``_run`` (inline) runs a busy block
plainly and checks whether the others can be skipped; ``_eval`` (out of
line) starts an evaluation.  For a leaf type ``_eval`` ends with the body,
a tail call, and ``_run`` settles the block after it: ``_eval`` marks a
full evaluation that may settle with the token IEC_SEL_PENDING, ``_run``
turns it into IEC_SEL_TOKEN when the written state compares equal.  No
state of the evaluation lives across a call, so the caller keeps its own
values in the registers the small ``_eval`` and body leave alone (a
block that keeps changing costs little more than its plain call).  A
type with nested user blocks keeps the whole evaluation in ``_eval``
(the saved ``ctx->sel_changed`` and ``ctx->sel_plain`` live across its
body).  The counters ``ctx->sel_evaluated`` (plus ``ctx->sel_plain``,
the plain runs of busy blocks) and ``ctx->sel_skipped`` count blocks per
task."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field

from .. import ast
from ..checks.symbols import Var
from ..checks.types import ArrayT, FBType, StructT, concrete
from . import analysis
from . import cnames as N

TIMERS = {"TON", "TOF", "TP", "RTC"}
MODES = ("all", "marked")


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
    idempotent: bool = False              # rule 8: one evaluation settles
    idem_note: str = ""                   # why not idempotent
    leaf: bool = False                    # no user FB instance inside

    @property
    def skippable(self):
        return self.reason is None


@dataclass
class SettleQuestion:
    """Rule 8 asked of one block type: which groups of its written state
    (``groups``: [[leaf path]], ``$self.<name>...``) must a full evaluation
    compare so that it settles the block, given its VAR_EXTERNALs
    (``externals``) and the POUs it uses (``closure``)?  Answered by the
    idempotence analysis (verify/idempotent.py, run by the driver)."""
    key: str
    pou: object
    externals: list
    closure: list
    groups: list


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
        self._feedback = {}
        self._ext_w = {}
        self._param_w = {}
        self._read_pragmas()
        self.blocks = {}
        for pou in project.pous.values():
            if pou.kind in ("FUNCTION_BLOCK", "PROGRAM"):
                self.blocks[pou.key] = self._analyse(pou)
        for b in self.blocks.values():
            b.layout = b.skippable and self._type_wanted(b.pou)
        # rule 8's questions, answered by an analysis the driver runs
        # (iec2kmod/compilation.py): this module decides on data only
        self.questions = []               # [SettleQuestion]
        for b in self.blocks.values():
            if b.layout:
                b.written = self._written(b.pou)
                closure, _ = self._closure(b.pou)
                b.leaf = all(p is b.pou or p.kind == "FUNCTION" for p in closure)
                self._settle(b)
        self.settled = not self.questions

    def settle(self, answers: dict) -> None:
        """Rule 8's answers: {POU key: (keep, note)} for every question of
        ``questions`` (keep: [] idempotent, the indexes of the groups to
        compare, or None: not proved; note: why not idempotent)."""
        for q in self.questions:
            keep, note = answers[q.key]
            b = self.blocks[q.key]
            if keep == []:
                b.idempotent = True
                b.written = []
                continue
            b.idem_note = note
            if keep is not None and q.groups:
                b.written = [b.written[i] for i in keep]
        self.settled = True

    # ------------------------------------------------------------ pragmas
    def _read_pragmas(self):
        """Each ``{selective on|off}`` applies to the node the parser
        attached it to (parse/lexical.attach): a POU, the variables of a
        declaration, a program instance; one attached to nothing
        (``SourceUnit.unattached``) is a warning.  Warnings in the order
        the pragmas are written."""
        infos = {id(p.node): p for p in self.project.pous.values() if p.node is not None}
        insts = {id(inst.node): inst for cfg in self.project.configurations
                 for r in cfg.resources for inst in r.programs if inst.node is not None}
        found = []                        # (unit index, pragma, kind, target)
        for n, unit in enumerate(self.project.units):
            found += [(n, m, None, None) for m in unit.unattached or ()]
            for node in unit.pous:
                info = infos.get(id(node))
                if info is None:
                    continue
                found += [(n, m, "pou", info) for m in node.pragmas or ()
                          if m.kind == "selective"]
                for b in node.blocks:
                    for d in b.decls:
                        found += [(n, m, "var", (info, d))
                                  for m in getattr(d, "pragmas", None) or ()]
            for cfg in unit.configurations:
                for r in cfg.resources:
                    for pc in r.programs:
                        inst = insts.get(id(pc))
                        if inst is not None:
                            found += [(n, m, "inst", inst) for m in pc.pragmas or ()]
        units = self.project.units
        for n, m, kind, obj in sorted(found, key=lambda f: (f[0], f[1].start)):
            src = units[n].src
            word = m.body.strip().lower()
            if word in ("", "on"):
                on = True
            elif word == "off":
                on = False
            else:
                self.warnings.append((src, m.start, "unknown selective pragma: write "
                                      "{selective on} or {selective off}"))
                continue
            if kind is None:
                self.warnings.append((src, m.start, "selective pragma applies to "
                                      "nothing: put it in front of a POU, a function "
                                      "block instance or a program instance"))
            elif kind == "pou":
                self.pou_mark[obj.key] = on
            elif kind == "var":
                info, decl = obj
                # several names in one declaration share the pragma
                for name, pos in decl.names:
                    v = info.vars.get(name.upper())
                    if v is None or v.pos != pos:
                        continue          # not declared ('already declared')
                    if not isinstance(v.type, FBType) or v.type.pou.standard:
                        self.warnings.append((src, m.start, f"selective pragma on "
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
        seen = set()
        for c, v, counts in _pointers(pou):
            if counts:
                b.reason = b.reason or (f"VAR_EXTERNAL {v.name} inside an array of function "
                                        "block instances")
            # every VAR_EXTERNAL of one name in an instance, at any depth,
            # is the same global (names resolve in the program's scope)
            if (v.section, v.name.upper()) in seen:
                continue
            seen.add((v.section, v.name.upper()))
            b.exts.append((c, v))
        return b

    def _written(self, pou) -> list:
        """The state an evaluation of pou may change and read again (rule
        4): the members its body may write, except those it provably
        assigns before it reads them (their value at the start of an
        evaluation is never read, so a change of theirs cannot make the
        next evaluation differ) and nested instances called selectively
        (they report).  An IL body: every member it may write."""
        stmts = pou.node.body if pou.node is not None else []
        il = getattr(pou.node, "language", "ST") == "IL"
        from .pou import has_fb
        out = []
        for v in pou.vars.values():
            if v.section in ("VAR_EXTERNAL", "VAR_IN_OUT", "VAR_TEMP"):
                continue
            w = writes(stmts, v, self.param_written)
            if has_fb(v.type) or isinstance(v.type, FBType):
                if v.section == "VAR" and self.call_kind(pou, v) == "sel" and not w:
                    continue      # reports its changes itself (ctx->sel_changed)
                if not il and not w and not _called(stmts, v):
                    continue      # never called, never written
            elif not il and (not w or (v.section != "VAR_INPUT" and
                                       not _entry_read(stmts, v))):
                # an input the body writes stays: the caller's next call
                # stores over it, and the evaluation would write it again
                continue
            out.append((N.var(v.name), v.type))
        for v in pou.inputs:
            if v.edge:
                n = v.name.lower()
                out.append((f"h_{n}", "iec_bool"))
                out.append((f"h_{n}_prev", "iec_bool"))
        return out

    def _settle(self, b):
        """Rule 8: idempotent (no written state, no confirm run), or the
        part of the written state a full evaluation must compare."""
        pou = b.pou
        why = self._settle_refused(b)
        if why:
            b.idem_note = why
            return
        closure, _ = self._closure(pou)
        exts = [v for _, v in b.exts if v.section == "VAR_EXTERNAL"]
        groups = []
        if b.leaf:
            # a nested user block reports (rule 4) instead of being compared:
            # only a type without one has its comparison narrowed
            names = {N.var(v.name): v for v in pou.vars.values()}
            split = []
            for member, t in b.written:
                v = names.get(member)
                std = v is not None and isinstance(v.type, FBType) and v.type.pou.standard \
                    and v.type.pou.name.upper().startswith(_STD_SPLIT)
                if not std:
                    split.append((member, t))
                    continue
                # a standard FB instance: field by field, its hidden memory
                # too; the memory is tried first, then the inputs, so that
                # what stays is what changes least (R_TRIG: Q, only on a rise)
                sp = v.type.pou
                # (the runtime's struct is member fb of one that keeps ENO)
                inner = "fb." if sp.keeps_eno else ""
                fields = [(f"{member}.{inner}{field}", "iec_bool")
                          for _, field in _std_hidden(sp.name.upper())]
                fields += [(f"{member}.{N.member(sp, f.name)}", f.type)
                           for f in sp.vars.values() if f.section == "VAR_INPUT"]
                fields += [(f"{member}.{N.member(sp, f.name)}", f.type)
                           for f in sp.vars.values() if f.section != "VAR_INPUT"]
                split += fields
            b.written = split
            for member, _ in b.written:
                head, _, field = member.partition(".")
                if head in names and field:
                    sp = names[head].type.pou
                    if sp.keeps_eno and field.startswith("fb."):
                        field = field[3:]
                    hidden = dict((f, h) for h, f in _std_hidden(sp.name.upper()))
                    leaf = hidden.get(field) or sp.vars[field.upper()].name
                    groups.append([f"$self.{names[head].name}.{leaf}"])
                elif member in names:
                    groups.append([f"$self.{names[member].name}"])
                elif member.startswith("h_") and member.endswith("_prev"):
                    v = next(v for v in pou.inputs if f"h_{v.name.lower()}_prev" == member)
                    groups.append([f"$self.${v.name}"])
                else:
                    groups.append([])     # the edge an input saw: set by every call
        self.questions.append(SettleQuestion(pou.key, pou, exts, closure, groups))

    def _settle_refused(self, b):
        pou = b.pou
        if b.loops:
            return "a loop (the loop budget of a skip)"
        closure, _ = self._closure(pou)
        for p in closure:
            if p.node is None or getattr(p, "sfc", None) is not None:
                return f"{p.name}: no body to encode"
        for _, v in b.exts:
            if self._ext_written(pou, v):
                return f"writes {v.name}"
        inouts = [v for v in pou.vars.values() if v.section == "VAR_IN_OUT"]
        for v in inouts:
            if pou.kind == "FUNCTION_BLOCK" and self.param_written(pou, v):
                return f"writes through {v.name}"
        if inouts and any(writes(pou.node.body or [], v, self.param_written)
                          for v in pou.inputs):
            return "an in-out beside a body that writes its inputs"
        return None

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

    def feedback(self, caller, inst: Var) -> bool:
        """May *caller* read the state of instance *inst* from before its
        call (so that a change of that state in an evaluation changes what
        the caller reads the next time)?  False only when provably not:
        *inst* is called exactly once, by a statement of the top level of
        an ST body that is the first to mention it and does not mention it
        in its arguments, and nothing inside a loop mentions it.  Then the
        call only reports whether the instance ended unsettled (rule 4)."""
        key = (caller.key, id(inst))
        if key in self._feedback:
            return self._feedback[key]
        self._feedback[key] = result = _feedback(caller, inst)
        return result

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
            if not b.layout:
                what = f"always evaluated: {b.reason}" if b.reason else \
                    "always evaluated: not marked"
            elif b.idempotent:
                what = "selective, idempotent"
            else:
                what = (f"selective (confirm run comparing {len(b.written)} members; "
                        f"not idempotent: {b.idem_note})")
            out.append(f"{b.pou.kind.lower()} {b.pou.name}: {what}")
        return out

    # ---------------------------------------------------------------- C
    def struct_lines(self, pou) -> list[str]:
        """``struct <prefix>_sel``: the selective state of an instance."""
        b = self.blocks[pou.key]
        name = f"{N.pou_struct(pou)}_sel"
        lines = [f"/* selective execution state of {pou.name} (iec2kmod/codegen/selective.py) */",
                 f"{name} {{", "\tiec_u32 tok;\t\t/* IEC_SEL_TOKEN: settled */",
                 "\tiec_u32 epoch;\t\t/* ctx->sel_epoch of the last evaluation */",
                 "\tiec_u64 busy_end;\t/* plain runs while ctx->sel_cycle is below */",
                 "\tiec_u8 fast;\t\t/* fast evaluations in a row */",
                 "\tiec_u8 level;\t\t/* the next busy period: IEC_SEL_BUSY << level */"]
        if b.loops:
            lines.append("\tiec_u32 cost;\t\t/* loop budget used by the last evaluation */")
        if b.idempotent:
            lines.append("\tiec_u32 last;\t\t/* ctx->sel_cycle of the last evaluation */")
        if pou.kind == "PROGRAM":
            lines.append("\tiec_u8 plain;\t\t/* this instance is always evaluated */")
        if b.inputs:
            lines.append(f"\t{N.pou_struct(pou)}_in i;\t/* the inputs at the last evaluation */")
        for k, (_, v) in enumerate(b.exts):
            lines.append(f"\t{N.declare(v.type, f'e{k}')};")
        for v in b.inouts:
            lines.append(f"\t{_pointer_decl(v, 'p_' + v.name.lower())};")
            lines.append(f"\t{N.declare(v.type, 'd_' + v.name.lower())};")
        for member, t in b.written:
            w = _wname(member)
            decl = f"{t} {w}" if isinstance(t, str) else N.declare(t, w)
            lines.append(f"\t{decl};")
        lines.append("};")
        if b.inputs:
            # the inputs lead the instance struct (pou.SECTION_ORDER): this
            # struct has their layout, and the span of the inputs is compared
            # and copied in one piece
            lines = [f"/* the inputs of {pou.name}, laid out as in its instance */",
                     f"{N.pou_struct(pou)}_in {{"] + \
                [f"\t{N.declare(v.type, N.var(v.name))};" for v in b.inputs] + ["};", ""] + lines
        return lines

    def run_function(self, pou) -> list[str]:
        """``<prefix>_check`` (inline: skip, or why not), ``<prefix>_eval``
        (out of line: evaluate, and settle when the evaluation is a full
        one) and ``<prefix>_run(self, ctx, fb)`` (what a selective call
        calls; *fb*: the caller may read the instance's state from before
        the call, SelectivePlan.feedback)."""
        b = self.blocks[pou.key]
        prefix = N.pou_prefix(pou)
        st = N.pou_struct(pou)
        s = "self->sel"

        def ne(a, b_, size):
            return f"iec_sel_ne({a}, {b_}, sizeof({size}))"

        span = None
        if b.inputs:
            span = f"IEC_SEL_SPAN({st}, {N.var(b.inputs[-1].name)})"
        args_ne = [f"iec_sel_ne(self, &{s}.i, {span})"] if span else []
        args_ne += [f"self->{N.var(v.name)} != {s}.p_{v.name.lower()}" for v in b.inouts]
        args_ne += [ne(f"self->{N.var(v.name)}", f"&{s}.d_{v.name.lower()}",
                       f"{s}.d_{v.name.lower()}") for v in b.inouts]
        args_ne += [ne(f"self->{c}", f"&{s}.e{k}", f"{s}.e{k}")
                    for k, (c, _) in enumerate(b.exts)]
        after = [ne(f"self->{c}", f"&{s}.e{k}", f"{s}.e{k}")
                 for k, (c, v) in enumerate(b.exts) if self._ext_written(pou, v)]
        after += [ne(f"self->{N.var(v.name)}", f"&{s}.d_{v.name.lower()}",
                     f"{s}.d_{v.name.lower()}") for v in b.inouts
                  if self.param_written(pou, v)]
        after += [ne(f"&self->{m}", f"&{s}.{_wname(m)}", f"{s}.{_wname(m)}")
                  for m, _ in b.written]
        # the check: 0 skipped, 1 the arguments changed, 2 they did not
        out = ["static inline __attribute__((__always_inline__)) int",
               f"{prefix}_check({st} *self, struct iec_ctx *ctx)", "{",
               "\tbool sel_changed = " + _disjunction(args_ne, "\t\t") + ";", ""]
        cond = ["!sel_changed", f"{s}.tok == IEC_SEL_TOKEN", f"{s}.epoch == ctx->sel_epoch"]
        if b.loops:
            cond.append(f"ctx->loop_budget > {s}.cost")
        out.append("\tif (" + " &&\n\t    ".join(cond) + ") {")
        if b.loops:
            out.append(f"\t\tctx->loop_budget -= {s}.cost;")
        out += ["\t\tctx->sel_skipped++;", "\t\treturn 0;", "\t}",
                "\treturn sel_changed ? 1 : 2;", "}", ""]
        if b.idempotent:
            out += self._idempotent_eval(b, prefix, st, span)
        else:
            out += self._confirm_eval(b, prefix, st, span, after)
        out += self._run_plain(b, prefix, st, after)
        return out

    def _copies(self, b, span):
        s = "self->sel"
        out = []
        if span:
            out.append(f"\tiec_memcpy(&{s}.i, self, {span});")
        for v in b.inouts:
            n = v.name.lower()
            out.append(f"\t{s}.p_{n} = self->{N.var(v.name)};")
            out.append(f"\tiec_memcpy(&{s}.d_{n}, self->{N.var(v.name)}, sizeof({s}.d_{n}));")
        for k, (c, v) in enumerate(b.exts):
            out.append(f"\tiec_memcpy(&{s}.e{k}, self->{c}, sizeof({s}.e{k}));")
        return out

    def _busy(self, ind):
        s = "self->sel"
        return [f"{ind}/* the arguments changed at every evaluation for a while:",
                f"{ind} * plain runs, twice as many as last time if they kept",
                f"{ind} * changing after the last plain runs too */",
                f"{ind}{s}.busy_end = ctx->sel_cycle + 1 + (IEC_SEL_BUSY << {s}.level);",
                f"{ind}if ({s}.level < IEC_SEL_BUSY_LEVELS)",
                f"{ind}\t{s}.level++;",
                f"{ind}{s}.fast = 0;"]

    def _idempotent_eval(self, b, prefix, st, span):
        """Rule 8: the type is proved idempotent, an evaluation without
        fault settles it by itself (no written state, no confirm run)."""
        s = "self->sel"
        out = ["static __attribute__((__noinline__, __unused__)) void",
               f"{prefix}_eval({st} *self, struct iec_ctx *ctx, int why)" if b.leaf else
               f"{prefix}_eval({st} *self, struct iec_ctx *ctx, int why, bool fb)", "{",
               "\tbool sel_settle;" if b.leaf else "\tbool sel_settle, sel_saved;", "",
               "\tctx->sel_evaluated++;",
               "\t/* proved idempotent: an evaluation without fault settles, the",
               "\t * next one on the same arguments would change nothing",
               "\t * (selective.py, rule 8) */",
               f"\tsel_settle = {s}.epoch == ctx->sel_epoch;",
               f"\t{s}.epoch = ctx->sel_epoch;",
               f"\t{s}.tok = 0;"]
        out += self._copies(b, span)
        out += ["\t/* evaluations on changed arguments in consecutive task cycles */",
                f"\tif (why == 2 || {s}.last + 1 != (iec_u32)ctx->sel_cycle) {{",
                f"\t\t{s}.fast = why == 1;",
                f"\t\t{s}.level = 0;",
                f"\t}} else if (++{s}.fast >= IEC_SEL_BUSY_AFTER) {{"]
        out += self._busy("\t\t")
        out += ["\t\t/* plain runs follow: not settled */",
                "\t\tsel_settle = false;",
                "\t}",
                f"\t{s}.last = (iec_u32)ctx->sel_cycle;"]
        if b.leaf:
            # the settling is _run's (leaf types, run_function)
            out += ["\tif (sel_settle)",
                    f"\t\t{s}.tok = IEC_SEL_PENDING;",
                    f"\t{prefix}_body(self, ctx);",
                    "}", ""]
            return out
        out.append("\tsel_saved = ctx->sel_changed;")
        out += [f"\t{prefix}_body(self, ctx);",
                "\tif (ctx->fault != IEC_FAULT_NONE)",
                "\t\treturn;",
                "\tif (sel_settle)",
                f"\t\t{s}.tok = IEC_SEL_TOKEN;"]
        out += self._report(b)
        out += ["}", ""]
        return out

    def _report(self, b):
        """What an evaluation tells its caller (ctx->sel_changed): to one
        that may read its state from before the call (fb), that it may
        have changed; to one that does not, whether it would be evaluated
        again.  A leaf type (no user block inside) runs no selective call,
        so its body leaves ctx->sel_changed and ctx->sel_plain alone: no
        save, no restore."""
        s = "self->sel"
        if b.leaf:
            return [f"\tif (fb || {s}.tok != IEC_SEL_TOKEN)",
                    "\t\tctx->sel_changed = true;"]
        return [f"\tctx->sel_changed = sel_saved || fb || {s}.tok != IEC_SEL_TOKEN;"]

    def _confirm_eval(self, b, prefix, st, span, after):
        s = "self->sel"
        out = []
        # the evaluation
        out += ["static __attribute__((__noinline__, __unused__)) void",
                f"{prefix}_eval({st} *self, struct iec_ctx *ctx, int why)" if b.leaf else
                f"{prefix}_eval({st} *self, struct iec_ctx *ctx, int why, bool fb)", "{",
                "\tbool sel_full;" if b.leaf else
                "\tbool sel_full, sel_settle, sel_saved = false;"]
        if not b.leaf:
            out.append("\tiec_u64 sel_plain = 0;")
        if b.loops and not b.leaf:
            out.append("\tiec_u32 sel_budget;")
        out += ["",
                "\tctx->sel_evaluated++;",
                "\t/* a full evaluation checks whether it settles: after a skip, or",
                "\t * again on unchanged arguments; arguments that keep changing get",
                "\t * fast ones (selective.py, rule 4) */",
                f"\tsel_full = why == 2 || {s}.tok == IEC_SEL_TOKEN;"]
        if b.leaf:
            out += ["\t/* _run settles it after the body if its written state is unchanged */",
                    f"\t{s}.tok = sel_full && {s}.epoch == ctx->sel_epoch ?",
                    "\t\tIEC_SEL_PENDING : 0;",
                    f"\t{s}.epoch = ctx->sel_epoch;"]
        else:
            out += [f"\tsel_settle = {s}.epoch == ctx->sel_epoch;",
                    f"\t{s}.epoch = ctx->sel_epoch;",
                    f"\t{s}.tok = 0;"]
        out += self._copies(b, span)
        out.append("\tif (sel_full) {")
        for m, t in b.written:
            out.append("\t\t" + _copy(f"{s}.{_wname(m)}", f"self->{m}", t))
        if not b.leaf:
            out += ["\t\tsel_saved = ctx->sel_changed;", "\t\tctx->sel_changed = false;",
                    "\t\tsel_plain = ctx->sel_plain;"]
        out += [f"\t\t{s}.fast = 0;",
                f"\t\t{s}.level = 0;",
                f"\t}} else if (++{s}.fast >= IEC_SEL_BUSY_AFTER) {{"]
        out += self._busy("\t\t")
        out += ["\t}"]
        if b.leaf:
            # the budget the body used and the settling are _run's; the
            # body is the last call (a tail call: the registers this
            # function uses are few, and the caller keeps its own in the
            # others across the call)
            if b.loops:
                out.append(f"\t{s}.cost = ctx->loop_budget;")
            out += [f"\t{prefix}_body(self, ctx);", "}", ""]
            return out
        if b.loops:
            out.append("\tsel_budget = ctx->loop_budget;")
        out += [f"\t{prefix}_body(self, ctx);",
                "\tif (ctx->fault != IEC_FAULT_NONE)",
                "\t\treturn;"]
        if b.loops:
            out.append(f"\t{s}.cost = sel_budget - ctx->loop_budget;")
        out += ["\tif (!sel_full) {",
                "\t\tctx->sel_changed = true;",
                "\t\treturn;",
                "\t}",
                "\tif (!(" + _disjunction(
                    ([] if b.leaf else ["ctx->sel_changed", "ctx->sel_plain != sel_plain"]) +
                    after, "\t      ") + ") &&",
                "\t    sel_settle)",
                f"\t\t{s}.tok = IEC_SEL_TOKEN;"]
        out += self._report(b)
        out += ["}", ""]
        return out

    def _run_plain(self, b, prefix, st, after):
        pou = b.pou
        s = "self->sel"
        out = []
        out += ["/* arguments that kept changing: evaluated plainly for a while, then",
                " * checked again (the next check makes a fast or a full evaluation,",
                " * and the shadows are taken anew) */",
                "static inline __attribute__((__always_inline__, __unused__)) void",
                f"{prefix}_plain({st} *self, struct iec_ctx *ctx)", "{",
                "\t/* an evaluation, and a change an enclosing full one sees */",
                "\tctx->sel_plain++;",
                f"\t{prefix}_body(self, ctx);",
                "}", ""]
        out += ["/* false: nothing can have faulted (skipped, or evaluated and checked) */",
                "static inline __attribute__((__always_inline__, __unused__)) bool",
                f"{prefix}_run({st} *self, struct iec_ctx *ctx, bool fb)", "{", "\tint why;", ""]
        if pou.kind == "PROGRAM":
            out += ["\tif (self->sel.plain) {",
                    f"\t\t{prefix}_body(self, ctx);",
                    "\t\tself->sel.tok = 0;",
                    "\t\treturn true;",
                    "\t}"]
        out += [f"\tif (iec_likely(ctx->sel_cycle < {s}.busy_end)) {{",
                f"\t\t{prefix}_plain(self, ctx);",
                "\t\treturn true;",
                "\t}",
                f"\twhy = {prefix}_check(self, ctx);",
                "\tif (!why)",
                "\t\treturn false;"]
        if not b.leaf:
            out += [f"\t{prefix}_eval(self, ctx, why, fb);",
                    "\treturn true;",
                    "}"]
            return out
        # a leaf type: _eval starts the evaluation and runs the body, the
        # settling is here, where the comparisons fold into the caller's
        # code (no state of the evaluation lives across a call)
        out += [f"\t{prefix}_eval(self, ctx, why);",
                "\tif (ctx->fault != IEC_FAULT_NONE)",
                "\t\treturn true;"]
        if b.loops and not b.idempotent:
            out.append(f"\t{s}.cost -= ctx->loop_budget;")
        if b.idempotent or not after:
            out += [f"\tif ({s}.tok == IEC_SEL_PENDING)",
                    f"\t\t{s}.tok = IEC_SEL_TOKEN;"]
        else:
            out += [f"\tif ({s}.tok == IEC_SEL_PENDING) {{",
                    "\t\tif (" + _disjunction(after, "\t\t    ") + ")",
                    f"\t\t\t{s}.tok = 0;",
                    "\t\telse",
                    f"\t\t\t{s}.tok = IEC_SEL_TOKEN;",
                    "\t}"]
        out += self._report(b)
        out += ["\treturn false;", "}"]
        return out

    def _ext_written(self, pou, ext_var) -> bool:
        """Does anything in pou's closure write the global that VAR_EXTERNAL
        (or a program's VAR_IN_OUT) *ext_var* names?"""
        key = (pou.key, ext_var.section, ext_var.name.upper())
        if key not in self._ext_w:
            closure, _ = self._closure(pou)
            hit = False
            for q in closure:
                v = q.vars.get(ext_var.name.upper())
                if v is None or v.section != ext_var.section:
                    continue
                if q.node is None or getattr(q, "sfc", None) is not None or \
                        writes(q.node.body or [], v, self.param_written):
                    hit = True
                    break
            self._ext_w[key] = hit
        return self._ext_w[key]

    def param_written(self, pou, v) -> bool:
        """May a call of *pou* write through its VAR_IN_OUT *v*?"""
        key = (pou.key, v.name.upper())
        if key not in self._param_w:
            self._param_w[key] = True       # (no recursion in IEC; but be safe)
            if pou.standard or pou.node is None or getattr(pou, "sfc", None) is not None:
                self._param_w[key] = True
            else:
                self._param_w[key] = writes(pou.node.body or [], v, self.param_written)
        return self._param_w[key]


def _walk(node):
    """analysis.walk, and the targets of assignments too (their variable
    and their index expressions: ``a[k] := 0`` reads k)."""
    for n in analysis.walk(node):
        yield n
        if isinstance(n, ast.Assign):
            yield from analysis.walk(n.target)


def _mentions(node, var) -> bool:
    key = var.name.upper()
    return any(getattr(n, "symbol", None) is var or getattr(n, "target", None) is var or
               (isinstance(n, ast.For) and n.var.upper() == key)
               for n in _walk(node))


def _called(stmts, var) -> bool:
    return any(isinstance(n, ast.Call) and (n.target is var or getattr(
        getattr(n, "ref", None), "symbol", None) is var) for n in _walk(stmts))


def _entry_read(stmts, var) -> bool:
    """May an evaluation of the ST statements read the value *var* had
    when it started?  No only when, on every path, each mention of *var*
    comes after an assignment of the whole variable that does not read it
    (definite assignment through IF and CASE with an ELSE; a loop, a
    condition or anything else that mentions it counts as a read)."""
    return _seq_status(stmts, var) == "read"


def _seq_status(stmts, var):
    """'read': the entry value may be read; 'assigned': the whole variable
    is assigned on every path before any read; 'none': neither."""
    for st in stmts or []:
        s = _stmt_status(st, var)
        if s != "none":
            return s
    return "none"


def _stmt_status(st, var):
    if not _mentions(st, var):
        return "none"
    if isinstance(st, ast.Assign):
        t = st.target
        whole = getattr(t, "symbol", None) is var and not t.accessors
        return "assigned" if whole and not _mentions(st.value, var) else "read"
    if isinstance(st, ast.If):
        if any(_mentions(c, var) for c, _ in st.branches):
            return "read"
        paths = [b for _, b in st.branches] + [st.else_]
    elif isinstance(st, ast.Case):
        if _mentions(st.selector, var) or any(_mentions(lab, var) for lab, _ in st.elements):
            return "read"
        paths = [b for _, b in st.elements] + [st.else_]
    else:
        return "read"
    status = [_seq_status(b, var) if b is not None else "none" for b in paths]
    if "read" in status:
        return "read"
    return "assigned" if all(s == "assigned" for s in status) else "none"


def _feedback(caller, inst) -> bool:
    node = caller.node
    if node is None or getattr(node, "language", "ST") != "ST" or \
            getattr(caller, "sfc", None) is not None:
        return True
    body = node.body or []
    calls = [n for n in _walk(body) if isinstance(n, ast.Call) and n.target is inst
             and getattr(n, "ref", None) is None]
    if len(calls) != 1:
        return True
    loops = [n for n in _walk(body) if isinstance(n, (ast.For, ast.While, ast.Repeat))]
    if any(_mentions(lp, inst) for lp in loops):
        return True
    first = next((st for st in body if _mentions(st, inst)), None)
    if not isinstance(first, ast.CallStmt) or first.call is not calls[0]:
        return True
    if any(_mentions(a, inst) for a in first.call.args):
        return True
    return False


def token_of(texts) -> int:
    """IEC_SEL_TOKEN of a module: from the code it runs, never 0."""
    h = hashlib.sha256()
    for t in texts:
        h.update(t.encode())
        h.update(b"\0")
    return int.from_bytes(h.digest()[:4], "big") | 1


def token_define(texts) -> str:
    return f"#define IEC_SEL_TOKEN 0x{token_of(texts):08x}U"


def _wname(member):
    """The shadow of a written member (``v_x``, or a field ``v_t.q`` of a
    standard FB instance)."""
    return "w_" + member.replace(".", "_")


# the standard FBs a narrowed comparison may keep field by field (rule 8)
_STD_SPLIT = ("R_TRIG", "F_TRIG", "SR", "RS", "CTU", "CTD", "CTUD")


def _std_hidden(name):
    """[(leaf of the z3 model, C field)]: the hidden memory of a standard
    FB (kmod_templates/runtime/iec_std_fb.h)."""
    if name in ("R_TRIG", "F_TRIG"):
        return [("$M", "prev")]        # F_TRIG: the model's M is NOT prev
    if name.startswith("CTUD"):
        return [("$CU", "cu_prev"), ("$CD", "cd_prev")]
    if name.startswith("CTU"):
        return [("$CU", "cu_prev")]
    if name.startswith("CTD"):
        return [("$CD", "cd_prev")]
    return []


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


def writes(stmts, var, inout_written=None) -> bool:
    """May the statements (ST or IL) write variable *var* or a part of it
    other than by calling it: an assignment, a FOR over it, an IL store,
    passing it (or a part) to a call as an output or VAR_IN_OUT."""
    key = var.name.upper()
    for n in _walk(stmts):
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
                if p.section == "VAR_IN_OUT" and inout_written is not None and \
                        getattr(pou, "node", None) is not None:
                    if inout_written(pou, p):
                        return True
                    continue
                if p.section != "VAR_INPUT":
                    return True
    return False
