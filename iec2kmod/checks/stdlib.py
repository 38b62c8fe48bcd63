"""The standard functions (overloaded, resolved by argument types) and the
standard function blocks of IEC 61131-3."""

from __future__ import annotations

from .symbols import POUInfo, Var
from .types import (BOOL, ELEMENTARY, INT, LREAL, TIME, AnyIntResult, Elementary, ErrorT,
                    LiteralT,
                    StringT, STRING, assignable, cat, common, concrete, concrete_bits, is_bit,
                    is_bool, is_int, is_num, is_real, is_string, is_elementary, not_bit_value)


class CallError(Exception):
    """The arguments do not fit the function (message says why)."""


class StdFunc:
    """A resolved call of a standard function: ``family`` tells the code
    generator which operation it is, ``param_types`` the type each argument
    is converted to, ``result`` the result type."""

    def __init__(self, name, family, param_types, result):
        self.name = name
        self.family = family
        self.param_types = param_types
        self.result = result
        self.standard = True


# ------------------------------------------------------------ families
# The families of StdFunc.family that back ends treat alike: one table.
ARITH_FAMILIES = ("ADD", "SUB", "MUL", "DIV", "MOD")
COMPARE_FAMILIES = ("GT", "GE", "EQ", "LE", "LT", "NE")
TIME_FAMILIES = frozenset({"ADD_TIME", "SUB_TIME", "MUL_TIME", "DIV_TIME", "ADD_TOD_TIME",
                           "ADD_DT_TIME", "SUB_TOD_TIME", "SUB_DT_TIME", "SUB_DATE_DATE",
                           "SUB_TOD_TOD", "SUB_DT_DT", "CONCAT_DATE_TOD"})
# TIME_FAMILIES but ADD_TIME, SUB_TIME, MUL_TIME, DIV_TIME: date and time of
# day arithmetic on fixed parameter types
DATE_TIME_FAMILIES = TIME_FAMILIES - {"ADD_TIME", "SUB_TIME", "MUL_TIME", "DIV_TIME"}
# the families whose untyped-literal result stays untyped without a context
# (computed exactly on the literals)
LITERAL_FAMILIES = ARITH_FAMILIES + ("EXPT",)
# the categories (types.cat) a family on untyped literals may be computed in:
# a context of another one (a bit string, BOOL, MOD into a REAL) is no
# context, and the value is stored by the implicit conversion, as a literal's
NUMERIC_CONTEXT = {"ADD": ("sint", "uint", "real"), "SUB": ("sint", "uint", "real"),
                   "MUL": ("sint", "uint", "real"), "DIV": ("sint", "uint", "real"),
                   "MOD": ("sint", "uint"), "EXPT": ("real",), "ABS": ("sint", "uint", "real")}


def call_types(fres: StdFunc, ctx_t=None):
    """The types a call of standard function *fres* is computed in, given
    the type its context wants (*ctx_t*, None when nothing does): (result,
    parameter types).  A call on untyped literals (ABS(-3), 1 + 2) takes the
    context's type; without one, ADD/SUB/MUL/DIV/MOD/EXPT stay untyped (a
    LiteralT: computed exactly on the values) and any other family takes the
    literal's own type (DINT, LINT or LREAL); a context the family cannot
    compute in (NUMERIC_CONTEXT: 1 + 2 into a BYTE, MOD(7, 2) into a REAL) is
    no context, and the result is converted to it as a literal is.  The
    back ends convert a result computed in a LiteralT or another type than
    the call's own to the call's type.  Comparisons and the time
    functions convert their operands to the parameters' common type, not the
    result's; MUX its K to K's own type and its inputs to the result's.
    Every back end (interp, verify, codegen) reads this one rule."""
    fam = fres.family
    pts = list(fres.param_types)
    res = fres.result
    if ctx_t is not None and fam in NUMERIC_CONTEXT and cat(ctx_t) not in NUMERIC_CONTEXT[fam]:
        ctx_t = None        # x := 1 + 2 into a BYTE: exact, then stored as a BYTE
    if isinstance(res, LiteralT):
        res = ctx_t if ctx_t is not None and not isinstance(ctx_t, LiteralT) else res
    res = concrete(res) if not isinstance(res, LiteralT) else res
    if isinstance(res, LiteralT) and fam not in LITERAL_FAMILIES:
        res = concrete(res)
    if fam == "MUX":
        # K is an integer of its own; the inputs are of the result's type
        # (an untyped one takes the context's: MUX(1, 5, 2147483647 * 2)
        # into a LINT multiplies in LINT)
        ptypes = [concrete(pts[0])] + [
            res if isinstance(pt, LiteralT) and not isinstance(res, LiteralT) else concrete(pt)
            for pt in pts[1:]]
    elif fam in COMPARE_FAMILIES or fam in TIME_FAMILIES:
        ptypes = [concrete(pt) for pt in pts]
    else:
        ptypes = [res if isinstance(pt, LiteralT) and not isinstance(res, LiteralT)
                  else pt for pt in pts]
    return res, ptypes


