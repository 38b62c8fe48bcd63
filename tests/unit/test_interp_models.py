"""The reference interpreter's standard FBs and string functions, step by
step against the independent Python models in tests/reference (seed 002's
timer automata, the standard's ST definitions of bistables and counters,
the string functions), on random input sequences."""

from __future__ import annotations

import random
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from reference import bistables as refb  # noqa: E402
from reference import strings as refs  # noqa: E402
from reference import timers as reft  # noqa: E402

from iec2kmod.checks import stdlib  # noqa: E402
from iec2kmod.interp import fbs, std  # noqa: E402
from iec2kmod.interp.conv import duration_text, to_text  # noqa: E402
from iec2kmod.interp.model import Initializer  # noqa: E402
from iec2kmod.checks.symbols import Project  # noqa: E402
from iec2kmod.checks.types import ELEMENTARY  # noqa: E402


class _RT:
    now = 0


def _instance(name):
    pou = stdlib.FUNCTION_BLOCKS[name]
    init = Initializer(Project())
    v = {var.key: init.value(var.type, None) for var in pou.vars.values()}
    body, hidden = fbs.body_of(pou)
    v.update(hidden)
    return v, body


@pytest.mark.parametrize("seed", range(40))
@pytest.mark.parametrize("name", ["TON", "TOF", "TP"])
def test_timer_matches_seed_002_model(name, seed):
    rng = random.Random(f"{name}-{seed}")
    v, body = _instance(name)
    model = reft.TIMERS[name.lower()]()
    rt = _RT()
    for step in range(300):
        dt = rng.choice([0, 1, 5_000_000, 10_000_000, rng.randint(0, 60_000_000)])
        rt.now += dt
        v["IN"] = rng.random() < 0.5 if rng.random() < 0.3 else v["IN"]
        if rng.random() < 0.05:
            v["PT"] = rng.choice([0, -5, 10_000_000, 30_000_000, rng.randint(-1, 100_000_000)])
        body(v, rt)
        q, et = model.step(v["IN"], v["PT"], dt)
        assert (v["Q"], v["ET"]) == (q, et), f"step {step}: {name} IN={v['IN']} PT={v['PT']}"


@pytest.mark.parametrize("seed", range(20))
def test_bistables_and_edges_match_the_standard(seed):
    rng = random.Random(seed)
    sr, sr_m = _instance("SR"), refb.SR()
    rs, rs_m = _instance("RS"), refb.RS()
    rt_, rt_m = _instance("R_TRIG"), refb.R_TRIG()
    ft, ft_m = _instance("F_TRIG"), refb.F_TRIG()
    for _ in range(200):
        a, b = rng.random() < 0.5, rng.random() < 0.5
        sr[0]["S1"], sr[0]["R"] = a, b
        sr[1](sr[0], None)
        assert sr[0]["Q1"] == sr_m.step(a, b)
        rs[0]["S"], rs[0]["R1"] = a, b
        rs[1](rs[0], None)
        assert rs[0]["Q1"] == rs_m.step(a, b)
        rt_[0]["CLK"] = a
        rt_[1](rt_[0], None)
        assert rt_[0]["Q"] == rt_m.step(a)
        ft[0]["CLK"] = b
        ft[1](ft[0], None)
        assert ft[0]["Q"] == ft_m.step(b)


@pytest.mark.parametrize("suffix", ["", "_DINT", "_UDINT"])
@pytest.mark.parametrize("seed", range(10))
def test_counters_match_the_standard(suffix, seed):
    rng = random.Random(f"{suffix}{seed}")
    t = stdlib.FUNCTION_BLOCKS["CTU" + suffix].vars["CV"].type
    lo, hi = t.range
    ctu, ctu_m = _instance("CTU" + suffix), refb.CTU(lo, hi)
    ctd, ctd_m = _instance("CTD" + suffix), refb.CTD(lo, hi)
    ctud, ctud_m = _instance("CTUD" + suffix), refb.CTUD(lo, hi)
    for _ in range(300):
        cu, cd = rng.random() < 0.5, rng.random() < 0.5
        r, ld = rng.random() < 0.05, rng.random() < 0.05
        pv = rng.choice([0, 3, lo, hi, rng.randint(lo, hi)])
        v = ctu[0]
        v["CU"], v["R"], v["PV"] = cu, r, pv
        ctu[1](v, None)
        assert (v["Q"], v["CV"]) == ctu_m.step(cu, r, pv)
        v = ctd[0]
        v["CD"], v["LD"], v["PV"] = cd, ld, pv
        ctd[1](v, None)
        assert (v["Q"], v["CV"]) == ctd_m.step(cd, ld, pv)
        v = ctud[0]
        v["CU"], v["CD"], v["R"], v["LD"], v["PV"] = cu, cd, r, ld, pv
        ctud[1](v, None)
        assert (v["QU"], v["QD"], v["CV"]) == ctud_m.step(cu, cd, r, ld, pv)


def test_string_functions_match_the_models():
    rng = random.Random(7)
    words = ["", "a", "abc", "abcabc", "xyz", "hello world", "aaaa"]
    for _ in range(3000):
        a, b = rng.choice(words), rng.choice(words)
        n, p = rng.randint(-3, 14), rng.randint(-3, 14)
        assert std.s_left(a, n) == refs.left(a, n)
        assert std.s_right(a, n) == refs.right(a, n)
        assert std.s_mid(a, n, p) == refs.mid(a, n, p)
        assert std.s_insert(a, b, p) == refs.insert(a, b, p)
        assert std.s_delete(a, n, p) == refs.delete(a, n, p)
        assert std.s_replace(a, b, n, p) == refs.replace(a, b, n, p)
        assert std.s_find(a, b) == refs.find(a, b)


def test_time_texts_match_the_models():
    rng = random.Random(3)
    for _ in range(2000):
        ns = rng.choice([0, 1, -1, rng.randint(-10**15, 10**15), rng.randint(0, 86_400 * 10**9)])
        assert duration_text(ns, "T#") == refs.time_to_string(ns)
        d = ns - ns % 86_400_000_000_000
        assert to_text(d, ELEMENTARY["DATE"]) == refs.date_to_string(d)
        assert to_text(ns % 86_400_000_000_000, ELEMENTARY["TOD"]) == \
            refs.tod_to_string(ns % 86_400_000_000_000)
        assert to_text(ns, ELEMENTARY["DT"]) == refs.dt_to_string(ns)
