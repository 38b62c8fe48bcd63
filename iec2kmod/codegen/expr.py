"""Expressions to C.

Every expression becomes a C expression of the C type of its IEC type.
Integer arithmetic goes through the runtime's wrapping helpers (two's
complement, no undefined behaviour); division, MOD, array indexes and MUX
go through helpers that record a runtime fault and return a defined value.
String results need storage: they are computed into temporaries declared
before the statement (``Frame.pre``)."""

from __future__ import annotations

from .. import ast
from ..checks import stdlib
from ..checks.symbols import EnumValue
from ..checks.symbols import Var
from ..checks.types import (BOOL, ELEMENTARY, ArrayT, Elementary, EnumT, FBType,
                            LiteralT, StringT, StructT, SubrangeT, concrete)
from . import cnames as N

INT64_MIN = -(1 << 63)


class CodegenError(Exception):
    """Something the checker accepted but the emitter cannot lower (a bug)."""


class BindingError(CodegenError):
    """A pointer member (VAR_EXTERNAL, VAR_IN_OUT) left without a binding:
    a bug of ours, never emitted as code (exit 70)."""


class CRNode(ast.CR):
    """The IL current result at a nesting depth, usable as an expression."""

    __slots__ = ("depth",)

    def __init__(self, pos, t, depth):
        super().__init__(pos, t)
        self.depth = depth


class Raw(ast.Expr):
    """Already-emitted C code standing for an expression of a known type."""

    __slots__ = ("code",)

    def __init__(self, code, t):
        super().__init__(None)
        self.code = code
        self.type = t


class Frame:
    """Per-statement emission state: temporaries and their setup code."""

    def __init__(self, body, pos=None):
        self.body = body      # BodyEmitter
        self.pos = pos        # the statement's: where its fault checks point
        self.pre: list[str] = []
        self.decls: list[str] = []
        self.may_fault = False
        self.pooled: dict[str, int] = {}
        self.calls = 0        # user FUNCTION calls emitted into pre
        self.checked = False  # the lines end with the statement's fault check

    def temp(self, t, prefix="tmp"):
        """A temporary of IEC type t for this statement.  In a POU body,
        strings, arrays and structures come from a pool declared once at
        the top of the function: only the innermost statement's
        temporaries are ever live, so the stack frame holds the largest
        statement's temporaries, not their sum (the kernel's stack is
        small; its frame-size warning is 2048 bytes)."""
        if self.body.pooling and isinstance(concrete(t), (StringT, ArrayT, StructT)):
            decl_key = N.declare(concrete(t), "@")
            i = self.pooled.get(decl_key, 0)
            self.pooled[decl_key] = i + 1
            return self.body.pool_name(decl_key, i)
        name = f"{prefix}{self.body.next_temp()}"
        self.decls.append(N.declare(t, name) + ";")
        return name

    def is_pooled(self, name):
        return name.startswith("frm->pool")


def c_int(value: int, t) -> str:
    t = concrete(t)
    if isinstance(t, SubrangeT):
        t = t.elem
    if isinstance(t, EnumT):
        t = N.enum_base(t)
    ct = t.c_type if isinstance(t, Elementary) else "iec_lint"
    if isinstance(t, Elementary) and t.cat == "real":
        return f"(({ct}){float(value)!r})"
    if isinstance(t, Elementary) and t.cat in ("sint", "uint", "bit", "bool", "time", "date",
                                               "tod", "dt"):
        # a constant outside the type (a folded -9223372036854775808, a bit
        # pattern) is taken modulo 2^bits, two's complement: never a C
        # constant too large for its type
        bits = t.bits if t.cat != "bool" else 8
        signed = t.cat not in ("uint", "bit", "bool")
        value &= (1 << bits) - 1
        if signed and value >= 1 << (bits - 1):
            value -= 1 << bits
    if value == INT64_MIN:
        return f"(({ct})(-9223372036854775807LL - 1))"
    if isinstance(t, Elementary) and t.cat in ("uint", "bit") and t.bits == 64:
        return f"(({ct}){value}ULL)"
    if abs(value) > 0x7FFFFFFF:
        return f"(({ct}){value}LL)"
    return f"(({ct}){value})"


def c_real(value: float, t) -> str:
    t = concrete(t)
    if value != value or value in (float("inf"), float("-inf")):
        raise CodegenError("non-finite real literal")
    text = repr(float(value))
    if t is ELEMENTARY["REAL"]:
        return f"((iec_real){text})"
    return f"((iec_lreal){text})"


def scalar_kind(t):
    t = concrete(t)
    if isinstance(t, SubrangeT):
        t = t.elem
    if isinstance(t, EnumT):
        return "enum"
    return t.cat if isinstance(t, Elementary) else None