# ------------------------------------------------------------------ helpers


def _need(pred, t, what, i, name):
    if isinstance(t, ErrorT):
        return
    if not pred(t):
        raise CallError(f"argument {i + 1} of {name} must be {what}, not {t.name}")


def _common_all(types, name):
    acc = types[0]
    for t in types[1:]:
        c = common(acc, t)
        if c is None:
            raise CallError(f"arguments of {name} have incompatible types {acc.name} and {t.name}")
        acc = c
    return acc


def _time_arith(name, types):
    """ADD/SUB/MUL/DIV on TIME, TOD, DT, DATE (the standard's time functions)."""
    a, b = cat(types[0]), cat(types[1]) if len(types) > 1 else None
    op = name
    if op == "ADD" and len(types) == 2:
        if a == "time" and b == "time":
            return "ADD_TIME", common(types[0], types[1]) or types[0]
        if a in ("tod", "dt") and b == "time":
            return f"ADD_{a.upper()}_TIME", types[0]
    if op == "SUB" and len(types) == 2:
        if a == "time" and b == "time":
            return "SUB_TIME", common(types[0], types[1]) or types[0]
        if a in ("tod", "dt") and b == "time":
            return f"SUB_{a.upper()}_TIME", types[0]
        if a == b and a in ("date", "tod", "dt"):
            return f"SUB_{a.upper()}_{a.upper()}", TIME
    if op in ("MUL", "DIV") and len(types) == 2 and a == "time" and is_num(types[1]):
        return f"{op}_TIME", types[0]
    return None


def _arith(name, types):
    if len(types) >= 2 and any(cat(t) in ("time", "tod", "dt", "date") for t in types):
        t = _time_arith(name, types)
        if t is None:
            raise CallError(f"{name} is not defined for " + ", ".join(x.name for x in types))
        family, result = t
        return StdFunc(name, family, list(types), result)
    for i, t in enumerate(types):
        _need(is_num, t, "a number (ANY_NUM)", i, name)
    if name == "MOD":
        for i, t in enumerate(types):
            _need(is_int, t, "an integer (ANY_INT)", i, name)
    r = _common_all(types, name)
    return StdFunc(name, name, [r] * len(types), r)


def _expt(name, types):
    base, exp = types
    _need(lambda t: is_num(t), base, "a number", 0, name)
    _need(is_num, exp, "a number (ANY_NUM)", 1, name)
    if isinstance(base, LiteralT) and base.cat == "real":
        if isinstance(exp, LiteralT):
            return StdFunc(name, "EXPT", [base, exp], LiteralT("real", 0.0))
        if is_real(exp):
            return StdFunc(name, "EXPT", [exp, exp], exp)
    if isinstance(base, LiteralT) or not is_real(base):
        if not isinstance(base, LiteralT) and not isinstance(base, ErrorT):
            raise CallError(f"argument 1 of {name} must be REAL or LREAL (ANY_REAL), not "
                            f"{base.name}: convert it with {base.name}_TO_REAL")
        base = LREAL
    exp = concrete(exp)
    return StdFunc(name, "EXPT", [base, exp], base)


