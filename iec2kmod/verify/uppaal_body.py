"""`export --uppaal`, the program bodies as edges of the Task automaton:
expressions as UPPAAL expressions over the exported variables (each
arithmetic result wrapped into its type), the standard functions exported;
ST statements as edges with guards (IF, CASE), unrolled FOR loops, RETURN;
function block instances inlined (the timers called through their
channels, the other standard FBs as updates on the calling edge); IL one
edge per instruction, the current result in one variable per nesting
level, jumps and RET as edges to their targets.  What cannot be exported
exactly is refused naming it.  ``ident`` names a variable in the model.

``BodyExport`` is mixed into uppaal.Exporter, whose state it uses (``sym``,
``enc``: the z3 encoder, asked for places only; ``task``, ``cur``: the
automaton and its current location; ``timers``, ``timer_paths``,
``extra``, ``dead``, ``ret_target``, ``depth``, ``_crs``) and whose
methods it calls: ``wrap``, ``ms``, ``name_of``, ``_refuse`` (uppaal.py).
It imports terms.py, the checker and the interpreter's values, never
uppaal.py (which imports it)."""

from __future__ import annotations

import re

from .. import ast
from ..checks import stdlib
from ..checks.symbols import EnumValue
from ..checks.symbols import Var
from ..checks.types import (BOOL, Elementary, FBType, LiteralT, StructT, common, concrete)
from ..interp.values import base_of
from .terms import TRUE, Frame

INT16 = None


def ident(path):
    s = re.sub(r"[^A-Za-z0-9_]", "_", path.replace("$", "h_"))
    return "v_" + s


