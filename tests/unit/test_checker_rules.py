"""Checker rules that the mutation benchmark (benchmarks/mutate.py, issue 29)
found untested: each test here fails on the mutant named in its docstring."""

from __future__ import annotations

from helpers import check

PROG = """PROGRAM p
VAR r : REAL; t : TIME; s : STRING; a : ARRAY[1..4] OF INT; i : INT; b : BOOL; w : WORD;
    d : DINT; END_VAR
{}
END_PROGRAM
"""


def _errors(stmt):
    return [d.split(": error: ", 1)[1] for d in check(PROG.format(stmt)) if ": error: " in d]


def test_bit_access_needs_a_bit_string_or_integer():
    """checks/expr.py: `isinstance(bt, Elementary) and bt.cat in (...)` with
    `or` accepted r.3 on a REAL."""
    assert _errors("b := r.3;") == ["bit access .3 needs a bit string, not REAL"]
    assert _errors("b := t.1;") == ["bit access .1 needs a bit string, not TIME"]
    assert _errors("b := s.0;") == ["bit access .0 needs a bit string, not STRING"]
    assert _errors("b := w.15; b := d.31; b := i.0;") == []
    assert _errors("b := w.16;") == ["bit 16 does not exist in WORD (bits 0..15)"]


def test_constant_index_arithmetic():
    """checks/expr.py _literal_value: `a is None or b is None` with `and`
    crashed (None + 1) on a[i + 1]; the constant forms are folded and
    checked against the bounds."""
    assert _errors("i := a[i + 1]; i := a[1 + i]; i := a[i * 2]; i := a[4 - i];") == []
    assert _errors("i := a[1 + 4];") == ["index 5 is out of bounds 1..4"]
    assert _errors("i := a[2 * 3];") == ["index 6 is out of bounds 1..4"]
    assert _errors("i := a[1 - 2];") == ["index -1 is out of bounds 1..4"]
    assert _errors("i := a[-(1)];") == ["index -1 is out of bounds 1..4"]
    assert _errors("i := a[5 - 1]; i := a[+4];") == []
