"""Textual SFC (IEC 61131-3 ed.2 2.6): the checks of a FUNCTION_BLOCK or
PROGRAM body made of steps, transitions and actions.

Declaration (``declare_steps``, from the pass 'declare'): every step is a
variable of the POU, of the structure type STEP_T (``X : BOOL; T : TIME``),
so that ``step.X`` and ``step.T`` read as any structure member in both
engines and show in the variable table; an initial step starts with
X = TRUE.  The program cannot write them (``check_writable``).

Resolution (``SFCChecker``, from the pass 'resolve'):

  * step names are unique and are not the names of variables; actions too;
  * every step named in a TRANSITION's FROM or TO is declared, at most once
    in one list; a transition's condition is BOOL (ST ``:= expr;``, or IL:
    a simple instruction list -- no label, jump, RET or CAL -- whose current
    result at the end is the condition);
  * networks: steps linked by transitions form a network; each network has
    exactly one INITIAL_STEP; every step of a network with an initial step
    can become active (a transition leads to it from steps that can);
  * action associations name a declared ACTION or a BOOL variable of the
    POU (ed.2 2.6.4.1: an action may be a Boolean variable); L, D, SD, DS
    and SL need a time (a TIME literal or variable) and the other
    qualifiers take none; indicators are BOOL variables;
  * an ACTION never associated with a step is a warning (it never runs).

The result is ``pou.sfc`` (SFCInfo), which code generation
(iec2kmod/codegen/sfc.py) and the reference interpreter
(iec2kmod/interp/sfc.py) each execute in their own way."""

from __future__ import annotations

from dataclasses import dataclass, field

from .. import ast
from .symbols import Var
from .types import BOOL, TIME, ErrorT, StructT, is_bool

QUALIFIERS = ("N", "R", "S", "P", "P0", "P1", "L", "D", "SD", "DS", "SL")
TIMED = ("L", "D", "SD", "DS", "SL")

# The step flag structure: one instance for every project (one C struct).
STEP_T = StructT("__SFC_STEP")
STEP_T.fields = {"X": ("X", BOOL, None), "T": ("T", TIME, None)}


@dataclass(eq=False)
class Association:
    step: Var                 # the step variable
    qualifier: str            # N R S P P0 P1 L D SD DS SL
    time: object = None       # TIME expression of a timed qualifier
    node: object = None       # ast.ActionAssoc


@dataclass(eq=False)
class ActionInfo:
    name: str
    node: object = None       # ast.Action, None for a BOOL variable action
    var: Var | None = None    # the BOOL variable of a variable action
    assocs: list = field(default_factory=list)   # [Association], source order


@dataclass(eq=False)
class TransitionInfo:
    node: object              # ast.Transition
    sources: list             # [Var] step variables
    targets: list             # [Var]
    priority: int | None
    index: int                # source order


@dataclass(eq=False)
class SFCInfo:
    steps: list = field(default_factory=list)        # [Var], source order
    transitions: list = field(default_factory=list)  # [TransitionInfo], source order
    actions: list = field(default_factory=list)      # [ActionInfo]: ACTIONs in source
    #                                                  order, then variable actions


def declare_steps(declarer, pou):
    """Declares the steps of an SFC body as variables of the POU."""
    node = pou.node
    src = node.src
    if node.sfc is None:
        return
    if pou.kind == "FUNCTION":
        declarer.error(src, node.sfc.pos, "a FUNCTION cannot have an SFC body (steps, "
                                          "transitions and actions belong to function blocks "
                                          "and programs)")
        return
    for step in node.sfc.steps:
        key = step.name.upper()
        old = pou.vars.get(key)
        if old is not None:
            if old.step is not None:
                declarer.error(src, step.pos, f"step '{step.name}' is already declared")
            else:
                declarer.error(src, step.pos, f"step '{step.name}' has the name of a variable "
                                              f"of {pou.name}")
            continue
        init = None
        if step.initial:
            lit = ast.Lit(step.pos, "TRUE", "bool", True)
            lit.type = BOOL
            init = ast.StructInit(step.pos, fields=[("X", lit, step.pos)])
        pou.vars[key] = Var(step.name, STEP_T, "VAR", step.pos, src, owner=pou, init=init,
                            used=True, step=step)