class BodyExport:
    # ---------------------------------------------------- expressions
    def place_name(self, r, frame):
        place = self.enc.place(r, frame, TRUE)
        if len(place.alts) != 1:
            self._refuse(frame.pou, r.pos, f"the access '{r!r}' with a variable index")
        cell = place.alts[0][1]
        if cell.bit is not None:
            self._refuse(frame.pou, r.pos, "a bit access")
        v = cell.c[cell.k]
        if isinstance(v, (list, dict)) or not hasattr(v, "sort"):
            self._refuse(frame.pou, r.pos, f"'{r!r}' (an array, structure or instance)")
        name = self.name_of(v, frame.pou, r.pos)
        if name.endswith("_ET") and str(v)[:-3] in self.timer_paths.values():
            self._refuse(frame.pou, r.pos, "a timer's ET (a clock of the timer automaton)")
        return name

    def expr(self, e, frame, want=None):
        """UPPAAL text of e, as a value of type ``want`` (or its own)."""
        t = e.type
        text = self._expr(e, frame)
        return self.conv(text, t, want if want is not None else t)

    def conv(self, text, src, dst):
        if dst is None or src is None:
            return text
        sb = base_of(concrete(src)) if not isinstance(src, LiteralT) else src
        db = base_of(concrete(dst)) if not isinstance(dst, LiteralT) else dst
        sbool = isinstance(sb, Elementary) and sb.cat == "bool"
        dbool = isinstance(db, Elementary) and db.cat == "bool"
        if sbool and not dbool and not isinstance(db, LiteralT):
            return f"({text} ? 1 : 0)"
        if dbool and not sbool:
            return f"({text} != 0)"
        if isinstance(db, Elementary) and isinstance(sb, Elementary) and \
                db.cat in ("sint", "uint", "bit") and sb.cat in ("sint", "uint", "bit"):
            lo, hi = db.range
            slo, shi = sb.range
            if not (lo <= slo and shi <= hi):
                return self.wrap(db, text)
        return text

    def _expr(self, e, frame):
        pou = frame.pou
        if isinstance(e, ast.Lit):
            if e.kind == "bool":
                return "true" if e.value else "false"
            if e.kind == "int":
                return str(int(e.value))
            if e.kind == "time":
                return str(self.ms(e.value, pou, e.pos))
            if e.kind == "enum":
                return str(concrete(e.type).values[e.value.upper()][1])
            self._refuse(pou, e.pos, f"the literal {e.text}")
        if isinstance(e, ast.Ref):
            if isinstance(e.symbol, EnumValue):
                return str(e.symbol.value)
            return self.place_name(e, frame)
        if isinstance(e, ast.Direct):
            return self.name_of(self.sym.direct_value(e.address), pou, e.pos)
        if isinstance(e, ast.CR):
            return self.acc(e.type)
        if isinstance(e, ast.UnOp):
            t = concrete(e.type)
            if isinstance(t, LiteralT) and isinstance(e.operand, ast.Lit):
                return f"(-{e.operand.value})" if e.op == "-" else str(e.operand.value)
            a = self.expr(e.operand, frame, t)
            if e.op == "NOT":
                if base_of(t) is BOOL:
                    return f"(!{a})"
                return self.wrap(t, f"(~{a})") if base_of(t).cat == "sint" else \
                    f"({a} ^ {(1 << base_of(t).bits) - 1})"
            if e.op == "-":
                return self.wrap(t, f"(-{a})")
            return a
        if isinstance(e, ast.BinOp):
            op = e.op
            if op in ("=", "<>", "<", ">", "<=", ">="):
                c = concrete(common(e.left.type, e.right.type))
                a, b = self.expr(e.left, frame, c), self.expr(e.right, frame, c)
                return f"({a} {({'=': '==', '<>': '!='}).get(op, op)} {b})"
            t = concrete(e.type)
            if isinstance(t, LiteralT):
                self._refuse(pou, e.pos, "arithmetic on untyped literals")
            a, b = self.expr(e.left, frame, t), self.expr(e.right, frame, t)
            if op in ("AND", "OR", "XOR"):
                if base_of(t) is BOOL:
                    return f"({a} {({'AND': '&&', 'OR': '||', 'XOR': '!='})[op]} {b})"
                return f"({a} {({'AND': '&', 'OR': '|', 'XOR': '^'})[op]} {b})"
            sym = {"+": "+", "-": "-", "*": "*", "/": "/", "MOD": "%"}.get(op)
            if sym is None:
                self._refuse(pou, e.pos, f"the operator {op}")
            return self.wrap(t, f"({a} {sym} {b})")
        if isinstance(e, ast.Call):
            if not isinstance(e.target, stdlib.StdFunc):
                self._refuse(pou, e.pos, f"the call of FUNCTION {e.name}")
            return self.std(e, frame)
        self._refuse(pou, getattr(e, "pos", None), f"the expression {e!r}")

    def std(self, c, frame):
        f = c.target
        fam = f.family
        args = [a.value for a in c.args if a.kind == "pos" or
                (a.name or "").upper() not in ("EN", "ENO")]
        if len(args) != len(c.args):
            self._refuse(frame.pou, c.pos, "EN/ENO")
        res = c.type
        if fam == "SEL":
            g = self.expr(args[0], frame, BOOL)
            return f"({g} ? {self.expr(args[2], frame, res)} : {self.expr(args[1], frame, res)})"
        if fam in ("MAX", "MIN"):
            xs = [self.expr(a, frame, res) for a in args]
            acc = xs[0]
            for x in xs[1:]:
                acc = f"({acc} {'>=' if fam == 'MAX' else '<='} {x} ? {acc} : {x})"
            return acc
        if fam == "LIMIT":
            mn, v, mx = [self.expr(a, frame, res) for a in args]
            m1 = f"({v} >= {mn} ? {v} : {mn})"
            return f"({m1} <= {mx} ? {m1} : {mx})"
        if fam == "MOVE":
            return self.expr(args[0], frame, res)
        if fam == "ABS":
            a = self.expr(args[0], frame, res)
            return self.wrap(res, f"({a} < 0 ? -{a} : {a})")
        if fam == "CONVERT":
            src = concrete(f.param_types[0])
            return self.conv(self.expr(args[0], frame, src), src, res)
        if fam in stdlib.COMPARE_FAMILIES and len(args) == 2:
            ct = concrete(f.param_types[0])
            a, b = self.expr(args[0], frame, ct), self.expr(args[1], frame, ct)
            op = {"GT": ">", "GE": ">=", "EQ": "==", "LE": "<=", "LT": "<", "NE": "!="}[fam]
            return f"({a} {op} {b})"
        self._refuse(frame.pou, c.pos, f"the standard function {f.name}")

    # ------------------------------------------------------ control flow
    def step(self, update=None, guard=None, sync=None, select=None, name=None):
        nxt = self.task.loc(name)
        self.task.edge(self.cur, nxt, guard, sync, update, select)
        self.cur = nxt
        return nxt

    def assign(self, target, value_text):
        self.step(update=f"{target} = {value_text}")

    def block(self, stmts, frame):
        for s in stmts:
            self.stmt(s, frame)

    def stmt(self, s, frame):
        pou = frame.pou
        if isinstance(s, ast.Assign):
            t = s.target.type
            self.assign(self.place_name(s.target, frame), self.store(
                self.expr(s.value, frame, t), t, pou, s.pos))
        elif isinstance(s, ast.CallStmt):
            c = s.call
            if not isinstance(c.target, Var):
                self._refuse(pou, s.pos, "a FUNCTION called as a statement")
            self.fb_call(c, frame)
        elif isinstance(s, ast.If):
            start = self.cur
            end = self.task.loc()
            rest = []
            for cond, body in s.branches:
                g = self.expr(cond, frame, BOOL)
                guard = " && ".join([f"!({r})" for r in rest] + [g])
                self.cur = start
                self.step(guard=guard)
                self.block(body, frame)
                self.task.edge(self.cur, end)
                rest.append(g)
            self.cur = start
            self.step(guard=" && ".join(f"!({r})" for r in rest))
            if s.else_:
                self.block(s.else_, frame)
            self.task.edge(self.cur, end)
            self.cur = end
        elif isinstance(s, ast.Case):
            st = concrete(s.selector.type)
            sel = self.expr(s.selector, frame, st)
            start = self.cur
            end = self.task.loc()
            taken = []
            for n, values in enumerate(s.values):
                conds = [f"{sel} == {lo}" if lo == hi else f"({sel} >= {lo} && {sel} <= {hi})"
                         for lo, hi in values]
                c = "(" + " || ".join(conds) + ")"
                self.cur = start
                self.step(guard=" && ".join([f"!{t}" for t in taken] + [c]))
                self.block(s.elements[n][1], frame)
                self.task.edge(self.cur, end)
                taken.append(c)
            self.cur = start
            self.step(guard=" && ".join(f"!{t}" for t in taken) or None)
            if s.else_:
                self.block(s.else_, frame)
            self.task.edge(self.cur, end)
            self.cur = end
        elif isinstance(s, ast.For):
            self.for_(s, frame)
        elif isinstance(s, ast.Return):
            self.task.edge(self.cur, self.ret_target)
            self.cur = self.task.loc()     # unreachable continuation
            self.dead.add(self.cur.id)
        elif isinstance(s, ast.Empty):
            pass
        else:
            self._refuse(pou, s.pos, f"the statement {type(s).__name__.upper()}")

    def store(self, text, t, pou, pos):
        ct = concrete(t)
        if isinstance(ct, (StructT,)) or hasattr(ct, "dims"):
            self._refuse(pou, pos, "an array or structure assignment")
        return text

    def for_(self, s, frame):
        pou = frame.pou
        v = pou.var(s.var)
        vals = []
        for e in (s.start, s.end, s.step):
            if e is None:
                vals.append(1)
                continue
            if not isinstance(e, ast.Lit) and not (isinstance(e, ast.UnOp) and
                                                   isinstance(e.operand, ast.Lit)):
                self._refuse(pou, e.pos, "a FOR loop whose bounds are not literals")
            vals.append(e.value if isinstance(e, ast.Lit) else
                        (-e.operand.value if e.op == "-" else e.operand.value))
        a, b, st = vals
        if st == 0:
            self._refuse(pou, s.pos, "a FOR loop with step 0")
        name = self.name_of(frame.inst.v[v.key], pou, s.pos)
        i = a
        n = 0
        lo_t, hi_t = base_of(v.type).range
        while not (i > b if st > 0 else i < b):
            self.assign(name, str(i))
            self.block(s.body, frame)
            n += 1
            if n > 256:
                self._refuse(pou, s.pos, "a FOR loop of more than 256 iterations")
            i += st
            if i < lo_t or i > hi_t:
                return
        self.assign(name, str(i))

    # ------------------------------------------------------ FB calls
    def fb_call(self, c, frame):
        pou = frame.pou
        place = self.enc.place(_ref(c.target, c.pos), frame, TRUE)
        if len(place.alts) != 1:
            self._refuse(pou, c.pos, "a call of an instance chosen by a variable index")
        inst = place.alts[0][1].c[place.alts[0][1].k]
        fpou = inst.pou
        for a in c.args:
            if (a.name or "").upper() in ("EN", "ENO"):
                self._refuse(pou, c.pos, "EN/ENO")
        ins, outs = [], []
        for key, a in (c.bound or {}).items():
            param = fpou.vars[key]
            if a.kind == "out":
                if a.value is not None:
                    outs.append((param, a))
            elif param.section == "VAR_IN_OUT":
                self._refuse(pou, a.pos, "a VAR_IN_OUT argument")
            elif a.value is not None:
                ins.append((param, a.value))
        pfx = Frame(inst, fpou)
        for param, value in ins:
            self.assign(self.name_of(inst.v[param.key], pou, value.pos),
                        self.expr(value, frame, param.type))
        v_eno = fpou.var("ENO")
        if v_eno is not None and v_eno.section == "VAR_OUTPUT":
            # ENO is TRUE when the body starts (the body may set it FALSE);
            # calls with EN are refused, so a standard block's stays TRUE
            self.assign(self.name_of(inst.v[v_eno.key], pou, c.pos), "true")
        if fpou.standard:
            self.std_fb(fpou, inst, pou, c.pos)
        else:
            self.body(fpou, pfx)
        for param, a in outs:
            val = self.name_of(inst.v[param.key], pou, a.pos)
            if a.negate:
                val = f"!{val}"
            self.assign(self.place_name(a.value, frame), self.conv(val, param.type,
                                                                     a.value.type))

    def std_fb(self, fpou, inst, pou, pos):
        name = fpou.name.upper()

        def n(k):
            return self.name_of(inst.v[k], pou, pos)
        if name in ("TON", "TOF", "TP"):
            base = ident(self.timer_paths[id(inst)])
            if not any(b == base for b, _ in self.timers):
                self.timers.append((base, name))
            self.step(sync=f"{base}_call!")
            return
        if name == "R_TRIG":
            m = f"{n('Q')[:-2]}_M"
            self.extra.add(f"bool {m} = false;")
            self.step(update=f"{n('Q')} = {n('CLK')} && !{m}, {m} = {n('CLK')}")
        elif name == "F_TRIG":
            m = f"{n('Q')[:-2]}_M"
            self.extra.add(f"bool {m} = true;")
            self.step(update=f"{n('Q')} = !{n('CLK')} && !{m}, {m} = !{n('CLK')}")
        elif name == "SR":
            self.step(update=f"{n('Q1')} = {n('S1')} || (!{n('R')} && {n('Q1')})")
        elif name == "RS":
            self.step(update=f"{n('Q1')} = !{n('R1')} && ({n('S')} || {n('Q1')})")
        elif name in ("CTU", "CTD", "CTUD"):
            lo, hi = base_of(fpou.vars["CV"].type).range
            cv, pv = n("CV"), n("PV")
            pre = n("CV")[:-3]
            ups = []
            if name in ("CTU", "CTUD"):
                self.extra.add(f"bool {pre}_CUM = false;")
                ups.append(f"{pre}_e_cu = {n('CU')} && !{pre}_CUM, {pre}_CUM = {n('CU')}")
                self.extra.add(f"bool {pre}_e_cu = false;")
            if name in ("CTD", "CTUD"):
                self.extra.add(f"bool {pre}_CDM = false;")
                ups.append(f"{pre}_e_cd = {n('CD')} && !{pre}_CDM, {pre}_CDM = {n('CD')}")
                self.extra.add(f"bool {pre}_e_cd = false;")
            up = f"{pre}_e_cu && {cv} < {hi}"
            down = f"{pre}_e_cd && {cv} > {lo}"
            if name == "CTU":
                new = f"({n('R')} ? 0 : ({up} ? {cv} + 1 : {cv}))"
                ups.append(f"{cv} = {new}, {n('Q')} = {cv} >= {pv}")
            elif name == "CTD":
                new = f"({n('LD')} ? {pv} : ({down} ? {cv} - 1 : {cv}))"
                ups.append(f"{cv} = {new}, {n('Q')} = {cv} <= 0")
            else:
                new = (f"({n('R')} ? 0 : ({n('LD')} ? {pv} : (({pre}_e_cu && {pre}_e_cd) ? {cv} "
                       f": ({up} ? {cv} + 1 : ({down} ? {cv} - 1 : {cv})))))")
                ups.append(f"{cv} = {new}, {n('QU')} = {cv} >= {pv}, {n('QD')} = {cv} <= 0")
            self.step(update=", ".join(ups))
        else:
            self._refuse(pou, pos, f"the standard function block {fpou.name}")

    def body(self, pou, frame):
        saved_ret = self.ret_target
        self.ret_target = self.task.loc()
        for v in pou.vars.values():
            if v.section == "VAR_TEMP":
                self._refuse(pou, v.pos, "VAR_TEMP")
            if v.section == "VAR_INPUT" and v.edge:
                self._refuse(pou, v.pos, "an R_EDGE/F_EDGE input")
        if pou.node.language == "IL":
            self.il(pou.node.body, frame)
        else:
            self.block(pou.node.body, frame)
        self.task.edge(self.cur, self.ret_target)
        self.cur = self.ret_target
        self.ret_target = saved_ret

    # -------------------------------------------------------------- IL
    def il(self, instrs, frame):
        """Seed 004: one edge per instruction, the current result in cr0
        (cr1, cr2... inside parentheses)."""
        pou = frame.pou
        labels = {}
        for n, i in enumerate(instrs):
            if i.label:
                labels[i.label.upper()] = n
        locs = [self.task.loc() for _ in instrs]
        end = self.task.loc()
        self.task.edge(self.cur, locs[0] if locs else end)
        self.depth = 0
        for n, i in enumerate(instrs):
            self.cur = locs[n]
            nxt = locs[n + 1] if n + 1 < len(instrs) else end
            op = i.op
            if op in ("JMP", "JMPC", "JMPCN", "RET", "RETC", "RETCN"):
                target = self.ret_target if op.startswith("RET") else \
                    locs[labels[i.operand.name.upper()]]
                c = self.conv(self.acc(i.cr_in), i.cr_in, BOOL) \
                    if op not in ("JMP", "RET") else None
                if op in ("JMP", "RET"):
                    self.task.edge(self.cur, target)
                else:
                    want = op in ("JMPC", "RETC")
                    self.task.edge(self.cur, target, guard=c if want else f"!{c}")
                    self.task.edge(self.cur, nxt, guard=f"!{c}" if want else c)
                continue
            self.il_instr(i, frame, pou)
            self.task.edge(self.cur, nxt)
        self.cur = end

    def acc(self, t):
        """The accumulator (seed 004) of the current nesting level for a
        current result of type t: crb<level> for BOOL, cr<level> otherwise."""
        self._crs = max(getattr(self, "_crs", 0), self.depth)
        return f"crb{self.depth}" if _is_bool(t) else f"cr{self.depth}"

    def il_instr(self, i, frame, pou):
        op = i.op
        cr = self.acc(i.cr_in)
        if op is None:
            self.step(update=f"{self.acc(i.cr_out)} = {self.expr(i.call, frame, None)}")
            return
        if i.deferred:
            out = self.acc(i.cr_out)
            self.depth += 1
            inner_t = i.nested[-1].cr_out if i.nested else i.operand.type
            if i.operand is not None:
                self.step(update=f"{self.acc(i.operand.type)} = {self.expr(i.operand, frame, None)}")
            for j in i.nested:
                self.il_instr(j, frame, pou)
            inner = self.acc(inner_t)
            self.depth -= 1
            self.step(update=f"{out} = {self.combine(op, cr, i.cr_in, inner, inner_t, pou, i.pos)}")
            return
        if op in ("LD", "LDN"):
            v = self.expr(i.operand, frame, None if not _is_bool(i.cr_out) else BOOL)
            if op == "LDN":
                if not _is_bool(i.cr_out):
                    self._refuse(pou, i.pos, "LDN of an integer")
                v = f"!{v}"
            self.step(update=f"{self.acc(i.cr_out)} = {v}")
            return
        if op in ("ST", "STN"):
            t = i.operand.type
            v = self.conv(cr, i.cr_in, t) if not _is_bool(i.cr_in) else cr
            if op == "STN":
                if not _is_bool(i.cr_in):
                    self._refuse(pou, i.pos, "STN of an integer")
                v = f"!{v}"
            self.assign(self.place_name(i.operand, frame), v)
            return
        if op in ("S", "R") and not isinstance(getattr(i.operand, "type", None), FBType):
            name = self.place_name(i.operand, frame)
            c = self.conv(cr, i.cr_in, BOOL)
            self.step(update=f"{name} = {c} ? {'true' if op == 'S' else 'false'} : {name}")
            return
        if op in ("S1", "R1", "CLK", "CU", "CD", "PV", "IN", "PT", "S", "R", "LD"):
            inst = self.enc.place(_ref(i.operand.symbol, i.pos), frame, TRUE).alts[0][1]
            inst = inst.c[inst.k]
            param = inst.pou.var(op)
            self.assign(self.name_of(inst.v[param.key], pou, i.pos),
                        self.conv(cr, i.cr_in, param.type))
            return
        if op == "NOT":
            if not _is_bool(i.cr_in):
                self._refuse(pou, i.pos, "NOT of an integer current result")
            self.step(update=f"{cr} = !{cr}")
            return
        if op in ("CAL", "CALC", "CALCN"):
            if op != "CAL":
                start = self.cur
                end = self.task.loc()
                c = self.conv(cr, i.cr_in, BOOL)
                self.step(guard=c if op == "CALC" else f"!{c}")
                self.fb_call(i.call, frame)
                self.task.edge(self.cur, end)
                self.task.edge(start, end, guard=f"!{c}" if op == "CALC" else c)
                self.cur = end
            else:
                self.fb_call(i.call, frame)
            return
        if op == "NOP":
            return
        b = self.expr(i.operand, frame, None)
        self.step(update=f"{self.acc(i.cr_out)} = "
                         f"{self.combine(op, cr, i.cr_in, b, i.operand.type, pou, i.pos)}")

    def combine(self, op, a, at, b, bt, pou, pos):
        base = op[:-1] if op in ("ANDN", "ORN", "XORN") else op
        neg = op in ("ANDN", "ORN", "XORN")
        if base in ("AND", "OR", "XOR"):
            if _is_bool(at):
                b = self.conv(b, bt, BOOL)
                if neg:
                    b = f"!{b}"
                return f"({a} {({'AND': '&&', 'OR': '||', 'XOR': '!='})[base]} {b})"
            self._refuse(pou, pos, f"{op} on integers")
        t = concrete(common(at, bt)) if not isinstance(common(at, bt), LiteralT) else INT16
        if base in stdlib.COMPARE_FAMILIES:
            o = {"GT": ">", "GE": ">=", "EQ": "==", "NE": "!=", "LE": "<=", "LT": "<"}[base]
            return f"({a} {o} {self.conv(b, bt, t)})"
        o = {"ADD": "+", "SUB": "-", "MUL": "*", "DIV": "/", "MOD": "%"}.get(base)
        if o is None:
            self._refuse(pou, pos, f"the IL operator {op}")
        return self.wrap(t, f"({a} {o} {self.conv(b, bt, t)})")


def _is_bool(t):
    return t is not None and not isinstance(t, LiteralT) and base_of(concrete(t)) is BOOL


def _ref(var, pos):
    r = ast.Ref(pos, var.name, [])
    r.symbol = var
    r.type = var.type
    return r