class ExprEmitter:
    """Emits expressions for one POU body (``body`` knows variable access)."""

    def __init__(self, body):
        self.body = body

    # ------------------------------------------------------------ entry
    def emit(self, f: Frame, e, want=None) -> str:
        """C code of e, converted to IEC type ``want`` when given."""
        t = e.type
        if isinstance(t, LiteralT) or t is None:
            t = want if want is not None else concrete(t) if t is not None else None
        code = self._emit(f, e, t)
        if want is not None and t is not None:
            return self.convert(code, t, want)
        return code

    def seq(self, f, items, info=None):
        """C code of operands [(expr, IEC type)], evaluated left to right as
        IEC says.  A user FUNCTION call is a statement of its own in f.pre,
        run before the operands computed inline: when a later operand calls
        one (which may change a variable through VAR_IN_OUT, or fault), each
        scalar operand before it is computed into a temporary first, and its
        fault checked, so the call sees (and is preceded by) what came
        before it in the source.  info receives (pre lines added, may
        fault) per operand."""
        codes, marks = [], []
        for e, t in items:
            before, n_pre = f.may_fault, len(f.pre)
            f.may_fault = False
            code = self.emit(f, e, t)
            faulted = f.may_fault
            f.may_fault = before or faulted
            codes.append(code)
            marks.append((len(f.pre), f.calls, faulted))
            if info is not None:
                info.append((len(f.pre) > n_pre, faulted))
        for i in range(len(items) - 2, -1, -1):
            end, calls, faulted = marks[i]
            e, t = items[i]
            t = concrete(t if t is not None else e.type)
            if f.calls == calls or _const_int(e) is not None or isinstance(e, ast.Lit) or \
                    not N.is_scalar(t) or isinstance(t, StringT):
                continue
            tmp = f"opd{self.body.next_temp()}"
            f.decls.append(f"{N.ctype(t)} {tmp};")
            hoist = [f"{tmp} = {codes[i]};"]
            if faulted:
                hoist.append(self.body.fault_check(f.pos))
            f.pre[end:end] = hoist
            codes[i] = tmp
        return codes

    def convert(self, code, src, dst):
        """Implicit widening (the checker allowed it) as a C cast."""
        src, dst = concrete(src), concrete(dst)
        if isinstance(dst, (StringT, StructT, ArrayT, FBType)):
            return code
        sc, dc = N.ctype(src), N.ctype(dst)
        if sc == dc:
            return code
        return f"(({dc}){code})"

    def _emit(self, f, e, t):
        if isinstance(e, ast.Lit):
            return self.literal(f, e, t)
        if isinstance(e, ast.Ref):
            return self.ref_value(f, e)
        if isinstance(e, ast.BinOp):
            return self.binop(f, e, t)
        if isinstance(e, ast.UnOp):
            return self.unop(f, e, t)
        if isinstance(e, ast.Call):
            return self.call(f, e, t)
        if isinstance(e, CRNode):
            return self.body.cr_var(e.cr_type, e.depth)
        if isinstance(e, ast.CR):
            return self.body.cr_var(e.cr_type, self.body.cr_depth)
        if isinstance(e, Raw):
            return e.code
        raise CodegenError(f"cannot emit {e!r}")

    # --------------------------------------------------------- literals
    def literal(self, f, e: ast.Lit, t):
        k = e.kind
        if k in ("int", "bool"):
            v = int(e.value)
            if isinstance(t, EnumT):
                raise CodegenError("integer literal typed as enumeration")
            if scalar_kind(t) == "real":
                return c_real(float(v), t)
            return c_int(v, t if t is not None else ELEMENTARY["DINT"])
        if k == "real":
            return c_real(e.value, t if scalar_kind(t) == "real" else ELEMENTARY["LREAL"])
        if k in ("time", "date", "tod", "dt"):
            return c_int(e.value, ELEMENTARY["LINT"]).replace("iec_lint", N.ctype(e.type))
        if k in ("string", "wstring"):
            return self.string_literal(f, e)
        if k == "enum":
            return N.enum_const(e.type, e.value)
        raise CodegenError(k)

    def string_literal(self, f, e):
        """A view of a string literal: no copy, a static array for WSTRING."""
        if e.kind == "string":
            data = e.value.encode("latin-1", errors="replace")
            return f"iec_strv_make({N.c_string(data)}, {len(data)}, {len(data)})"
        data = ", ".join(str(ord(c) & 0xFFFF) for c in e.value) or "0"
        arr = f"wlit{self.body.next_temp()}"
        f.decls.append(f"static const iec_u16 {arr}[] = {{ {data} }};")
        return f"iec_wstrv_make({arr}, {len(e.value)}, {len(e.value)})"

    # -------------------------------------------------------- variables
    def ref_value(self, f, r: ast.Ref) -> str:
        if isinstance(r.symbol, EnumValue):
            return N.enum_const(r.symbol.enum, r.symbol.name)
        code, t, bit = self.lvalue(f, r)
        if bit is not None:
            return f"((iec_bool)(({code} >> {bit}) & 1))"
        return code

    def lvalue(self, f, r: ast.Ref):
        """(C lvalue, IEC type, bit number or None) of a variable access."""
        v: Var = r.symbol
        code = self.body.var_access(v)
        t = v.type
        flat = None     # pending flattened index into a C array
        bit = None
        for kind, val, _pos in r.accessors:
            if kind == "index":
                offset = flat
                for idx_expr, (lo, hi) in zip(val, t.dims):
                    idx = self.index(f, idx_expr, lo, hi)
                    stride = hi - lo + 1
                    offset = idx if offset is None else f"({offset}) * {stride} + {idx}"
                t = t.elem
                if isinstance(t, ArrayT):
                    flat = offset
                    continue
                code = f"{code}[{offset}]"
                flat = None
            elif kind == "member":
                if isinstance(t, FBType):
                    code = f"{code}.{N.member(t.pou, val)}"
                    t = t.pou.var(val).type
                else:
                    code = f"{code}.{N.var(val)}"
                    t = t.fields[val.upper()][1]
            else:
                bit = val
                t = BOOL
        return code, t, bit

    def index(self, f, e, lo, hi):
        v = _const_int(e)
        if v is not None and lo <= v <= hi:
            return str(v - lo)
        r = self.value_range(e)
        if r is not None and lo <= r[0] and r[1] <= hi:
            # provably inside the bounds (a FOR variable, maybe +- a constant)
            return f"((iec_lint){self.emit(f, e, ELEMENTARY['LINT'])} - {lo}LL)"
        f.may_fault = True
        code = self.emit(f, e, ELEMENTARY["LINT"])
        return f"iec_index(ctx, {code}, {lo}LL, {hi}LL)"

    def value_range(self, e):
        """(lo, hi) the value of an integer expression is known to lie in
        (constants, FOR control variables with constant bounds, sums and
        differences of them that do not leave their type), or None."""
        v = _const_int(e)
        if v is not None:
            return (v, v)
        if isinstance(e, ast.Ref) and not e.accessors and id(e.symbol) in self.body.ranges:
            return self.body.ranges[id(e.symbol)]
        if isinstance(e, ast.BinOp) and e.op in ("+", "-"):
            a, b = self.value_range(e.left), self.value_range(e.right)
            t = concrete(e.type)
            if a is None or b is None or not isinstance(t, Elementary) or t.range is None:
                return None
            r = (a[0] + b[0], a[1] + b[1]) if e.op == "+" else (a[0] - b[1], a[1] - b[0])
            return r if t.range[0] <= r[0] and r[1] <= t.range[1] else None
        return None

    # -------------------------------------------------------- operators
    def binop(self, f, e, t):
        op = e.op
        if op in ("=", "<>", "<", ">", "<=", ">="):
            c = e.sig[1][0]
            if isinstance(c, StringT):
                a, b = self.strv(f, e.left), self.strv(f, e.right)
                if not c.wide and op in ("=", "<>"):
                    return f"((iec_bool){'!' if op == '<>' else ''}iec_str_eq({a}, {b}))"
                fn = "iec_cmp_wstring" if c.wide else "iec_cmp_string"
                return f"((iec_bool)({fn}({a}, {b}) {_cop(op)} 0))"
            a, b = self.seq(f, [(e.left, c), (e.right, c)])
            return compare(a, _cop(op), b, c)
        if op in ("AND", "OR", "XOR"):
            rtype = concrete(t)
            info = []
            a, b = self.seq(f, [(e.left, rtype), (e.right, rtype)], info)
            if rtype is BOOL and op != "XOR" and info[1] == (False, False):
                # the right operand cannot fault and has no side effect: the
                # compiler may skip it (C's && and ||), the value is the same
                return f"((iec_bool)({a} {'&&' if op == 'AND' else '||'} {b}))"
            if rtype is BOOL:
                return f"((iec_bool)({a} {'&' if op == 'AND' else '|' if op == 'OR' else '^'} {b}))"
            return f"iec_{op.lower()}_{N.type_tag(rtype)}({a}, {b})"
        if e.fn is None:
            # a declaration's constant expression (an initial value, an
            # input's default: 2 + 3): the body checker never types one, so
            # it has no sig; its value is the checker's fold (checks/fold.py)
            # in type t, as the interpreter's initial values (interp/model.py)
            if e.const is None:
                raise CodegenError(f"constant expression {e!r} has no folded value")
            v = e.const
            lit = ast.Lit(e.pos, repr(e), "bool" if isinstance(v, bool) else
                          "int" if isinstance(v, int) else "real", v)
            return self.literal(f, lit, t)
        return self.std_result(self.std_apply(f, e.fn, [e.left, e.right], e.sig), e.sig, t)

    def std_result(self, code, sig, t):
        """The C of a standard call computed in its sig, as the type t it is
        used in: a call the checker computes without the context's type
        (exactly on untyped literals: 1 + 2 into a BYTE, stdlib.call_types)
        is converted to it as a literal would be."""
        if isinstance(sig[0], LiteralT) and t is not None and not isinstance(t, LiteralT):
            return self.convert(code, concrete(sig[0]), t)
        return code

    def unop(self, f, e, t):
        rtype = concrete(t)
        if e.op == "-" and scalar_kind(rtype) in ("sint", "uint", "time"):
            v = _const_int(e)
            if v is not None:
                return c_int(v, rtype)      # -128, -9223372036854775808: one constant
        if e.op == "-" and scalar_kind(rtype) in ("bit", "bool") and e.const is not None:
            # an untyped -(-3) stored into a bit string: its folded value, as
            # a literal (a bit string has no negation; the checker refuses a
            # value the type cannot hold)
            return c_int(int(e.const), rtype)
        a = self.emit(f, e.operand, rtype)
        if e.op == "+":
            return a
        if e.op == "NOT":
            if rtype is BOOL:
                return f"((iec_bool)!{a})"
            return f"iec_not_{N.type_tag(rtype)}({a})"
        k = scalar_kind(rtype)
        if k == "real":
            return f"(-{a})"
        if k == "time":
            return f"(({N.ctype(rtype)})iec_neg_lint({a}))"
        return f"iec_neg_{N.type_tag(rtype)}({a})"

    # ------------------------------------------------------------ calls
    def call(self, f, c: ast.Call, t):
        en = next((a for a in c.args if a.kind == "in" and a.name and
                   a.name.upper() == "EN" and a.value is not None), None)
        eno = next((a for a in c.args if a.kind == "out" and a.name and
                    a.name.upper() == "ENO" and a.value is not None), None)
        if en is None and eno is None:
            return self.plain_call(f, c, t)
        return self.guarded_call(f, c, t, en, eno)

    def guarded_call(self, f, c: ast.Call, t, en, eno):
        """A function call with EN/ENO (IEC 61131-3 ed.3 6.6.1.5): with EN =
        FALSE the function does not run (its arguments are not evaluated),
        ENO is FALSE and the call's value is its type's default; otherwise
        ENO is TRUE after the call."""
        if isinstance(c.target, stdlib.StdFunc):
            rt = c.sig[0]
        else:
            rt = c.target.vars[c.target.key].type
        rt = concrete(rt)
        en_code = self.emit(f, en.value, BOOL) if en is not None else None
        inner = Frame(self.body, f.pos)
        inner.pooled = f.pooled          # one pool of temporaries per statement
        code = self.plain_call(inner, c, rt)
        res = f.temp(rt, "en")
        if N.is_scalar(rt):
            run = inner.pre + [f"{res} = {code};"]
            if isinstance(rt, EnumT):
                first = next(iter(rt.values))
                skip = [f"{res} = {N.enum_const(rt, rt.values[first][0])};"]
            elif isinstance(rt, SubrangeT):
                skip = [f"{res} = {c_int(rt.low, rt.elem)};"]
            else:
                skip = [f"{res} = 0;"]
        else:
            run = inner.pre + self.body.assign_code(inner, res, rt, Raw(code, rt))
            addr = res if isinstance(rt, ArrayT) else f"&{res}"
            skip = [f"iec_memset({addr}, 0, sizeof({res}));"]
        if eno is not None:
            if (c.bound or {}).get("ENO") is not eno:
                # a function that declares no ENO: TRUE when it ran (one that
                # does hands its own ENO on, as an output of the call)
                run += self.body.assign_ref(inner, eno.value, Raw("1", BOOL))
            skip += self.body.assign_ref(inner, eno.value, Raw("0", BOOL))
        f.decls += inner.decls
        f.may_fault = f.may_fault or inner.may_fault
        f.calls += inner.calls
        if en_code is None:
            f.pre += run
        else:
            f.pre += [f"if ({en_code}) {{"] + ["\t" + ln for ln in run] + ["} else {"] + \
                ["\t" + ln for ln in skip] + ["}"]
        return res

    def plain_call(self, f, c: ast.Call, t):
        target = c.target
        if isinstance(target, stdlib.StdFunc):
            args = [a.value for a in c.args if a.kind == "pos" or a.name.upper() not in
                    ("EN", "ENO")]
            return self.std_result(self.std_apply(f, target, args, c.sig), c.sig, t)
        return self.body.user_function_call(f, c)

    def std_apply(self, f, fres: stdlib.StdFunc, args, sig):
        """C code of standard function ``fres`` on argument expressions, in
        the types ``sig`` (the call's, checks/settle.py); a computation on
        untyped literals is done in C in the literal's own type."""
        fam = fres.family
        pts = fres.param_types
        res = concrete(sig[0])
        tag = lambda ty: N.type_tag(ty)
        if fam in stdlib.ARITH_FAMILIES:
            vs = self.seq(f, [(a, res) for a in args])
            if scalar_kind(res) == "real":
                if fam == "MOD":
                    raise CodegenError("MOD on REAL")
                if fam == "DIV":        # never a bare '/': see iec_real.h
                    return f"iec_div_{tag(res)}({vs[0]}, {vs[1]})"
                sym = {"ADD": "+", "SUB": "-", "MUL": "*"}[fam]
                return "(" + f" {sym} ".join(vs) + ")"
            fn = f"iec_{fam.lower()}_{tag(res)}"
            if fam in ("DIV", "MOD"):
                if not _const_int(args[1]):
                    f.may_fault = True      # a divisor that is not a non-zero constant
                return f"{fn}(ctx, {vs[0]}, {vs[1]})"
            acc = vs[0]
            for v in vs[1:]:
                acc = f"{fn}({acc}, {v})"
            return acc
        if fam in ("ADD_TIME", "SUB_TIME"):
            a, b = self.seq(f, [(x, res) for x in args])
            return f"iec_{fam.lower().replace('_time', '')}_{tag(res)}({a}, {b})"
        if fam in stdlib.DATE_TIME_FAMILIES:
            a, b = self.seq(f, [(args[0], pts[0]), (args[1], pts[1])])
            return f"iec_{fam.lower()}({a}, {b})"
        if fam in ("MUL_TIME", "DIV_TIME"):
            tt = concrete(pts[0])
            a = self.emit(f, args[0], tt)
            nt = concrete(args[1].type)
            if scalar_kind(nt) == "real":
                b = self.emit(f, args[1], ELEMENTARY["LREAL"])
                return (f"iec_{fam.lower().replace('_time', '')}_{tag(tt)}_lreal("
                        f"{'ctx, ' if fam == 'DIV_TIME' else ''}{a}, {b})")
            b = self.emit(f, args[1], ELEMENTARY["LINT"])
            if fam == "DIV_TIME":
                f.may_fault = True
                return f"iec_div_{tag(tt)}(ctx, {a}, {b})"
            return f"iec_mul_{tag(tt)}({a}, {b})"
        if fam == "EXPT":
            a = self.emit(f, args[0], pts[0])
            b = self.emit(f, args[1], pts[0] if scalar_kind(pts[1]) == "real" else pts[1])
            if scalar_kind(pts[1]) == "real":
                return f"iec_expt_{tag(pts[0])}({a}, {b})"
            return f"iec_expt_{tag(pts[0])}_lint({a}, {self.convert(b, pts[1], ELEMENTARY['LINT'])})"
        if fam == "MOVE":
            return self.emit(f, args[0], res)
        if fam == "ABS":
            a = self.emit(f, args[0], res)
            return f"iec_abs_{tag(res)}({a})"
        if fam in ("SQRT", "LN", "LOG", "EXP", "SIN", "COS", "TAN", "ASIN", "ACOS", "ATAN",
                   "ATAN2"):
            vs = self.seq(f, [(a, res) for a in args])
            return f"iec_{fam.lower()}_{tag(res)}({', '.join(vs)})"
        if fam in ("SHL", "SHR", "ROL", "ROR"):
            a, n = self.seq(f, [(args[0], res), (args[1], ELEMENTARY["LINT"])])
            return f"iec_{fam.lower()}_{tag(res)}({a}, {n})"
        if fam in ("AND", "OR", "XOR"):
            vs = self.seq(f, [(a, res) for a in args])
            if res is BOOL:
                sym = {"AND": "&", "OR": "|", "XOR": "^"}[fam]
                return "((iec_bool)(" + f" {sym} ".join(vs) + "))"
            acc = vs[0]
            for v in vs[1:]:
                acc = f"iec_{fam.lower()}_{tag(res)}({acc}, {v})"
            return acc
        if fam == "NOT":
            a = self.emit(f, args[0], res)
            return f"((iec_bool)!{a})" if res is BOOL else f"iec_not_{tag(res)}({a})"
        if fam in ("SEL", "MUX", "MAX", "MIN", "LIMIT") and isinstance(res, StringT):
            return self.string_select(f, fam, args, res)
        if fam == "SEL":
            g = self.eager(f, args[0], BOOL)
            a, b = self.eager(f, args[1], res), self.eager(f, args[2], res)
            return f"({g} ? {b} : {a})"
        if fam in ("MAX", "MIN"):
            vs = self.seq(f, [(a, res) for a in args])
            acc = vs[0]
            for v in vs[1:]:
                acc = f"iec_{fam.lower()}_{tag(res)}({acc}, {v})"
            return acc
        if fam == "LIMIT":
            vs = self.seq(f, [(a, res) for a in args])
            return f"iec_limit_{tag(res)}({', '.join(vs)})"
        if fam == "MUX":
            # a function's inputs are all evaluated before it runs (a fault
            # in one that is not selected is a fault), then K is checked
            k = self.eager(f, args[0], ELEMENTARY["LINT"])
            vs = [self.eager(f, a, res) for a in args[1:]]
            n = len(args) - 1
            sel = f.temp(ELEMENTARY["UDINT"], "mux")
            f.pre.append(f"{sel} = iec_mux_index(ctx, {k}, {n});")
            f.may_fault = True
            out = vs[-1]
            for i in range(n - 2, -1, -1):
                out = f"({sel} == {i} ? {vs[i]} : {out})"
            return out
        if fam in stdlib.COMPARE_FAMILIES:
            c = concrete(sig[1][0])     # the checker's (two literals: a type holding both)
            sym = {"GT": ">", "GE": ">=", "EQ": "==", "LE": "<=", "LT": "<", "NE": "!="}[fam]
            if isinstance(c, StringT):
                vs = [self.strv(f, a) for a in args]
                cmp = "iec_cmp_wstring" if c.wide else "iec_cmp_string"
                parts = [f"({cmp}({vs[i]}, {vs[i + 1]}) {sym} 0)" for i in range(len(vs) - 1)]
            else:
                vs = self.seq(f, [(a, c) for a in args])
                parts = [compare(vs[i], sym, vs[i + 1], c) for i in range(len(vs) - 1)]
            return "((iec_bool)(" + " && ".join(parts) + "))"
        if fam == "LEN":
            s = self.strv(f, args[0])
            return f"((iec_int)iec_len_{tag(args[0].type)}({s}))"
        if fam == "FIND":
            a, b = self.strv(f, args[0]), self.strv(f, args[1])
            return f"((iec_int)iec_find_{tag(args[0].type)}({a}, {b}))"
        if fam in ("LEFT", "RIGHT", "MID", "CONCAT", "INSERT", "DELETE", "REPLACE"):
            return self.string_function(f, fam, args, pts, res)
        if fam == "CONVERT":
            return self.conversion(f, fres, args[0])
        if fam == "TRUNC":
            # TRUNC (LREAL -> DINT) and the typed REAL_TRUNC_INT ... forms
            src = concrete(pts[0])
            a = self.emit(f, args[0], src)
            return f"iec_{tag(src)}_trunc_{tag(res)}({a})"
        if fam in ("BCD_TO", "TO_BCD"):
            src, dst = concrete(pts[0]), res
            a = self.emit(f, args[0], src)
            if fres.name == "BCD_TO_INT":
                return f"((iec_int)iec_word_bcd_to_uint({a}))"
            if fres.name.endswith("_TO_BCD"):
                # the overloaded X_TO_BCD, typed by its context: a negative
                # value or one with more digits than fit gives 0
                enc = "iec__bcd_encode_s" if src.cat == "sint" else "iec__bcd_encode"
                cast = "iec_s64" if src.cat == "sint" else "iec_u64"
                return f"(({dst.c_type}){enc}(({cast}){a}, {dst.bits // 4}))"
            if fam == "BCD_TO":
                return f"iec_{tag(src)}_bcd_to_{tag(dst)}({a})"
            return f"iec_{tag(src)}_to_bcd_{tag(dst)}({a})"
        raise CodegenError(f"standard function family {fam} not lowered")

    def conversion(self, f, fres, arg):
        src, dst = concrete(fres.param_types[0]), concrete(fres.result)
        if fres.name.upper().split("_TO_")[0] in ("TIME_OF_DAY", "DATE_AND_TIME") or \
                "_TRUNC_" in fres.name.upper():
            pass
        if "_TRUNC_" in fres.name.upper():
            a = self.emit(f, arg, src)
            return f"iec_{tag_of(src)}_trunc_{tag_of(dst)}({a})"
        if isinstance(dst, StringT):
            out = f.temp(dst)
            if isinstance(src, StringT):
                f.pre.append(f"iec_{tag_of(src)}_to_{tag_of(dst)}({self.strbuf(out, dst)}, "
                             f"{self.strv(f, arg)});")
            else:
                a = self.emit(f, arg, src)
                f.pre.append(f"iec_{tag_of(src)}_to_{tag_of(dst)}({self.strbuf(out, dst)}, {a});")
            return out
        if isinstance(src, StringT):
            return f"iec_{tag_of(src)}_to_{tag_of(dst)}({self.strv(f, arg)})"
        a = self.emit(f, arg, src)
        st, dt = tag_of(src), tag_of(dst)
        if st in _TIMEISH and dt in _TIMEISH and (st, dt) not in _TIME_CONV:
            # not a standard conversion (DATE_TO_DT, TOD_TO_TIME ...), but
            # accepted: every time type counts nanoseconds, so the value is
            # kept, then made a valid DATE (whole days) or TOD (< 24 h)
            if dt == "date":
                return f"iec_dt_to_date({a})"
            if dt == "tod":
                return f"iec_dt_to_tod({a})"
            return f"(({N.ctype(dst)}){a})"
        if st == "bool" and dt in _TIMEISH:
            # BOOL_TO_TIME: 0 or 1 of the integer unit of the time type
            return f"iec_lint_to_{dt}((iec_lint){a})"
        return f"iec_{st}_to_{dt}({a})"

    # ---------------------------------------------------------- strings
    def strv(self, f, e) -> str:
        """A read-only view (iec_strv / iec_wstrv) of a string expression."""
        if isinstance(e, ast.Lit) and e.kind in ("string", "wstring"):
            return self.string_literal(f, e)
        t = concrete(e.type)
        fres = std_target(e)
        if fres is not None and fres.family in ("LEFT", "RIGHT", "MID") and not t.wide:
            # a substring is a view into its input: no copy
            args = std_args(e)
            src = self.strv(f, args[0])
            rest = [self.emit(f, a, ELEMENTARY["LINT"]) for a in args[1:]]
            return f"iec_strv_{fres.family.lower()}({', '.join([src] + rest)})"
        code = self.emit(f, e)
        return f"IEC_{'W' if t.wide else ''}STRV({code})"

    def concat_parts(self, f, args):
        """The pieces of a narrow CONCAT: (helper, C argument) to append."""
        parts = []
        for a in args:
            fres = std_target(a)
            src = concrete(fres.param_types[0]) if fres is not None and \
                fres.family == "CONVERT" else None
            if src is not None and isinstance(concrete(fres.result), StringT) and \
                    not concrete(fres.result).wide and scalar_kind(src) in ("sint", "uint", "bit"):
                # INT_TO_STRING(x) appended as digits, without a temporary
                arg = std_args(a)[0]
                if src.bits <= 32 and (scalar_kind(src) == "sint" or src.bits < 32):
                    parts.append(("iec_str_append_s32", f"(iec_s32){self.emit(f, arg, src)}"))
                elif scalar_kind(src) == "sint":
                    parts.append(("iec_str_append_s64", self.emit(f, arg, src)))
                else:
                    parts.append(("iec_str_append_u64", f"(iec_u64){self.emit(f, arg, src)}"))
            else:
                parts.append(("iec_str_append", self.strv(f, a)))
        return parts

    @staticmethod
    def concat_lines(buf, parts):
        """Set the first piece, append the others (each truncates)."""
        out = []
        for k, (fn, arg) in enumerate(parts):
            if k == 0 and fn == "iec_str_append":
                out.append(f"iec_str_set({buf}, {arg});")
                continue
            if k == 0:
                out.append(f"iec_str_set({buf}, iec_strv_make(\"\", 0, 0));")
            out.append(f"{fn}({buf}, {arg});")
        return out

    @staticmethod
    def strbuf(code, t) -> str:
        return f"IEC_{'W' if t.wide else ''}STRBUF({code})"

    def string_function(self, f, fam, args, pts, res):
        out = f.temp(res)
        w = "wstring" if res.wide else "string"
        buf = self.strbuf(out, res)
        if fam == "CONCAT" and not res.wide:
            # set, then append piece after piece, into one temporary
            f.pre += self.concat_lines(buf, self.concat_parts(f, args))
            return out
        if fam == "CONCAT":
            # CONCAT(a, b, c) = CONCAT(CONCAT(a, b), c), accumulated in out
            first = self.strv(f, args[0])
            second = self.strv(f, args[1])
            f.pre.append(f"iec_concat_{w}({buf}, {first}, {second});")
            for a in args[2:]:
                nxt = f.temp(res)
                f.pre.append(f"iec_concat_{w}({self.strbuf(nxt, res)}, IEC_{'W' if res.wide else ''}"
                             f"STRV({out}), {self.strv(f, a)});")
                out = nxt
            return out
        vals = []
        for a, pt in zip(args, pts):
            if isinstance(concrete(pt), StringT):
                vals.append(self.strv(f, a))
            else:
                vals.append(self.emit(f, a, ELEMENTARY["LINT"]))
        f.pre.append(f"iec_{fam.lower()}_{w}({buf}, {', '.join(vals)});")
        return out

    def eager(self, f, e, t):
        """A scalar input of SEL/MUX: when it can fault it is computed into a
        temporary before the selection, so that its fault is raised whether
        or not it is selected (C's ?: would skip it)."""
        before, f.may_fault = f.may_fault, False
        code = self.emit(f, e, t)
        if f.may_fault:
            tmp = f.temp(t, "in")
            f.pre.append(f"{tmp} = {code};")
            code = tmp
        f.may_fault = f.may_fault or before
        return code

    def string_select(self, f, fam, args, res):
        # the result holds any of the inputs: as long as the longest one
        lens = [concrete(a.type).length for a in args[1 if fam in ("SEL", "MUX") else 0:]
                if isinstance(concrete(a.type), StringT)]
        if lens and max(lens) > res.length:
            res = StringT(max(lens), res.wide)
        out = f.temp(res)
        w = "wstring" if res.wide else "string"
        buf = self.strbuf(out, res)
        if fam == "SEL":
            g = self.emit(f, args[0], BOOL)
            a, b = self.strv(f, args[1]), self.strv(f, args[2])
            f.pre.append(f"iec_assign_{w}({buf}, {g} ? {b} : {a});")
            return out
        if fam == "MUX":
            k = self.emit(f, args[0], ELEMENTARY["LINT"])
            sel = f.temp(ELEMENTARY["UDINT"], "mux")
            f.pre.append(f"{sel} = iec_mux_index(ctx, {k}, {len(args) - 1});")
            f.may_fault = True
            vs = [self.strv(f, a) for a in args[1:]]
            pick = vs[-1]
            for i in range(len(vs) - 2, -1, -1):
                pick = f"({sel} == {i} ? {vs[i]} : {pick})"
            f.pre.append(f"iec_assign_{w}({buf}, {pick});")
            return out
        vs = [self.strv(f, a) for a in args]
        cmp = f"iec_cmp_{w}"
        if fam in ("MAX", "MIN"):
            best = vs[0]
            sym = ">" if fam == "MAX" else "<"
            for v in vs[1:]:
                best = f"({cmp}({v}, {best}) {sym} 0 ? {v} : {best})"
            f.pre.append(f"iec_assign_{w}({buf}, {best});")
            return out
        mn, x, mx = vs
        f.pre.append(f"iec_assign_{w}({buf}, {cmp}({x}, {mn}) < 0 ? {mn} : "
                     f"({cmp}({x}, {mx}) > 0 ? {mx} : {x}));")
        return out


