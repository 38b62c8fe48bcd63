# SPDX-License-Identifier: MIT
"""The standard FBs built as a shared library and driven through ctypes,
step by step against the independent reference models in tests/reference
(timers.py: TON/TOF/TP automata; bistables.py: SR, RS, triggers, counters)."""
import ctypes as C

import pytest
from hypothesis import given, settings, strategies as st, HealthCheck

from reference import bistables as refb
from reference import timers as reft
from rt_helpers import cfile, rt

pytestmark = pytest.mark.execution

S64_MIN, S64_MAX = -2**63, 2**63 - 1


def wrap64(v):
    v &= 2**64 - 1
    return v - 2**64 if v >= 2**63 else v


class Ctx(C.Structure):
    _fields_ = [("now_ns", C.c_int64), ("wall_ns", C.c_int64), ("loop_budget", C.c_uint32),
                ("loop_budget_cycle", C.c_uint32), ("budget_fault", C.c_int),
                ("fault", C.c_int), ("fault_pou", C.c_char_p), ("fault_line", C.c_int),
                ("fault_count", C.c_uint32), ("sel_epoch", C.c_uint32),
                ("sel_changed", C.c_bool), ("sel_evaluated", C.c_uint64),
                ("sel_plain", C.c_uint64), ("sel_skipped", C.c_uint64),
                ("sel_cycle", C.c_uint64), ("frame_base", C.c_void_p),
                ("frame_size", C.c_uint32), ("frame_used", C.c_uint32),
                ("task_id", C.c_uint32)]


class Timer(C.Structure):
    _fields_ = [("in_", C.c_uint8), ("pt", C.c_int64), ("q", C.c_uint8),
                ("et", C.c_int64), ("state", C.c_uint8),
                ("prev_in", C.c_uint8), ("start", C.c_int64)]


def counter_structs(T):
    class CTU(C.Structure):
        _fields_ = [("cu", C.c_uint8), ("r", C.c_uint8), ("pv", T),
                    ("q", C.c_uint8), ("cv", T), ("cu_prev", C.c_uint8)]

    class CTD(C.Structure):
        _fields_ = [("cd", C.c_uint8), ("ld", C.c_uint8), ("pv", T),
                    ("q", C.c_uint8), ("cv", T), ("cd_prev", C.c_uint8)]

    class CTUD(C.Structure):
        _fields_ = [("cu", C.c_uint8), ("cd", C.c_uint8), ("r", C.c_uint8),
                    ("ld", C.c_uint8), ("pv", T), ("qu", C.c_uint8),
                    ("qd", C.c_uint8), ("cv", T), ("cu_prev", C.c_uint8),
                    ("cd_prev", C.c_uint8)]
    return CTU, CTD, CTUD


COUNTER_TYPES = {
    "": (C.c_int16, -2**15, 2**15 - 1),
    "_int": (C.c_int16, -2**15, 2**15 - 1),
    "_dint": (C.c_int32, -2**31, 2**31 - 1),
    "_lint": (C.c_int64, S64_MIN, S64_MAX),
    "_udint": (C.c_uint32, 0, 2**32 - 1),
    "_ulint": (C.c_uint64, 0, 2**64 - 1),
}


class Bool3(C.Structure):
    _fields_ = [("a", C.c_uint8), ("b", C.c_uint8), ("q", C.c_uint8)]


@pytest.fixture(scope="module")
def lib(builder):
    so = builder.build([*rt("iec_std_fb.c"), cfile("fb_layout.c")],
                       shared=True)
    lib = C.CDLL(str(so))
    lib.iec_test_layout.restype = C.c_long
    lib.iec_test_layout.argtypes = [C.c_char_p]
    return lib


