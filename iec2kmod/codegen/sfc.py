"""SFC bodies to C (textual SFC, IEC 61131-3 ed.2 2.6).

The state of an SFC lives in the instance struct: every step is a member
``v_<step>`` of ``struct t___sfc_step`` (X, T: the variables the checks
declared, iec2kmod/checks/sfc.py), plus hidden members ``h_sfc_t0_<step>``
(activation time), ``h_sfc_started`` and one ``struct
iec_fb_action_control h_sfc_ac<k>`` per action (the standard's
ACTION_CONTROL block, kmod_templates/runtime/iec_std_fb.c).

The cycle model (one call of the body; ``now`` is ctx->now_ns, the start of
the task's cycle; the reference interpreter implements the same rules on
its own, iec2kmod/interp/sfc.py):

  0. The first call after initialisation takes ``now`` as the activation
     time of the initial steps (X = TRUE from the start, ed.2 2.6.3 rule 1).
  1. Every active step gets T := now - its activation time.  An inactive
     step keeps the T it had when it was deactivated (ed.2 2.6.2).
  2. Transitions are evaluated with the step states of the start of the
     cycle: a transition is enabled when all its preceding steps are active;
     the condition of every enabled transition is evaluated (ST expression or
     IL current result), in priority order: transitions with PRIORITY first,
     lowest number first, then those without, each group in source order.
     A condition that faults stops the body there (nothing is cleared).
  3. Selection (divergence, ed.2 figure 11): going through the transitions
     in that order, a transition with a TRUE condition is cleared unless it
     shares a preceding step with a transition cleared before it.
  4. Clearing, all at once (ed.2 2.6.3 rules 3 and 4): the preceding steps
     of every cleared transition are deactivated (X := FALSE, T kept) and
     the following steps activated (X := TRUE, T := T#0s, activation time
     := now).  A step that is both deactivated and activated stays active
     without interruption (its T keeps counting); so does an active step
     that is activated again.  A step activated here is active for at least
     this cycle's actions and the next cycle's transition evaluation: it is
     active for one cycle at least.  Transitions come first in every cycle:
     an initial step whose transition is TRUE in the first cycle is left
     before its actions ever run (as in MatIEC's generated code).
  5. Action control: for every action, each qualifier input of its
     ACTION_CONTROL block is the OR of the X flags (after clearing) of the
     steps that associate it with that qualifier (no qualifier is N; P and
     P1 pulse on the rising edge, P0 on the falling edge; P is part of the
     action flag Q, P1 and P0 only of the activation A).  T is the time of
     the first timed association, in source order, whose step is active; it
     keeps its value while none is (a stored SD/SL timer runs on).  The
     blocks of all actions are evaluated, in the order of the actions
     (ACTIONs as declared, then Boolean-variable actions in the order of
     their first association), before any body runs.
  6. Action bodies: every ACTION whose A is TRUE runs once, in declaration
     order; a Boolean-variable action's variable gets Q (ed.2 2.6.4.5: Q is
     FALSE during an execution invoked by P1 or P0).  No final scan: an
     action does not run once more after Q falls (the standard leaves the
     choice to the implementation; MatIEC has none either).  RETURN ends the
     action's body, a fault stops the whole body (the task's fault rules).
"""

from __future__ import annotations

from ..checks.sfc import TIMED
from ..checks.types import TIME
from . import cnames as N
from .expr import CodegenError, Frame

# qualifier -> member of struct iec_fb_action_control
INPUT = {"N": "n", "R": "r", "S": "s0", "L": "l", "D": "d", "P": "p", "P1": "p1",
         "P0": "p0", "SD": "sd", "DS": "ds", "SL": "sl"}
INPUT_ORDER = ("N", "R", "S", "L", "D", "P", "P1", "P0", "SD", "DS", "SL")


def transition_order(sfc):
    """Transitions in evaluation (priority) order."""
    return sorted(sfc.transitions,
                  key=lambda t: (0, t.priority, t.index) if t.priority is not None
                  else (1, 0, t.index))


def struct_members(pou) -> list[str]:
    """The hidden members of an SFC instance (declared after the variables)."""
    sfc = pou.sfc
    lines = ["/* SFC: activation times, first call, ACTION_CONTROL of each action */"]
    lines += [f"iec_s64 h_sfc_t0_{v.name.lower()};" for v in sfc.steps]
    lines.append("iec_bool h_sfc_started;")
    lines += [f"struct iec_fb_action_control h_sfc_ac{k};" for k in range(len(sfc.actions))]
    return lines


