"""The standard function blocks (IEC 61131-3 ed.3, 6.6.3.5): bistables,
edge detection, counters and timers, each a Python body working on an
instance's variables.  Hidden state lives under keys starting with '$'.

Timers follow the timed automata of seed 002 (Init / Work / Tout, and On
for TOF): the clock x runs only in Work, x being the time since the call
that entered Work, read from the task cycle's start time (one cycle sees
one time); a negative PT acts as T#0s; PT is read at every call."""

from __future__ import annotations

INIT, WORK, TOUT, ON = 0, 1, 2, 3


def sr(v, rt):
    v["Q1"] = bool(v["S1"] or (not v["R"] and v["Q1"]))


def rs(v, rt):
    v["Q1"] = bool(not v["R1"] and (v["S"] or v["Q1"]))


def r_trig(v, rt):
    clk = v["CLK"]
    v["Q"] = bool(clk and not v["$M"])
    v["$M"] = bool(clk)


def f_trig(v, rt):
    # M holds NOT CLK of the previous call and starts TRUE ("CLK was FALSE"),
    # so a FALSE CLK on the first call is no falling edge
    clk = v["CLK"]
    v["Q"] = bool(not clk and not v["$M"])
    v["$M"] = not clk


def _edge(v, name):
    x = v[name]
    e = bool(x and not v["$" + name])
    v["$" + name] = bool(x)
    return e


def counter(kind, lo, hi):
    if kind == "CTU":
        def ctu(v, rt):
            cu = _edge(v, "CU")
            if v["R"]:
                v["CV"] = 0
            elif cu and v["CV"] < hi:
                v["CV"] += 1
            v["Q"] = v["CV"] >= v["PV"]
        return ctu
    if kind == "CTD":
        def ctd(v, rt):
            cd = _edge(v, "CD")
            if v["LD"]:
                v["CV"] = v["PV"]
            elif cd and v["CV"] > lo:
                v["CV"] -= 1
            v["Q"] = v["CV"] <= 0
        return ctd

    def ctud(v, rt):
        cu = _edge(v, "CU")
        cd = _edge(v, "CD")
        if v["R"]:
            v["CV"] = 0
        elif v["LD"]:
            v["CV"] = v["PV"]
        elif not (cu and cd):
            if cu and v["CV"] < hi:
                v["CV"] += 1
            elif cd and v["CV"] > lo:
                v["CV"] -= 1
        v["QU"] = v["CV"] >= v["PV"]
        v["QD"] = v["CV"] <= 0
    return ctud


def _x(v, rt):
    return rt.now - v["$T0"]


def _timer_out(v, rt, st, pt):
    if st == WORK:
        v["ET"] = _x(v, rt)
    elif st == TOUT:
        v["ET"] = pt
    else:
        v["ET"] = 0


def ton(v, rt):
    pt = max(v["PT"], 0)
    st = v["$S"]
    if not v["IN"]:
        st = INIT
    else:
        if st == INIT:
            st = WORK
            v["$T0"] = rt.now
        if st == WORK and _x(v, rt) >= pt:
            st = TOUT
    v["$S"] = st
    v["Q"] = st == TOUT
    _timer_out(v, rt, st, pt)


def tof(v, rt):
    pt = max(v["PT"], 0)
    st = v["$S"]
    if v["IN"]:
        st = ON
    else:
        if st == ON:
            st = WORK
            v["$T0"] = rt.now
        if st == WORK and _x(v, rt) >= pt:
            st = TOUT
    v["$S"] = st
    v["Q"] = st in (ON, WORK)
    _timer_out(v, rt, st, pt)


def tp(v, rt):
    pt = max(v["PT"], 0)
    st = v["$S"]
    inp = bool(v["IN"])
    rising = inp and not v["$LAST"]
    if st in (INIT, TOUT) and rising:
        st = WORK
        v["$T0"] = rt.now
    if st == WORK:
        if _x(v, rt) >= pt:
            st = TOUT if inp else INIT
    elif st == TOUT and not inp:
        st = INIT
    v["$LAST"] = inp
    v["$S"] = st
    v["Q"] = st == WORK
    _timer_out(v, rt, st, pt)


# The clock RTC reads in the interpreter (and the simulator): the simulated
# time from the epoch DT#1970-01-01-00:00:00 (DT 0), so runs are
# deterministic; the kernel reads the wall clock at the cycle's release.
RTC_EPOCH = 0


def _s64(x):
    return (x + (1 << 63)) % (1 << 64) - (1 << 63)


def rtc(v, rt):
    """RTC as MatIEC defines it: OFFSET := PDT - clock on a rising IN,
    CDT := clock + OFFSET while IN, CDT := clock otherwise; Q := IN."""
    now = _s64(RTC_EPOCH + rt.now)
    inp = bool(v["IN"])
    if inp:
        if not v["$LAST"]:
            v["$OFS"] = _s64(v["PDT"] - now)
        v["CDT"] = _s64(now + v["$OFS"])
    else:
        v["CDT"] = now
    v["Q"] = inp
    v["$LAST"] = inp


def body_of(pou):
    """(Python body, hidden state {key: initial value}) of a standard FB."""
    name = pou.name.upper()
    if name == "SR":
        return sr, {}
    if name == "RS":
        return rs, {}
    if name == "R_TRIG":
        return r_trig, {"$M": False}
    if name == "F_TRIG":
        return f_trig, {"$M": True}
    if name in ("TON", "TOF", "TP"):
        return {"TON": ton, "TOF": tof, "TP": tp}[name], {"$S": INIT, "$T0": 0, "$LAST": False}
    if name == "RTC":
        return rtc, {"$LAST": False, "$OFS": 0}
    for kind in ("CTUD", "CTU", "CTD"):
        if name.startswith(kind):
            t = pou.vars["CV"].type
            lo, hi = t.range
            hidden = {"$CU": False, "$CD": False}
            return counter(kind, lo, hi), hidden
    raise AssertionError(f"standard FB {name}")
