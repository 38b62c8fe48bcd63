"""POU bodies to C: ST statements and IL instructions.

Fault protocol (kmod_templates/runtime/iec_fault.h): a statement that can
fault (division, MOD, index, subrange, MUX, a call of a POU) is followed by
IEC_FAULT_CHECK, which records the POU and source line and returns; every
loop iteration ticks the cycle's loop budget."""

from __future__ import annotations

import re

from .. import ast
from ..checks.il import IL_ARITH, IL_COMPARE, IL_LOGIC
from ..checks.symbols import Var
from ..execmodel import LOOP_BUDGET
from ..checks.types import (BOOL, ArrayT, EnumT, ErrorT, FBType,
                            LiteralT, StringT, StructT, SubrangeT, concrete, identical)
from . import analysis
from . import cnames as N
from .expr import (BindingError, CodegenError, CRNode, ExprEmitter, Frame, Raw, _const_int,
                   c_int, scalar_kind)

# the pointer to a body's frame (its strings, arrays, structures and FB
# instances that are not state: temporaries, VAR_TEMP, a function's VAR)
FRAME = "frm"

UNSIGNED = {8: "iec_u8", 16: "iec_u16", 32: "iec_u32", 64: "iec_u64", 1: "iec_u8"}


class BodyEmitter:
    def __init__(self, pou, ind="\t"):
        self.pooling = False            # set for real POU bodies (pou_body): they have a frame
        self.pool: dict[str, str] = {}  # pooled temporary name -> declaration
        self._pool_names: dict = {}
        self.pou = pou
        self.src = pou.src
        self.is_function = pou.kind == "FUNCTION"
        self.expr = ExprEmitter(self)
        self._temp = 0
        self._label = 0
        self.exit_labels: list[str] = []
        self.continue_labels: list[str] = []
        self.cr_vars: dict[str, str] = {}   # C name -> C type (scalars, on the stack)
        self.frame_vars: dict[str, str] = {}   # frame member -> declaration (string CRs)
        self.ind = ind
        self.uses_ret_label = False
        self.used_labels: set[str] = set()
        self.cr_depth = 0
        self.ranges: dict[int, tuple] = {}   # id(Var) -> (lo, hi) inside a FOR body
        self.return_label = None        # inside an SFC action: where RETURN goes
        self.return_label_used = False
        self.il_label_prefix = ""       # IL labels of an SFC action: their own names
        self.sel = None                 # SelectivePlan (selective.py) or None: plain

    # ---------------------------------------------------------- helpers
    def pool_name(self, decl_key, i):
        """The i-th pooled temporary of a C type (see Frame.temp): a member
        of the body's frame (iec_fault.h, iec_frame_push), not of the
        stack."""
        key = (decl_key, i)
        if key not in self._pool_names:
            name = f"pool{len(self._pool_names) + 1}"
            self._pool_names[key] = name
            self.pool[name] = decl_key.replace("@", name) + ";"
        return f"{FRAME}->{self._pool_names[key]}"

    def pool_snapshot(self):
        return dict(self.pool), dict(self._pool_names)

    def pool_restore(self, snap):
        self.pool, self._pool_names = dict(snap[0]), dict(snap[1])

    def pool_decls(self):
        return list(self.pool.values())

    def next_temp(self):
        self._temp += 1
        return self._temp

    def new_label(self, what):
        self._label += 1
        return f"{what}_{self._label}"

    def line(self, pos):
        return self.src.linecol(pos)[0] if pos is not None else 0

    def fault_check(self, pos):
        name = N.c_string(self.pou.name.encode())
        if self.is_function and self.ret_value():
            return f"IEC_FAULT_CHECK_RET(ctx, {name}, {self.line(pos)}, {self.ret_value()});"
        return f"IEC_FAULT_CHECK(ctx, {name}, {self.line(pos)});"

    def loop_tick(self, pos):
        name = N.c_string(self.pou.name.encode())
        if self.is_function and self.ret_value():
            return f"IEC_LOOP_TICK_RET(ctx, {name}, {self.line(pos)}, {self.ret_value()});"
        return f"IEC_LOOP_TICK(ctx, {name}, {self.line(pos)});"

    def ret_value(self):
        result = self.pou.vars[self.pou.key]
        if N.is_scalar(result.type):
            return N.var(self.pou.name)
        return ""

    def var_access(self, v: Var) -> str:
        """C lvalue of a variable of this POU."""
        name = N.var(v.name)
        if self.in_frame(v):
            return f"{FRAME}->{name}"
        if self.is_function:
            if v.section == "VAR_INPUT":
                if isinstance(v.type, ArrayT) or N.is_scalar(v.type):
                    return name
                return f"(*{name})"
            if v.section in ("VAR_OUTPUT", "VAR_IN_OUT"):
                return name if isinstance(v.type, ArrayT) else f"(*{name})"
            if v.section == "RESULT" and not N.is_scalar(v.type):
                return "ret" if isinstance(v.type, ArrayT) else "(*ret)"
            return name
        if v.section == "VAR_TEMP":
            return name
        if v.section == "VAR_INPUT" and v.edge:
            # inside the block an R_EDGE/F_EDGE input reads as its edge
            return f"self->h_{v.name.lower()}"
        if v.section in ("VAR_EXTERNAL", "VAR_IN_OUT"):
            # arrays are passed as a pointer to their first element
            return f"self->{name}" if isinstance(v.type, ArrayT) else f"(*self->{name})"
        return f"self->{name}"

    def in_frame(self, v: Var) -> bool:
        """Does a variable of this POU live in its frame?  Those that are
        no state and no parameter, and are not scalars."""
        if not self.pooling or N.is_scalar(v.type):
            return False
        if self.is_function:
            # a written aggregate input: the copy the body works on
            return v.section in ("VAR", "VAR_TEMP") or (v.section == "VAR_INPUT" and v.copied)
        return v.section == "VAR_TEMP"

    def cr_var(self, t, depth=0):
        t = concrete(t)
        if isinstance(t, StringT):
            # a string current result has the length of its type
            name = f"cr{depth}_{'w' if t.wide else ''}s{t.length}"
            if not self.pooling:
                self.cr_vars[name] = N.string_struct(t)
                return name
            self.frame_vars[name] = f"{N.string_struct(t)} {name};"
            return f"{FRAME}->{name}"
        if isinstance(t, (ArrayT, StructT, FBType, ErrorT)) or t is None:
            raise CodegenError(f"IL current result of type {getattr(t, 'name', t)}")
        name = f"cr{depth}_{N.type_tag(t)}"
        self.cr_vars[name] = N.ctype(t)
        return name

    def cr_set(self, f, t, depth, value) -> list[str]:
        """Current result := value (C code of IEC type t, or an expression)."""
        cr = self.cr_var(t, depth)
        if isinstance(concrete(t), StringT):
            return self.assign_code(f, cr, t, Raw(value, t) if isinstance(value, str) else value)
        code = value if isinstance(value, str) else self.expr.emit(f, value, concrete(t))
        return [f"{cr} = {code};"]

    # ------------------------------------------------------------- body
    def body(self, stmts) -> list[str]:
        if self.pou.node.language == "SFC":
            from .sfc import SFCEmitter
            return SFCEmitter(self).lines()
        if self.pou.node.language == "IL":
            return self.il_body(stmts)
        out = []
        for s in stmts:
            out += self.stmt(s)
        return out

    def wrap(self, f: Frame, lines, pos, check=True) -> list[str]:
        """Statement lines with their temporaries and a fault check."""
        body = f.pre + lines
        if check and f.may_fault:
            body.append(self.fault_check(pos))
        if f.decls:
            return ["{"] + [self.ind + d for d in f.decls] + [self.ind + b for b in body] + ["}"]
        return body

    def indent(self, lines):
        return [self.ind + ln for ln in lines]

    # ------------------------------------------------------- statements
    def stmt(self, s) -> list[str]:
        if isinstance(s, ast.Assign):
            f = Frame(self, s.pos)
            snap = self.pool_snapshot()
            lines = self.assign_ref(f, s.target, s.value)
            if f.may_fault:
                # emitted again: the pooled temporaries of this try are not
                # declared (an unused one is a warning)
                self.pool_restore(snap)
            if f.may_fault and N.is_scalar(concrete(s.target.type)):
                return self.guarded_assign(s.target, s.value, s.pos)
            if f.may_fault:
                return self.guarded_store(s.target, s.value, s.pos)
            return self.wrap(f, lines, s.pos)
        if isinstance(s, ast.CallStmt):
            return self.call_stmt(s.call, s.pos)
        if isinstance(s, ast.If):
            return self.if_(s.branches, s.else_)
        if isinstance(s, ast.Case):
            return self.case(s)
        if isinstance(s, ast.For):
            return self.for_(s)
        if isinstance(s, ast.While):
            return self.while_(s)
        if isinstance(s, ast.Repeat):
            return self.repeat(s)
        if isinstance(s, ast.Exit):
            label, on_exit = self.exit_labels[-1]
            self.used_labels.add(label)
            return list(on_exit) + [f"goto {label};"]
        if isinstance(s, ast.Continue):
            label = self.continue_labels[-1]
            self.used_labels.add(label)
            return [f"goto {label};"]
        if isinstance(s, ast.Return):
            return [self.return_stmt()]
        if isinstance(s, ast.Empty):
            return []
        raise CodegenError(f"statement {s!r}")

    def return_stmt(self):
        if self.return_label is not None:
            self.return_label_used = True
            return f"goto {self.return_label};"
        if self.is_function:
            rv = self.ret_value()
            return f"return {rv};" if rv else "return;"
        self.uses_ret_label = True
        return "goto out;"

    def block(self, stmts):
        out = []
        for s in stmts:
            out += self.stmt(s)
        return self.indent(out)

    def cond(self, f, e):
        return self.expr.emit(f, e, BOOL)

    def checked_value(self, f, code, ctype, pos):
        """A condition or selector that can fault is computed first, into a
        temporary, and the fault checked before any branch runs."""
        if not f.may_fault:
            return code
        tmp = f"sel{self.next_temp()}"
        f.decls.append(f"{ctype} {tmp};")
        f.pre += [f"{tmp} = {code};", self.fault_check(pos)]
        f.may_fault = False
        return tmp

    def if_(self, branches, else_):
        cond, body = branches[0]
        f = Frame(self, cond.pos)
        c = self.checked_value(f, self.cond(f, cond), "iec_bool", cond.pos)
        lines = [f"if ({c}) {{"] + self.block(body)
        rest = branches[1:]
        if rest or else_:
            inner = self.if_(rest, else_) if rest else None
            if inner is not None:
                lines += ["} else {"] + self.indent(inner) + ["}"]
            else:
                lines += ["} else {"] + self.block(else_) + ["}"]
        else:
            lines.append("}")
        return self.wrap(f, lines, cond.pos, check=False) if f.pre or f.decls else lines

    def case(self, s):
        f = Frame(self, s.pos)
        st = concrete(s.selector.type)
        sel = self.checked_value(f, self.expr.emit(f, s.selector), N.ctype(st), s.pos)
        lines = [f"switch ({sel}) {{"]
        for (labels, body), values in zip(s.elements, s.values):
            for lo, hi in values:
                a, b = c_int(lo, st), c_int(hi, st)
                lines.append(f"case {a}:" if lo == hi else f"case {a} ... {b}:")
            lines += self.block(body) + [self.ind + "break;"]
        lines.append("default:")
        if s.else_:
            lines += self.block(s.else_)
        lines += [self.ind + "break;", "}"]
        return self.wrap(f, lines, s.pos)

    def loop(self, pos, head, body_stmts, tail=(), tick=True, on_exit=()):
        """for (;;) { head; tick; body; tail }: EXIT jumps past it after the
        on_exit statements, CONTINUE to the tail (the FOR step, the REPEAT
        test)."""
        exit_label = self.new_label("exit")
        cont_label = "next" + exit_label[len("exit"):]
        self.exit_labels.append((exit_label, on_exit))
        self.continue_labels.append(cont_label)
        inner = self.block(body_stmts)
        self.exit_labels.pop()
        self.continue_labels.pop()
        lines = ["for (;;) {"] + self.indent(list(head))
        if tick:
            lines.append(self.ind + self.loop_tick(pos))
        lines += inner
        if cont_label in self.used_labels:
            lines.append(f"{cont_label}:;")
        lines += self.indent(list(tail)) + ["}"]
        if exit_label in self.used_labels:
            lines.append(f"{exit_label}:;")
        return lines

    def while_(self, s):
        f = Frame(self, s.cond.pos)
        c = self.checked_value(f, self.cond(f, s.cond), "iec_bool", s.cond.pos)
        head = f.pre + [f"if (!({c}))", self.ind + "break;"]
        lines = self.loop(s.pos, head, s.body)
        return (["{"] + self.indent(f.decls + lines) + ["}"]) if f.decls else lines

    def repeat(self, s):
        f = Frame(self, s.cond.pos)
        c = self.checked_value(f, self.cond(f, s.cond), "iec_bool", s.cond.pos)
        tail = f.pre + [f"if ({c})", self.ind + "break;"]
        lines = self.loop(s.pos, [], s.body, tail)
        return (["{"] + self.indent(f.decls + lines) + ["}"]) if f.decls else lines

    def for_(self, s):
        v = self.pou.var(s.var)
        vt = concrete(v.type)
        ct = N.ctype(vt)
        f = Frame(self, s.pos)
        var = self.var_access(v)
        cstart, cend = _const_int(s.start), _const_int(s.end)
        cstep = 1 if s.step is None else _const_int(s.step)
        start = self.expr.emit(f, s.start, vt)
        end = self.expr.emit(f, s.end, vt)
        n = self.next_temp()
        if not cstep:
            return self.for_generic(s, v, vt, f, var, start, end, n)
        # a constant step: the loop test and the increment are known
        lo_t, hi_t = vt.range
        e_name = f"for_end{n}"
        setup = list(f.pre)
        if f.may_fault:
            # the head faults before the control variable is set
            start = self.for_start(f, setup, start, ct, n)
        if cend is not None:
            e_name = c_int(cend, vt)
        else:
            f.decls.append(f"{ct} {e_name};")
            setup.append(f"{e_name} = {end};")
        if f.may_fault:
            setup.append(self.fault_check(s.pos))
        setup.append(f"{var} = {start};")
        head = [f"if ({var} {'>' if cstep > 0 else '<'} {e_name})", self.ind + "break;"]
        if cend is not None and cend == (hi_t if cstep > 0 else lo_t):
            head = []       # up to the type's limit: the increment ends the loop
        # the control variable cannot change but by the loop itself
        safe = v.section in ("VAR", "VAR_TEMP", "VAR_INPUT", "VAR_OUTPUT", "RESULT") and \
            not analysis.modifies(s.body, v)
        if safe and cend is not None and lo_t <= cend + cstep <= hi_t:
            # var stays within start..end inside the loop: var + step cannot
            # leave the type
            tail = [f"{var} = ({ct})({var} + {c_int(cstep, vt)});"]
        else:
            nx = f"for_next{n}"
            f.decls.append(f"{ct} {nx};")
            tail = [f"if (__builtin_add_overflow({var}, {c_int(cstep, vt)}, &{nx}))",
                    self.ind + "break;", f"{var} = {nx};"]
        # constant bounds: the control variable's range inside the body
        known = safe and cstart is not None and cend is not None
        trips = 0
        if cstart is not None and cend is not None:
            trips = max(0, (cend - cstart) // cstep + 1)
        # an innermost loop of a known number of iterations charges them to
        # the loop budget at once (EXIT gives back the ones not run); one of
        # more trips than the budget faults as it counts them
        charge = safe and 0 < trips <= LOOP_BUDGET and not analysis.has_loop(s.body) and \
            not analysis.has_return(s.body)
        on_exit = ()
        if charge:
            setup.append(self.loop_charge(s.pos, trips))
            left = (f"((iec_lint){c_int(cend, vt)} - (iec_lint){var})" if cstep > 0 else
                    f"((iec_lint){var} - (iec_lint){c_int(cend, vt)})")
            on_exit = [f"IEC_LOOP_REFUND(ctx, {left} / {abs(cstep)});"]
        if known:
            self.ranges[id(v)] = (min(cstart, cend), max(cstart, cend))
        try:
            lines = setup + self.loop(s.pos, head, s.body, tail, tick=not charge,
                                      on_exit=on_exit)
        finally:
            self.ranges.pop(id(v), None)
        return ["{"] + self.indent(f.decls + lines) + ["}"] if f.decls else lines

    def for_generic(self, s, v, vt, f, var, start, end, n):
        ct = N.ctype(vt)
        step = self.expr.emit(f, s.step, vt) if s.step is not None else c_int(1, vt)
        e_name, s_name, nx = f"for_end{n}", f"for_step{n}", f"for_next{n}"
        f.decls += [f"{ct} {e_name};", f"{ct} {s_name};", f"{ct} {nx};"]
        setup = list(f.pre)
        if f.may_fault:
            # start, end, step, in this order, and the fault checked before
            # the control variable is set
            start = self.for_start(f, setup, start, ct, n)
        setup += [f"{e_name} = {end};", f"{s_name} = {step};"]
        if f.may_fault:
            setup.append(self.fault_check(s.pos))
        setup.append(f"{var} = {start};")
        signed = scalar_kind(vt) == "sint"
        neg = f"{s_name} < 0 ? {var} < {e_name} : " if signed else ""
        head = [f"if ({neg}{var} > {e_name})", self.ind + "break;"]
        tail = [f"if (__builtin_add_overflow({var}, {s_name}, &{nx}))", self.ind + "break;",
                f"{var} = {nx};"]
        lines = setup + self.loop(s.pos, head, s.body, tail)
        return ["{"] + self.indent(f.decls + lines) + ["}"]

    @staticmethod
    def for_start(f, setup, start, ct, n):
        """The FOR start value into a temporary of its own (computed first)."""
        name = f"for_start{n}"
        f.decls.append(f"{ct} {name};")
        setup.append(f"{name} = {start};")
        return name

    def loop_charge(self, pos, n):
        name = N.c_string(self.pou.name.encode())
        if self.is_function and self.ret_value():
            return f"IEC_LOOP_CHARGE_RET(ctx, {name}, {self.line(pos)}, {n}U, {self.ret_value()});"
        return f"IEC_LOOP_CHARGE(ctx, {name}, {self.line(pos)}, {n}U);"

    # ------------------------------------------------------- assignment
    def assign_ref(self, f, target: ast.Ref, value) -> list[str]:
        code, t, bit = self.expr.lvalue(f, target)
        if bit is not None:
            return [self.set_bit(f, code, target, bit, self.expr.emit(f, value, BOOL))]
        return self.assign_code(f, code, t, value)

    def guarded_assign(self, target, value, pos) -> list[str]:
        """A scalar assignment that can fault stores nothing when it faults:
        the value, then the place (its indexes), then the subrange check of
        the store are computed first, in that order, and the fault checked
        before the store (the plain form would complete the statement with
        the runtime's substitute value: element [low], 0, the low limit)."""
        f = Frame(self, pos)
        t0 = target.type
        t = concrete(t0)
        n = self.next_temp()
        val = f"val{n}"
        f.decls.append(f"{N.ctype(t)} {val};")
        f.pre.append(f"{val} = {self.expr.emit(f, value, t)};")
        lv, lt, bit = self.expr.lvalue(f, target)
        holder = self._holder_type(target) if bit is not None else concrete(lt)
        ptr = f"ptr{n}"
        f.decls.append(f"{N.ctype(holder)} *{ptr};")
        f.pre.append(f"{ptr} = &{lv};")
        if isinstance(t0, SubrangeT) and not _within(value, t0):
            wide = "ulint" if scalar_kind(t0.elem) == "uint" else "lint"
            f.pre.append(f"{val} = ({N.ctype(t0.elem)})iec_range_{wide}(ctx, {val}, "
                         f"{t0.low}LL, {t0.high}LL);")
        f.may_fault = False
        store = self.set_bit(f, f"(*{ptr})", target, bit, val) if bit is not None else \
            f"*{ptr} = {val};"
        return self.wrap(f, [self.fault_check(pos), store], pos, check=False)

    def guarded_store(self, target, value, pos) -> list[str]:
        """A STRING, array or structure assignment that can fault stores
        nothing when it faults: the value into a temporary of the target's
        type, then the place, then the fault check, then the copy."""
        f = Frame(self, pos)
        t = concrete(target.type)
        tmp = f.temp(t, "val")
        lines = self.assign_code(f, tmp, t, value)
        lv, _, _ = self.expr.lvalue(f, target)
        ptr = f"ptr{self.next_temp()}"
        f.decls.append(f"{self.pointer_type(t)}{ptr};")
        if isinstance(t, ArrayT):
            lines.append(f"{ptr} = {lv};")
            place = ptr
        else:
            lines.append(f"{ptr} = &{lv};")
            place = f"(*{ptr})"
        f.may_fault = False
        lines += [self.fault_check(pos), copy_value(place, tmp, t)]
        return self.wrap(f, lines, pos, check=False)

    def set_bit(self, f, code, target, bit, val):
        """x.bit := val, where val is a BOOL (0 or 1, never anything else)."""
        # the variable holding the bit: its type is the expression before .bit
        holder_t = self._holder_type(target)
        width = holder_t.bits
        u = UNSIGNED[width]
        ct = N.ctype(holder_t)
        if val in ("1", "((iec_bool)1)"):
            return f"{code} = ({ct})(({u}){code} | (({u})1 << {bit}));"
        if val in ("0", "((iec_bool)0)"):
            return f"{code} = ({ct})(({u}){code} & ~(({u})1 << {bit}));"
        return (f"{code} = ({ct})((({u}){code} & ~(({u})1 << {bit})) | "
                f"(({u}){val} << {bit}));")

    @staticmethod
    def _holder_type(target):
        t = target.symbol.type
        for kind, val, _ in target.accessors[:-1]:
            if kind == "index":
                t = t.elem
            elif kind == "member":
                t = t.pou.var(val).type if isinstance(t, FBType) else t.fields[val.upper()][1]
        return concrete(t).base

    def assign_code(self, f, code, t, value) -> list[str]:
        """Stores expression ``value`` into C lvalue ``code`` of IEC type t."""
        t0 = t
        t = concrete(t)
        if isinstance(t, StringT):
            return self.assign_string(f, code, t, value)
        if isinstance(t, ArrayT):
            src = self.expr.emit(f, value)
            elem, count = N.array_flat(t)
            return [f"iec_memcpy({code}, {src}, {count} * sizeof({N.ctype(elem)}));"]
        if isinstance(t, StructT):
            return [f"{code} = {self.expr.emit(f, value)};"]
        val = self.expr.emit(f, value, t)
        if isinstance(t0, SubrangeT) and not _within(value, t0):
            f.may_fault = True
            wide = "ulint" if scalar_kind(t0.elem) == "uint" else "lint"
            val = (f"(({N.ctype(t0.elem)})iec_range_{wide}(ctx, {val}, {t0.low}LL, "
                   f"{t0.high}LL))")
        return [f"{code} = {val};"]

    def assign_string(self, f, code, t, value) -> list[str]:
        from .expr import std_target, std_args
        buf = self.expr.strbuf(code, t)
        vt = concrete(value.type) if value.type is not None else None
        if isinstance(value, ast.Ref) and isinstance(vt, StringT) and vt.wide == t.wide and \
                vt.length == t.length and not any(k == "bit" for k, _, _ in value.accessors):
            # the same string type: a structure copy
            lv, _, _ = self.expr.lvalue(f, value)
            return [f"{code} = {lv};"]
        if t.wide:
            return [f"iec_assign_wstring({buf}, {self.expr.strv(f, value)});"]
        fres = std_target(value)
        if fres is not None and fres.family == "CONCAT" and not code.startswith("(*"):
            parts = self.expr.concat_parts(f, std_args(value))
            # the variable holding the destination (a[k] and a[ABS(j)] may
            # be the same element): a piece that reads it is read before
            # the destination is written, through a temporary
            root = re.match(r"[^\[.]*", code).group(0)
            if not any(root in arg for _, arg in parts[1:]):
                # built in place: truncating each piece at the destination's
                # capacity gives the truncated whole
                return self.expr.concat_lines(buf, parts)
            tmp = f.temp(concrete(fres.result))
            return self.expr.concat_lines(self.expr.strbuf(tmp, concrete(fres.result)),
                                          parts) + [f"iec_str_set({buf}, IEC_STRV({tmp}));"]
        return [f"iec_str_set({buf}, {self.expr.strv(f, value)});"]

    # ------------------------------------------------------------ calls
    def call_stmt(self, c: ast.Call, pos) -> list[str]:
        f = Frame(self, pos)
        target = c.target
        if isinstance(target, Var):           # a function block instance
            lines = self.fb_call(f, c, target)
            check = (not _fb_pou(c).standard or f.may_fault) and not f.checked
            return self.wrap(f, lines, pos, check=check)
        code = self.expr.emit(f, c)
        return self.wrap(f, [f"(void){code};"], pos)

    def fb_call(self, f, c, inst: Var) -> list[str]:
        """A call of a function block instance.  The arguments are evaluated
        and stored one after the other, left to right; one that can fault
        is computed into a temporary and checked before it is stored, so a
        fault stores nothing more and the block does not run; a fault in
        the block's body leaves its outputs where they are."""
        pou = _fb_pou(c)
        lines = []
        sel_end = None
        v_eno = pou.var("ENO")
        if v_eno is not None and v_eno.section != "VAR_OUTPUT":
            v_eno = None
        eno_member = v_eno is not None
        en_arg = any(a.name and a.name.upper() == "EN" and a.kind == "in" for a in c.args)
        if c.ref is not None:
            # an element of an array of instances: its index is computed
            # (and checked) once, before the arguments
            sub = self.sub_frame(f)
            lv, _, _ = self.expr.lvalue(sub, c.ref)
            lines += self.absorb(f, sub)
            ptr = f"fbp{self.next_temp()}"
            f.decls.append(f"{N.pou_struct(pou)} *{ptr};")
            lines.append(f"{ptr} = &{lv};")
            if sub.may_fault:
                lines.append(self.fault_check(f.pos))
            base = f"(*{ptr})"
        else:
            base = self.var_access(inst)
        # the element of an array of instances is known (and its index
        # checked) before EN is evaluated, whatever EN is: an index out of
        # range faults with EN = FALSE too, and an instance that keeps its
        # ENO gets FALSE (the order of the interpreter and of verify)
        pre, lines = (lines, []) if en_arg else ([], lines)
        eno = None
        en = None
        for a in c.args:
            if a.name and a.name.upper() == "EN" and a.kind == "in":
                en = self.expr.emit(f, a.value, BOOL)
            elif a.name and a.name.upper() == "ENO" and a.kind == "out":
                eno = a
        bound = c.bound or {}
        for v in pou.inouts:
            # the pointer is set by this call, or the body would run with the
            # previous call's target (or none): the front end requires it
            if bound.get(v.key) is None or bound[v.key].value is None:
                raise BindingError(f"call of {inst.name} leaves VAR_IN_OUT {v.name} unbound")
        for key, a in bound.items():
            param = pou.var(key)
            member = f"{base}.{N.member(pou, param.name)}"
            if a.kind == "out":
                continue
            if param.section == "VAR_IN_OUT":
                sub = self.sub_frame(f)
                lv, _, _ = self.expr.lvalue(sub, a.value)
                ptr = f"&{lv}" if not isinstance(param.type, ArrayT) else lv
                lines += self.absorb(f, sub)
                if sub.may_fault:
                    tmp = f"ref{self.next_temp()}"
                    f.decls.append(f"{self.pointer_type(param.type)} {tmp};")
                    lines += [f"{tmp} = {ptr};", self.fault_check(f.pos)]
                    ptr = tmp
                lines.append(f"{member} = {ptr};")
            elif a.value is not None:
                lines += self.checked_input(f, member, param.type, a.value)
        if en is not None and pou.var("EN") is not None and not pou.standard:
            # a block that declares EN sees it TRUE when it runs
            lines.append(f"{base}.{N.member(pou, pou.var('EN').name)} = 1;")
        if eno_member:
            # ENO is TRUE when the body starts; the body may set it FALSE
            lines.append(f"{base}.{N.member(pou, v_eno.name)} = 1;")
        body_fn = N.pou_prefix(pou) + ("" if pou.standard else "_body")
        inline = _INLINE_FB.get(pou.name.upper()) if pou.standard else None
        if inline:
            # the bistables and edge detectors of iec_std_fb.c, written out
            b = f"{base}.fb" if pou.keeps_eno else base
            lines += [ln.format(b=b) for ln in inline]
        else:
            if self.sel is None:
                kind = None
            elif c.ref is not None:
                # an element of an array of instances is always evaluated
                kind = "plain" if self.sel.has_layout(pou) else None
            else:
                kind = self.sel.call_kind(self.pou, inst)
            if kind == "sel":
                # fb: the caller may read the instance's state from before the
                # call (selective.py, rule 4)
                fb = "true" if self.sel.feedback(self.pou, inst) else "false"
                # a skipped block cannot have faulted: the check is only
                # after a run (_run returns false when there is nothing to
                # check)
                lines += [f"if ({N.pou_prefix(pou)}_run(&{base}, ctx, {fb}))",
                          self.ind + self.fault_check(f.pos)]
                sel_end = len(lines)
            else:
                lines.append(f"{body_fn}(&{base}, ctx);")
            if kind == "plain":
                lines.append(f"{base}.sel.tok = 0;")
        if not pou.standard:
            f.may_fault = True
            if any(a.kind == "out" and a.value is not None for a in bound.values()) or \
                    eno is not None:
                # a fault in the block: its outputs are not copied out
                lines.append(self.fault_check(f.pos))
        for key, a in bound.items():
            param = pou.var(key)
            if a.kind != "out" or a.value is None:
                continue
            member = f"{base}.{N.member(pou, param.name)}"
            val = f"((iec_bool)!{member})" if a.negate else member
            lines += self.checked_store(f, a.value, Raw(val, param.type))
        if eno is not None and eno.value is not None and bound.get("ENO") is not eno:
            lines += self.checked_store(f, eno.value, Raw("1", BOOL))
        if en is not None:
            out = pre + [f"if ({en}) {{"] + self.indent(lines) + ["}"]
            off = [f"{base}.{N.member(pou, v_eno.name)} = 0;"] if eno_member else []
            if eno is not None and eno.value is not None:
                off += self.checked_store(f, eno.value, Raw("0", BOOL))
            if off:
                out += ["else {"] + self.indent(off) + ["}"]
            return out
        # a selective call that ends the lines has made the statement's check
        f.checked = sel_end == len(lines)
        return lines

    # ---------------------------------------- left to right, fault by fault
    def sub_frame(self, f):
        """A frame for one argument of a call in frame f: its temporaries
        come from f's pool, its code is placed where the argument is."""
        sub = Frame(self, f.pos)
        sub.pooled = f.pooled
        return sub

    @staticmethod
    def absorb(f, sub):
        """sub's declarations into f; its setup code, to be placed next."""
        f.decls += sub.decls
        f.may_fault = f.may_fault or sub.may_fault
        f.calls += sub.calls
        return sub.pre

    def pointer_type(self, t, const=False):
        t = concrete(t)
        if isinstance(t, ArrayT):
            elem, _ = N.array_flat(t)
            return f"{'const ' if const else ''}{N.ctype(elem)} *"
        return f"{'const ' if const else ''}{N.ctype(t)} *"

    def checked_input(self, f, member, t, value) -> list[str]:
        """member := value for an input of a call: when computing the value
        can fault, it goes into a temporary first and the fault is checked
        before the store (the input keeps its value, nothing after runs)."""
        snapshot, snap = dict(f.pooled), self.pool_snapshot()
        sub = self.sub_frame(f)
        code = self.assign_code(sub, member, t, value)
        if not sub.may_fault:
            return self.absorb(f, sub) + code
        # again, into a temporary of the parameter's type
        f.pooled.clear()
        f.pooled.update(snapshot)
        self.pool_restore(snap)
        sub = self.sub_frame(f)
        if N.is_scalar(concrete(t)):
            tmp = f"arg{self.next_temp()}"
            sub.decls.append(f"{N.ctype(t)} {tmp};")
        else:
            tmp = sub.temp(t, "arg")
        code = self.assign_code(sub, tmp, t, value)
        return self.absorb(f, sub) + code + [self.fault_check(f.pos),
                                              copy_value(member, tmp, t)]

    def checked_store(self, f, target, value) -> list[str]:
        """target := value (an output copied out of a call): when the place
        can fault (an index), it is computed and checked first and nothing
        is stored on a fault."""
        snapshot, snap = dict(f.pooled), self.pool_snapshot()
        sub = self.sub_frame(f)
        code = self.assign_ref(sub, target, value)
        if not sub.may_fault:
            return self.absorb(f, sub) + code
        f.pooled.clear()
        f.pooled.update(snapshot)
        self.pool_restore(snap)
        sub = self.sub_frame(f)
        lv, lt, bit = self.expr.lvalue(sub, target)
        n = self.next_temp()
        holder = self._holder_type(target) if bit is not None else concrete(lt)
        ptr = f"ptr{n}"
        if isinstance(holder, ArrayT):
            sub.decls.append(f"{self.pointer_type(holder)}{ptr};")
            place, pre = ptr, [f"{ptr} = {lv};"]
        else:
            sub.decls.append(f"{N.ctype(holder)} *{ptr};")
            place, pre = f"(*{ptr})", [f"{ptr} = &{lv};"]
        lines = self.absorb(f, sub) + pre + [self.fault_check(f.pos)]
        sub = self.sub_frame(f)
        if bit is not None:
            store = [self.set_bit(sub, place, target, bit, self.expr.emit(sub, value, BOOL))]
        else:
            store = self.assign_code(sub, place, lt, value)
        return lines + self.absorb(f, sub) + store

    def user_function_call(self, f, c: ast.Call) -> str:
        """A call of a user FUNCTION, as a statement of its own in f.pre, in
        the order of the source.  Its arguments are evaluated left to right;
        a fault before the call (in this statement, or in an argument) means
        the function does not run, a fault in the function means its outputs
        are not copied out."""
        pou = c.target
        bound = c.bound or {}
        args = ["ctx"]
        result = pou.vars[pou.key]
        ret_tmp = None
        if not N.is_scalar(result.type):
            ret_tmp = f.temp(result.type)
            args.append(f"&{ret_tmp}" if not isinstance(result.type, ArrayT) else ret_tmp)
        outs = []
        arg_marks = []
        hoisted = set()
        for v in pou.vars.values():
            if v.section not in ("VAR_INPUT", "VAR_IN_OUT", "VAR_OUTPUT"):
                continue
            a = bound.get(v.key)
            sub = self.sub_frame(f)
            if v.section == "VAR_INPUT":
                if a is None or a.value is None:
                    code = self.default_value(sub, v)
                elif N.is_scalar(v.type):
                    code = self.expr.emit(sub, a.value, v.type)
                    if isinstance(v.type, SubrangeT) and not _within(a.value, v.type):
                        # passing a value is assigning it: checked as a store is
                        sub.may_fault = True
                        wide = "ulint" if scalar_kind(v.type.elem) == "uint" else "lint"
                        code = (f"(({N.ctype(v.type.elem)})iec_range_{wide}(ctx, {code}, "
                                f"{v.type.low}LL, {v.type.high}LL))")
                else:
                    code = self.by_reference(sub, a.value, v.type)
                ctype = N.ctype(v.type) + " " if N.is_scalar(v.type) else \
                    self.pointer_type(v.type, const=True)
            elif v.section == "VAR_IN_OUT":
                if a is None or a.value is None:
                    raise BindingError(f"call of {pou.name} leaves VAR_IN_OUT {v.name} unbound")
                lv, _, _ = self.expr.lvalue(sub, a.value)
                code = lv if isinstance(v.type, ArrayT) else f"&{lv}"
                ctype = self.pointer_type(v.type)
            else:
                tmp = sub.temp(v.type, "out")
                code = tmp if isinstance(v.type, ArrayT) else f"&{tmp}"
                ctype = None
                if a is not None and a.value is not None:
                    outs.append((a, tmp, v))
            f.pre += self.absorb(f, sub)
            arg_marks.append((len(args), len(f.pre), f.calls, v))
            if sub.may_fault and ctype is not None:
                hoisted.add(len(args))
                # computed and checked before the next argument
                tmp = f"arg{self.next_temp()}"
                f.decls.append(f"{ctype}{tmp};")
                f.pre += [f"{tmp} = {code};", self.fault_check(f.pos)]
                code = tmp
            args.append(code)
        for i, end, calls, v in reversed(arg_marks):
            # a later argument calls a function (which may change this one's
            # variables through VAR_IN_OUT): this one is computed before it
            if calls == f.calls or v.section != "VAR_INPUT" or not N.is_scalar(v.type) or \
                    i in hoisted or isinstance(concrete(v.type), StringT):
                continue
            tmp = f"arg{self.next_temp()}"
            f.decls.append(f"{N.ctype(v.type)} {tmp};")
            f.pre[end:end] = [f"{tmp} = {args[i]};"]
            args[i] = tmp
        if f.may_fault:
            # something before the call may have faulted: it does not run
            f.pre.append(self.fault_check(f.pos))
        f.may_fault = True
        f.calls += 1
        call = f"{N.fn(pou.name)}({', '.join(args)})"
        # every call is a statement of its own, in the order of the source
        # (left to right): a call may change the caller's variables through
        # VAR_IN_OUT, and C leaves the order of operands unspecified
        if ret_tmp is not None:
            f.pre.append(f"{call};")
            result_code = ret_tmp
        else:
            result_code = f.temp(result.type, "ret")
            f.pre.append(f"{result_code} = {call};")
        if outs:
            # a fault in the function: nothing is copied out
            f.pre.append(self.fault_check(f.pos))
        for a, tmp, v in outs:
            val = f"((iec_bool)!{tmp})" if a.negate else tmp
            f.pre += self.checked_store(f, a.value, Raw(val, v.type))
        return result_code

    def by_reference(self, f, e, t):
        """Pointer to a string/array/struct argument (functions take them
        const).  A variable of the parameter's own type is passed where it
        is; anything else (an expression, a string of another length, which
        the function sees truncated to its parameter's) is first copied
        into a temporary of the parameter's type."""
        if isinstance(e, ast.Ref) and e.type is not None and identical(concrete(e.type),
                                                                       concrete(t)):
            lv, _, _ = self.expr.lvalue(f, e)
            return lv if isinstance(t, ArrayT) else f"&{lv}"
        tmp = f.temp(t)
        f.pre += self.assign_code(f, tmp, t, e)
        return tmp if isinstance(t, ArrayT) else f"&{tmp}"

    def default_value(self, f, v):
        if v.init is not None and isinstance(v.init, ast.Expr) and N.is_scalar(v.type):
            return self.expr.emit(f, v.init, v.type)
        t = concrete(v.type)
        if N.is_scalar(t):
            if isinstance(t, EnumT):
                first = next(iter(t.values.values()))
                return N.enum_const(t, first[0])
            if isinstance(v.type, SubrangeT):
                return c_int(v.type.low, t)
            return c_int(0, t)
        tmp = f.temp(t)
        if f.is_pooled(tmp):
            f.pre.append(f"iec_memset(&{tmp}, 0, sizeof({tmp}));")
        else:
            f.decls[-1] = f.decls[-1][:-1] + " = { 0 };"
        if v.init is not None:
            f.pre += self.assign_code(f, tmp, t, v.init)
        return tmp if isinstance(t, ArrayT) else f"&{tmp}"

    # --------------------------------------------------------------- IL
    def il_body(self, instrs) -> list[str]:
        lines = []
        self.il_labels_seen = set()
        self.il_label_cr = {i.label.upper(): i.cr_in for i in instrs if i.label}
        # a label no jump names is not written out (an unused C label is an
        # error with -Werror=unused-label, and valid IL labels any line)
        self.il_jump_targets = {i.operand.name.upper() for i in instrs
                                if i.op in ("JMP", "JMPC", "JMPCN") and
                                isinstance(i.operand, ast.Ref)}
        prev = None
        for i in instrs:
            if i.label:
                self.il_labels_seen.add(i.label.upper())
                if prev is not None and prev.op not in ("JMP", "RET"):
                    lines += self.cr_handover(prev.cr_out, i.cr_in)
            lines += self.il(i, 0)
            prev = i
        return lines

    def cr_handover(self, src, dst) -> list[str]:
        """At a label reached with an untyped literal's current result on
        one path and a typed one on another, the literal's path takes the
        label's type (the checker's join): its value moves to the current
        result variable of that type."""
        if src is None or dst is None or isinstance(src, ErrorT) or isinstance(dst, ErrorT):
            return []
        if concrete(src) is concrete(dst) or not N.is_scalar(concrete(dst)) or \
                not N.is_scalar(concrete(src)):
            return []
        return [f"{self.cr_var(dst, 0)} = {self.expr.convert(self.cr_var(src, 0), src, dst)};"]

    def il(self, i, depth) -> list[str]:
        out = []
        if i.label and i.label.upper() in getattr(self, "il_jump_targets", (i.label.upper(),)):
            out.append(f"L_{self.il_label_prefix}{i.label.lower()}:;")
        f = Frame(self, i.pos)
        op = i.op
        lines = []
        cr_in = i.cr_in
        if op is None:
            call = i.call
            res = i.cr_out
            self.cr_depth = depth       # the current result passed as first input
            code = self.expr.emit(f, call, res)
            lines += self.cr_set(f, res, depth, code)
        elif i.deferred:
            inner = []
            if i.operand is not None:
                inner += self.cr_set(f, i.operand.type, depth + 1, i.operand)
            for n in i.nested:
                inner += self.il(n, depth + 1)
            inner_t = i.nested[-1].cr_out if i.nested else i.operand.type
            rhs = CRNode(i.pos, inner_t, depth + 1)
            lines += self.wrap(f, inner, i.pos)
            f = Frame(self, i.pos)
            lines += self.il_apply(f, i, op, cr_in, rhs, depth)
        elif op in ("LD", "LDN"):
            t = concrete(i.operand.type) if not isinstance(i.operand.type, LiteralT) else \
                concrete(i.cr_out)
            if isinstance(t, StringT):
                lines += self.cr_set(f, t, depth, i.operand)
            else:
                val = self.expr.emit(f, i.operand, t)
                if op == "LDN":
                    val = f"((iec_bool)!{val})" if t is BOOL else f"iec_not_{N.type_tag(t)}({val})"
                lines.append(f"{self.cr_var(t, depth)} = {val};")
        elif op in ("ST", "STN"):
            cr = self.cr_var(cr_in, depth)
            st_t = cr_in
            if op == "STN":     # negated in the checker's type (sig)
                st_t = concrete(i.sig[0])
                cr = self.expr.convert(cr, cr_in, st_t)
                cr = f"((iec_bool)!{cr})" if st_t is BOOL else f"iec_not_{N.type_tag(st_t)}({cr})"
            probe = Frame(self, i.pos)
            snap = self.pool_snapshot()
            lines += self.assign_ref(probe, i.operand, Raw(cr, st_t))
            if probe.may_fault:
                self.pool_restore(snap)
            if probe.may_fault and N.is_scalar(concrete(i.operand.type)):
                return out + self.guarded_assign(i.operand, Raw(cr, st_t), i.pos)
            if probe.may_fault:
                return out + self.guarded_store(i.operand, Raw(cr, st_t), i.pos)
            f = probe
        elif op in ("S", "R") and not isinstance(getattr(i.operand, "type", None), FBType):
            lv, _, bit = self.expr.lvalue(f, i.operand)
            val = "1" if op == "S" else "0"
            store = self.set_bit(f, lv, i.operand, bit, val) if bit is not None else \
                f"{lv} = {val};"
            lines += [f"if ({self.cr_var(cr_in, depth)})", self.ind + store]
        elif op in ("S1", "R1", "CLK", "CU", "CD", "PV", "IN", "PT", "S", "R", "LD"):
            inst = i.operand.symbol
            pou = inst.type.pou
            param = pou.var(op)
            member = f"{self.var_access(inst)}.{N.member(pou, param.name)}"
            lines += self.assign_code(f, member, param.type, Raw(self.cr_var(cr_in, depth),
                                                                  cr_in))
        elif op == "NOT":       # in the result's type: a bit string for a literal
            res = concrete(i.cr_out)
            cr = self.expr.convert(self.cr_var(cr_in, depth), cr_in, res)
            lines.append(f"{self.cr_var(res, depth)} = " +
                         (f"((iec_bool)!{cr});" if res is BOOL else
                          f"iec_not_{N.type_tag(res)}({cr});"))
        elif op in IL_LOGIC or op in IL_ARITH or op in IL_COMPARE:
            lines += self.il_apply(f, i, op, cr_in, i.operand, depth)
        elif op in ("JMP", "JMPC", "JMPCN"):
            jump = self.cr_handover(cr_in, self.il_label_cr.get(i.operand.name.upper())) + \
                [f"goto L_{self.il_label_prefix}{i.operand.name.lower()};"]
            if i.operand.name.upper() in self.il_labels_seen:
                # a backward jump closes a loop: it ticks the loop budget like
                # every iteration of an ST loop, so an endless IL loop faults
                jump.insert(0, self.loop_tick(i.pos))
            if op == "JMP":
                lines += jump
            else:
                neg = "!" if op == "JMPCN" else ""
                lines += [f"if ({neg}{self.cr_var(cr_in, depth)}) {{"] + self.indent(jump) + \
                    ["}"]
        elif op in ("RET", "RETC", "RETCN"):
            ret = self.return_stmt()
            if op == "RET":
                lines.append(ret)
            else:
                neg = "!" if op == "RETCN" else ""
                lines += [f"if ({neg}{self.cr_var(cr_in, depth)})", self.ind + ret]
        elif op in ("CAL", "CALC", "CALCN"):
            call_lines = self.fb_call(f, i.call, i.call.target)
            if op == "CAL":
                lines += call_lines
            else:
                neg = "!" if op == "CALCN" else ""
                lines += [f"if ({neg}{self.cr_var(cr_in, depth)}) {{"] + self.indent(call_lines) + ["}"]
            f.may_fault = f.may_fault or not _fb_pou(i.call).standard
        elif op == "NOP":
            pass                # a label on a line of its own
        else:
            raise CodegenError(f"IL operator {op}")
        return out + self.wrap(f, lines, i.pos)

    def il_apply(self, f, i, op, cr_in, operand, depth):
        res = concrete(i.cr_out)
        left = CRNode(i.pos, cr_in, depth)
        neg = op.endswith("N") and op in IL_LOGIC
        if op in IL_LOGIC:
            r = self.expr.emit(f, operand, res)
            if neg:
                r = f"((iec_bool)!{r})" if res is BOOL else f"iec_not_{N.type_tag(res)}({r})"
            l = self.expr.convert(self.cr_var(cr_in, depth), cr_in, res)
            fam = IL_LOGIC[op]
            code = (f"((iec_bool)({l} {'&' if fam == 'AND' else '|' if fam == 'OR' else '^'} {r}))"
                    if res is BOOL else f"iec_{fam.lower()}_{N.type_tag(res)}({l}, {r})")
        else:               # arithmetic and comparisons: the checker's function
            code = self.expr.std_apply(f, i.std, [left, operand], i.sig)
        return [f"{self.cr_var(res, depth)} = {code};"]


# Standard FBs simple enough to be written out at the call (the same
# statements as their bodies in kmod_templates/runtime/iec_std_fb.c).
_INLINE_FB = {
    "SR": ["{b}.q1 = {b}.s1 || (!{b}.r && {b}.q1);"],
    "RS": ["{b}.q1 = !{b}.r1 && ({b}.s || {b}.q1);"],
    "R_TRIG": ["{b}.q = {b}.clk && !{b}.prev;", "{b}.prev = !!{b}.clk;"],
    "F_TRIG": ["{b}.q = !{b}.clk && {b}.prev;", "{b}.prev = !!{b}.clk;"],
}


def copy_value(dst, src, t):
    """C statement copying a value of IEC type t from lvalue src to dst."""
    t = concrete(t)
    if isinstance(t, StringT):
        w = "W" if t.wide else ""
        return f"iec_assign_{w.lower()}string(IEC_{w}STRBUF({dst}), IEC_{w}STRV({src}));"
    if isinstance(t, ArrayT):
        elem, count = N.array_flat(t)
        return f"iec_memcpy({dst}, {src}, {count} * sizeof({N.ctype(elem)}));"
    return f"{dst} = {src};"


def _within(value, t: SubrangeT) -> bool:
    from .expr import _const_int
    v = _const_int(value)
    return v is not None and t.low <= v <= t.high


def _fb_pou(c):
    """The function block (POUInfo) a call statement of an instance calls:
    of the instance variable, or of the array element c.ref leads to."""
    return (c.ref.type if c.ref is not None else c.target.type).pou