def _abs(name, types):
    t = types[0]
    _need(is_num, t, "a number (ANY_NUM)", 0, name)
    if type(t) is LiteralT:     # ABS(-5): the literal 5, which a BYTE holds
        return StdFunc(name, name, [t], LiteralT(t.cat, abs(t.value)))
    return StdFunc(name, name, [t], t)


def _realfn(name, types):
    for i, t in enumerate(types):
        _need(is_num, t, "a number", i, name)
    t = types[0]
    if all(isinstance(x, LiteralT) and x.cat == "real" for x in types):
        # SQRT(2.0): an untyped real literal takes the type its context
        # requires (REAL in X := SQRT(2.0) with X : REAL), LREAL where
        # nothing does (ed.2 2.2.1, ed.3 6.3.3)
        lit = LiteralT("real", 0.0)
        return StdFunc(name, name, [lit] * len(types), lit)
    if isinstance(t, LiteralT):
        t = LREAL
    elif not is_real(t) and not isinstance(t, ErrorT):
        raise CallError(f"argument 1 of {name} must be REAL or LREAL (ANY_REAL), not {t.name}: "
                        f"convert it with {t.name}_TO_REAL")
    return StdFunc(name, name, [t] * len(types), t)


def _shift(name, types):
    t, n = types
    _need(is_bit, t, "a bit string (ANY_BIT)", 0, name)
    _need(is_int, n, "an integer (ANY_INT)", 1, name)
    if isinstance(t, LiteralT):
        t = ELEMENTARY["DWORD"]
    return StdFunc(name, name, [t, concrete(n)], t)


def _bitwise(name, types):
    for i, t in enumerate(types):
        _need(is_bit, t, "BOOL or a bit string (ANY_BIT)", i, name)
    r = _common_all(types, name)
    if type(r) is LiteralT:
        # untyped literals only: a bit string as for the shifts (DWORD;
        # LWORD for a value beyond 32 bits), not the integer default DINT,
        # which has no bitwise operations (types.concrete_bits)
        lits = [t for t in types if isinstance(t, LiteralT)]
        r = concrete_bits(*lits)
        if r is None:
            raise CallError(not_bit_value(name, lits))
    return StdFunc(name, name, [r] * len(types), r)


def _sel(name, types):
    _need(is_bool, types[0], "BOOL", 0, name)
    r = _common_all(types[1:], name)
    return StdFunc(name, name, [BOOL, r, r], r)


def _maxmin(name, types):
    for i, t in enumerate(types):
        _need(is_elementary, t, "an elementary value", i, name)
    r = _common_all(types, name)
    return StdFunc(name, name, [r] * len(types), r)


def _mux(name, types):
    _need(is_int, types[0], "an integer (ANY_INT)", 0, name)
    r = _common_all(types[1:], name)
    return StdFunc(name, name, [concrete(types[0])] + [r] * (len(types) - 1), r)


def _compare(name, types):
    for i, t in enumerate(types):
        _need(is_elementary, t, "an elementary value", i, name)
    r = _common_all(types, name)
    return StdFunc(name, name, [r] * len(types), BOOL)


def _strfn(sig, result):
    """sig: letters S (string) or I (integer) per parameter."""

    def resolve(name, types):
        ptypes = []
        for i, (kind, t) in enumerate(zip(sig, types)):
            if kind == "S":
                _need(is_string, t, "a STRING", i, name)
                ptypes.append(t)
            else:
                _need(is_int, t, "an integer (ANY_INT)", i, name)
                ptypes.append(concrete(t) if isinstance(t, LiteralT) else t)
        res = result
        if res == "S":
            strs = [t for t in types if isinstance(t, StringT)]
            res = StringT(max((s.length for s in strs), default=254) if name != "CONCAT"
                          else min(sum(s.length for s in strs), 65534),
                          strs[0].wide if strs else False)
            if name in ("LEFT", "RIGHT", "MID", "DELETE"):
                res = strs[0] if strs else STRING
            if name in ("INSERT", "REPLACE"):
                res = StringT(min(sum(s.length for s in strs), 65534),
                              strs[0].wide if strs else False)
        return StdFunc(name, name, ptypes, res)

    return resolve


