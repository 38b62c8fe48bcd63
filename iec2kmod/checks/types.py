"""The IEC 61131-3 type system: elementary types, derived types, and the
implicit conversions the standard allows (ed.3, figure 11: widening only)."""

from __future__ import annotations


class Type:
    kind = "?"
    name = "?"

    def __repr__(self):
        return self.name

    @property
    def base(self) -> "Type":
        """The elementary type a subrange is made of; the type itself otherwise."""
        return self


class Elementary(Type):
    """``cat`` is one of bool, sint (signed), uint (unsigned), real, bit,
    time, date, tod, dt."""

    kind = "elementary"

    def __init__(self, name, cat, bits, c_type):
        self.name = name
        self.cat = cat
        self.bits = bits
        self.c_type = c_type

    @property
    def range(self):
        if self.cat == "sint":
            return -(1 << (self.bits - 1)), (1 << (self.bits - 1)) - 1
        if self.cat in ("uint", "bit", "bool"):
            return 0, (1 << self.bits) - 1
        return None


_ELEMENTARY = [
    ("BOOL", "bool", 1, "iec_bool"),
    ("SINT", "sint", 8, "iec_sint"), ("INT", "sint", 16, "iec_int"),
    ("DINT", "sint", 32, "iec_dint"), ("LINT", "sint", 64, "iec_lint"),
    ("USINT", "uint", 8, "iec_usint"), ("UINT", "uint", 16, "iec_uint"),
    ("UDINT", "uint", 32, "iec_udint"), ("ULINT", "uint", 64, "iec_ulint"),
    ("REAL", "real", 32, "iec_real"), ("LREAL", "real", 64, "iec_lreal"),
    ("BYTE", "bit", 8, "iec_byte"), ("WORD", "bit", 16, "iec_word"),
    ("DWORD", "bit", 32, "iec_dword"), ("LWORD", "bit", 64, "iec_lword"),
    ("TIME", "time", 64, "iec_time"), ("LTIME", "time", 64, "iec_ltime"),
    ("DATE", "date", 64, "iec_date"), ("LDATE", "date", 64, "iec_date"),
    ("TOD", "tod", 64, "iec_tod"), ("LTOD", "tod", 64, "iec_tod"),
    ("DT", "dt", 64, "iec_dt"), ("LDT", "dt", 64, "iec_dt"),
]

ELEMENTARY: dict[str, Elementary] = {n: Elementary(n, c, b, ct) for n, c, b, ct in _ELEMENTARY}
ELEMENTARY["TIME_OF_DAY"] = ELEMENTARY["TOD"]
ELEMENTARY["DATE_AND_TIME"] = ELEMENTARY["DT"]

BOOL = ELEMENTARY["BOOL"]
INT = ELEMENTARY["INT"]
DINT = ELEMENTARY["DINT"]
LREAL = ELEMENTARY["LREAL"]
REAL = ELEMENTARY["REAL"]
TIME = ELEMENTARY["TIME"]


class StringT(Type):
    kind = "string"

    def __init__(self, length=254, wide=False):
        self.length = length
        self.wide = wide
        self.name = ("WSTRING" if wide else "STRING") + (f"[{length}]" if length != 254 else "")


STRING = StringT()
WSTRING = StringT(wide=True)


class ArrayT(Type):
    kind = "array"

    def __init__(self, dims, elem):
        self.dims = dims  # [(low, high)]
        self.elem = elem
        self.name = "ARRAY[" + ", ".join(f"{lo}..{hi}" for lo, hi in dims) + f"] OF {elem.name}"

    @property
    def count(self):
        n = 1
        for lo, hi in self.dims:
            n *= hi - lo + 1
        return n


class StructT(Type):
    kind = "struct"

    def __init__(self, name):
        self.name = name
        self.fields = {}  # upper name -> (display name, Type, init)


class EnumT(Type):
    kind = "enum"

    def __init__(self, name, base=None):
        self.name = name
        self.values = {}  # upper name -> (display name, int value)
        self.elem_base = base  # Elementary for typed enumerations, or None

    def has(self, value_name: str) -> bool:
        return value_name.upper() in self.values


class SubrangeT(Type):
    kind = "subrange"

    def __init__(self, name, elem, low, high):
        self.name = name
        self.elem = elem
        self.low = low
        self.high = high

    @property
    def base(self):
        return self.elem


