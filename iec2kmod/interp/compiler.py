"""From the checked AST to Python closures.

Each expression becomes a function ``f(env) -> value`` and each statement a
function ``s(env) -> None | EXIT | RETURN | CONTINUE``, ``env`` being the Instance of
the running POU.  This is still an interpreter of the AST -- one closure per
node, built once, run every cycle -- only without re-dispatching on node
types at every evaluation.

``PouCompiler`` is one class written in four files, one mixin per part, in
the order a reader meets them:

    compiler.py       PouCompiler: statements (blocks with their fault
                      locations, IF, CASE, the loops and their budget), a
                      POU body (SFC, IL or ST; VAR_TEMP, edge inputs)
    compile_expr.py   ExprCompiler: variable access (read, write, cell)
                      and expressions
    compile_calls.py  CallCompiler: standard functions, user functions and
                      FB instances (EN/ENO, argument binding)
    compile_il.py     ILCompiler: IL, its current result and its jumps

What they share -- statement results, implicit conversions -- is
closures.py.  The mixins reach each other and the compiler's state
(``m``, ``rt``, ``pou``, ``src``, ``name``) through ``self``; they import
closures.py and the interpreter's other modules, never compiler.py (which
imports them).  SFC bodies are sfc.py's, run with the same compiler."""

from __future__ import annotations

from .. import ast
from ..checks.symbols import Var
from ..checks.types import ArrayT, EnumT, FBType, concrete
from .closures import CONTINUE, EXIT, RETURN, _const
from .compile_calls import CallCompiler
from .compile_expr import ExprCompiler
from .compile_il import ILCompiler
from .errors import ENUM, LOOP, Fault
from .values import base_of


