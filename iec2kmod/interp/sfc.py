"""SFC bodies in the reference interpreter (textual SFC, IEC 61131-3 ed.2
2.6), written from the standard's evolution rules, not from the C code.

A step is the structure value the checks declared (``inst.v[STEP] ==
{"X": bool, "T": ns}``); what the standard keeps hidden lives in
``inst.e["$SFC"]``: the activation times of the steps, whether the first
call happened, and one ACTION_CONTROL state per action.

One call of the body, ``now`` being the start of the task's cycle:

  * First call: the initial steps (active from initialisation) are taken
    to be activated now.
  * Step times: an active step's T is now minus its activation; an
    inactive step shows the T it had when deactivated.
  * Transition evaluation: with the situation at the start of the call,
    every transition whose preceding steps are all active is enabled and
    its condition computed; they are visited by priority (PRIORITY given:
    smaller first; then the others; ties in source order).
  * Which transitions clear: visiting in that order, a TRUE transition
    clears unless one already cleared shares one of its preceding steps
    (a divergence takes its first TRUE branch).
  * Clearing is simultaneous: all preceding steps of clearing transitions
    leave, all following steps enter (X TRUE, T 0, activation now); a step
    that leaves and enters at once, or enters while active, simply stays.
  * ACTION_CONTROL (ed.2 2.6.4.5, figure 14, no final scan) for every
    action in turn: each qualifier input is TRUE when some step associating
    the action with that qualifier is active (P and P1 rising edge, P0
    falling edge); T comes from the first active step with a timed
    association (kept when none); the action flag Q and the activation A
    (Q, or a P1/P0 pulse, which Q never shows) are computed for all actions
    first.
  * Then the bodies: each ACTION with A runs once, in declaration order;
    a Boolean variable used as an action receives Q.
"""

from __future__ import annotations

from .fbs import INIT, ton
from .errors import Fault

TIMED = {"L", "D", "SD", "DS", "SL"}


class _Timer(dict):
    """A TON instance as fbs.ton expects it."""

    def __init__(self):
        super().__init__(IN=False, PT=0, Q=False, ET=0)
        self["$S"] = INIT
        self["$T0"] = 0
        self["$LAST"] = False


class ActionControl:
    """The ACTION_CONTROL block of one action: RS flip-flops, TON timers
    and edge triggers wired as in the standard's figure."""

    def __init__(self):
        self.inputs = dict.fromkeys(("N", "R", "S", "L", "D", "P", "P1", "P0", "SD", "DS", "SL"),
                                    False)
        self.T = 0
        self.Q = False
        self.A = False
        self.S_FF = self.SD_FF = self.DS_FF = self.SL_FF = False
        self.mem = {"P": False, "P1": False, "P0": False}
        self.L_TMR, self.D_TMR = _Timer(), _Timer()
        self.SD_TMR, self.DS_TMR, self.SL_TMR = _Timer(), _Timer(), _Timer()

    @staticmethod
    def _rs(set_, reset1, q):
        return (not reset1) and (set_ or q)

    @staticmethod
    def _ton(tmr, inp, pt, rt):
        tmr["IN"] = inp
        tmr["PT"] = pt
        ton(tmr, rt)
        return tmr["Q"]

    def run(self, rt):
        i = self.inputs
        R = i["R"]
        self.S_FF = self._rs(i["S"], R, self.S_FF)
        l_q = self._ton(self.L_TMR, i["L"], self.T, rt)
        d_q = self._ton(self.D_TMR, i["D"], self.T, rt)
        rising = {}
        for q in ("P", "P1"):
            rising[q] = i[q] and not self.mem[q]
            self.mem[q] = i[q]
        falling = self.mem["P0"] and not i["P0"]
        self.mem["P0"] = i["P0"]
        self.SD_FF = self._rs(i["SD"], R, self.SD_FF)
        sd_q = self._ton(self.SD_TMR, self.SD_FF, self.T, rt)
        ds_q = self._ton(self.DS_TMR, i["DS"], self.T, rt)
        self.DS_FF = self._rs(ds_q, R, self.DS_FF)
        self.SL_FF = self._rs(i["SL"], R, self.SL_FF)
        sl_q = self._ton(self.SL_TMR, self.SL_FF, self.T, rt)
        self.Q = (not R) and bool(i["N"] or self.S_FF or (i["L"] and not l_q) or d_q
                                  or rising["P"] or sd_q or self.DS_FF
                                  or (self.SL_FF and not sl_q))
        self.A = bool(self.Q or rising["P1"] or falling)