def test_ctypes_mirrors_match_c_layout(lib):
    L = lambda k: lib.iec_test_layout(k.encode())
    assert L("ctx") == C.sizeof(Ctx)
    assert L("ctx.fault") == Ctx.fault.offset
    assert L("ctx.fault_count") == Ctx.fault_count.offset
    for f in ("sel_skipped", "frame_base", "task_id"):
        assert L("ctx." + f) == getattr(Ctx, f).offset
    assert L("ton") == C.sizeof(Timer)
    for f in ("pt", "q", "et", "state", "start"):
        assert L("ton." + f) == getattr(Timer, f).offset
    _, _, CTUD = counter_structs(C.c_int64)
    assert L("ctud_lint") == C.sizeof(CTUD)
    for f in ("pv", "cv", "cd_prev"):
        assert L("ctud_lint." + f) == getattr(CTUD, f).offset
    _, _, CTUD16 = counter_structs(C.c_int16)
    assert L("ctud") == C.sizeof(CTUD16)
    assert L("ctud.cv") == CTUD16.cv.offset


# ---------------------------------------------------------------- timers

pts = st.one_of(st.sampled_from([-5, 0, 1, 2, 3, 10, 50]),
                st.integers(-10, 1000), st.integers(0, 2**63 - 1))
dts = st.one_of(st.sampled_from([0, 1, 2, 3, 5, 10, 49, 50, 51]),
                st.integers(0, 2000))
starts = st.one_of(st.sampled_from([0, 2**63 - 300, 2**63 - 1, -300, -1,
                                    S64_MIN]),
                   st.integers(S64_MIN, S64_MAX))


@st.composite
def traces(draw):
    n = draw(st.integers(1, 60))
    # PT mostly constant with occasional changes, IN with short pulses
    pt = draw(pts)
    steps = []
    for _ in range(n):
        if draw(st.integers(0, 9)) == 0:
            pt = draw(pts)
        steps.append((draw(st.booleans()), pt, draw(dts)))
    return draw(starts), steps


def run_timer(lib, name, t0, steps, fn=None):
    body = getattr(lib, "iec_fb_" + (fn or name))
    fb, ctx = Timer(), Ctx()
    model = reft.TIMERS[name]()
    t = t0
    for i, (IN, PT, dt) in enumerate(steps):
        t += dt
        ctx.now_ns = wrap64(t)
        fb.in_, fb.pt = IN, PT
        body(C.byref(fb), C.byref(ctx))
        q, et = model.step(IN, PT, dt)
        assert (bool(fb.q), fb.et) == (q, et), (
            f"{name} step {i}: IN={IN} PT={PT} dt={dt} now={ctx.now_ns}: "
            f"C Q={fb.q} ET={fb.et}, model Q={q} ET={et} ({model.loc})")
        # the automaton invariants
        assert 0 <= fb.et <= max(PT, 0)
        if model.loc == reft.WORK:
            assert fb.et < max(PT, 0) or PT <= 0


