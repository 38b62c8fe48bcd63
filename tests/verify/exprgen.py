"""Random typed ST expressions over every elementary numeric type, for the
verifier's own differential tier (test_encode_diff.py, issue 29): a PROGRAM
whose VAR_INPUTs (free in the verifier, drawn by ``boundary_value`` in the
interpreter) of every integer type (signed, unsigned, bit strings, all
widths), REAL/LREAL and TIME feed outputs computed by random expressions;
diffverify compares the encoding and the interpreter output by output.

Divisions are guarded (a divisor of 0 becomes 1) so that a run is not cut
short by the first division fault; overflow wraps in both engines and is
compared like any value."""

from __future__ import annotations

import random

SINTS = [("SINT", 8), ("INT", 16), ("DINT", 32), ("LINT", 64)]
UINTS = [("USINT", 8), ("UINT", 16), ("UDINT", 32), ("ULINT", 64)]
BITS = [("BYTE", 8), ("WORD", 16), ("DWORD", 32), ("LWORD", 64)]
REALS = [("REAL", 32), ("LREAL", 64)]
INTS = [n for n, _ in SINTS + UINTS]
BITN = [n for n, _ in BITS]
REALN = [n for n, _ in REALS]
WIDTH = dict(SINTS + UINTS + BITS + REALS)
TYPES = INTS + BITN + REALN + ["TIME", "BOOL"]
N_INPUTS = 2


def limits(t):
    w = WIDTH[t]
    if t in dict(SINTS):
        return -(1 << (w - 1)), (1 << (w - 1)) - 1
    return 0, (1 << w) - 1


def boundary_ints(t):
    """The type limits and their neighbours, 2^(n-1) and around it."""
    lo, hi = limits(t)
    w = WIDTH[t]
    vals = {0, 1, -1, 2, lo, lo + 1, hi, hi - 1, 1 << (w - 1), (1 << (w - 1)) - 1,
            (1 << (w - 1)) + 1, 100, 127, 128, 255, 256, -128, -129}
    return sorted(v for v in vals if lo <= v <= hi)


FLOATS = [0.0, -0.0, 1.0, -1.0, 0.5, 1.5, 2.5, -2.5, 1e30, -1e30, 3.4e38, 1e-40,
          float("inf"), float("-inf"), float("nan"), 2.0 ** 63, -2.0 ** 63, 2.0 ** 64,
          2.0 ** 31, 4294967295.5, 127.5, -128.5, 255.5, 65535.0, 1e300]


def boundary_value(rnd, leaf, fallback):
    """The differential's input values: boundaries with probability 0.6,
    the rest from diffverify's own generator."""
    from iec2kmod.checks.types import concrete
    from iec2kmod.verify.terms import base_of, kind
    t = concrete(leaf.type)
    k = kind(t)
    if rnd.random() >= 0.6 or k not in ("bv", "fp"):
        return fallback(rnd, leaf)
    b = base_of(t)
    if k == "fp":
        x = rnd.choice(FLOATS)
        if b.bits == 32:
            from iec2kmod.interp.values import f32
            x = f32(x)
        return x
    if b.cat == "time":
        return rnd.choice([0, 1, -1, 1000, -(1 << 63), (1 << 63) - 1, 10 ** 9])
    return rnd.choice(boundary_ints(b.name))


CONFIG = """CONFIGURATION C
RESOURCE R ON PLC
TASK T(INTERVAL := T#10ms, PRIORITY := 1);
PROGRAM p WITH T : P;
END_RESOURCE
END_CONFIGURATION
"""