_TIMEISH = {"time", "ltime", "date", "tod", "dt"}
# time-to-time conversions of the standard (the runtime's iec_<a>_to_<b>)
_TIME_CONV = {("time", "ltime"), ("ltime", "time"), ("dt", "date"), ("dt", "tod")}


def std_target(e):
    """The resolved standard function of a call expression, or None; None
    too for a call with EN/ENO, which only ExprEmitter.call emits (no fast
    path may skip its EN test)."""
    if isinstance(e, ast.Call) and isinstance(getattr(e, "target", None), stdlib.StdFunc) \
            and not any(a.kind != "pos" and a.name and a.name.upper() in ("EN", "ENO")
                        for a in e.args):
        return e.target
    return None


def std_args(e):
    """Argument expressions of a standard function call, in parameter order."""
    return [a.value for a in e.args if a.kind == "pos" or a.name.upper() not in ("EN", "ENO")]


def tag_of(t):
    return N.type_tag(t)


_CMP_NAME = {"==": "eq", "!=": "ne", "<": "lt", "<=": "le", ">": "gt", ">=": "ge"}


def compare(a, sym, b, t):
    """C for ``a sym b`` on operands of IEC type t.  Integers (and BOOL,
    enumerations, times) go through the runtime's typed inline comparisons
    (iec_int.h), so that a comparison the user may write but C finds
    always true or false (u <= 255 on a USINT, w >= 0 on a UINT, x = x)
    is not a -Wtype-limits/-Wtautological-compare error in the generated C;
    reals keep C's operators (a NaN is not equal to itself)."""
    if scalar_kind(t) == "real":
        return f"((iec_bool)({a} {sym} {b}))"
    t = concrete(t)
    if isinstance(t, SubrangeT):
        t = t.elem
    unsigned = isinstance(t, Elementary) and t.cat in ("uint", "bit", "bool")
    return f"iec_{_CMP_NAME[sym]}_{'u64' if unsigned else 's64'}({a}, {b})"


def _cop(op):
    return {"=": "==", "<>": "!="}.get(op, op)


def _const_int(e):
    """The value of an integer literal or a negated one (the checker's
    Expr.const), else None: the C emitter treats only these as constants (an
    index without a run-time check, a FOR loop's trip count, a divisor that
    cannot be zero); a wider rule would change the generated C."""
    if isinstance(e, ast.Lit) and e.kind == "int" or (
            isinstance(e, ast.UnOp) and e.op == "-" and _const_int(e.operand) is not None):
        return e.const
    return None