class SFCChecker:
    """Checks the SFC body of one POU with its BodyChecker (expressions,
    statements and IL are checked by it)."""

    def __init__(self, body_checker):
        self.bc = body_checker
        self.pou = body_checker.pou
        self.error = body_checker.error
        self.warning = body_checker.warning

    def check(self):
        sfc = self.pou.node.sfc
        info = SFCInfo()
        self.pou.sfc = info
        steps = {}
        self.refused = set()    # steps refused at declaration: no second error
        for s in sfc.steps:
            v = self.pou.vars.get(s.name.upper())
            if v is not None and v.step is s:
                steps[s.name.upper()] = v
                info.steps.append(v)
            else:
                self.refused.add(s.name.upper())
        if not sfc.steps:
            self.error(sfc.pos, "an SFC body needs an INITIAL_STEP")
        actions = {}
        for a in sfc.actions:
            key = a.name.upper()
            if key in actions:
                self.error(a.pos, f"action '{a.name}' is already declared")
                continue
            if key in self.pou.vars:
                what = "a step" if self.pou.vars[key].step is not None else "a variable"
                self.error(a.pos, f"action '{a.name}' has the name of {what} of {self.pou.name}")
                continue
            actions[key] = ActionInfo(a.name, node=a)
        info.actions = list(actions.values())
        var_actions = {}
        for s in sfc.steps:
            v = steps.get(s.name.upper())
            for assoc in s.assocs:
                self.association(assoc, v, actions, var_actions)
        info.actions += list(var_actions.values())
        names = {}
        for t in sfc.transitions:
            if t.name:
                key = t.name.upper()
                if key in names:
                    self.error(t.pos, f"transition '{t.name}' is already declared")
                names[key] = t
            ti = TransitionInfo(t, self.step_list(t.sources, steps, "FROM"),
                                self.step_list(t.targets, steps, "TO"), t.priority, t.index)
            self.condition(t)
            if ti.sources is not None and ti.targets is not None:
                info.transitions.append(ti)
        self.networks(sfc, steps, info.transitions)
        for a in info.actions:
            if a.node is not None:
                self.action_body(a.node)
                if not a.assocs:
                    self.warning(a.node.pos, f"action '{a.name}' is not associated with any "
                                             "step: it never runs")

    # ------------------------------------------------------------ parts
    def step_list(self, names, steps, what):
        out = []
        seen = set()
        ok = True
        for name, pos in names:
            v = steps.get(name.upper())
            if v is None:
                if name.upper() not in self.refused:
                    self.error(pos, f"undeclared step '{name}' in {what}")
                ok = False
                continue
            if name.upper() in seen:
                self.error(pos, f"step '{name}' is named twice in {what}")
                ok = False
                continue
            seen.add(name.upper())
            out.append(v)
        return out if ok else None

    def condition(self, t):
        if t.cond is not None:
            self.bc.condition(t.cond, "TRANSITION")
            return
        instrs = t.il or []
        for i in instrs:
            bad = None
            if i.label:
                bad = f"a label ('{i.label}')"
            elif i.op in ("JMP", "JMPC", "JMPCN", "RET", "RETC", "RETCN", "CAL", "CALC",
                          "CALCN"):
                bad = i.op
            if bad:
                self.error(i.label_pos if i.label else i.pos,
                           f"{bad} is not allowed in a transition condition (a simple "
                           "instruction list: its current result at the end is the condition)")
                return
        saved = self.pou.labels
        self.pou.labels = {}
        try:
            self.bc.check_il(instrs)
        finally:
            self.pou.labels = saved
        last = instrs[-1].cr_out if instrs else None
        if last is None:
            self.error(t.pos, "the transition condition computes no value (load it with LD)")
        elif not isinstance(last, ErrorT) and not is_bool(last):
            self.error(instrs[-1].pos, f"TRANSITION condition must be BOOL, not {last.name}")

    def association(self, assoc, step, actions, var_actions):
        q = assoc.qualifier or "N"
        key = assoc.action.upper()
        target = actions.get(key)
        if target is None:
            target = var_actions.get(key)
        if target is None:
            v = self.pou.vars.get(key)
            if v is not None and v.step is None and v.type is BOOL and \
                    v.section in ("VAR", "VAR_OUTPUT", "VAR_IN_OUT", "VAR_EXTERNAL",
                                  "VAR_GLOBAL") and not v.constant:
                v.used = v.assigned = True
                target = var_actions[key] = ActionInfo(v.name, var=v)
            elif v is not None:
                why = "a step" if v.step is not None else (
                    f"a variable of type {v.type.name}" if v.type is not BOOL else
                    f"{'a constant' if v.constant else 'an input'}")
                self.error(assoc.pos, f"'{assoc.action}' is {why}, not an action (an action is "
                                      "an ACTION ... END_ACTION or a BOOL variable)")
            else:
                self.error(assoc.pos, f"action '{assoc.action}' is not declared (declare ACTION "
                                      f"{assoc.action}: ... END_ACTION or a BOOL variable)")
        args = list(assoc.args)
        time = None
        if q in TIMED:
            if not args or not _time_like(args[0]):
                self.error(assoc.qual_pos or assoc.pos,
                           f"qualifier {q} needs a time: write {assoc.action}({q}, T#1s)")
            else:
                time = args.pop(0)
                if isinstance(time, ast.Ref) and time.accessors:
                    # ed.2 B.1.6: action_time ::= duration | variable_name
                    self.error(time.pos, f"the time of qualifier {q} is a TIME literal or the "
                                         "name of a TIME variable")
                    time = None
                else:
                    t = self.bc.expr(time)
                    if not isinstance(t, ErrorT) and t is not TIME:
                        self.error(time.pos, f"the time of qualifier {q} must be TIME, "
                                             f"not {t.name}")
        elif args and _time_like(args[0]) and isinstance(args[0], ast.Lit):
            self.error(args[0].pos, f"qualifier {q} takes no time (only L, D, SD, DS and SL do)")
            args.pop(0)
        assoc.time = time
        for n, ind in enumerate(args):
            if not isinstance(ind, ast.Ref) or ind.accessors:
                # ed.2 B.1.6: indicator_name ::= variable_name
                self.error(ind.pos, "an indicator is the name of a BOOL variable")
                continue
            t = self.bc.expr(ind)
            if t is TIME and n == 0 and q not in TIMED:
                self.error(ind.pos, f"qualifier {q} takes no time (only L, D, SD, DS and SL do)")
            elif not isinstance(t, ErrorT) and t is not BOOL:
                self.error(ind.pos, f"an indicator must be a BOOL variable, not {t.name}")
        assoc.indicators = args
        if target is not None and step is not None:
            target.assocs.append(Association(step, q, time, assoc))

    def networks(self, sfc, steps, transitions):
        """One INITIAL_STEP per network; every step can become active."""
        parent = {k: k for k in steps}

        def find(k):
            while parent[k] != k:
                parent[k] = parent[parent[k]]
                k = parent[k]
            return k
        for t in transitions:
            keys = [v.key for v in t.sources + t.targets]
            for k in keys[1:]:
                parent[find(k)] = find(keys[0])
        initial = {}
        for s in sfc.steps:
            key = s.name.upper()
            if key not in steps or steps[key].step is not s or not s.initial:
                continue
            root = find(key)
            if root in initial:
                first = initial[root]
                self.error(s.pos, f"second INITIAL_STEP '{s.name}' in the network of "
                                  f"'{first.name}' (one network has one initial step)")
            else:
                initial[root] = s
        reported = set()
        for s in sfc.steps:
            key = s.name.upper()
            if key not in steps or steps[key].step is not s:
                continue
            root = find(key)
            if root not in initial and root not in reported:
                reported.add(root)
                self.error(s.pos, f"no INITIAL_STEP in the network of step '{s.name}'")
        active = {k for k in steps if steps[k].step.initial}
        changed = True
        while changed:
            changed = False
            for t in transitions:
                if all(v.key in active for v in t.sources):
                    for v in t.targets:
                        if v.key not in active:
                            active.add(v.key)
                            changed = True
        for s in sfc.steps:
            key = s.name.upper()
            if key in steps and steps[key].step is s and key not in active and \
                    find(key) in initial:
                self.error(s.pos, f"step '{s.name}' is unreachable: no transition leads to it "
                                  "from the initial step")

    def action_body(self, a):
        bc = self.bc
        if a.language == "IL":
            saved = self.pou.labels
            self.pou.labels = {}
            try:
                bc.check_il(a.body)
            finally:
                self.pou.labels = saved
        else:
            bc.stmts(a.body)


def _time_like(e):
    if isinstance(e, ast.Lit):
        return e.kind == "time"
    return isinstance(e, ast.Ref)