@pytest.mark.parametrize("name", ["ton", "tof", "tp"])
@settings(max_examples=250, deadline=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(trace=traces())
def test_timer_matches_reference(lib, name, trace):
    t0, steps = trace
    run_timer(lib, name, t0, steps)


@pytest.mark.parametrize("name", ["ton", "tof", "tp"])
@settings(max_examples=150, deadline=None)
@given(trace=traces())
def test_ltime_timer_matches_reference(lib, name, trace):
    t0, steps = trace
    run_timer(lib, name, t0, steps, fn=name + "_ltime")


def _series(lib, name, t0, steps):
    body = getattr(lib, "iec_fb_" + name)
    fb, ctx, out, t = Timer(), Ctx(), [], t0
    for IN, PT, dt in steps:
        t += dt
        ctx.now_ns = wrap64(t)
        fb.in_, fb.pt = IN, PT
        body(C.byref(fb), C.byref(ctx))
        out.append((fb.q, fb.et))
    return out


@pytest.mark.parametrize("t0", [0, 2**63 - 25, -25])
def test_timing_diagrams(lib, t0):
    """The standard's diagrams at PT = 50, cycle 10, across clock wraps."""
    IN = [0, 1, 1, 1, 1, 1, 1, 1, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0]
    steps = [(b, 50, 10) for b in IN]
    assert _series(lib, "ton", t0, steps) == [
        (0, 0), (0, 0), (0, 10), (0, 20), (0, 30), (0, 40), (1, 50), (1, 50),
        (0, 0), (0, 0), (0, 0), (0, 0), (0, 0), (0, 0), (0, 0), (0, 0),
        (0, 0), (0, 0)]
    assert _series(lib, "tof", t0, steps) == [
        (0, 0), (1, 0), (1, 0), (1, 0), (1, 0), (1, 0), (1, 0), (1, 0),
        (1, 0), (1, 10), (1, 0), (1, 0), (1, 10), (1, 20), (1, 30), (1, 40),
        (0, 50), (0, 50)]
    assert _series(lib, "tp", t0, steps) == [
        (0, 0), (1, 0), (1, 10), (1, 20), (1, 30), (1, 40), (0, 50), (0, 50),
        (0, 0), (0, 0), (1, 0), (1, 10), (1, 20), (1, 30), (1, 40), (0, 0),
        (0, 0), (0, 0)]


# ---------------------------------------------------- bistables, triggers

@settings(max_examples=300, deadline=None)
@given(seq=st.lists(st.tuples(st.booleans(), st.booleans()), max_size=40))
def test_bistables_and_triggers(lib, seq):
    sr, rs, rt_, ft = Bool3(), Bool3(), Bool3(), Bool3()
    msr, mrs, mrt, mft = refb.SR(), refb.RS(), refb.R_TRIG(), refb.F_TRIG()
    ctx = Ctx()
    for a, b in seq:
        sr.a, sr.b = a, b
        lib.iec_fb_sr(C.byref(sr), C.byref(ctx))
        rs.a, rs.b = a, b
        lib.iec_fb_rs(C.byref(rs), C.byref(ctx))
        rt_.a = a
        lib.iec_fb_r_trig(C.byref(rt_), C.byref(ctx))
        ft.a = a
        lib.iec_fb_f_trig(C.byref(ft), C.byref(ctx))
        assert bool(sr.q) == msr.step(a, b)
        assert bool(rs.q) == mrs.step(a, b)
        # R_TRIG/F_TRIG: clk, q, prev -> Bool3 a=clk, b=q, q=prev
        assert bool(rt_.b) == mrt.step(a)
        assert bool(ft.b) == mft.step(a)


# --------------------------------------------------------------- counters

@pytest.mark.parametrize("suffix", sorted(COUNTER_TYPES))
@settings(max_examples=120, deadline=None)
@given(data=st.data())
def test_counters_match_reference(lib, suffix, data):
    T, lo, hi = COUNTER_TYPES[suffix]
    CTU, CTD, CTUD = counter_structs(T)
    near = st.one_of(st.integers(lo, hi), st.integers(lo, min(lo + 3, hi)),
                     st.integers(max(hi - 3, lo), hi), st.integers(-3, 3)
                     .filter(lambda v: lo <= v <= hi))
    cv0, pv = data.draw(near), data.draw(near)
    ctx = Ctx()
    u, d, ud = CTU(), CTD(), CTUD()
    mu, md, mud = (refb.CTU(lo, hi), refb.CTD(lo, hi), refb.CTUD(lo, hi))
    u.cv = d.cv = ud.cv = cv0
    mu.CV = md.CV = mud.CV = cv0
    for _ in range(data.draw(st.integers(1, 30))):
        cu, cd, r, ld = (data.draw(st.booleans()) for _ in range(4))
        r = r and data.draw(st.booleans())      # resets less often
        ld = ld and data.draw(st.booleans())
        u.cu, u.r, u.pv = cu, r, pv
        lib["iec_fb_ctu" + suffix](C.byref(u), C.byref(ctx))
        assert (bool(u.q), u.cv) == mu.step(cu, r, pv)
        d.cd, d.ld, d.pv = cd, ld, pv
        lib["iec_fb_ctd" + suffix](C.byref(d), C.byref(ctx))
        assert (bool(d.q), d.cv) == md.step(cd, ld, pv)
        ud.cu, ud.cd, ud.r, ud.ld, ud.pv = cu, cd, r, ld, pv
        lib["iec_fb_ctud" + suffix](C.byref(ud), C.byref(ctx))
        assert (bool(ud.qu), bool(ud.qd), ud.cv) == mud.step(cu, cd, r, ld, pv)


# ------------------------------------------------------ SFC ACTION_CONTROL

QUALS = ("n", "r", "s0", "l", "d", "p", "p1", "p0", "sd", "ds", "sl")


class ActionControl(C.Structure):
    _fields_ = [(q, C.c_uint8) for q in QUALS] + [
        ("t", C.c_int64), ("q", C.c_uint8), ("a", C.c_uint8),
        ("s_ff", C.c_uint8), ("sd_ff", C.c_uint8), ("ds_ff", C.c_uint8), ("sl_ff", C.c_uint8),
        ("p_prev", C.c_uint8), ("p1_prev", C.c_uint8), ("p0_prev", C.c_uint8),
        ("l_tmr", Timer), ("d_tmr", Timer), ("sd_tmr", Timer), ("ds_tmr", Timer),
        ("sl_tmr", Timer)]


def test_action_control_mirror_matches_c_layout(lib):
    L = lambda k: lib.iec_test_layout(k.encode())
    assert L("action_control") == C.sizeof(ActionControl)
    for f in ("t", "q", "a", "p0_prev", "l_tmr", "sl_tmr"):
        assert L("action_control." + f) == getattr(ActionControl, f).offset


@st.composite
def action_traces(draw):
    """Qualifier inputs as step activity flags (each held for a few calls,
    as steps are), a T that sometimes changes, 0-20 ms between calls."""
    used = draw(st.lists(st.sampled_from(QUALS), min_size=1, max_size=4, unique=True))
    n = draw(st.integers(1, 50))
    state = dict.fromkeys(QUALS, False)
    t = draw(st.sampled_from([0, 10, 30, 50]))
    steps = []
    for _ in range(n):
        for q in used:
            if draw(st.integers(0, 3)) == 0:
                state[q] = not state[q]
        if draw(st.integers(0, 9)) == 0:
            t = draw(st.sampled_from([0, 10, 30, 50]))
        steps.append((dict(state), t, draw(st.sampled_from([0, 5, 10, 20]))))
    return steps


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(trace=action_traces())
def test_action_control_matches_the_interpreter(lib, trace):
    """The runtime's ACTION_CONTROL (kmod_templates/runtime/iec_std_fb.c)
    against the reference interpreter's own (iec2kmod/interp/sfc.py), call
    by call: Q and A for every qualifier, timers included."""
    from iec2kmod.interp.sfc import ActionControl as Ref

    class Rt:
        now = 0
    # a context of the C struct's own size (only now_ns is read here)
    size, at = lib.iec_test_layout(b"ctx"), lib.iec_test_layout(b"ctx.now_ns")
    ctx = (C.c_uint8 * size)()
    now_ns = C.c_int64.from_buffer(ctx, at)
    fb, ref, rt_ = ActionControl(), Ref(), Rt()
    key = {"s0": "S"}
    now = 0
    for i, (inputs, t_ms, dt) in enumerate(trace):
        now += dt * 1_000_000
        now_ns.value = now
        rt_.now = now
        for q in QUALS:
            setattr(fb, q, inputs[q])
        fb.t = ref.T = t_ms * 1_000_000
        ref.inputs = {key.get(q, q.upper()): inputs[q] for q in QUALS}
        lib.iec_fb_action_control(C.byref(fb), C.byref(ctx))
        ref.run(rt_)
        assert (bool(fb.q), bool(fb.a)) == (ref.Q, ref.A), \
            f"call {i}: inputs {inputs}, T={t_ms} ms, now={now}"