class FBType(Type):
    """A function block type (user-defined or standard): instances of it."""

    kind = "fb"

    def __init__(self, name, pou):
        self.name = name
        self.pou = pou  # symbols.POUInfo


class LiteralT(Type):
    """The type of an untyped numeric literal: adapts to its context."""

    kind = "literal"

    def __init__(self, cat, value):
        self.cat = cat  # "int" or "real"
        self.value = value
        self.name = "integer literal" if cat == "int" else "real literal"


class AnyIntResult(LiteralT):
    """The result of a generic function whose integer result type comes from
    its context (TRUNC: ANY_REAL -> ANY_INT, ed.3 table 22): adapts to any
    integer type as an integer literal would, without a value to check."""

    generic = "TRUNC"

    def __init__(self, func="TRUNC"):
        super().__init__("int", 0)
        self.generic = func
        self.name = "ANY_INT"


class ErrorT(Type):
    """The type of an expression that already produced an error."""

    kind = "error"
    name = "<error>"


ERROR = ErrorT()

# --------------------------------------------------------------- widening

_WIDEN = {
    "SINT": {"INT", "DINT", "LINT", "REAL", "LREAL"},
    "INT": {"DINT", "LINT", "REAL", "LREAL"},
    "DINT": {"LINT", "LREAL"},
    "LINT": set(),
    "USINT": {"UINT", "UDINT", "ULINT", "INT", "DINT", "LINT", "REAL", "LREAL"},
    "UINT": {"UDINT", "ULINT", "DINT", "LINT", "REAL", "LREAL"},
    "UDINT": {"ULINT", "LINT", "LREAL"},
    "ULINT": set(),
    "REAL": {"LREAL"},
    "LREAL": set(),
    "BOOL": {"BYTE", "WORD", "DWORD", "LWORD"},
    "BYTE": {"WORD", "DWORD", "LWORD"},
    "WORD": {"DWORD", "LWORD"},
    "DWORD": {"LWORD"},
    "LWORD": set(),
    "TIME": {"LTIME"},
    "DATE": {"LDATE"},
    "TOD": {"LTOD"},
    "DT": {"LDT"},
}

INT_CATS = ("sint", "uint")


def is_int(t) -> bool:
    t = t.base
    return (isinstance(t, Elementary) and t.cat in INT_CATS) or (
        isinstance(t, LiteralT) and t.cat == "int")


def is_real(t) -> bool:
    t = t.base
    return (isinstance(t, Elementary) and t.cat == "real") or (
        isinstance(t, LiteralT) and t.cat == "real")


def is_num(t) -> bool:
    return is_int(t) or is_real(t)


def is_bit(t) -> bool:
    """ANY_BIT: BOOL, BYTE, WORD, DWORD, LWORD (and integer literals)."""
    t = t.base
    return (isinstance(t, Elementary) and t.cat in ("bool", "bit")) or (
        isinstance(t, LiteralT) and t.cat == "int")


def is_bool(t) -> bool:
    return t.base is BOOL


def is_string(t) -> bool:
    return isinstance(t, StringT)


def is_elementary(t) -> bool:
    return isinstance(t.base, (Elementary, StringT, LiteralT)) or isinstance(t, EnumT)


def cat(t):
    t = t.base
    return getattr(t, "cat", None)


def literal_fits(lit: LiteralT, target: Type) -> bool:
    target = target.base
    if not isinstance(target, Elementary):
        return False
    if isinstance(lit, AnyIntResult):
        return target.cat in INT_CATS
    if lit.cat == "real":
        return target.cat == "real"
    if target.cat == "real":
        return True
    if target.cat == "bool":
        return lit.value in (0, 1)
    rng = target.range
    return rng is not None and rng[0] <= lit.value <= rng[1]


def same(a: Type, b: Type) -> bool:
    """Values of a may be stored in b as they are (a string of another
    length is truncated; the elements of arrays must be identical)."""
    if a is b:
        return True
    if isinstance(a, StringT) and isinstance(b, StringT):
        return a.wide == b.wide
    if isinstance(a, ArrayT) and isinstance(b, ArrayT):
        return identical(a, b)
    return False


