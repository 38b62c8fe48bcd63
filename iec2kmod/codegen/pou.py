"""POUs to C: the project header (types, instance structs, init functions)
and one body file per POU.  See iec2kmod/codegen/__init__.py for how the
pieces are put together."""

from __future__ import annotations

from .. import ast
from ..checks.types import (ArrayT, Elementary, EnumT, FBType, StringT, StructT, SubrangeT,
                            concrete)
from . import cnames as N
from .body import FRAME, BodyEmitter
from .expr import Frame, c_int

SECTION_ORDER = ("VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR_EXTERNAL", "VAR_GLOBAL", "VAR")


def member_decl(v) -> str:
    name = N.var(v.name)
    if v.section in ("VAR_EXTERNAL", "VAR_IN_OUT"):
        if isinstance(v.type, ArrayT):
            elem, _ = N.array_flat(v.type)
            return f"{N.ctype(elem)} *{name};"
        return f"{N.ctype(v.type)} *{name};"
    return N.declare(v.type, name) + ";"


def has_fb(t) -> bool:
    """Whether a value of type t contains a user FB instance (a VAR_TEMP of
    such a type starts every call from a prototype member of the instance,
    N.temp_proto, initialised and bound with it)."""
    if isinstance(t, FBType):
        return not t.pou.standard
    if isinstance(t, ArrayT):
        return has_fb(N.array_flat(t)[0])
    if isinstance(t, StructT):
        return any(has_fb(ft) for _, ft, _ in t.fields.values())
    return False


def pointer_members(pou, c_prefix="", iec_prefix="", counts=()):
    """Every pointer member that must be set when an instance of *pou* is
    initialised, as (C path from the instance with ``[*]`` for every element
    of an array, IEC path, element counts of those arrays): the VAR_EXTERNALs
    of the POU and of every FB instance in it, at any depth, and a program's
    VAR_IN_OUTs.  An FB's VAR_IN_OUT is set by every call instead (the front
    end requires it to be connected).

    This walks the struct layout that member_decl() declares; the binding
    table comes from the front end's scope resolution, and each must cover
    the other (plan.check_bindings)."""
    out = []
    for v in pou.vars.values():
        c, iec = f"{c_prefix}{N.var(v.name)}", f"{iec_prefix}{v.name}"
        if v.section == "VAR_TEMP":
            if not has_fb(v.type):
                continue
            c = f"{c_prefix}{N.temp_proto(v.name)}"
        if v.section == "VAR_EXTERNAL" or (v.section == "VAR_IN_OUT" and pou.kind == "PROGRAM"):
            out.append((c, iec, counts))
        elif v.section != "VAR_IN_OUT":
            out += _pointers_in(v.type, c, iec, counts)
    return out


def _pointers_in(t, c, iec, counts):
    if isinstance(t, FBType):
        return [] if t.pou.standard else pointer_members(t.pou, c + ".", iec + ".", counts)
    if isinstance(t, ArrayT):
        elem, count = N.array_flat(t)
        return _pointers_in(elem, c + "[*]", iec + "[*]", counts + (count,))
    if isinstance(t, StructT):
        out = []
        for fname, ft, _ in t.fields.values():
            out += _pointers_in(ft, f"{c}.{N.var(fname)}", f"{iec}.{fname}", counts)
        return out
    return []


