"""The verifier's own differential tier (issue 29): random expressions over
every integer type (signed, unsigned and bit strings of every width),
REAL/LREAL and TIME (exprgen.py), encoded by verify/encode.py and evaluated
by z3 on the same inputs as the reference interpreter, output by output, on
random and boundary values (type limits and their neighbours, 2^(n-1),
NaN, +-Inf, -0.0).  A wrong bit-vector or floating-point operator in the
encoding (an unsigned comparison encoded signed, issue 29's M15) fails
here in seconds.

Reproduce or widen: python3 benchmarks/verify_encode_diff.py --count N --seed S"""

from __future__ import annotations

import pytest

import diffverify
import exprgen

try:
    import z3  # noqa: F401
except ImportError:     # the tier fails and says what to install
    z3 = None

SEED = 20261127
PROGRAMS = 6        # programs of OUTPUTS expressions each
OUTPUTS = 60
CYCLES = 12


def run_one(tmp_path, seed, outputs=OUTPUTS, cycles=CYCLES):
    from iec2kmod.cli import front_end
    d = tmp_path / f"p{seed}"
    d.mkdir()
    text = exprgen.Gen(seed).program(outputs)
    (d / "p.st").write_text(text)
    project = front_end([str(d)])
    diffs, done = diffverify.run(project, cycles, seed, values=exprgen.boundary_value)
    return text, diffs, done


@pytest.mark.parametrize("k", range(PROGRAMS))
def test_encoding_equals_interpreter(tmp_path, k):
    if z3 is None:
        pytest.fail("z3-solver is not installed: pip install z3-solver (scripts/setup.sh)")
    seed = SEED + k
    text, diffs, done = run_one(tmp_path, seed)
    lines = text.splitlines()
    report = []
    for cyc, name, theirs, mine in diffs[:5]:
        src = next((ln for ln in lines if ln.startswith(name.split(".")[-1] + " :=")), "")
        report.append(f"cycle {cyc}: {name}: interpreter {theirs!r}, encoding {mine!r}  [{src}]")
    assert not diffs, f"seed {seed}:\n" + "\n".join(report)
    assert done == CYCLES


def test_unsigned_comparison_on_high_values(tmp_path):
    """Issue 29's M15 as a pinned program: b <= BYTE#100 with b above 127."""
    from iec2kmod.cli import front_end
    d = tmp_path / "m15"
    d.mkdir()
    (d / "p.st").write_text("""PROGRAM P
VAR_INPUT b : BYTE; u : ULINT; s : USINT; END_VAR
VAR_OUTPUT small : BOOL; big : BOOL; lt : BOOL; END_VAR
small := b <= BYTE#100;
big := u > ULINT#1;
lt := s < USINT#130;
END_PROGRAM
""" + exprgen.CONFIG)

    def high(rnd, leaf, fallback):
        return {"b": 232, "u": (1 << 64) - 1, "s": 200}[leaf.name.split(".")[-1]]
    diffs, done = diffverify.run(front_end([str(d)]), 2, 1, values=high)
    assert not diffs and done == 2, diffs