def _concat(name, types):
    if types and all(cat(t) == "date" or cat(t) == "tod" for t in types[:2]) and len(types) == 2 \
            and cat(types[0]) == "date" and cat(types[1]) == "tod":
        return StdFunc(name, "CONCAT_DATE_TOD", list(types), ELEMENTARY["DT"])
    return _strfn("S" * len(types), "S")(name, types)


def _fixed(params, result, family=None):
    def resolve(name, types):
        for i, (p, t) in enumerate(zip(params, types)):
            if not assignable(t, p):
                raise CallError(f"argument {i + 1} of {name} must be {p.name}, not {t.name}")
        return StdFunc(name, family or name, list(params), result)

    return resolve


def _trunc(name, types):
    """TRUNC: ANY_REAL -> ANY_INT (ed.3 table 22), the integer type given by
    the context (i := TRUNC(r) with i : INT truncates into INT), DINT where
    nothing gives one."""
    t = types[0]
    if isinstance(t, LiteralT):
        if t.cat != "real":
            raise CallError(f"argument 1 of {name} must be REAL or LREAL (ANY_REAL), not an "
                            "integer")
        t = LREAL
    elif not is_real(t) and not isinstance(t, ErrorT):
        raise CallError(f"argument 1 of {name} must be REAL or LREAL (ANY_REAL), not {t.name}")
    return StdFunc(name, "TRUNC", [t], AnyIntResult(name.upper()))


def _move(name, types):
    t = concrete(types[0])
    return StdFunc(name, name, [t], t)


