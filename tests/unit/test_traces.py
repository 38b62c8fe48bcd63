# SPDX-License-Identifier: MIT
"""The trace file formats both engines and the verifier share
(iec2kmod/traces.py, execmodel.element_path): a value written by
input_literal reads back as the same value, a --watch name maps to one
table index, an array element's path is the one both tables use."""

import math
from types import SimpleNamespace as NS

import pytest

from iec2kmod.checks.types import BOOL, DINT, LREAL, REAL, EnumT
from iec2kmod.execmodel import element_path
from iec2kmod.parse.literals import classify
from iec2kmod.traces import TraceError, input_literal, watch_indexes


def test_element_path_is_row_major_with_iec_bounds():
    dims = [(1, 2), (-1, 1)]
    got = [element_path("a", dims, n) for n in range(6)]
    assert got == ["a[1,-1]", "a[1,0]", "a[1,1]", "a[2,-1]", "a[2,0]", "a[2,1]"]
    assert element_path("v", [(0, 9)], 7) == "v[7]"


@pytest.mark.parametrize("t, v, text", [
    (BOOL, True, "TRUE"), (BOOL, 0, "FALSE"), (DINT, 5, "5"),
    (REAL, 1e-05, "1.0E-05"), (LREAL, 2, "2.0"), (REAL, 2.5e20, "2.5E+20"),
])
def test_input_literal_reads_back(t, v, text):
    assert input_literal(t, v) == text
    kind, value, _ = classify(text)
    if t is BOOL:
        assert kind == "bool" and value == bool(v)
    elif t in (REAL, LREAL):
        assert math.isclose(value, float(v), rel_tol=0, abs_tol=0)
    else:
        assert value == v


def test_input_literal_names_an_enumeration_value():
    e = EnumT("Mode")
    e.values.update({"OFF": ("Off", 0), "RUN": ("Run", 1)})
    assert input_literal(e, 1) == "Mode#Run"
    assert input_literal(e, 7) == "7"


def test_watch_indexes():
    table = [NS(path="g", owner="global"), NS(path="P.x", owner="P"),
             NS(path="%IX0.0", owner="direct"), NS(path="P.y", owner="P")]
    addresses = {"%IX0.0": "%IX0.0"}
    assert watch_indexes(table, addresses, None) == [0, 2]
    assert watch_indexes(table, addresses, ["p.y", " P.X ", "P.y"]) == [3, 1]
    with pytest.raises(TraceError, match="unknown variable 'nope'"):
        watch_indexes(table, addresses, ["nope"])
