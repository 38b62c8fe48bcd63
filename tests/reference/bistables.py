# SPDX-License-Identifier: MIT
"""Reference models of SR, RS, R_TRIG, F_TRIG and the counters CTU, CTD,
CTUD, transcribed from the standard's ST definitions (IEC 61131-3 ed.3,
6.6.3.5).  The counters take the limits of their CV type."""


class SR:
    def __init__(self):
        self.Q1 = False

    def step(self, S1, R):
        self.Q1 = bool(S1) or (not R and self.Q1)
        return self.Q1


class RS:
    def __init__(self):
        self.Q1 = False

    def step(self, S, R1):
        self.Q1 = (not R1) and (bool(S) or self.Q1)
        return self.Q1


class R_TRIG:
    def __init__(self):
        self.M = False

    def step(self, CLK):
        Q = bool(CLK) and not self.M
        self.M = bool(CLK)
        return Q


class F_TRIG:
    # M starts TRUE: no falling edge is reported on the first call
    def __init__(self):
        self.M = True

    def step(self, CLK):
        Q = (not CLK) and not self.M
        self.M = not CLK
        return Q


class CTU:
    def __init__(self, lo, hi):
        self.lo, self.hi = lo, hi
        self.CV = 0
        self.edge = R_TRIG()

    def step(self, CU, R, PV):
        cu = self.edge.step(CU)
        if R:
            self.CV = 0
        elif cu and self.CV < self.hi:
            self.CV += 1
        return self.CV >= PV, self.CV


class CTD:
    def __init__(self, lo, hi):
        self.lo, self.hi = lo, hi
        self.CV = 0
        self.edge = R_TRIG()

    def step(self, CD, LD, PV):
        cd = self.edge.step(CD)
        if LD:
            self.CV = PV
        elif cd and self.CV > self.lo:
            self.CV -= 1
        return self.CV <= 0, self.CV


class CTUD:
    def __init__(self, lo, hi):
        self.lo, self.hi = lo, hi
        self.CV = 0
        self.up = R_TRIG()
        self.down = R_TRIG()

    def step(self, CU, CD, R, LD, PV):
        cu = self.up.step(CU)
        cd = self.down.step(CD)
        if R:
            self.CV = 0
        elif LD:
            self.CV = PV
        elif not (cu and cd):
            if cu and self.CV < self.hi:
                self.CV += 1
            elif cd and self.CV > self.lo:
                self.CV -= 1
        return self.CV >= PV, self.CV <= 0, self.CV