# name -> (resolver, formal parameter names, min args, max args or None)
_T = ELEMENTARY
FUNCTIONS = {
    "ADD": (_arith, "IN", 2, None), "MUL": (_arith, "IN", 2, None),
    "SUB": (_arith, ["IN1", "IN2"], 2, 2), "DIV": (_arith, ["IN1", "IN2"], 2, 2),
    "MOD": (_arith, ["IN1", "IN2"], 2, 2), "EXPT": (_expt, ["IN1", "IN2"], 2, 2),
    "MOVE": (_move, ["IN"], 1, 1), "ABS": (_abs, ["IN"], 1, 1),
    "SQRT": (_realfn, ["IN"], 1, 1), "LN": (_realfn, ["IN"], 1, 1),
    "LOG": (_realfn, ["IN"], 1, 1), "EXP": (_realfn, ["IN"], 1, 1),
    "SIN": (_realfn, ["IN"], 1, 1), "COS": (_realfn, ["IN"], 1, 1),
    "TAN": (_realfn, ["IN"], 1, 1), "ASIN": (_realfn, ["IN"], 1, 1),
    "ACOS": (_realfn, ["IN"], 1, 1), "ATAN": (_realfn, ["IN"], 1, 1),
    "ATAN2": (_realfn, ["Y", "X"], 2, 2),
    "SHL": (_shift, ["IN", "N"], 2, 2), "SHR": (_shift, ["IN", "N"], 2, 2),
    "ROL": (_shift, ["IN", "N"], 2, 2), "ROR": (_shift, ["IN", "N"], 2, 2),
    "AND": (_bitwise, "IN", 2, None), "OR": (_bitwise, "IN", 2, None),
    "XOR": (_bitwise, "IN", 2, None), "NOT": (_bitwise, ["IN"], 1, 1),
    "SEL": (_sel, ["G", "IN0", "IN1"], 3, 3),
    "MAX": (_maxmin, "IN", 2, None), "MIN": (_maxmin, "IN", 2, None),
    "LIMIT": (_maxmin, ["MN", "IN", "MX"], 3, 3),
    "MUX": (_mux, "K", 3, None),
    "GT": (_compare, "IN", 2, None), "GE": (_compare, "IN", 2, None),
    "EQ": (_compare, "IN", 2, None), "LE": (_compare, "IN", 2, None),
    "LT": (_compare, "IN", 2, None), "NE": (_compare, ["IN1", "IN2"], 2, 2),
    "LEN": (_strfn("S", INT), ["IN"], 1, 1),
    "LEFT": (_strfn("SI", "S"), ["IN", "L"], 2, 2),
    "RIGHT": (_strfn("SI", "S"), ["IN", "L"], 2, 2),
    "MID": (_strfn("SII", "S"), ["IN", "L", "P"], 3, 3),
    "CONCAT": (_concat, "IN", 2, None),
    "INSERT": (_strfn("SSI", "S"), ["IN1", "IN2", "P"], 3, 3),
    "DELETE": (_strfn("SII", "S"), ["IN", "L", "P"], 3, 3),
    "REPLACE": (_strfn("SSII", "S"), ["IN1", "IN2", "L", "P"], 4, 4),
    "FIND": (_strfn("SS", INT), ["IN1", "IN2"], 2, 2),
    "ADD_TIME": (_fixed([TIME, TIME], TIME), ["IN1", "IN2"], 2, 2),
    "SUB_TIME": (_fixed([TIME, TIME], TIME), ["IN1", "IN2"], 2, 2),
    "MUL_TIME": (_fixed([TIME, LREAL], TIME), ["IN1", "IN2"], 2, 2),
    "DIV_TIME": (_fixed([TIME, LREAL], TIME), ["IN1", "IN2"], 2, 2),
    # ed.2's names of MUL_TIME and DIV_TIME (ed.2 table 30), the same functions
    "MULTIME": (_fixed([TIME, LREAL], TIME, "MUL_TIME"), ["IN1", "IN2"], 2, 2),
    "DIVTIME": (_fixed([TIME, LREAL], TIME, "DIV_TIME"), ["IN1", "IN2"], 2, 2),
    "ADD_TOD_TIME": (_fixed([_T["TOD"], TIME], _T["TOD"]), ["IN1", "IN2"], 2, 2),
    "ADD_DT_TIME": (_fixed([_T["DT"], TIME], _T["DT"]), ["IN1", "IN2"], 2, 2),
    "SUB_TOD_TIME": (_fixed([_T["TOD"], TIME], _T["TOD"]), ["IN1", "IN2"], 2, 2),
    "SUB_DT_TIME": (_fixed([_T["DT"], TIME], _T["DT"]), ["IN1", "IN2"], 2, 2),
    "SUB_DATE_DATE": (_fixed([_T["DATE"], _T["DATE"]], TIME), ["IN1", "IN2"], 2, 2),
    "SUB_TOD_TOD": (_fixed([_T["TOD"], _T["TOD"]], TIME), ["IN1", "IN2"], 2, 2),
    "SUB_DT_DT": (_fixed([_T["DT"], _T["DT"]], TIME), ["IN1", "IN2"], 2, 2),
    "CONCAT_DATE_TOD": (_fixed([_T["DATE"], _T["TOD"]], _T["DT"]), ["IN1", "IN2"], 2, 2),
    "TRUNC": (_trunc, ["IN"], 1, 1),
}

# names of conversion sources and targets
CONVERTIBLE = [n for n in ("BOOL", "SINT", "INT", "DINT", "LINT", "USINT", "UINT", "UDINT",
                           "ULINT", "REAL", "LREAL", "BYTE", "WORD", "DWORD", "LWORD", "TIME",
                           "LTIME", "DATE", "TOD", "DT", "STRING", "WSTRING")]
