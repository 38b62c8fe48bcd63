# SPDX-License-Identifier: MIT
"""REAL/LREAL <-> STRING: every formatted value reads back (in Python, a
correctly rounding reader) as the same value, with no more digits than the
shortest representation; the runtime reads Python's shortest repr back."""
import math
import re
import struct
import subprocess

import pytest
from hypothesis import given, settings, strategies as st, HealthCheck

from rt_helpers import cfile, rt

pytestmark = pytest.mark.execution

FORMAT = re.compile(r"^-?(\d+\.\d+(E[+-]\d+)?|NaN|Inf)$")


@pytest.fixture(scope="module", params=["strict", "sanitize"])
def calc(request, builder):
    exe = builder.build([cfile("calc_real.c"),
                         *rt("iec_math.c", "iec_real.c", "iec_string.c")],
                        mode=request.param)
    p = subprocess.Popen([str(exe)], stdin=subprocess.PIPE,
                         stdout=subprocess.PIPE, text=True, bufsize=1)

    def ask(line):
        p.stdin.write(line + "\n")
        p.stdin.flush()
        return p.stdout.readline().strip()
    yield ask
    p.stdin.close()
    assert p.wait(timeout=30) == 0


def digits(s):
    m = s.lstrip("-").split("E")[0].replace(".", "").lstrip("0").rstrip("0")
    return max(len(m), 1)


def shortest_digits(v):
    return digits(repr(abs(v)).upper().replace("E", "E"))


@settings(max_examples=1000, deadline=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(v=st.floats(allow_nan=False, allow_infinity=False))
def test_lreal_to_string_roundtrips(calc, v):
    bits = struct.unpack("<Q", struct.pack("<d", v))[0]
    s = calc(f"d2s {bits:016x}")
    assert FORMAT.match(s), s
    assert float(s) == v and math.copysign(1, float(s)) == math.copysign(1, v), s
    # shortest: Python's repr is the shortest round-trip string
    assert digits(s) <= shortest_digits(v), (s, repr(v))
    # and the runtime reads Python's repr back exactly
    got = int(calc(f"s2d {repr(v)}"), 16)
    assert got == bits, (repr(v), hex(got))


@settings(max_examples=1000, deadline=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(v=st.floats(width=32, allow_nan=False, allow_infinity=False))
def test_real_to_string_roundtrips(calc, v):
    bits = struct.unpack("<I", struct.pack("<f", v))[0]
    s = calc(f"f2s {bits:08x}")
    assert FORMAT.match(s), s
    assert int(calc(f"s2f {s}"), 16) == bits, s
    assert digits(s) <= 9


@pytest.mark.parametrize("text,value", [
    ("0.1", 0.1), ("1E-5", 1e-5), ("123456789012345678901234567890",
                                   1.2345678901234568e29),
    ("0.30000000000000004", 0.30000000000000004),
    ("2.2250738585072011e-308", 2.225073858507201e-308),
    ("1.7976931348623158e308", 1.7976931348623157e308),
    ("9007199254740993", 9007199254740992.0),
    ("1_0.2_5", 10.25), ("+3.0", 3.0),
])
def test_string_to_lreal_examples(calc, text, value):
    assert int(calc(f"s2d {text}"), 16) == \
        struct.unpack("<Q", struct.pack("<d", value))[0]