class InitEmitter:
    """Initial values: C statements that bring storage to its declared state
    (after it was zeroed)."""

    def __init__(self, project, pou=None):
        self.project = project
        self.type_inits = project.types.get("__init__", {})
        self.body = BodyEmitter(pou) if pou is not None else None

    def lines(self, code, t, init, f) -> list[str]:
        if init is None:
            return self.default(code, t, f)
        if isinstance(init, ast.ArrayInit):
            elem = t.elem
            out = []
            k = 0
            per = elem.count if isinstance(elem, ArrayT) else 1
            for count, value in init.items:
                for _ in range(count or 1):
                    if k >= t.count:
                        break
                    out += self.element(code, elem, k, per, value, f)
                    k += 1
            for rest in range(k, t.count):
                out += self.element(code, elem, rest, per, None, f)
            return out
        if isinstance(init, ast.StructInit):
            out = []
            if isinstance(t, FBType):
                given = {n.upper(): val for n, val, _ in init.fields}
                out += self.default(code, t, f)
                for key, val in given.items():
                    v = t.pou.var(key)
                    out += self.lines(f"{code}.{N.member(t.pou, v.name)}", v.type, val, f)
                return out
            given = {n.upper(): val for n, val, _ in init.fields}
            for key, (name, ft, finit) in t.fields.items():
                out += self.lines(f"{code}.{N.var(name)}", ft,
                                  given.get(key, finit), f)
            return out
        return self.scalar(code, t, init, f)

    def element(self, code, elem, k, per, value, f):
        if isinstance(elem, ArrayT):
            # a nested array: its elements are a slice of the flat C array
            out = []
            sub = [(value.items if isinstance(value, ast.ArrayInit) else [])]
            flat_items = []
            for count, v in sub[0]:
                flat_items += [v] * (count or 1)
            for j in range(elem.count):
                inner = flat_items[j] if j < len(flat_items) else None
                out += self.element(code, elem.elem, k * per + j,
                                    elem.elem.count if isinstance(elem.elem, ArrayT) else 1,
                                    inner, f) if isinstance(elem.elem, ArrayT) else \
                    self.lines(f"{code}[{k * per + j}]", elem.elem, inner, f)
            return out
        return self.lines(f"{code}[{k}]", elem, value, f)

    def scalar(self, code, t, init, f):
        if isinstance(concrete(t), StringT):
            return self.body_emitter().assign_code(f, code, t, init)
        be = self.body_emitter()
        if isinstance(init, ast.Ref) and isinstance(t, EnumT) and t.has(init.name):
            return [f"{code} = {N.enum_const(t, init.name)};"]
        init.type = init.type or _lit_type(init, t)
        return be.assign_code(f, code, t, init)

    def body_emitter(self):
        if self.body is None:
            from ..checks.symbols import POUInfo
            self.body = BodyEmitter(POUInfo("FUNCTION_BLOCK", "<init>"))
        return self.body

    def default(self, code, t, f) -> list[str]:
        name = getattr(t, "name", "").upper()
        if name in self.type_inits and not isinstance(t, (Elementary, StringT)):
            return self.lines(code, t, self.type_inits[name], f)
        if isinstance(t, SubrangeT) and t.low != 0:   # the lower limit (IEC 61131-3 ed.3 6.4.2)
            return [f"{code} = {c_int(t.low, t.elem)};"]
        if isinstance(t, EnumT):
            first_name, first_val = next(iter(t.values.values()))
            if first_val != 0:
                return [f"{code} = {N.enum_const(t, first_name)};"]
            return []
        if isinstance(t, StructT):
            out = []
            for key, (name, ft, finit) in t.fields.items():
                out += self.lines(f"{code}.{N.var(name)}", ft, finit, f)
            return out
        if isinstance(t, ArrayT):
            out = []
            elem, count = N.array_flat(t)
            probe = self.default(f"{code}[i]", elem, f)
            if probe:
                out.append(f"for (i = 0; i < {count}; i++) {{")
                out += ["\t" + ln for ln in probe]
                out.append("}")
            return out
        if isinstance(t, FBType):
            return [f"{N.pou_prefix(t.pou)}_init(&{code});"]
        return []


def _lit_type(init, t):
    return t