_ALIASES = {"TIME_OF_DAY": "TOD", "DATE_AND_TIME": "DT"}
_BCD = {"BYTE": "USINT", "WORD": "UINT", "DWORD": "UDINT", "LWORD": "ULINT"}
_BCD_SOURCES = {"SINT": "BYTE", "USINT": "BYTE", "INT": "WORD", "UINT": "WORD",
                "DINT": "DWORD", "UDINT": "DWORD", "LINT": "LWORD", "ULINT": "LWORD"}


def bcd_by_context(f, target):
    """The call *f* of an overloaded X_TO_BCD retyped for the bit string
    *target* its result is stored in (BIN_LEVEL := INT_TO_BCD(n) with
    BIN_LEVEL : BYTE, ed.2 Annex F.5), or None when it is not one."""
    if not isinstance(f, StdFunc) or f.family != "TO_BCD" or not f.name.endswith("_TO_BCD"):
        return None
    t = target.base if target is not None else None
    if not isinstance(t, Elementary) or t.cat != "bit" or t.name not in _BCD or t is f.result:
        return None
    return StdFunc(f.name, "TO_BCD", list(f.param_types), t)


def _type_by_name(n):
    n = _ALIASES.get(n, n)
    if n == "STRING":
        return STRING
    if n == "WSTRING":
        return StringT(wide=True)
    return ELEMENTARY.get(n)


def _conversion_allowed(src, dst) -> bool:
    sc, dc = src, dst
    timeish = ("TIME", "LTIME", "DATE", "TOD", "DT")
    if sc in ("DATE", "TOD") and dc not in ("STRING", "WSTRING", "LINT", "ULINT", "LWORD",
                                            "DT", "DATE", "TOD", "LTIME", "TIME"):
        return False
    if sc in timeish and dc in ("BOOL",):
        return False
    if dc in ("DATE", "TOD") and sc not in ("DT", "STRING", "LINT", "ULINT", "LWORD", "DATE",
                                            "TOD"):
        return False
    return True


def conversion(name: str):
    """Resolves X_TO_Y, X_TRUNC_Y, X_BCD_TO_Y, X_TO_BCD_Y, BCD_TO_INT,
    INT_TO_BCD: returns (source type, target type, family) or None."""
    up = name.upper()
    if up == "BCD_TO_INT":
        return ELEMENTARY["WORD"], INT, "BCD_TO"
    if up.endswith("_TO_BCD") and up[:-7] in _BCD_SOURCES:
        # ed.2's overloaded *_TO_BCD (INT_TO_BCD, ...): ANY_INT -> ANY_BIT, the
        # bit string given by the context (bcd_by_context), else the one of
        # the source's width
        return ELEMENTARY[up[:-7]], ELEMENTARY[_BCD_SOURCES[up[:-7]]], "TO_BCD"
    if "_TRUNC_" in up:
        s, d = up.split("_TRUNC_", 1)
        if s in ("REAL", "LREAL") and d in ELEMENTARY and ELEMENTARY[d].cat in ("sint", "uint"):
            return ELEMENTARY[s], ELEMENTARY[d], "TRUNC"
        return None
    if "_BCD_TO_" in up:
        s, d = up.split("_BCD_TO_", 1)
        if s in _BCD and d in ELEMENTARY and ELEMENTARY[d].cat == "uint":
            return ELEMENTARY[s], ELEMENTARY[d], "BCD_TO"
        return None
    if "_TO_BCD_" in up:
        s, d = up.split("_TO_BCD_", 1)
        if d in _BCD and s in ELEMENTARY and ELEMENTARY[s].cat == "uint":
            return ELEMENTARY[s], ELEMENTARY[d], "TO_BCD"
        return None
    if "_TO_" not in up:
        return None
    for i in range(len(up)):
        if up.startswith("_TO_", i):
            s, d = up[:i], up[i + 4:]
            s2, d2 = _ALIASES.get(s, s), _ALIASES.get(d, d)
            if s2 in CONVERTIBLE and d2 in CONVERTIBLE and s2 != d2 and \
                    _conversion_allowed(s2, d2):
                return _type_by_name(s2), _type_by_name(d2), "CONVERT"
    return None


