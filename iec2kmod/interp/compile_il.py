"""PouCompiler, instruction lists: the instructions as closures run by a
program counter, the current result held in ``env.cr``, deferred
operators ``OP(``, S/R, the FB input operators, CAL/CALC/CALCN, jumps (a
backward jump costs one unit of the loop budget) and RET.

``ILCompiler`` is mixed into compiler.PouCompiler and calls its methods:
``line``, ``_tick`` (compiler.py), ``expr``, ``expr_as``, ``storer``,
``writer`` (compile_expr.py), ``call_expr``, ``fb_call``, ``apply_std``
(compile_calls.py).  It imports closures.py and the interpreter's library
modules, never compiler.py."""

from __future__ import annotations

from ..checks import stdlib
from ..checks.types import BOOL, FBType, LiteralT, concrete
from . import std
from .closures import RETURN, _Slot, implicit
from .errors import Fault
from .values import base_of


class ILCompiler:
    # -------------------------------------------------------------------- IL
    def il_body(self, instrs):
        """The instruction list as a program of closures run by a
        program counter; each returns None (next), an index (jump) or
        RET_PC (return)."""
        labels = {}
        for n, i in enumerate(instrs):
            if i.label:
                labels[i.label.upper()] = n
        ops = [self.il_instr(i, labels, n) for n, i in enumerate(instrs)]
        lines = [self.line(i.pos) for i in instrs]
        name = self.name
        src = self.src
        count = len(ops)

        def run(env):
            pc = 0
            try:
                while pc < count:
                    r = ops[pc](env)
                    if r is None:
                        pc += 1
                    elif r < 0:
                        return RETURN
                    else:
                        pc = r
            except Fault as x:
                if x.pou is None:
                    x.pou, x.line, x.file = name, lines[pc], src.path
                raise
            return None
        return run

    def il_seq(self, instrs):
        """Nested instructions of a deferred operation (no labels, no jumps
        out): run in order."""
        ops = [self.il_instr(i, {}, n) for n, i in enumerate(instrs)]

        def run(env):
            for f in ops:
                f(env)
        return run

    def il_instr(self, i, labels, n):
        op = i.op
        cr_in = i.cr_in
        if op is None:
            f = self.call_expr(i.call)

            def fn_call(env):
                env.cr = f(env)
            return fn_call
        if i.deferred:
            inner_t = i.nested[-1].cr_out if i.nested else i.operand.type
            first = self.expr(i.operand) if i.operand is not None else None
            seq = self.il_seq(i.nested)
            comb = self.il_combine(i, op, cr_in, inner_t)

            def deferred(env):
                outer = env.cr
                env.cr = first(env) if first is not None else None
                seq(env)
                inner = env.cr
                env.cr = comb(outer, inner)
            return deferred
        if op in ("LD", "LDN"):
            t = i.cr_out
            f = self.expr_as(i.operand, t) if not isinstance(i.operand.type, LiteralT) else \
                self.expr_as(i.operand, concrete(t))
            if op == "LDN":
                nf = std.not_fn(concrete(t))

                def ldn(env):
                    env.cr = nf(f(env))
                return ldn

            def ld(env):
                env.cr = f(env)
            return ld
        if op in ("ST", "STN"):
            if op == "STN":     # negated in the checker's type (sig)
                st_t = concrete(i.sig[0])
                w = self.writer(i.operand, st_t)
                nf = std.not_fn(st_t)
                cv = implicit(cr_in, st_t) or (lambda v: v)

                def stn(env):
                    w(env, nf(cv(env.cr)))
                return stn
            w = self.writer(i.operand, cr_in)

            def st(env):
                w(env, env.cr)
            return st
        if op in ("S", "R") and not isinstance(getattr(i.operand, "type", None), FBType):
            w = self.writer(i.operand, BOOL)
            val = op == "S"

            def set_reset(env):
                if env.cr:
                    w(env, val)
            return set_reset
        if op in ("S1", "R1", "CLK", "CU", "CD", "PV", "IN", "PT", "S", "R", "LD"):
            inst_var = i.operand.symbol
            param = inst_var.type.pou.var(op)
            pk = param.key
            st_ = self.storer(param.type, cr_in)
            kv = inst_var.key

            def fb_input(env):
                env.v[kv].v[pk] = st_(env.cr)
            return fb_input
        if op == "NOT":         # in the result's type: a bit string for a literal
            res = concrete(i.cr_out)
            nf = std.not_fn(res)
            cv = implicit(cr_in, res) or (lambda v: v)

            def not_(env):
                env.cr = nf(cv(env.cr))
            return not_
        if op in ("AND", "ANDN", "OR", "ORN", "XOR", "XORN", "ADD", "SUB", "MUL", "DIV",
                  "MOD", "GT", "GE", "EQ", "NE", "LE", "LT"):
            f = self.expr(i.operand)
            comb = self.il_combine(i, op, cr_in, i.operand.type)

            def apply(env):
                env.cr = comb(env.cr, f(env))
            return apply
        if op in ("JMP", "JMPC", "JMPCN"):
            target = labels[i.operand.name.upper()]
            backward = target <= n
            tick = self._tick() if backward else None
            if op == "JMP":
                if tick:
                    def jmp_back(env):
                        tick()
                        return target
                    return jmp_back
                return lambda env: target
            want = op == "JMPC"

            def jmpc(env):
                if bool(env.cr) == want:
                    if tick:
                        tick()
                    return target
                return None
            return jmpc
        if op in ("RET", "RETC", "RETCN"):
            if op == "RET":
                return lambda env: -1
            want = op == "RETC"
            return lambda env: -1 if bool(env.cr) == want else None
        if op in ("CAL", "CALC", "CALCN"):
            f = self.fb_call(i.call)
            if op == "CAL":
                return f
            want = op == "CALC"

            def calc(env):
                if bool(env.cr) == want:
                    f(env)
                return None
            return calc
        if op == "NOP":
            return lambda env: None
        raise AssertionError(f"IL operator {op}")

    def il_combine(self, i, op, cr_t, op_t):
        """g(cr, operand) -> new current result for a binary IL operator."""
        base = op[:-1] if op in ("ANDN", "ORN", "XORN") else op
        neg = op in ("ANDN", "ORN", "XORN")
        if base in ("AND", "OR", "XOR"):
            t = i.sig[1][0]
            ca, cb = implicit(cr_t, t), implicit(op_t, t)
            b = base_of(t)
            if b is BOOL:
                fn = {"AND": lambda x, y: bool(x and y), "OR": lambda x, y: bool(x or y),
                      "XOR": lambda x, y: bool(x) != bool(y)}[base]
                nf = (lambda y: not y)
            else:
                mask = (1 << b.bits) - 1
                fn = {"AND": lambda x, y: x & y, "OR": lambda x, y: x | y,
                      "XOR": lambda x, y: x ^ y}[base]
                nf = (lambda y: ~y & mask)

            def logic(x, y):
                if ca:
                    x = ca(x)
                if cb:
                    y = cb(y)
                if neg:
                    y = nf(y)
                return fn(x, y)
            return logic
        if base in stdlib.ARITH_FAMILIES:
            holder = _Holder()
            fargs = [_Slot(0, cr_t), _Slot(1, op_t)]
            f = self.apply_std(i.std, fargs, i.sig)

            def arith(x, y):
                holder.vals = (x, y)
                return f(holder)
            return arith
        t = i.sig[1][0]
        ca, cb = implicit(cr_t, t), implicit(op_t, t)
        fn = std.COMPARE[base]

        def cmp(x, y):
            if ca:
                x = ca(x)
            if cb:
                y = cb(y)
            return fn(x, y)
        return cmp


class _Holder:
    __slots__ = ("vals",)