class SFCEmitter:
    def __init__(self, be):
        self.be = be
        self.pou = be.pou
        self.sfc = be.pou.sfc

    def x(self, v):
        return f"{self.be.var_access(v)}.{N.var('X')}"

    def t(self, v):
        return f"{self.be.var_access(v)}.{N.var('T')}"

    @staticmethod
    def t0(v):
        return f"self->h_sfc_t0_{v.name.lower()}"

    def lines(self) -> list[str]:
        be = self.be
        sfc = self.sfc
        ind = be.ind
        now = "ctx->now_ns"
        order = transition_order(sfc)
        # 0. the first call: the initial steps' activation time
        out = ["if (!self->h_sfc_started) {", ind + "self->h_sfc_started = 1;"]
        for v in sfc.steps:
            out += [ind + f"if ({self.x(v)})", ind * 2 + f"{self.t0(v)} = {now};"]
        out.append("}")
        # 1. elapsed time of the active steps
        for v in sfc.steps:
            out += [f"if ({self.x(v)})",
                    ind + f"{self.t(v)} = (iec_time)((iec_u64){now} - (iec_u64){self.t0(v)});"]
        # 2. conditions of the enabled transitions
        tc = {}
        for k, t in enumerate(order):
            name = f"sfc_tc{k}"
            tc[id(t)] = name
            out.append(f"{name} = 0;")
            enabled = " && ".join(self.x(v) for v in t.sources)
            out += [f"if ({enabled}) {{"] + be.indent(self.condition(t, name)) + ["}"]
        # 3. selection among transitions sharing a preceding step
        for k, t in enumerate(order):
            earlier = [tc[id(o)] for o in order[:k]
                       if any(v in o.sources for v in t.sources)]
            if earlier:
                out.append(f"{tc[id(t)]} = {tc[id(t)]} && "
                           + " && ".join(f"!{e}" for e in earlier) + ";")
        # 4. clearing
        for v in sfc.steps:
            act = [tc[id(t)] for t in order if v in t.targets]
            deact = [tc[id(t)] for t in order if v in t.sources]
            if act:
                out += [f"if ({' || '.join(act)}) {{",
                        ind + f"if (!{self.x(v)}) {{",
                        ind * 2 + f"{self.x(v)} = 1;",
                        ind * 2 + f"{self.t(v)} = 0;",
                        ind * 2 + f"{self.t0(v)} = {now};",
                        ind + "}"]
                if deact:
                    out += [f"}} else if ({' || '.join(deact)}) {{", ind + f"{self.x(v)} = 0;"]
                out.append("}")
            elif deact:
                out += [f"if ({' || '.join(deact)})", ind + f"{self.x(v)} = 0;"]
        # 5. action control
        for k, a in enumerate(sfc.actions):
            ac = f"self->h_sfc_ac{k}"
            for q in INPUT_ORDER:
                steps = []
                for s in a.assocs:
                    if s.qualifier == q and s.step not in steps:
                        steps.append(s.step)
                if steps:
                    out.append(f"{ac}.{INPUT[q]} = " + " || ".join(self.x(v) for v in steps)
                               + ";")
            timed = [s for s in a.assocs if s.qualifier in TIMED]
            for n, s in enumerate(timed):
                f = Frame(be, s.node.pos)
                code = be.expr.emit(f, s.time, TIME)
                if f.pre or f.decls or f.may_fault:
                    # the checks allow a literal or a variable name only
                    raise CodegenError(f"the time of {a.name}({s.qualifier}) needs code")
                out.append(f"{'else ' if n else ''}if ({self.x(s.step)})")
                out.append(ind + f"{ac}.t = {code};")
            out.append(f"iec_fb_action_control(&{ac}, ctx);")
        # 6. action bodies, then Boolean-variable actions
        for k, a in enumerate(sfc.actions):
            ac = f"self->h_sfc_ac{k}"
            if a.var is not None:
                out.append(f"{be.var_access(a.var)} = {ac}.q;")
                continue
            body, end = self.action_body(a, k)
            out += [f"if ({ac}.a) {{"] + be.indent(body)
            if end:
                out.append(f"{end}:;")
            out.append("}")
        decls = [f"iec_bool sfc_tc{k};" for k in range(len(order))]
        return ["{"] + be.indent(decls + out) + ["}"]

    def condition(self, t, name) -> list[str]:
        be = self.be
        node = t.node
        if node.cond is not None:
            f = Frame(be, node.cond.pos)
            c = be.checked_value(f, be.cond(f, node.cond), "iec_bool", node.cond.pos)
            return be.wrap(f, [f"{name} = {c};"], node.cond.pos, check=False)
        lines = be.il_body(node.il)
        last = node.il[-1].cr_out
        return lines + [f"{name} = {be.cr_var(last, 0)};"]

    def action_body(self, a, k):
        """The C lines of an ACTION's body and the label RETURN jumps to
        (None when unused)."""
        be = self.be
        end = f"sfc_a{k}_end"
        saved = (be.return_label, be.il_label_prefix)
        be.return_label, be.il_label_prefix = end, f"a{k}_"
        be.return_label_used = False
        try:
            if a.node.language == "IL":
                lines = be.il_body(a.node.body)
            else:
                lines = []
                for s in a.node.body:
                    lines += be.stmt(s)
            used = be.return_label_used
        finally:
            be.return_label, be.il_label_prefix = saved
        return lines, (end if used else None)


__all__ = ["SFCEmitter", "struct_members", "transition_order", "INPUT"]
