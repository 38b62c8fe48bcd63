# SPDX-License-Identifier: MIT
"""Property tests of the STRING/WSTRING functions and the string
conversions against tests/reference/strings.py, through c/calc_str.c."""
import subprocess

import pytest
from hypothesis import given, settings, strategies as st, HealthCheck

from rt_helpers import cfile, rt
from reference import strings as ref

pytestmark = pytest.mark.execution

S64 = (-2**63, 2**63 - 1)


class Calc:
    def __init__(self, exe):
        self.p = subprocess.Popen([str(exe)], stdin=subprocess.PIPE,
                                  stdout=subprocess.PIPE, text=True, bufsize=1)

    def ask(self, line):
        self.p.stdin.write(line + "\n")
        self.p.stdin.flush()
        out = self.p.stdout.readline().strip()
        assert out and not out.startswith("ERR"), (line, out)
        return out

    def close(self):
        self.p.stdin.close()
        assert self.p.wait(timeout=30) == 0


@pytest.fixture(scope="module", params=["strict", "sanitize"])
def calc(request, builder):
    exe = builder.build([cfile("calc_str.c"), *rt("iec_string.c")],
                        mode=request.param)
    c = Calc(exe)
    yield c
    c.close()


def hx(b):
    return b.hex() if b else "-"


def hxw(t):
    return "".join(f"{c:04x}" for c in t) if t else "-"


def unhx(s):
    return b"" if s == "-" else bytes.fromhex(s)


def unhxw(s):
    return () if s == "-" else tuple(int(s[i:i + 4], 16) for i in range(0, len(s), 4))


OPS = {
    "left": lambda a, b, n, p: ref.left(a, n),
    "right": lambda a, b, n, p: ref.right(a, n),
    "mid": lambda a, b, n, p: ref.mid(a, n, p),
    "concat": lambda a, b, n, p: ref.concat(a, b),
    "insert": lambda a, b, n, p: ref.insert(a, b, p),
    "delete": lambda a, b, n, p: ref.delete(a, n, p),
    "replace": lambda a, b, n, p: ref.replace(a, b, n, p),
    "assign": lambda a, b, n, p: a,
}

small = st.integers(-3, 40)
big = st.one_of(small, st.integers(-2**63, 2**63 - 1))
alphabet = st.sampled_from(b"ab\x00\xff")


@st.composite
def case(draw, wide=False):
    op = draw(st.sampled_from(sorted(OPS)))
    mode = draw(st.sampled_from([0, 1, 2, 3]))
    cap = draw(st.integers(0, 30))
    if wide:
        chars = st.sampled_from([0x61, 0x62, 0x0, 0xffff, 0x263a])
        mk = lambda m: tuple(draw(st.lists(chars, max_size=m)))
    else:
        mk = lambda m: bytes(draw(st.lists(alphabet, max_size=m)))
    a = mk(cap if mode in (1, 3) else 40)
    b = a if mode == 3 else mk(cap if mode == 2 else 40)
    return op, mode, cap, a, b, draw(big), draw(big)