_TIME_TYPES = ("TIME", "LTIME", "DATE", "TOD", "DT")
# ed.2 Table 30 (13, 14): the only conversions between time types the standard names
_TABLE30_CONVERSIONS = {("DT", "TOD"), ("DT", "DATE")}


def implementation_conversion(name: str) -> bool:
    """True for a conversion between two time types that ed.2 does not name:
    Table 22 leaves the list of *_TO_** conversions to the implementation
    (footnote a) and Table 30 names only DT_TO_TOD and DT_TO_DATE.  This
    implementation provides e.g. TOD_TO_TIME and DATE_TO_DT; MatIEC does not,
    and libraries written for it (OSCAT) define their own.  A user FUNCTION
    of such a name replaces ours (declare.py warns)."""
    conv = conversion(name)
    if conv is None or conv[2] != "CONVERT":
        return False
    s, d = (t.name for t in conv[:2])
    s, d = _ALIASES.get(s, s), _ALIASES.get(d, d)
    return s in _TIME_TYPES and d in _TIME_TYPES and (s, d) not in _TABLE30_CONVERSIONS


def ed3_only(name: str) -> bool:
    """Standard names that IEC 61131-3 ed.3 added (ATAN2, table 23; the typed
    counters CTU_DINT ..., table 43; the typed REAL_TRUNC_INT ... forms,
    table 22): an ed.2 project may define a POU of that name, which then
    replaces the standard one (with a warning)."""
    up = name.upper()
    if up == "ATAN2" or "_TRUNC_" in up and conversion(up) is not None:
        return True
    head, _, tail = up.partition("_")
    return head in ("CTU", "CTD", "CTUD") and tail in ("DINT", "LINT", "UDINT", "ULINT")


def is_std_function(name: str) -> bool:
    up = name.upper()
    return up in FUNCTIONS or conversion(up) is not None


def resolve(name: str, types: list):
    """Resolves a call of a standard function with positional argument
    types; raises CallError with a clear message."""
    up = name.upper()
    if up in FUNCTIONS:
        fn, params, lo, hi = FUNCTIONS[up]
        if len(types) < lo or (hi is not None and len(types) > hi):
            want = f"{lo}" if lo == hi else (f"at least {lo}" if hi is None else f"{lo} to {hi}")
            raise CallError(f"{up} takes {want} argument{'s' if (hi or 2) > 1 else ''}, "
                            f"{len(types)} given")
        return fn(up, list(types))
    conv = conversion(up)
    if conv is None:
        raise CallError(f"unknown function '{name}'")
    src, dst, family = conv
    if len(types) != 1:
        raise CallError(f"{up} takes 1 argument, {len(types)} given")
    t = types[0]
    if not isinstance(t, ErrorT) and not assignable(t, src):
        raise CallError(f"argument of {up} must be {src.name}, not {t.name}")
    return StdFunc(up, family, [src], dst)


def formal_names(name: str, nargs: int) -> list[str]:
    up = name.upper()
    if up in FUNCTIONS:
        params = FUNCTIONS[up][1]
        if isinstance(params, str):
            if params == "K":
                return ["K"] + [f"IN{i}" for i in range(max(nargs - 1, 2))]
            return [f"IN{i + 1}" for i in range(max(nargs, 2))]
        return list(params)
    return ["IN"]


# ------------------------------------------------------- function blocks

def _fb(name, inputs, outputs, internals=()):
    pou = POUInfo("FUNCTION_BLOCK", name, standard=True)
    for n, t, *edge in inputs:
        v = Var(n, t, "VAR_INPUT", edge=edge[0] if edge else None, owner=pou)
        pou.vars[n] = v
        pou.inputs.append(v)
    for n, t in outputs:
        v = Var(n, t, "VAR_OUTPUT", owner=pou)
        pou.vars[n] = v
        pou.outputs.append(v)
    for n, t in internals:
        pou.vars[n] = Var(n, t, "VAR", owner=pou)
    return pou