def pou_struct(pou, sel=None) -> list[str]:
    """The C struct of a FUNCTION_BLOCK or PROGRAM instance (with its
    selective execution state at the end when *sel* gives it one)."""
    lines = [f"{N.pou_struct(pou)} {{"]
    for section in SECTION_ORDER:
        vs = [v for v in pou.vars.values() if v.section == section]
        if not vs:
            continue
        lines.append(f"\t/* {section} */")
        lines += ["\t" + member_decl(v) for v in vs]
    protos = [v for v in pou.vars.values() if v.section == "VAR_TEMP" and has_fb(v.type)]
    if protos:
        lines.append("\t/* fresh copies of VAR_TEMPs holding FB instances, bound at init */")
        lines += ["\t" + N.declare(v.type, N.temp_proto(v.name)) + ";" for v in protos]
    edges = [v for v in pou.inputs if v.edge]
    if edges:
        lines.append("\t/* edge detection of R_EDGE / F_EDGE inputs */")
        for v in edges:
            lines.append(f"\tiec_bool h_{v.name.lower()};")
            lines.append(f"\tiec_bool h_{v.name.lower()}_prev;")
    if pou.sfc is not None:
        from .sfc import struct_members
        lines += ["\t" + ln for ln in struct_members(pou)]
    if len(lines) == 1:
        lines.append("\tiec_u8 h_empty;")
    if sel is not None and sel.has_layout(pou):
        lines.append(f"\t{N.pou_struct(pou)}_sel sel;")
        lines.append("};")
        return sel.struct_lines(pou) + [""] + lines
    lines.append("};")
    return lines


def pou_init(project, pou) -> list[str]:
    """``<prefix>_init(self)``: zero, then declared initial values."""
    ie = InitEmitter(project, pou)
    f = Frame(ie.body_emitter())
    body = []
    for v in pou.vars.values():
        if v.section == "VAR_TEMP" and has_fb(v.type):
            body += ie.lines(f"self->{N.temp_proto(v.name)}", v.type, v.init, f)
        if v.section in ("VAR_EXTERNAL", "VAR_IN_OUT", "VAR_TEMP"):
            continue
        body += ie.lines(f"self->{N.var(v.name)}", v.type, v.init, f)
    needs_i = any("for (i = 0;" in ln for ln in body)
    out = [f"static inline void {N.pou_prefix(pou)}_init({N.pou_struct(pou)} *self)", "{"]
    decls = (["\tiec_u32 i;"] if needs_i else []) + ["\t" + d for d in f.decls]
    if f.decls or f.pre:
        decls.append("\tstruct iec_ctx ctx_init = { 0 };")
        decls.append("\tstruct iec_ctx *ctx = &ctx_init;")
    out += decls
    out.append("\tiec_memset(self, 0, sizeof(*self));")
    out += ["\t" + ln for ln in f.pre + body]
    out.append("}")
    if f.decls or f.pre:
        out.insert(out.index("\tiec_memset(self, 0, sizeof(*self));"),
                   "\t(void)ctx;")
    return out


def function_signature(pou, cname=None, scope="IEC_POU_SCOPE", frame=None) -> str:
    """C signature of a FUNCTION (cname: another C name; frame: the C type
    of a frame pointer parameter, for the body behind the frame wrapper)."""
    result = pou.vars[pou.key]
    params = ["struct iec_ctx *ctx"] + ([f"{frame} *{FRAME}"] if frame else [])
    if N.is_scalar(result.type):
        ret = N.ctype(result.type)
    else:
        ret = "void"
        if isinstance(result.type, ArrayT):
            elem, _ = N.array_flat(result.type)
            params.append(f"{N.ctype(elem)} *ret")
        else:
            params.append(f"{N.ctype(result.type)} *ret")
    for v in pou.vars.values():
        name = param_name(v)
        if v.section == "VAR_INPUT":
            if N.is_scalar(v.type):
                params.append(f"{N.ctype(v.type)} {name}")
            elif isinstance(v.type, ArrayT):
                elem, _ = N.array_flat(v.type)
                params.append(f"const {N.ctype(elem)} *{name}")
            else:
                params.append(f"const {N.ctype(v.type)} *{name}")
        elif v.section in ("VAR_IN_OUT", "VAR_OUTPUT"):
            if isinstance(v.type, ArrayT):
                elem, _ = N.array_flat(v.type)
                params.append(f"{N.ctype(elem)} *{name}")
            else:
                params.append(f"{N.ctype(v.type)} *{name}")
    return f"{scope} {ret} {cname or N.fn(pou.name)}({', '.join(params)})"


def param_name(v) -> str:
    """The C parameter of a function's variable: an aggregate input the body
    writes arrives as the caller's value (<name>_in_, read-only) and is
    copied into the frame, where the body works on it (an IEC name never
    ends with '_', so no variable meets it)."""
    return N.var(v.name) + ("_in_" if v.section == "VAR_INPUT" and v.copied else "")