def identical(a: Type, b: Type) -> bool:
    """The same type, with the same storage: what a reference (VAR_IN_OUT,
    VAR_EXTERNAL) and the elements of an array assignment need.  A STRING[8]
    is not a STRING[4] here: an array of one is not copied element by
    element into an array of the other, and a reference to one cannot
    stand for the other."""
    if a is b:
        return True
    if isinstance(a, StringT) and isinstance(b, StringT):
        return a.wide == b.wide and a.length == b.length
    if isinstance(a, ArrayT) and isinstance(b, ArrayT):
        return a.dims == b.dims and identical(a.elem, b.elem)
    if isinstance(a, FBType) and isinstance(b, FBType):
        return a.pou is b.pou
    return False


def assignable(src: Type, dst: Type) -> bool:
    """May a value of type src be stored in dst without an explicit conversion?"""
    if isinstance(src, ErrorT) or isinstance(dst, ErrorT):
        return True
    if same(src, dst):
        return True
    if isinstance(src, LiteralT):
        return literal_fits(src, dst)
    if isinstance(dst, StringT) and isinstance(src, StringT):
        return src.wide == dst.wide  # truncated to the destination's length
    if isinstance(dst, SubrangeT):
        # checked at run time against the subrange
        return assignable(src, dst.elem)
    if isinstance(src, SubrangeT):
        return assignable(src.elem, dst)
    if isinstance(src, Elementary) and isinstance(dst, Elementary):
        return dst.name in _WIDEN.get(src.name, ()) or src.c_type == dst.c_type and src.cat == dst.cat
    return False


def common(a: Type, b: Type):
    """The type both operands convert to implicitly, or None."""
    if isinstance(a, ErrorT) or isinstance(b, ErrorT):
        return ERROR
    a0, b0 = a, b
    a, b = a.base, b.base
    if isinstance(a, LiteralT) and isinstance(b, LiteralT):
        if a.cat == "real" or b.cat == "real":
            return LiteralT("real", 0.0)
        if isinstance(a, AnyIntResult) or isinstance(b, AnyIntResult):
            return AnyIntResult(a.generic if isinstance(a, AnyIntResult) else b.generic)
        return LiteralT("int", 0)
    if isinstance(a, LiteralT):
        return b if literal_fits(a, b) else None
    if isinstance(b, LiteralT):
        return a if literal_fits(b, a) else None
    if same(a, b):
        return a if a0 is b0 else a
    if assignable(a, b):
        return b
    if assignable(b, a):
        return a
    return None


def not_bit_value(what: str, lits) -> str | None:
    """The message for the first of values *lits* (LiteralT, or a folded
    number) that no bit string holds (a negative, a REAL, over 64 bits) as
    an operand of *what* ("operator AND", "OR"), or None when all fit: the
    words of every bitwise operation on untyped literals (statements,
    standard calls, initial values)."""
    for lit in lits:
        v = lit.value if isinstance(lit, LiteralT) else lit
        if isinstance(v, bool):
            continue
        if not isinstance(v, int) or not 0 <= v <= (1 << 64) - 1:
            return (f"{what} on untyped literals: {v} is not a bit string value "
                    "(0 .. 16#FFFF_FFFF_FFFF_FFFF)")
    return None


def concrete_bits(*lits: LiteralT):
    """The bit string AND, OR, XOR or NOT on untyped integer literals (``5
    AND 3``, ``NOT 16#FF``) is computed in where nothing else decides: the
    bit-string counterpart of ``concrete``'s DINT, DWORD, and LWORD where a
    value needs more than 32 bits; None when a value is negative or needs
    more than 64 bits (no bit string holds it).  A DINT, the integer
    default, has no bitwise operations (ed.3 table 23: ANY_BIT)."""
    if any(not 0 <= lit.value <= (1 << 64) - 1 for lit in lits):
        return None
    if all(lit.value <= (1 << 32) - 1 for lit in lits):
        return ELEMENTARY["DWORD"]
    return ELEMENTARY["LWORD"]


def concrete(t: Type) -> Type:
    """A literal type made concrete (DINT or LREAL) where nothing else decides."""
    if isinstance(t, LiteralT):
        if t.cat == "real":
            return LREAL
        lo, hi = -(1 << 31), (1 << 31) - 1
        return DINT if lo <= t.value <= hi else ELEMENTARY["LINT"]
    return t