def keeping_eno(pou):
    """A copy of the standard FB pou whose instances keep the ENO of their
    last call (an output, TRUE initially; FALSE after a call with EN =
    FALSE, TRUE after any other: a standard FB's body never sets it FALSE),
    for a project that reads ``t.ENO`` (checks/eno.fb_eno).  Its
    instances are the runtime's struct and an ENO member
    (codegen/cnames.py)."""
    from .. import ast
    copy = POUInfo("FUNCTION_BLOCK", pou.name, standard=True, keeps_eno=True)
    copy.vars = dict(pou.vars)
    copy.inputs = list(pou.inputs)
    copy.outputs = list(pou.outputs)
    lit = ast.Lit(None, "TRUE", "bool", True)
    lit.type = BOOL
    v = Var("ENO", BOOL, "VAR_OUTPUT", init=lit, owner=copy)
    copy.vars["ENO"] = v
    copy.outputs.append(v)
    return copy


def _counters():
    out = {}
    for suffix, t in (("", INT), ("_DINT", ELEMENTARY["DINT"]), ("_LINT", ELEMENTARY["LINT"]),
                      ("_UDINT", ELEMENTARY["UDINT"]), ("_ULINT", ELEMENTARY["ULINT"])):
        out["CTU" + suffix] = _fb("CTU" + suffix, [("CU", BOOL, "R_EDGE"), ("R", BOOL), ("PV", t)],
                                  [("Q", BOOL), ("CV", t)])
        out["CTD" + suffix] = _fb("CTD" + suffix, [("CD", BOOL, "R_EDGE"), ("LD", BOOL),
                                                   ("PV", t)], [("Q", BOOL), ("CV", t)])
        out["CTUD" + suffix] = _fb("CTUD" + suffix,
                                   [("CU", BOOL, "R_EDGE"), ("CD", BOOL, "R_EDGE"), ("R", BOOL),
                                    ("LD", BOOL), ("PV", t)],
                                   [("QU", BOOL), ("QD", BOOL), ("CV", t)])
    return out


FUNCTION_BLOCKS = {
    "SR": _fb("SR", [("S1", BOOL), ("R", BOOL)], [("Q1", BOOL)]),
    "RS": _fb("RS", [("S", BOOL), ("R1", BOOL)], [("Q1", BOOL)]),
    "R_TRIG": _fb("R_TRIG", [("CLK", BOOL)], [("Q", BOOL)]),
    "F_TRIG": _fb("F_TRIG", [("CLK", BOOL)], [("Q", BOOL)]),
    "TP": _fb("TP", [("IN", BOOL), ("PT", TIME)], [("Q", BOOL), ("ET", TIME)]),
    "TON": _fb("TON", [("IN", BOOL), ("PT", TIME)], [("Q", BOOL), ("ET", TIME)]),
    "TOF": _fb("TOF", [("IN", BOOL), ("PT", TIME)], [("Q", BOOL), ("ET", TIME)]),
    # ed.1 table 35 (MatIEC's definition): Q is IN; a rising IN sets the
    # clock to PDT, CDT then advances with it; IN FALSE: CDT is the clock
    "RTC": _fb("RTC", [("IN", BOOL), ("PDT", ELEMENTARY["DT"])],
               [("Q", BOOL), ("CDT", ELEMENTARY["DT"])]),
    **_counters(),
}


def operand_message(exc, lt, rt):
    """The message for operands an operator refuses, with the conversion
    function that would make them agree when there is one."""
    msg = str(exc)
    if "incompatible" in msg:
        s, d = concrete(lt), concrete(rt)
        hint = ""
        if isinstance(s, Elementary) and isinstance(d, Elementary) and \
                conversion(f"{s.name}_TO_{d.name}"):
            hint = f": convert one operand explicitly, e.g. {s.name}_TO_{d.name}"
        return f"incompatible operands {lt.name} and {rt.name}{hint}"
    return msg
