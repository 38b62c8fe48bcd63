"""The standard functions of IEC 61131-3 (ed.3, clause 6.6.2.5), written
from the standard's tables, one Python function per operation.

Every function takes the argument values already converted to the
parameter types the front end resolved (``StdFunc.param_types``) and
returns a value of the result type.  Faults are raised as Fault.

Floating point: REAL results are rounded to binary32 after every
operation (values.f32).  The transcendental functions SQRT excepted --
LN LOG EXP SIN COS TAN ASIN ACOS ATAN ATAN2 EXPT -- use Python's math
module (the platform libm, correctly rounded in most cases); the C runtime
has its own libm accurate to 1-2 ULP, so those results may differ in the
last one or two ULPs.  SQRT and + - * / are exact IEEE in both."""

from __future__ import annotations

import math

from ..checks.types import Elementary, StringT
from .errors import Fault, DIV_ZERO, MUX
from .values import base_of, f32_safe, wrap, wrap64

NS_PER_MS = 1_000_000
NS_PER_S = 1_000_000_000
NS_PER_DAY = 86_400 * NS_PER_S
INT64_MIN, INT64_MAX = -(1 << 63), (1 << 63) - 1

# functions whose REAL/LREAL result may differ from the C runtime in the
# last ULP(s): the harness compares these with a tolerance
ULP_TOLERANT = ("LN", "LOG", "EXP", "SIN", "COS", "TAN", "ASIN", "ACOS", "ATAN", "ATAN2",
                "EXPT")


def rnd(x, t):
    """A real result in the precision of type t."""
    return f32_safe(x) if base_of(t).bits == 32 else x


# ------------------------------------------------------------- arithmetic
def int_div(a, b):
    if b == 0:
        raise Fault(DIV_ZERO)
    q = abs(a) // abs(b)
    return q if (a >= 0) == (b >= 0) else -q


def int_mod(a, b):
    if b == 0:
        raise Fault(DIV_ZERO)
    r = abs(a) % abs(b)
    return r if a >= 0 else -r


def real_div(a, b):
    try:
        return a / b
    except ZeroDivisionError:
        if a != a or a == 0:
            return math.nan
        neg = (math.copysign(1.0, a) < 0) != (math.copysign(1.0, b) < 0)
        return -math.inf if neg else math.inf


def arith(op, t):
    """A two-operand arithmetic function on numbers of type t."""
    b = base_of(t)
    if b.cat == "real":
        single = b.bits == 32
        fn = {"ADD": lambda x, y: x + y, "SUB": lambda x, y: x - y,
              "MUL": lambda x, y: x * y, "DIV": real_div}[op]
        if single:
            return lambda x, y: f32_safe(fn(x, y))
        return fn
    if b.cat in ("sint", "uint", "bit"):
        bits = b.bits
        mask = (1 << bits) - 1
        signed = b.cat == "sint"
        top = 1 << (bits - 1)
        full = 1 << bits

        def w(v):
            v &= mask
            return v - full if signed and v & top else v
        if op == "ADD":
            return lambda x, y: w(x + y)
        if op == "SUB":
            return lambda x, y: w(x - y)
        if op == "MUL":
            return lambda x, y: w(x * y)
        if op == "DIV":
            return lambda x, y: w(int_div(x, y))
        if op == "MOD":
            return lambda x, y: w(int_mod(x, y))
    if b.cat in ("time", "date", "tod", "dt"):
        if op == "ADD":
            return lambda x, y: wrap64(x + y)
        if op == "SUB":
            return lambda x, y: wrap64(x - y)
    raise AssertionError(f"{op} on {t}")


def expt(base_t, exp_t, res_t):
    """EXPT(IN1, IN2): IN1 ** IN2 (REAL/LREAL base; integer or real exponent)."""
    def f(x, y):
        if x == 0 and y < 0:
            # IEEE pow: a pole; -0 to an odd integer power keeps the sign
            odd = float(y).is_integer() and int(y) % 2 == 1
            return rnd(math.copysign(math.inf, x) if odd else math.inf, res_t)
        try:
            r = math.pow(x, y)
        except ZeroDivisionError:
            # 0 ** negative
            odd = float(y).is_integer() and int(y) % 2 == 1
            r = math.copysign(math.inf, x) if odd else math.inf
        except ValueError:
            r = math.nan
        except OverflowError:
            neg = x < 0 and float(y).is_integer() and int(y) % 2 == 1
            r = -math.inf if neg else math.inf
        return rnd(r, res_t)
    return f


def _m(fn):
    def g(x):
        try:
            return fn(x)
        except (ValueError, ZeroDivisionError):
            return math.nan
        except OverflowError:
            return math.inf
    return g


def _ln(x):
    if x == 0:
        return -math.inf
    if x < 0 or x != x:
        return math.nan
    if x == math.inf:
        return math.inf
    return math.log(x)


def _log10(x):
    if x == 0:
        return -math.inf
    if x < 0 or x != x:
        return math.nan
    if x == math.inf:
        return math.inf
    return math.log10(x)


def _sqrt(x):
    if x != x or x < 0:
        return math.nan if not (x == 0) else x
    return math.sqrt(x)


def _exp(x):
    if x != x:
        return x
    try:
        return math.exp(x)
    except OverflowError:
        return math.inf


REALFN = {"SQRT": _sqrt, "LN": _ln, "LOG": _log10, "EXP": _exp,
          "SIN": _m(math.sin), "COS": _m(math.cos), "TAN": _m(math.tan),
          "ASIN": _m(math.asin), "ACOS": _m(math.acos), "ATAN": _m(math.atan)}