def function_args(pou) -> list[str]:
    """The parameter names of function_signature(pou), in order."""
    args = ["ctx"] + ([] if N.is_scalar(pou.vars[pou.key].type) else ["ret"])
    return args + [param_name(v) for v in pou.vars.values()
                   if v.section in ("VAR_INPUT", "VAR_IN_OUT", "VAR_OUTPUT")]


def _frame_prefix(pou) -> str:
    return N.fn(pou.name) if pou.kind == "FUNCTION" else N.pou_prefix(pou)


def frame_struct(pou) -> str:
    return f"struct {_frame_prefix(pou)}_frame"


def frame_need(pou) -> str:
    """Name of the C constant: bytes of frame area a call of pou needs,
    with everything it calls (see iec_fault.h, iec_frame_push)."""
    return f"IEC_FRAME_NEED_{_frame_prefix(pou).upper()}"


def callees(project, pou) -> list:
    """User POUs a POU may call: the functions it calls, the types of its
    FB instances (an over-approximation is safe: it only sizes frames)."""
    keys = set(pou.calls)
    for v in pou.vars.values():
        t = v.type
        while isinstance(concrete(t), ArrayT):
            t = concrete(t).elem
        if isinstance(concrete(t), FBType) and not concrete(t).pou.standard:
            keys.add(concrete(t).pou.key)
    return [project.pous[k] for k in sorted(keys)
            if k in project.pous and not getattr(project.pous[k], "standard", False)]


def frame_max(terms: list[str], empty: str = "0U") -> str:
    """IEC_FRAME_MAX over terms in one expression, as a balanced tree (the
    task frame size of sim over the task's program instances).  The macro
    names each argument twice, so a chain MAX(a, MAX(b, MAX(c, ...))) of k
    terms expands to 2^k copies; balanced, each term is copied
    2^ceil(log2 k) <= 2k times.  The POUs' own needs are enumeration
    constants (_frame_lines), linear in their callees."""
    if not terms:
        return empty
    if len(terms) == 1:
        return terms[0]
    half = (len(terms) + 1) // 2
    return f"IEC_FRAME_MAX({frame_max(terms[:half])}, {frame_max(terms[half:])})"


def _frame_lines(project, pou, members) -> list[str]:
    """The frame struct of a body (if it has members) and its need."""
    need = [frame_need(c) for c in callees(project, pou)]
    # enumeration constants, not nested macros: IEC_FRAME_MAX names each
    # operand twice, so a macro nesting it once per callee grew exponentially
    # (a program calling 44 OSCAT functions gave gcc an expression it never
    # finished); each partial maximum is a constant of its own
    out = []
    inner = "0U"
    for i, n in enumerate(need):
        if i:
            out.append(f"enum {{ {frame_need(pou)}_M{i} = IEC_FRAME_MAX({n}, {inner}) }};")
            inner = f"{frame_need(pou)}_M{i}"
        else:
            inner = n
    if members:
        out += [f"{frame_struct(pou)} {{"] + ["\t" + m for m in members] + ["};", ""]
        own = f"IEC_FRAME_ALIGN(sizeof({frame_struct(pou)}))"
        out.append(f"enum {{ {frame_need(pou)} = {own} + {inner} }};" if need else
                   f"enum {{ {frame_need(pou)} = {own} }};")
    else:
        out.append(f"enum {{ {frame_need(pou)} = {inner} }};")
    return out + [""]


def _function_zero_outputs(pou) -> list[str]:
    """A FUNCTION's outputs and non-scalar result set to zero (what its
    caller reads when the call faults before the body ran)."""
    out = []
    result = pou.vars[pou.key]
    places = [("ret", result.type)] if not N.is_scalar(result.type) else []
    places += [(N.var(v.name), v.type) for v in pou.vars.values() if v.section == "VAR_OUTPUT"]
    for name, t in places:
        if isinstance(t, ArrayT):
            _, count = N.array_flat(t)
            out.append(f"iec_memset({name}, 0, {count} * sizeof(*{name}));")
        else:
            out.append(f"iec_memset({name}, 0, sizeof(*{name}));")
    return out