class Gen:
    def __init__(self, seed):
        self.r = random.Random(seed)

    def var(self, t):
        return f"i_{t}_{self.r.randrange(N_INPUTS)}"

    def lit(self, t):
        r = self.r
        if t == "BOOL":
            return r.choice(["TRUE", "FALSE"])
        if t in REALN:
            return f"{t}#" + r.choice(["0.0", "1.5", "-2.5", "1.0E10", "-3.0E-3", "100.0"])
        if t == "TIME":
            return r.choice(["T#0s", "T#1ms", "T#1s", "T#-5s", "T#2h"])
        v = r.choice(boundary_ints(t))
        if v < 0:
            return f"{t}#{v}" if t in dict(SINTS) else f"{t}#0"
        return f"{t}#{v}" if t not in BITN else f"{t}#16#{v:X}"

    def atom(self, t):
        return self.var(t) if self.r.random() < 0.75 else self.lit(t)

    def expr(self, t, d=0):
        r = self.r
        if d >= 2 or r.random() < 0.25:
            return self.atom(t)
        if t == "BOOL":
            return self.e_bool(d)
        if t in INTS:
            return self.e_int(t, d)
        if t in BITN:
            return self.e_bit(t, d)
        if t in REALN:
            return self.e_real(t, d)
        return self.e_time(d)

    def e_bool(self, d):
        r = self.r
        k = r.random()
        if k < 0.7:
            u = r.choice(INTS + BITN + REALN + ["TIME"])
            op = r.choice(["<", "<=", ">", ">=", "=", "<>"])
            return f"({self.expr(u, d + 1)} {op} {self.expr(u, d + 1)})"
        if k < 0.85:
            return f"({self.expr('BOOL', d + 1)} {r.choice(['AND', 'OR', 'XOR'])} " \
                   f"{self.expr('BOOL', d + 1)})"
        return f"NOT {self.expr('BOOL', d + 1)}"

    def _div(self, t, d):
        x = self.expr(t, d + 1)
        return f"SEL({x} = {t}#0, {x}, {t}#1)"

    def e_int(self, t, d):
        r = self.r
        k = r.random()
        a = lambda: self.expr(t, d + 1)     # noqa: E731
        if k < 0.45:
            op = r.choice(["+", "-", "*", "/", "MOD"])
            b = self._div(t, d) if op in ("/", "MOD") else a()
            return f"({a()} {op} {b})"
        if k < 0.6:
            f = r.choice(["MIN", "MAX"])
            return f"{f}({a()}, {a()})"
        if k < 0.65:
            return f"LIMIT({a()}, {a()}, {a()})"
        if k < 0.7:
            return f"SEL({self.expr('BOOL', d + 1)}, {a()}, {a()})"
        if k < 0.75 and t in dict(SINTS):
            return f"ABS({a()})" if r.random() < 0.5 else f"(-{a()})"
        src = r.choice(INTS + BITN + REALN)
        if src == t:
            return a()
        return f"{src}_TO_{t}({self.expr(src, d + 1)})"

    def e_bit(self, t, d):
        r = self.r
        k = r.random()
        a = lambda: self.expr(t, d + 1)     # noqa: E731
        if k < 0.35:
            return f"({a()} {r.choice(['AND', 'OR', 'XOR'])} {a()})"
        if k < 0.45:
            return f"NOT {a()}"
        if k < 0.7:
            f = r.choice(["SHL", "SHR", "ROL", "ROR"])
            return f"{f}({a()}, {r.randrange(0, WIDTH[t] + 2)})"
        if k < 0.8:
            return f"MAX({a()}, {a()})"
        src = r.choice(INTS + BITN)
        if src == t:
            return a()
        return f"{src}_TO_{t}({self.expr(src, d + 1)})"

    def e_real(self, t, d):
        r = self.r
        k = r.random()
        a = lambda: self.expr(t, d + 1)     # noqa: E731
        if k < 0.5:
            return f"({a()} {r.choice(['+', '-', '*', '/'])} {a()})"
        if k < 0.6:
            f = r.choice(["MIN", "MAX", "ABS"])
            return f"ABS({a()})" if f == "ABS" else f"{f}({a()}, {a()})"
        src = r.choice(INTS + REALN)
        if src == t:
            return f"(-{a()})"
        return f"{src}_TO_{t}({self.expr(src, d + 1)})"

    def e_time(self, d):
        r = self.r
        k = r.random()
        a = lambda: self.expr("TIME", d + 1)  # noqa: E731
        if k < 0.5:
            return f"({a()} {r.choice(['+', '-'])} {a()})"
        if k < 0.7:
            return f"({a()} * {self.expr(r.choice(['DINT', 'INT', 'LINT']), d + 1)})"
        if k < 0.85:
            return f"{r.choice(['MIN', 'MAX'])}({a()}, {a()})"
        return f"LINT_TO_TIME({self.expr('LINT', d + 1)})"

    def program(self, n_out):
        """A PROGRAM text with n_out outputs over every type."""
        ins = [f"    i_{t}_{k} : {t};" for t in TYPES for k in range(N_INPUTS)]
        outs, body = [], []
        for j in range(n_out):
            t = TYPES[j % len(TYPES)] if j < len(TYPES) else self.r.choice(TYPES)
            outs.append(f"    o_{j} : {t};")
            body.append(f"o_{j} := {self.expr(t)};")
        return ("PROGRAM P\nVAR_INPUT\n" + "\n".join(ins) + "\nEND_VAR\nVAR_OUTPUT\n"
                + "\n".join(outs) + "\nEND_VAR\n" + "\n".join(body) + "\nEND_PROGRAM\n" + CONFIG)