@settings(max_examples=600, deadline=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(c=case())
def test_string_functions_match_reference(calc, c):
    op, mode, cap, a, b, n, p = c
    got = unhx(calc.ask(f"{op} {mode} {cap} {hx(a)} {hx(b)} {n} {p}"))
    assert got == ref.truncate(OPS[op](a, b, n, p), cap)


@settings(max_examples=300, deadline=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(c=case(wide=True))
def test_wstring_functions_match_reference(calc, c):
    op, mode, cap, a, b, n, p = c
    got = unhxw(calc.ask(f"w{op} {mode} {cap} {hxw(a)} {hxw(b)} {n} {p}"))
    assert got == ref.truncate(OPS[op](a, b, n, p), cap)


@settings(max_examples=300, deadline=None)
@given(a=st.binary(max_size=12).map(lambda b: bytes(x % 3 + 97 for x in b)),
       b=st.binary(max_size=4).map(lambda b: bytes(x % 3 + 97 for x in b)))
def test_find_and_compare(calc, a, b):
    assert int(calc.ask(f"find {hx(a)} {hx(b)}")) == ref.find(a, b)
    assert int(calc.ask(f"cmp {hx(a)} {hx(b)}")) == ref.cmp(a, b)
    wa, wb = tuple(a), tuple(b)
    assert int(calc.ask(f"wfind {hxw(wa)} {hxw(wb)}")) == ref.find(wa, wb)
    assert int(calc.ask(f"wcmp {hxw(wa)} {hxw(wb)}")) == ref.cmp(wa, wb)


def test_standard_examples(calc):
    def run(op, a, b=b"", n=0, p=0, cap=254):
        return unhx(calc.ask(f"{op} 0 {cap} {hx(a)} {hx(b)} {n} {p}"))
    assert run("mid", b"ASTR", n=2, p=2) == b"ST"
    assert run("insert", b"ABC", b"XY", p=2) == b"ABXYC"
    assert run("delete", b"ABXYC", n=2, p=3) == b"ABC"
    assert run("replace", b"ABCDE", b"X", n=2, p=3) == b"ABXE"
    assert run("left", b"ASTR", n=3) == b"AST"
    assert run("right", b"ASTR", n=3) == b"STR"
    assert run("concat", b"AB", b"CD") == b"ABCD"
    assert run("concat", b"AB", b"CD", cap=3) == b"ABC"
    assert int(calc.ask(f"find {hx(b'ABCBC')} {hx(b'BC')}")) == 2


INT_TYPES = {
    "sint": (-2**7, 2**7 - 1), "int": (-2**15, 2**15 - 1),
    "dint": (-2**31, 2**31 - 1), "lint": S64,
    "usint": (0, 2**8 - 1), "uint": (0, 2**16 - 1),
    "udint": (0, 2**32 - 1), "ulint": (0, 2**64 - 1),
    "byte": (0, 2**8 - 1), "word": (0, 2**16 - 1),
    "dword": (0, 2**32 - 1), "lword": (0, 2**64 - 1),
}


@settings(max_examples=400, deadline=None)
@given(t=st.sampled_from(sorted(INT_TYPES)), data=st.data())
def test_int_string_roundtrip_and_saturation(calc, t, data):
    lo, hi = INT_TYPES[t]
    v = data.draw(st.integers(lo, hi))
    assert unhx(calc.ask(f"i2s {t} {v}")).decode() == str(v)
    assert int(calc.ask(f"s2i {t} {hx(str(v).encode())}")) == v
    # any integer text saturates to the type's range
    w = data.draw(st.integers(-2**70, 2**70))
    text = data.draw(st.sampled_from([
        str(w), f"  {w}\t", f"{w:_}", (f"16#{w:X}" if w >= 0 else f"-16#{-w:X}"),
        (f"2#{w:b}" if w >= 0 else f"-2#{-w:b}"), f"{t.upper()}#{w}"]))
    assert int(calc.ask(f"s2i {t} {hx(text.encode())}")) == max(lo, min(w, hi))


@pytest.mark.parametrize("text", ["", "abc", "1 2", "12a", "_1", "1_", "1__2",
                                  "3#12", "16#", "+", "16#FG", "1.5"])
def test_invalid_integer_text_is_zero(calc, text):
    assert int(calc.ask(f"s2i dint {hx(text.encode())}")) == 0


def test_bool_strings(calc):
    for text, v in [("TRUE", 1), ("true", 1), (" False ", 0), ("1", 1),
                    ("0", 0), ("7", 1), ("yes", 0), ("BOOL#TRUE", 1)]:
        assert int(calc.ask(f"s2i bool {hx(text.encode())}")) == v, text
    assert unhx(calc.ask("i2s bool 1")) == b"TRUE"
    assert unhx(calc.ask("i2s bool 0")) == b"FALSE"


@settings(max_examples=400, deadline=None)
@given(v=st.integers(*S64))
def test_time_string_roundtrip(calc, v):
    s = unhx(calc.ask(f"i2s time {v}")).decode()
    assert s == ref.time_to_string(v)
    assert int(calc.ask(f"s2i time {hx(s.encode())}")) == v
    s = unhx(calc.ask(f"i2s ltime {v}")).decode()
    assert s == ref.time_to_string(v, "LTIME#")
    assert int(calc.ask(f"s2i ltime {hx(s.encode())}")) == v


DAY = 86400 * 10**9
# the DT range whose date part is representable too
DT_RANGE = (-(2**63 // DAY) * DAY, 2**63 - 1)


@settings(max_examples=400, deadline=None)
@given(v=st.integers(*DT_RANGE))
def test_date_time_string_roundtrip(calc, v):
    for t, fmt, val in [("dt", ref.dt_to_string, v),
                        ("date", ref.date_to_string, v - v % DAY),
                        ("tod", ref.tod_to_string, v % DAY)]:
        s = unhx(calc.ask(f"i2s {t} {val}")).decode()
        assert s == fmt(val)
        assert int(calc.ask(f"s2i {t} {hx(s.encode())}")) == val, s


@pytest.mark.parametrize("t,text,ns", [
    ("time", "T#1.5s", 1500 * 10**6),
    ("time", "t#1h_30m", 5400 * 10**9),
    ("time", "TIME#-2.25ms", -2250000),
    ("time", "T#1d2h3m4s5ms6us7ns",
     ((((24 + 2) * 60 + 3) * 60 + 4) * 10**9) + 5 * 10**6 + 6000 + 7),
    ("time", "T#0.0000000019s", 1),
    ("time", "T#1.5d", 36 * 3600 * 10**9),
    ("time", "T#5", 0), ("time", "T#1x", 0), ("time", "T#", 0),
    ("tod", "TOD#12:00:00.5", 12 * 3600 * 10**9 + 5 * 10**8),
    ("tod", "TIME_OF_DAY#23:59:59", 86399 * 10**9),
    ("tod", "TOD#24:00:00", 0), ("tod", "TOD#12:60:00", 0),
    ("date", "D#2024-02-29", 19782 * DAY),
    ("date", "DATE#2023-02-29", 0), ("date", "D#2023-13-01", 0),
    ("date", "D#1969-12-31", -DAY),
    ("dt", "DT#1970-01-02-00:00:01", DAY + 10**9),
    ("dt", "DATE_AND_TIME#1970-01-01-00:00", 0),
])
def test_time_literals(calc, t, text, ns):
    assert int(calc.ask(f"s2i {t} {hx(text.encode())}")) == ns