def _frame_wrapper(pou, signature, inner_call, ret_type) -> list[str]:
    """The POU's C function: pushes its frame, runs the body, pops.  When
    the push fails (never, by construction) a function's outputs are zeroed
    as its body would have done, so no caller reads an unset value."""
    name = N.c_string(pou.name.encode())
    line = pou.src.linecol(pou.node.pos)[0]
    zero = _function_zero_outputs(pou) if pou.kind == "FUNCTION" else []
    out = [signature, "{", f"\t{frame_struct(pou)} *{FRAME};", "\tiec_u32 frame_mark;"]
    if ret_type:
        out.append(f"\t{ret_type} r;")
    out += ["", f"\t{FRAME} = iec_frame_push(ctx, sizeof(*{FRAME}), &frame_mark);",
            f"\tif (!{FRAME}) {{"] + ["\t\t" + z for z in zero] + [
            f"\t\tiec_fault_locate(ctx, {name}, {line});",
            "\t\treturn 0;" if ret_type else "\t\treturn;", "\t}"]
    out.append(f"\tr = {inner_call};" if ret_type else f"\t{inner_call};")
    out.append("\tiec_frame_pop(ctx, frame_mark);")
    if ret_type:
        out.append("\treturn r;")
    out.append("}")
    return out


def pou_body(project, pou, sel=None) -> list[str]:
    """The body function of a POU (and, for a selective block type, its
    ``_run`` function: selective.py)."""
    be = BodyEmitter(pou)
    be.pooling = True
    be.sel = sel
    stmts = be.body(pou.node.body)
    out = []
    members = []       # of the frame
    if pou.kind == "FUNCTION":
        inner = []
        locals_ = []
        ie = InitEmitter(project, pou)
        ie.body = be
        f = Frame(be)
        init = []
        for v in pou.vars.values():
            if v.section in ("VAR", "VAR_TEMP") or (v.section == "RESULT" and
                                                    N.is_scalar(v.type)):
                where = members if be.in_frame(v) else locals_
                where.append(N.declare(v.type, N.var(v.name)) + ";")
                name = be.var_access(v) if be.in_frame(v) else N.var(v.name)
                init.append(f"iec_memset(&{name}, 0, sizeof({name}));")
                init += ie.lines(name, v.type, v.init if v.section != "RESULT" else None, f)
            elif v.section == "RESULT":
                # the result starts from its type's initial value
                if isinstance(v.type, ArrayT):
                    _, count = N.array_flat(v.type)
                    init.append(f"iec_memset(ret, 0, {count} * sizeof(*ret));")
                    init += ie.lines("ret", v.type, None, f)
                else:
                    init.append("iec_memset(ret, 0, sizeof(*ret));")
                    init += ie.lines("(*ret)", v.type, None, f)
            elif v.section == "VAR_INPUT" and be.in_frame(v):
                # the copy of a written aggregate input (param_name)
                members.append(N.declare(v.type, N.var(v.name)) + ";")
                name = be.var_access(v)
                init.append(f"iec_memcpy(&{name}, {param_name(v)}, sizeof({name}));")
            elif v.section == "VAR_OUTPUT":
                # outputs start from their initial values at every call, even
                # when the function returns before writing them
                name = N.var(v.name)
                if isinstance(v.type, ArrayT):
                    elem, count = N.array_flat(v.type)
                    init.append(f"iec_memset({name}, 0, {count} * sizeof(*{name}));")
                    init += ie.lines(name, v.type, v.init, f)
                else:
                    init.append(f"iec_memset({name}, 0, sizeof(*{name}));")
                    init += ie.lines(f"(*{name})", v.type, v.init, f)
        if any("for (i = 0;" in ln for ln in init):
            locals_.append("iec_u32 i;")
        locals_ += f.decls
        members += be.pool_decls() + [d for _, d in sorted(be.frame_vars.items())]
        locals_ += [f"{ct} {name};" for name, ct in sorted(be.cr_vars.items())]
        # a parameter the body does not use is valid IEC: every one is
        # marked used (-Wunused-parameter is an error in the module build)
        used = ["(void)ctx;"] + (["(void)ret;"] if not N.is_scalar(pou.vars[pou.key].type)
                                 else [])
        used += [f"(void){param_name(v)};" for v in pou.vars.values()
                 if v.section in ("VAR_INPUT", "VAR_IN_OUT", "VAR_OUTPUT")]
        used += [f"(void){FRAME};"] if members else []
        # an IL current result may be loaded and never used (valid IL)
        used += [f"(void){name};" for name in sorted(be.cr_vars)]
        inner += ["\t" + ln for ln in locals_ + used + [x for x in f.pre + init if x]]
        inner += ["\t" + ln for ln in stmts]
        rv = be.ret_value()
        inner.append(f"\treturn {rv};" if rv else "\treturn;")
        inner.append("}")
        out = _frame_lines(project, pou, members)
        if not members:
            return out + [function_signature(pou), "{"] + inner
        framed = N.fn(pou.name) + "_framed"
        result = pou.vars[pou.key]
        out += [function_signature(pou, framed, "static inline", frame_struct(pou)), "{"]
        out += inner + [""]
        args = function_args(pou)
        call = f"{framed}({', '.join([args[0], FRAME] + args[1:])})"
        return out + _frame_wrapper(pou, function_signature(pou), call,
                                    N.ctype(result.type) if N.is_scalar(result.type) else None)
    body_fn = f"{N.pou_prefix(pou)}_body"
    locals_ = []
    ie = InitEmitter(project, pou)
    ie.body = be
    f = Frame(be)
    init = []
    for v in pou.vars.values():
        if v.section == "VAR_TEMP":
            (members if be.in_frame(v) else locals_).append(N.declare(v.type, N.var(v.name)) +
                                                            ";")
            name = be.var_access(v)
            if has_fb(v.type):
                # a fresh instance whose externals are bound: the prototype
                proto = f"self->{N.temp_proto(v.name)}"
                init.append(f"iec_memcpy({'' if isinstance(v.type, ArrayT) else '&'}"
                            f"{name}, {'' if isinstance(v.type, ArrayT) else '&'}"
                            f"{proto}, sizeof({name}));")
                continue
            init.append(f"iec_memset(&{name}, 0, sizeof({name}));")
            init += ie.lines(name, v.type, v.init, f)
    if any("for (i = 0;" in ln for ln in init):
        locals_.append("iec_u32 i;")
    locals_ += f.decls
    members += be.pool_decls() + [d for _, d in sorted(be.frame_vars.items())]
    locals_ += [f"{ct} {name};" for name, ct in sorted(be.cr_vars.items())]
    edge = []
    for v in pou.inputs:
        if v.edge:
            n = v.name.lower()
            cur = f"self->v_{n}"
            prev = f"self->h_{n}_prev"
            expr = f"{cur} && !{prev}" if v.edge == "R_EDGE" else f"!{cur} && {prev}"
            edge += [f"self->h_{n} = {expr};", f"{prev} = {cur};"]
    # an IL current result may be loaded and never used (valid IL)
    used = ["(void)self;", "(void)ctx;"] + [f"(void){name};" for name in sorted(be.cr_vars)]
    used += [f"(void){FRAME};"] if members else []
    inner = ["\t" + ln for ln in locals_ + used + f.pre + init + edge]
    inner += ["\t" + ln for ln in stmts]
    if be.uses_ret_label:
        inner.append("out:")
        inner.append("\treturn;")
    inner.append("}")
    out = _frame_lines(project, pou, members)
    sig = f"IEC_POU_SCOPE void {body_fn}({N.pou_struct(pou)} *self, struct iec_ctx *ctx)"
    if not members:
        out += [sig, "{"] + inner
    else:
        out += [f"static inline void {body_fn}_framed({N.pou_struct(pou)} *self, "
                f"struct iec_ctx *ctx, {frame_struct(pou)} *{FRAME})", "{"]
        out += inner + [""]
        out += _frame_wrapper(pou, sig, f"{body_fn}_framed(self, ctx, {FRAME})", None)
    if sel is not None and sel.has_layout(pou):
        out += [""] + sel.run_function(pou)
    return out