class PouCompiler(ExprCompiler, CallCompiler, ILCompiler):
    """Compiles the body of one POU."""

    def __init__(self, machine, pou):
        self.m = machine
        self.rt = machine.rt
        self.pou = pou
        self.src = pou.src
        self.name = pou.name
        self.is_function = pou.kind == "FUNCTION"

    def line(self, pos):
        return self.src.linecol(pos)[0] if pos is not None else 0

    # ------------------------------------------------------------ statements
    def block(self, stmts):
        fns = [self.stmt(s) for s in stmts]
        lines = [self.line(s.pos) for s in stmts]
        name = self.name
        if not fns:
            return lambda env: None
        if len(fns) == 1:
            f0, l0 = fns[0], lines[0]

            def one(env):
                try:
                    return f0(env)
                except Fault as x:
                    if x.pou is None:
                        x.pou, x.line, x.file = name, l0, self.src.path
                    raise
            return one

        def run(env):
            i = 0
            try:
                for i, f in enumerate(fns):
                    r = f(env)
                    if r is not None:
                        return r
            except Fault as x:
                if x.pou is None:
                    x.pou, x.line, x.file = name, lines[i], self.src.path
                raise
            return None
        return run

    def located(self, f, pos):
        """f, with a fault in it located at the line of pos (conditions of
        IF/ELSIF/WHILE/UNTIL: the line of the condition itself)."""
        line = self.line(pos)
        name = self.name
        path = self.src.path

        def at(env):
            try:
                return f(env)
            except Fault as x:
                if x.pou is None:
                    x.pou, x.line, x.file = name, line, path
                raise
        return at

    def cond(self, e):
        return self.located(self.expr(e), e.pos)

    def stmt(self, s):
        if isinstance(s, ast.Assign):
            val = self.expr(s.value)
            w = self.writer(s.target, s.value.type)

            def assign(env):
                w(env, val(env))
            return assign
        if isinstance(s, ast.CallStmt):
            c = s.call
            if isinstance(c.target, Var):
                return self.fb_call(c)
            f = self.call_expr(c)

            def call(env):
                f(env)
            return call
        if isinstance(s, ast.If):
            branches = [(self.cond(cnd), self.block(body)) for cnd, body in s.branches]
            els = self.block(s.else_) if s.else_ else None
            if len(branches) == 1:
                (c0, b0), = branches

                def if1(env):
                    if c0(env):
                        return b0(env)
                    if els is not None:
                        return els(env)
                    return None
                return if1

            def if_(env):
                for cnd, body in branches:
                    if cnd(env):
                        return body(env)
                if els is not None:
                    return els(env)
                return None
            return if_
        if isinstance(s, ast.Case):
            return self.case(s)
        if isinstance(s, ast.For):
            return self.for_(s)
        if isinstance(s, ast.While):
            return self.while_(s)
        if isinstance(s, ast.Repeat):
            return self.repeat(s)
        if isinstance(s, ast.Exit):
            return lambda env: EXIT
        if isinstance(s, ast.Continue):
            return lambda env: CONTINUE
        if isinstance(s, ast.Return):
            return lambda env: RETURN
        if isinstance(s, ast.Empty):
            return lambda env: None
        raise AssertionError(f"statement {s!r}")

    def case(self, s):
        sel = self.expr(s.selector)
        st = concrete(s.selector.type)
        bodies = [self.block(body) for _, body in s.elements]
        els = self.block(s.else_) if s.else_ else None
        table = {}
        ranges = []
        for n, values in enumerate(s.values):
            for lo, hi in values:
                if hi - lo < 64:
                    for v in range(lo, hi + 1):
                        table.setdefault(v, n)
                else:
                    ranges.append((lo, hi, n))
        enum_values = set(v for _, v in st.values.values()) if isinstance(st, EnumT) else None

        def case(env):
            v = sel(env)
            if enum_values is not None and v not in enum_values:
                raise Fault(ENUM)
            n = table.get(v)
            if n is None:
                for lo, hi, k in ranges:
                    if lo <= v <= hi:
                        n = k
                        break
            if n is not None:
                return bodies[n](env)
            if els is not None:
                return els(env)
            return None
        return case

    def _tick(self):
        rt = self.rt

        def tick():
            rt.budget -= 1
            if rt.budget < 0:
                raise Fault(LOOP)
        return tick

    def for_(self, s):
        v = self.pou.var(s.var)
        vt = concrete(v.type)
        k = v.key
        start = self.expr_as(s.start, vt)
        end = self.expr_as(s.end, vt)
        step = self.expr_as(s.step, vt) if s.step is not None else _const(1)
        body = self.block(s.body)
        lo_t, hi_t = base_of(vt).range
        rt = self.rt

        def for_(env):
            a = start(env)
            e = end(env)
            st = step(env)
            vv = env.v
            vv[k] = a
            i = a
            up = st >= 0
            while True:
                if (i > e) if up else (i < e):
                    break
                rt.budget -= 1
                if rt.budget < 0:
                    raise Fault(LOOP)
                r = body(env)
                if r is not None and r != CONTINUE:
                    if r == EXIT:
                        break
                    return r
                i = vv[k] + st
                if i < lo_t or i > hi_t:
                    break
                vv[k] = i
            return None
        return for_

    def while_(self, s):
        cond = self.cond(s.cond)
        body = self.block(s.body)
        rt = self.rt

        def while_(env):
            while cond(env):
                rt.budget -= 1
                if rt.budget < 0:
                    raise Fault(LOOP)
                r = body(env)
                if r is not None and r != CONTINUE:
                    if r == EXIT:
                        break
                    return r
            return None
        return while_

    def repeat(self, s):
        cond = self.cond(s.cond)
        body = self.block(s.body)
        rt = self.rt

        def repeat(env):
            while True:
                rt.budget -= 1
                if rt.budget < 0:
                    raise Fault(LOOP)
                r = body(env)
                if r is not None and r != CONTINUE:
                    if r == EXIT:
                        break
                    return r
                if cond(env):
                    break
            return None
        return repeat

    # ----------------------------------------------------------- POU bodies
    def body(self):
        node = self.pou.node
        if node.language == "SFC":
            from .sfc import compile_sfc
            run = compile_sfc(self)
        elif node.language == "IL":
            run = self.il_body(node.body)
        else:
            run = self.block(node.body)
        pou = self.pou
        edges = [(v.key, v.edge) for v in pou.inputs if v.edge]
        temps = []
        if not self.is_function:
            m = self.m
            for v in pou.vars.values():
                if v.section != "VAR_TEMP":
                    continue
                t = concrete(v.type)
                if isinstance(t, FBType):
                    # a fresh instance per call, its externals bound in the caller's scope
                    temps.append((v.key, None, (t.pou, v.init, None)))
                elif isinstance(t, ArrayT) and isinstance(concrete(t.elem), FBType):
                    temps.append((v.key, None, (concrete(t.elem).pou, None, t.count)))
                else:
                    temps.append((v.key, m.maker(v), None))
        if not edges and not temps:
            return run
        m = self.m

        def body(env):
            iv = env.v
            for k, mk, fb in temps:
                if mk is not None:
                    iv[k] = mk()
                elif fb[2] is None:
                    iv[k] = m.new_instance(fb[0], env.s, fb[1])
                else:
                    iv[k] = [m.new_instance(fb[0], env.s, None) for _ in range(fb[2])]
            e = env.e
            for k, kind in edges:
                cur = bool(iv[k])
                prev = e.get("$" + k, False)
                e[k] = (cur and not prev) if kind == "R_EDGE" else (prev and not cur)
                e["$" + k] = cur
            return run(env)
        return body