class _State:
    def __init__(self, n_actions):
        self.started = False
        self.since = {}                 # step key -> activation time
        self.controls = [ActionControl() for _ in range(n_actions)]


def compile_sfc(pc):
    """The body closure of an SFC POU (pc: the PouCompiler)."""
    sfc = pc.pou.sfc
    rt = pc.rt
    steps = [v.key for v in sfc.steps]
    ranked = sorted(sfc.transitions,
                    key=lambda t: (t.priority is None, t.priority or 0, t.index))
    transitions = []
    for t in ranked:
        node = t.node
        if node.cond is not None:
            cond = pc.cond(node.cond)
        else:
            cond = _il_condition(pc, node.il)
        transitions.append(([v.key for v in t.sources], [v.key for v in t.targets], cond))
    actions = []
    for a in sfc.actions:
        assocs = []
        for s in a.assocs:
            time = pc.located(pc.expr(s.time), s.time.pos) if s.time is not None else None
            assocs.append((s.step.key, s.qualifier, time))
        if a.var is not None:
            body = None
            target = pc.writer(_ref_to(a.var), a.var.type, check=False)
        else:
            target = None
            if a.node.language == "IL":
                body = pc.il_body(a.node.body)
            else:
                body = pc.block(a.node.body)
        actions.append((assocs, body, target))

    def run(env):
        v = env.v
        state = env.e.get("$SFC")
        if state is None:
            state = env.e["$SFC"] = _State(len(actions))
        now = rt.now
        if not state.started:
            state.started = True
            for k in steps:
                if v[k]["X"]:
                    state.since[k] = now
        for k in steps:
            if v[k]["X"]:
                v[k]["T"] = now - state.since[k]
        # which transitions clear, from the situation at the start
        fire = []
        taken = set()
        results = []
        for sources, targets, cond in transitions:
            ok = all(v[k]["X"] for k in sources) and bool(cond(env))
            results.append(ok)
        for (sources, targets, _), ok in zip(transitions, results):
            if ok and not taken.intersection(sources):
                fire.append((sources, targets))
                taken.update(sources)
        leaving = {k for s, _ in fire for k in s}
        entering = {k for _, t in fire for k in t}
        for k in leaving - entering:
            v[k]["X"] = False
        for k in entering:
            if not v[k]["X"]:
                v[k]["X"] = True
                v[k]["T"] = 0
                state.since[k] = now
        # action control of every action, then the bodies
        for (assocs, _, _), ac in zip(actions, state.controls):
            inputs = dict.fromkeys(ac.inputs, False)
            chosen = None
            for step, q, time in assocs:
                active = bool(v[step]["X"])
                inputs[q] = inputs[q] or active
                if q in TIMED and active and chosen is None:
                    chosen = time
            if chosen is not None:
                ac.T = chosen(env)
            ac.inputs = inputs
            ac.run(rt)
        for (_, body, target), ac in zip(actions, state.controls):
            if target is not None:
                target(env, ac.Q)
            elif ac.A:
                body(env)       # RETURN ends the action only
        return None
    return run


def _il_condition(pc, instrs):
    body = pc.il_body(instrs)

    def cond(env):
        saved = env.cr
        try:
            body(env)
            return env.cr
        finally:
            env.cr = saved
    return cond


def _ref_to(var):
    from .. import ast
    r = ast.Ref(var.pos, var.name, [])
    r.symbol = var
    r.type = var.type
    return r


__all__ = ["compile_sfc", "ActionControl", "Fault"]
