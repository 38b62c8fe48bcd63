"""IEC names to C names, and IEC types to C types.

IEC identifiers are case-insensitive; C's are not, and the kernel defines
macros with ordinary names (``current``, ``min``, ``jiffies``).  So every
generated name is lower-case and carries a prefix no macro or keyword has:

    variable / member     v_<name>          (hidden members: h_<name>)
    user type             struct t_<name>   (enumeration values: E_<TYPE>_<VALUE>)
    function              fn_<name>
    function block        struct fb_<name>, fb_<name>_body(), fb_<name>_init()
    program               struct prog_<name>, prog_<name>_body(), prog_<name>_init()
"""

from __future__ import annotations

import re

from ..checks.types import (ArrayT, Elementary, EnumT, FBType, LiteralT, StringT, StructT,
                            SubrangeT, concrete)


def var(name: str) -> str:
    return "v_" + name.lower()


def temp_proto(name: str) -> str:
    """Member holding a fresh, bound copy of a VAR_TEMP that contains FB
    instances: each call starts its temporary from it (pou.has_fb)."""
    return "h_" + name.lower() + "_proto"


def fn(name: str) -> str:
    return "fn_" + name.lower()


def pou_struct(pou) -> str:
    if pou.standard:
        return f"struct {pou_prefix(pou)}"
    return f"struct {'prog' if pou.kind == 'PROGRAM' else 'fb'}_{pou.name.lower()}"


def pou_prefix(pou) -> str:
    if pou.standard:
        # a standard FB whose ENO is read: the runtime's struct (member fb)
        # and ENO in one (codegen.std_eno_type)
        return f"iec_fb{'e' if pou.keeps_eno else ''}_{pou.name.lower()}"
    return f"{'prog' if pou.kind == 'PROGRAM' else 'fb'}_{pou.name.lower()}"


def member(pou, name: str) -> str:
    """Member of an FB instance struct (standard FBs use plain lower case)."""
    if pou.standard and pou.keeps_eno:
        return "eno" if name.upper() == "ENO" else "fb." + name.lower()
    return name.lower() if pou.standard else var(name)


def enum_const(t: EnumT, value: str) -> str:
    return f"E_{t.name.upper()}_{value.upper()}"


def type_tag(t) -> str:
    """The suffix of runtime helpers for a type: int, real, time, bool ..."""
    t = concrete(t)
    if isinstance(t, SubrangeT):
        t = t.elem
    if isinstance(t, EnumT):
        return enum_base(t).name.lower()
    if isinstance(t, Elementary):
        return {"TIME_OF_DAY": "tod", "DATE_AND_TIME": "dt"}.get(t.name, t.name.lower())
    if isinstance(t, StringT):
        return "wstring" if t.wide else "string"
    raise ValueError(f"no runtime type tag for {t.name}")


def enum_base(t: EnumT) -> Elementary:
    from ..checks.types import ELEMENTARY
    if t.elem_base is not None:
        return t.elem_base
    return ELEMENTARY["DINT"]


def string_struct(t: StringT) -> str:
    if t.length == 254:
        return "struct iec_wstring" if t.wide else "struct iec_string"
    return f"struct iec_{'w' if t.wide else ''}string_{t.length}"


def ctype(t) -> str:
    """The C type of a scalar or struct-valued IEC type (not arrays)."""
    t = concrete(t)
    if isinstance(t, SubrangeT):
        return t.elem.c_type
    if isinstance(t, EnumT):
        return enum_base(t).c_type
    if isinstance(t, Elementary):
        return t.c_type
    if isinstance(t, StringT):
        return string_struct(t)
    if isinstance(t, StructT):
        return f"struct t_{t.name.lower()}"
    if isinstance(t, FBType):
        return pou_struct(t.pou)
    if isinstance(t, ArrayT):
        raise ValueError("arrays are declared with declare()")
    raise ValueError(f"no C type for {t.name}")


def ctype_or_none(t):
    try:
        return ctype(t)
    except ValueError:
        return None


def array_flat(t: ArrayT):
    """(element type, total count) of a possibly nested array type."""
    count = t.count
    elem = t.elem
    while isinstance(elem, ArrayT):
        count *= elem.count
        elem = elem.elem
    return elem, count


def declare(t, name: str) -> str:
    """A C declaration of ``name`` with IEC type t (arrays flattened)."""
    if isinstance(t, ArrayT):
        elem, count = array_flat(t)
        return f"{ctype(elem)} {name}[{count}]"
    return f"{ctype(t)} {name}"


_C_STRING_SAFE = re.compile(r"[ -~]")


# printable ASCII but '"', '?' (trigraphs) and '\\': spelled as they are
_C_STRING_PLAIN = re.compile(rb"[\x20\x21\x23-\x3e\x40-\x5b\x5d-\x7e]*")


def c_string(data: bytes) -> str:
    """A C string literal with every byte spelled safely."""
    if _C_STRING_PLAIN.fullmatch(data):
        return '"' + data.decode("ascii") + '"'
    out = []
    for b in data:
        ch = chr(b)
        if ch in '"\\?':
            out.append("\\" + ch if ch != "?" else "\\?")
        elif _C_STRING_SAFE.fullmatch(ch):
            out.append(ch)
        else:
            out.append(f"\\{b:03o}")
    return '"' + "".join(out) + '"'


def is_scalar(t) -> bool:
    t = concrete(t)
    return isinstance(t, (Elementary, EnumT, SubrangeT, LiteralT))
