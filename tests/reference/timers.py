# SPDX-License-Identifier: MIT
"""Reference model of the IEC 61131-3 timers TON, TOF and TP.

Written from the timed automata of seed 002 (Li Yuzhen, 2019: locations
Init with ET = 0, Work with 0 < ET < PT while the clock runs, Tout with
ET = PT) and the timing diagrams of IEC 61131-3, independently of the C
runtime.  The model differs from the C code in how it keeps time: a timer
owns a clock x that the simulation advances by the time that passed between
two calls (x' = x + dt, exactly, in unbounded Python integers), instead of
subtracting 64-bit time stamps; so it also checks the C code's wrap-around
arithmetic.

A PLC calls a timer once per cycle: `step(IN, PT, dt)` is one call, dt
being the time since the previous call.  Outputs (Q, ET) are sampled right
after the call.  Guards are evaluated at the call (a cyclic program cannot
observe anything between calls).  PT is read at every call; a negative PT
behaves as 0.

Automata (x: the clock; urgent transitions taken within the same call):

TON   Init --IN--> Work (x := 0)          Init: Q = 0, ET = 0
      Work --not IN--> Init                Work: Q = 0, ET = x
      Work --x >= PT--> Tout               Tout: Q = 1, ET = PT
      Tout --not IN--> Init

TOF   (On: IN is true, Q = 1, ET = 0; Init: Q = 0, ET = 0 before any IN)
      * --IN--> On
      On --not IN--> Work (x := 0)         Work: Q = 1, ET = x
      Work --x >= PT--> Tout               Tout: Q = 0, ET = PT
      Work --IN--> On;  Tout --IN--> On

TP    Init/Tout --rising edge of IN--> Work (x := 0)   Work: Q = 1, ET = x
      Work --x >= PT--> Tout if IN, Init if not IN     (IN ignored in Work)
      Tout --not IN--> Init                            Tout: Q = 0, ET = PT
"""

INIT, WORK, TOUT, ON = "Init", "Work", "Tout", "On"


class Timer:
    kind = None

    def __init__(self):
        self.loc = INIT
        self.x = 0          # the automaton's clock, ns
        self.last_in = False
        self.Q = False
        self.ET = 0
        self.pt = 0

    def step(self, IN, PT, dt):
        """One call of the FB, dt ns after the previous call."""
        assert dt >= 0
        if self.loc == WORK:
            self.x += dt     # only Work lets the clock run
        self.pt = max(PT, 0)
        self._transition(bool(IN))
        self.last_in = bool(IN)
        self._outputs()
        return self.Q, self.ET

    def _enter_work(self):
        self.loc = WORK
        self.x = 0


class TON(Timer):
    def _transition(self, IN):
        if not IN:
            self.loc = INIT
            return
        if self.loc == INIT:
            self._enter_work()
        if self.loc == WORK and self.x >= self.pt:
            self.loc = TOUT

    def _outputs(self):
        self.Q = self.loc == TOUT
        self.ET = {INIT: 0, WORK: self.x, TOUT: self.pt}[self.loc]


class TOF(Timer):
    def _transition(self, IN):
        if IN:
            self.loc = ON
            return
        if self.loc == ON:
            self._enter_work()
        if self.loc == WORK and self.x >= self.pt:
            self.loc = TOUT

    def _outputs(self):
        self.Q = self.loc in (ON, WORK)
        self.ET = {INIT: 0, ON: 0, WORK: self.x, TOUT: self.pt}[self.loc]


class TP(Timer):
    def _transition(self, IN):
        rising = IN and not self.last_in
        if self.loc in (INIT, TOUT) and rising:
            self._enter_work()
        if self.loc == WORK:
            if self.x < self.pt:
                return
            self.loc = TOUT if IN else INIT
        elif self.loc == TOUT and not IN:
            self.loc = INIT

    def _outputs(self):
        self.Q = self.loc == WORK
        self.ET = {INIT: 0, WORK: self.x, TOUT: self.pt}[self.loc]


TIMERS = {"ton": TON, "tof": TOF, "tp": TP}