def realfn(name, t):
    fn = REALFN[name]
    return lambda x: rnd(fn(x), t)


def atan2(t):
    def f(y, x):
        if x != x or y != y:
            return math.nan
        return rnd(math.atan2(y, x), t)
    return f


def abs_fn(t):
    b = base_of(t)
    if b.cat == "real":
        return lambda x: abs(x)
    return lambda x: wrap(abs(x), b)


# ------------------------------------------------------------ bit strings
def shift(name, t):
    b = base_of(t)
    bits = b.bits
    mask = (1 << bits) - 1

    if name == "SHL":
        return lambda v, n: 0 if n < 0 or n >= bits else (v << n) & mask
    if name == "SHR":
        return lambda v, n: 0 if n < 0 or n >= bits else v >> n
    if name == "ROL":
        def rol(v, n):
            r = n % bits
            return ((v << r) | (v >> (bits - r))) & mask if r else v
        return rol
    if name == "ROR":
        def ror(v, n):
            r = n % bits
            return ((v >> r) | (v << (bits - r))) & mask if r else v
        return ror
    raise AssertionError(name)


def bitwise(name, t):
    b = base_of(t)
    if b.cat == "bool":
        return {"AND": lambda *a: all(a), "OR": lambda *a: any(a),
                "XOR": lambda *a: sum(1 for x in a if x) % 2 == 1}[name]
    if name == "AND":
        def f(*a):
            r = a[0]
            for x in a[1:]:
                r &= x
            return r
    elif name == "OR":
        def f(*a):
            r = a[0]
            for x in a[1:]:
                r |= x
            return r
    else:
        def f(*a):
            r = a[0]
            for x in a[1:]:
                r ^= x
            return r
    return f


def not_fn(t):
    b = base_of(t)
    if b.cat == "bool":
        return lambda v: not v
    mask = (1 << b.bits) - 1
    return lambda v: ~v & mask


# -------------------------------------------------------------- selection
def _is_nan(x):
    return isinstance(x, float) and x != x


def max_fn(*a):
    r = a[0]
    for x in a[1:]:
        if _is_nan(r):
            return r
        if _is_nan(x):
            return x
        if not r >= x:
            r = x
    return r


def min_fn(*a):
    r = a[0]
    for x in a[1:]:
        if _is_nan(r):
            return r
        if _is_nan(x):
            return x
        if not r <= x:
            r = x
    return r


def limit_fn(mn, v, mx):
    return min_fn(max_fn(v, mn), mx)


def mux_fn(k, *ins):
    if k < 0 or k >= len(ins):
        raise Fault(MUX)
    return ins[k]


COMPARE = {"GT": lambda a, b: a > b, "GE": lambda a, b: a >= b, "EQ": lambda a, b: a == b,
           "LE": lambda a, b: a <= b, "LT": lambda a, b: a < b, "NE": lambda a, b: a != b}


def compare(name):
    op = COMPARE[name]
    if name == "NE":
        return op

    def chain(*a):
        return all(op(a[i], a[i + 1]) for i in range(len(a) - 1))
    return chain


# ---------------------------------------------------------------- strings
def _clamp(v, hi):
    return 0 if v <= 0 else (hi if v >= hi else v)


def s_left(s, n):
    return s[:_clamp(n, len(s))]


def s_right(s, n):
    k = _clamp(n, len(s))
    return s[len(s) - k:]


def s_mid(s, n, p):
    if p < 1 or p > len(s):
        return ""
    start = p - 1
    return s[start:start + _clamp(n, len(s) - start)]


def s_insert(a, b, p):
    k = _clamp(p, len(a))
    return a[:k] + b + a[k:]


def s_delete(s, n, p):
    if p < 1 or p > len(s):
        return s
    start = p - 1
    k = _clamp(n, len(s) - start)
    return s[:start] + s[start + k:]


def s_replace(a, b, n, p):
    start = 0 if p <= 1 else _clamp(p - 1, len(a))
    k = _clamp(n, len(a) - start)
    return a[:start] + b + a[start + k:]


def s_find(a, b):
    if not b or len(b) > len(a):
        return 0
    return a.find(b) + 1


# ------------------------------------------------------------------- time
def add_tod_time(tod, t):
    return ((tod % NS_PER_DAY) + (t % NS_PER_DAY)) % NS_PER_DAY


def sub_tod_time(tod, t):
    return ((tod % NS_PER_DAY) - (t % NS_PER_DAY)) % NS_PER_DAY


def round_half_even(x: float) -> float:
    return float(round(x)) if abs(x) < 2.0 ** 52 else x


def sat_i64(r: float) -> int:
    if r != r:
        return 0
    if r < -9.223372036854775808e18:
        return INT64_MIN
    if r >= 9.223372036854775808e18:
        return INT64_MAX
    return int(r)


def mul_time_real(t, f):
    return sat_i64(round_half_even(float(t) * f))


def div_time_real(t, f):
    if f == 0:
        raise Fault(DIV_ZERO)
    return sat_i64(round_half_even(real_div(float(t), f)))


def mul_time_int(t, n):
    return wrap64(t * n)


def div_time_int(t, n):
    if n == 0:
        raise Fault(DIV_ZERO)
    return wrap64(int_div(t, n))


def is_string_type(t):
    return isinstance(t, StringT)


def is_elem(t, *cats):
    b = base_of(t)
    return isinstance(b, Elementary) and b.cat in cats
