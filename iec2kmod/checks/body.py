"""Pass 'resolve': name resolution and strong typing of every POU body, ST
and IL.  Every expression gets ``.type``; every variable access gets
``.symbol``; every call gets ``.target``."""

from __future__ import annotations

from .. import ast
from ..diagnostics import INPUT_WRITE_RULE
from . import fold, stdlib
from .il import ILChecks
from .settle import settle
from .symbols import POUInfo, Var
from .types import (BOOL, ELEMENTARY, ERROR, AnyIntResult, ArrayT, Elementary, EnumT, ErrorT, FBType,
                    LiteralT, StringT, StructT, SubrangeT, assignable, cat, common,
                    concrete, concrete_bits, identical, is_bit, is_bool, is_int,
                    literal_fits)

ARITH = {"+": "ADD", "-": "SUB", "*": "MUL", "/": "DIV", "MOD": "MOD"}
COMPARE = {"=": "EQ", "<>": "NE", "<": "LT", ">": "GT", "<=": "LE", ">=": "GE"}
LOGIC = {"AND", "OR", "XOR"}



class EnumValue:
    """What an unqualified or qualified enumeration value resolves to."""

    def __init__(self, enum, name):
        self.enum = enum
        self.name = name
        self.value = enum.values[name.upper()][1]


class BodyChecker(ILChecks):
    def __init__(self, project, declarer, diags, pou: POUInfo):
        self.p = project
        self.decl = declarer
        self.diags = diags
        self.pou = pou
        self.src = pou.src
        self.loop_vars: list[Var] = []
        self.loop_depth = 0
        self.depth = 0          # of expr() calls under way
        self.roots: list = []   # expressions checked at depth 0, settled at the end

    def error(self, pos, msg):
        self.diags.error(self.src, pos, msg)

    def warning(self, pos, msg):
        self.diags.warning(self.src, pos, msg)

    # ------------------------------------------------------------ entry
    def check(self):
        scope = self.decl.pou_scope(self.pou)
        with self.decl.constants_of(scope):
            self._check()
            self.settle_roots()
        self.decl.mark_used(scope, self.pou.vars)

    def settle_roots(self):
        """The types every standard call checked so far is computed in
        (checks/settle.py): once the statements around them are checked,
        for check_assign gives an untyped value its target's type."""
        for e in self.roots:
            settle(e)
        self.roots = []

    def _check(self):
        node = self.pou.node
        if node.language == "SFC":
            from .sfc import SFCChecker
            if node.sfc is not None and self.pou.kind != "FUNCTION":
                SFCChecker(self).check()
        elif node.language == "IL":
            self.check_il(node.body)
        else:
            self.stmts(node.body)

    # ------------------------------------------------------- statements
    def stmts(self, lst):
        for s in lst:
            self.stmt(s)

    def stmt(self, s):
        if isinstance(s, ast.Assign):
            tt = self.lvalue(s.target)
            vt = self.expr(s.value)
            self.check_assign(vt, tt, s.value, s.target)
        elif isinstance(s, ast.CallStmt):
            self.call(s.call, statement=True)
        elif isinstance(s, ast.If):
            for cond, body in s.branches:
                self.condition(cond, "IF")
                self.stmts(body)
            if s.else_:
                self.stmts(s.else_)
        elif isinstance(s, ast.Case):
            self.case(s)
        elif isinstance(s, ast.For):
            self.for_(s)
        elif isinstance(s, ast.While):
            self.condition(s.cond, "WHILE")
            self.loop_depth += 1
            self.stmts(s.body)
            self.loop_depth -= 1
        elif isinstance(s, ast.Repeat):
            self.loop_depth += 1
            self.stmts(s.body)
            self.loop_depth -= 1
            self.condition(s.cond, "UNTIL")
        elif isinstance(s, ast.Exit):
            if self.loop_depth == 0:
                self.error(s.pos, "EXIT outside of a loop")
        elif isinstance(s, ast.Continue):
            if self.loop_depth == 0:
                self.error(s.pos, "CONTINUE outside of a loop")
        elif isinstance(s, (ast.Return, ast.Empty)):
            pass
        else:
            raise AssertionError(f"unknown statement {s!r}")

    def condition(self, cond, what):
        t = self.expr(cond)
        if not isinstance(t, ErrorT) and not is_bool(t):
            self.error(cond.pos, f"{what} condition must be BOOL, not {t.name}")

    def check_assign(self, vt, tt, value, target_node, what=None):
        if isinstance(vt, ErrorT) or isinstance(tt, ErrorT) or tt is None or vt is None:
            return
        if isinstance(tt, FBType) or isinstance(vt, FBType):
            self.error(value.pos, "function block instances cannot be assigned")
            return
        bcd = stdlib.bcd_by_context(getattr(value, "target", None), tt)
        if bcd is not None and isinstance(value, ast.Call):
            value.target = bcd
            value.type = vt = bcd.result
        if assignable(vt, tt):
            if isinstance(vt, LiteralT):
                value.type = tt.base if isinstance(tt, SubrangeT) else tt
            if isinstance(tt, SubrangeT) and isinstance(value, ast.Expr):
                v = _literal_value(value)
                if v is not None and not tt.low <= v <= tt.high:
                    self.error(value.pos, f"{v} is outside the subrange {tt.low}..{tt.high} "
                                          f"of {tt.name}")
            return
        if isinstance(vt, AnyIntResult):
            self.error(value.pos, f"{vt.generic} gives an integer (ANY_INT), and {tt.name} is not "
                                  f"one: convert it explicitly (e.g. DINT_TO_{tt.name})"
                       if isinstance(tt.base, Elementary) else
                       f"{vt.generic} gives an integer (ANY_INT), not {tt.name}")
            return
        if isinstance(vt, LiteralT) and isinstance(tt.base, Elementary) and vt.cat == "int":
            if tt.base.cat in ("sint", "uint", "bit", "bool"):
                self.error(value.pos, f"{vt.value} is out of range for {tt.name}")
                return
            if tt.base.cat in ("time", "date", "tod", "dt"):
                example = {"time": "T#5s", "date": "D#2024-01-31", "tod": "TOD#08:30:00",
                           "dt": "DT#2024-01-31-08:30:00"}[tt.base.cat]
                self.error(value.pos, f"an integer is not a {tt.base.name}: write a literal "
                                      f"such as {example}")
                return
        msg = f"cannot assign {vt.name} to {what or _describe(target_node)} of type {tt.name}"
        s, d = concrete(vt).base, tt.base
        if isinstance(s, (Elementary, StringT)) and isinstance(d, (Elementary, StringT)) and \
                stdlib.conversion(f"{_tname(s)}_TO_{_tname(d)}"):
            msg += f": convert explicitly with {_tname(s)}_TO_{_tname(d)}"
        self.error(value.pos, msg)

    def case(self, s):
        st = self.expr(s.selector)
        if not isinstance(st, ErrorT) and not (is_int(st) or isinstance(st, EnumT)):
            self.error(s.selector.pos, f"CASE selector must be an integer or an enumeration, "
                                       f"not {st.name}")
            st = ERROR
        seen: list[tuple[int, int, int]] = []
        s.values = []
        for labels, body in s.elements:
            values = []
            s.values.append(values)
            for low, high in labels:
                lo = self.case_label(low, st)
                hi = self.case_label(high, st) if high is not None else lo
                if lo is None or hi is None:
                    continue
                values.append((lo, hi))
                if lo > hi:
                    self.error(low.pos, f"empty CASE range {lo}..{hi}")
                    continue
                for a, b, _ in seen:
                    if lo <= b and a <= hi:
                        self.error(low.pos, "duplicate CASE label: "
                                            f"{_label_text(low, high)} overlaps an earlier label")
                        break
                seen.append((lo, hi, low.pos))
            self.stmts(body)
        if s.else_:
            self.stmts(s.else_)

    def case_label(self, e, st):
        if isinstance(st, EnumT):
            if isinstance(e, ast.Ref) and not e.accessors and st.has(e.name):
                e.type = st
                e.symbol = EnumValue(st, e.name)
                return st.values[e.name.upper()][1]
            if isinstance(e, ast.Lit) and e.kind == "enum":
                t = self.decl.lookup_type(e.type_name, self.src, e.pos, report=False)
                if t is st and st.has(e.value):
                    e.type = st
                    return st.values[e.value.upper()][1]
            self.error(e.pos, f"CASE label must be a value of {st.name}")
            return None
        if (isinstance(e, ast.Lit) and e.kind == "enum") or (
                isinstance(e, ast.Ref) and not e.accessors and self.pou.var(e.name) is None
                and self.decl.enum_values.get(e.name.upper())):
            self.error(e.pos, f"CASE label {e!r} is an enumeration value; the selector is "
                              f"{st.name}")
            return None
        try:
            v = self.decl.const_value(e, self.src, "CASE label")
        except Exception as exc:  # ConstError
            self.error(e.pos, str(exc))
            return None
        if isinstance(v, bool) or not isinstance(v, int):
            self.error(e.pos, "CASE label must be an integer constant")
            return None
        if isinstance(st, (Elementary, SubrangeT)):
            rng = st.base.range
            if rng and not rng[0] <= v <= rng[1]:
                self.error(e.pos, f"CASE label {v} is out of range for {st.name}")
                return None
        e.type = st
        return v

    def for_(self, s):
        v = self.pou.var(s.var)
        if v is None:
            self.error(s.var_pos, f"unknown variable '{s.var}'")
            vt = ERROR
        else:
            v.used = True
            v.assigned = True
            vt = v.type
            if v.section == "VAR_INPUT":
                # the standard asks of the control variable only an integer
                # type and no change by the repeated statements (ed.2
                # 3.3.2.4, ed.3 7.3.3.4.2), not a local: an input as control
                # variable is a write to the input, under that rule
                self.input_write(s.var_pos, v)
            elif v.section not in ("VAR", "VAR_TEMP"):
                self.error(s.var_pos, f"FOR control variable '{s.var}' must be a local variable "
                                      f"(VAR or VAR_TEMP), not {v.section}")
            elif not is_int(vt):
                self.error(s.var_pos, f"FOR control variable must be an integer, not {vt.name}")
                vt = ERROR
            elif isinstance(vt, SubrangeT):
                self.error(s.var_pos, "FOR control variable cannot be of a subrange type")
            if v in self.loop_vars:
                self.error(s.var_pos, f"'{s.var}' is already the control variable of an "
                                      "enclosing FOR loop")
        for e, what in ((s.start, "start"), (s.end, "end"), (s.step, "step")):
            if e is None:
                continue
            t = self.expr(e)
            self.check_assign(t, vt, e, None, what=f"FOR {what} of '{s.var}'")
        if s.step is not None:
            try:
                step = self.decl.const_value(s.step, self.src)
                if step == 0:
                    self.error(s.step.pos, "FOR step must not be 0")
            except Exception:
                pass
        self.loop_depth += 1
        if v is not None:
            self.loop_vars.append(v)
        self.stmts(s.body)
        if v is not None:
            self.loop_vars.pop()
        self.loop_depth -= 1

    # ------------------------------------------------------- variables
    def lookup(self, name, pos, report=True):
        v = self.pou.var(name)
        if v is not None:
            return v
        hits = self.decl.enum_values.get(name.upper(), [])
        if len(hits) == 1:
            return EnumValue(hits[0], name)
        if len(hits) > 1:
            if report:
                self.error(pos, f"'{name}' is a value of several enumerations "
                                f"({', '.join(h.name for h in hits)}): qualify it as Type#{name}")
            return None
        if report:
            if name.upper() in self.p.pous or name.upper() in self.p.types:
                self.error(pos, f"'{name}' is not a variable")
            else:
                self.error(pos, f"unknown variable '{name}'")
        return None

    def ref(self, r: ast.Ref, write=False):
        sym = self.lookup(r.name, r.pos)
        if sym is None:
            r.type = ERROR
            return ERROR
        r.symbol = sym
        if isinstance(sym, EnumValue):
            if write:
                self.error(r.pos, f"cannot assign to the enumeration value '{r.name}'")
            if r.accessors:
                self.error(r.accessors[0][2], "an enumeration value has no members")
            r.type = sym.enum
            return sym.enum
        sym.used = True
        t = sym.type
        fb_member_of = None
        for kind, val, pos in r.accessors:
            if isinstance(t, ErrorT):
                break
            if kind == "index":
                t = self.index(t, val, pos)
            elif kind == "member":
                base = t
                t, fb_member_of = self.member(t, val, pos)
                if write and isinstance(base, FBType) and fb_member_of is not None and \
                        fb_member_of.section == "VAR_OUTPUT":
                    self.error(pos, f"output '{val}' of function block instance "
                                    f"'{r.name}' cannot be assigned")
            else:
                bt = t.base
                if not (isinstance(bt, Elementary) and bt.cat in ("bit", "sint", "uint")):
                    self.error(pos, f"bit access .{val} needs a bit string, not {t.name}")
                    t = ERROR
                elif val >= bt.bits:
                    self.error(pos, f"bit {val} does not exist in {bt.name} "
                                    f"(bits 0..{bt.bits - 1})")
                    t = ERROR
                else:
                    t = BOOL
        if write:
            self.check_writable(sym, r)
        r.type = t
        return t

    def check_writable(self, v: Var, r: ast.Ref):
        member_write = any(k == "member" for k, _, _ in r.accessors) and isinstance(v.type, FBType)
        if v.step is not None:
            self.error(r.pos, f"cannot assign to step '{v.name}': only transitions change a "
                              "step's state")
        elif v.section == "VAR_INPUT" and not member_write:
            self.input_write(r.pos, v, part=bool(r.accessors))
            v.assigned = True
        elif v.constant:
            self.error(r.pos, f"cannot assign to constant '{v.name}'")
        elif v in self.loop_vars and not r.accessors:
            self.error(r.pos, f"cannot assign to '{v.name}': it controls the enclosing FOR loop")
        else:
            v.assigned = True

    def input_write(self, pos, v: Var, part=False):
        """A write to an input inside its own POU: a warning naming the rule
        (an error under --strict, diagnostics.STRICT_RULES)."""
        what = f"a part of input '{v.name}'" if part else f"input '{v.name}'"
        t = v.type.base if v.type is not None else None
        if self.pou.kind == "FUNCTION" and isinstance(t, (ArrayT, StructT, StringT)):
            # the C code passes it by reference (a const pointer): a function
            # that writes it works on a copy, made when it is called
            v.copied = True
        self.warning(pos, f"{INPUT_WRITE_RULE} {what} inside its "
                          f"{self.pou.kind.lower().replace('_', ' ')}: an input is set by the "
                          "caller and is read-only inside the POU by the rule IEC 61131-3 tools "
                          "check (Beckhoff SA0037); accepted as CODESYS, TwinCAT and MatIEC "
                          "accept it, the write changing the POU's own copy of the input, not the "
                          "caller's variable; "
                          "--strict makes it an error")

    def index(self, t, indexes, pos):
        if not isinstance(t, ArrayT):
            self.error(pos, f"{t.name} is not an array")
            for e in indexes:
                self.expr(e)
            return ERROR
        if len(indexes) != len(t.dims):
            self.error(pos, f"array has {len(t.dims)} dimension(s), {len(indexes)} index(es) given")
        for e, (lo, hi) in zip(indexes, t.dims):
            it = self.expr(e)
            if not isinstance(it, ErrorT) and not is_int(it):
                self.error(e.pos, f"array index must be an integer, not {it.name}")
                continue
            v = _literal_value(e)
            if v is not None and not lo <= v <= hi:
                self.error(e.pos, f"index {v} is out of bounds {lo}..{hi}")
            if isinstance(it, LiteralT):
                e.type = concrete(it)
        for e in indexes[len(t.dims):]:
            self.expr(e)
        return t.elem

    def member(self, t, name, pos):
        if isinstance(t, StructT):
            f = t.fields.get(name.upper())
            if f is None:
                self.error(pos, f"structure {t.name} has no member '{name}'")
                return ERROR, None
            return f[1], None
        if isinstance(t, FBType):
            v = t.pou.var(name)
            if v is None or v.section not in ("VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT"):
                if v is None:
                    self.error(pos, f"function block {t.name} has no input or output '{name}'")
                else:
                    self.error(pos, f"'{name}' is internal to function block {t.name}")
                return ERROR, None
            if v.section == "VAR_IN_OUT":
                # the instance holds a reference to the variable its last call
                # connected (none before the first call): only its body uses
                # it; the caller has the variable (read or write: the C of
                # such an access did not compile, and a read before the
                # first call would follow a null reference)
                self.error(pos, f"'{name}' is a VAR_IN_OUT of function block {t.name}: it "
                                "refers to the variable the caller connects and cannot be "
                                "used through the instance; use the connected variable "
                                "itself")
                return ERROR, None
            return v.type, v
        self.error(pos, f"{t.name} has no members")
        return ERROR, None

    def lvalue(self, r):
        if isinstance(r, ast.Ref):
            return self.ref(r, write=True)
        self.error(r.pos, "cannot assign to this expression")
        return ERROR

    # ------------------------------------------------------ expressions
    def expr(self, e):
        if self.depth == 0:
            self.roots.append(e)
        self.depth += 1
        try:
            t = self._expr(e)
        finally:
            self.depth -= 1
        e.type = t
        e.const = fold.node(e)
        return t

    def _expr(self, e):
        if isinstance(e, ast.Lit):
            return self.literal(e)
        if isinstance(e, ast.Ref):
            return self.ref(e)
        if isinstance(e, ast.BinOp):
            return self.binop(e)
        if isinstance(e, ast.UnOp):
            return self.unop(e)
        if isinstance(e, ast.Call):
            return self.call(e, statement=False)
        if isinstance(e, ast.CR):
            return e.cr_type
        if isinstance(e, ast.Direct):
            what = self.pou.kind.lower().replace("_", " ")
            self.error(e.pos, f"directly represented variable {e.address} used in a {what}: "
                              "only a PROGRAM's statements may name an address (iec2kmod "
                              "reaches it through the one variable located there); declare it "
                              "with a name in the program's VAR or in the "
                              f"configuration's VAR_GLOBAL (name AT {e.address} : ...) and use "
                              "that name here (through VAR_EXTERNAL for a global), or connect "
                              "it to an input or output of the program "
                              f"(PROGRAM inst WITH task : type (x {'=>' if e.address[1] == 'Q' else ':='} "
                              f"{e.address}))")
            return ERROR
        raise AssertionError(f"unknown expression {e!r}")

    def literal(self, e: ast.Lit):
        k = e.kind
        if e.type_name and k in ("int", "real", "bool", "string", "wstring"):
            t = self.decl.lookup_type(e.type_name, self.src, e.pos, report=False)
            if t is None or not isinstance(t.base, (Elementary, StringT)):
                self.error(e.pos, f"unknown type '{e.type_name}' in literal {e.text}")
                return ERROR
            if k in ("string", "wstring"):
                if not isinstance(t, StringT):
                    self.error(e.pos, f"{e.text}: a string cannot be a {t.name}")
                    return ERROR
                return StringT(max(len(e.value), 1), k == "wstring")
            lit = LiteralT("real" if k == "real" else "int", int(e.value) if k == "bool" else e.value)
            if not literal_fits(lit, t):
                self.error(e.pos, f"{e.text}: value does not fit {t.name}")
                return ERROR
            return t
        if k == "int":
            return LiteralT("int", e.value)
        if k == "real":
            return LiteralT("real", e.value)
        if k == "bool":
            return BOOL
        if k == "time":
            return ELEMENTARY[e.type_name or "TIME"]
        if k in ("date", "tod", "dt"):
            return ELEMENTARY[e.type_name]
        if k in ("string", "wstring"):
            return StringT(max(len(e.value), 1), k == "wstring")
        if k == "enum":
            t = self.decl.lookup_type(e.type_name, self.src, e.pos, report=False)
            if not isinstance(t, EnumT):
                self.error(e.pos, f"'{e.type_name}' is not an enumeration type")
                return ERROR
            if not t.has(e.value):
                self.error(e.pos, f"'{e.value}' is not a value of {t.name}")
                return ERROR
            return t
        raise AssertionError(k)

    def binop(self, e: ast.BinOp):
        lt = self.expr(e.left)
        rt = self.expr(e.right)
        if isinstance(lt, ErrorT) or isinstance(rt, ErrorT):
            return ERROR
        op = e.op
        if op in ARITH or op == "**":
            name = ARITH.get(op, "EXPT")
            try:
                f = stdlib.resolve(name, [lt, rt])
            except stdlib.CallError as exc:
                self.error(e.pos, f"operator {op}: {stdlib.operand_message(exc, lt, rt)}")
                return ERROR
            e.fn = f
            self._fold(e, f.result)
            return f.result
        if op in COMPARE:
            c = common(lt, rt)
            if c is None or isinstance(c, FBType) or isinstance(c, (ArrayT, StructT)):
                self.error(e.pos, f"cannot compare {lt.name} with {rt.name}")
                return ERROR
            return BOOL
        if op in LOGIC:
            if not is_bit(lt) or not is_bit(rt):
                bad = lt if not is_bit(lt) else rt
                self.error(e.pos, f"operator {op} needs BOOL or bit string operands, not {bad.name}")
                return ERROR
            c = common(lt, rt)
            if c is None:
                self.error(e.pos, f"operator {op}: incompatible operands {lt.name} and {rt.name}")
                return ERROR
            if isinstance(c, LiteralT):
                if c.cat != "int":
                    return ERROR
                if isinstance(c, AnyIntResult):
                    return concrete(c)
                return self._literal_bits(e, op, lt, rt)
            return c
        raise AssertionError(op)

    def _literal_bits(self, e, op, *lits):
        """The type of AND, OR, XOR or NOT on untyped integer literals:
        types.concrete_bits (DWORD, LWORD beyond 32 bits)."""
        t = concrete_bits(*lits)
        if t is None:
            bad = next(lit.value for lit in lits if concrete_bits(lit) is None)
            self.error(e.pos, f"operator {op} on untyped literals: {bad} is not a bit string "
                              f"value (0 .. 16#FFFF_FFFF_FFFF_FFFF)")
            return ERROR
        return t

    def _fold(self, e, t):
        if isinstance(t, LiteralT):
            v = _literal_value(e)
            if v is not None:
                t.value = v

    def unop(self, e: ast.UnOp):
        t = self.expr(e.operand)
        if isinstance(t, ErrorT):
            return ERROR
        if e.op == "NOT":
            if not is_bit(t):
                self.error(e.pos, f"NOT needs BOOL or a bit string, not {t.name}")
                return ERROR
            if isinstance(t, LiteralT) and not isinstance(t, AnyIntResult):
                return self._literal_bits(e, "NOT", t)
            return concrete(t)
        if isinstance(t, LiteralT):
            v = _literal_value(e)
            return LiteralT(t.cat, v if v is not None else 0)
        c = cat(t)
        if e.op == "-" and c == "uint":
            self.error(e.pos, f"unary minus on unsigned {t.name}: convert it to a signed type first")
            return ERROR
        if c not in ("sint", "uint", "real", "time"):
            self.error(e.pos, f"unary {e.op} needs a number or TIME, not {t.name}")
            return ERROR
        return t.base if isinstance(t, SubrangeT) else t

    # ------------------------------------------------------------ calls
    def call(self, c: ast.Call, statement: bool):
        if statement:
            self.roots.append(c)
        if c.ref is not None:
            return self.element_call(c)
        key = c.name.upper()
        if not statement or self.pou.var(c.name) is not None:
            v = self.pou.var(c.name)
            if v is not None and v.section != "RESULT":
                if isinstance(v.type, FBType):
                    if not statement:
                        self.error(c.pos, f"function block instance '{c.name}' called inside an "
                                          "expression: call it as a statement, then read its "
                                          "outputs")
                        return ERROR
                    v.used = True
                    c.target = v
                    self.pou.calls.add(v.type.pou.key)
                    self.fb_args(c, v.type.pou)
                    return None
                self.error(c.pos, f"'{c.name}' is a variable of type {v.type.name}, not a "
                                  "function")
                self.args_exprs(c)
                return ERROR
        pou = self.p.pous.get(key)
        if pou is not None:
            if pou.kind == "FUNCTION":
                c.target = pou
                self.pou.calls.add(key)
                return self.user_function(c, pou)
            self.error(c.pos, f"'{c.name}' is a {pou.kind.lower().replace('_', ' ')} type: "
                              "declare an instance and call the instance")
            self.args_exprs(c)
            return ERROR
        if stdlib.is_std_function(key):
            return self.std_function(c)
        if key in stdlib.FUNCTION_BLOCKS:
            self.error(c.pos, f"'{c.name}' is a standard function block type: declare an "
                              "instance and call the instance")
        else:
            self.error(c.pos, f"unknown function '{c.name}'" + _vendor_note(key))
        self.args_exprs(c)
        return ERROR

    def element_call(self, c: ast.Call):
        """A call statement of an element of an array of FB instances,
        t[i](IN := x) (ed.3 6.6.3.4: an instance is any variable of a
        function block type).  Only array indexes may lead to it."""
        r = c.ref
        if any(k != "index" for k, _, _ in r.accessors):
            self.error(r.pos, f"'{r!r}' cannot be called: only an element of an array of "
                              "function block instances can be called this way")
            self.args_exprs(c)
            return ERROR
        t = self.ref(r)
        if isinstance(t, ErrorT):
            self.args_exprs(c)
            return ERROR
        if not isinstance(t, FBType):
            self.error(r.pos, f"'{r!r}' is {t.name}, not a function block instance: it cannot be "
                              "called")
            self.args_exprs(c)
            return ERROR
        c.target = r.symbol
        self.pou.calls.add(t.pou.key)
        self.fb_args(c, t.pou)
        return None

    def args_exprs(self, c):
        for a in c.args:
            if a.value is not None:
                self.expr(a.value) if a.kind != "out" else self.lvalue(a.value)

    def _en_eno(self, a) -> bool:
        """EN := BOOL input and ENO => BOOL output, allowed on every call."""
        up = a.name.upper() if a.name else None
        if a.kind == "in" and up == "EN":
            if a.value is not None:
                t = self.expr(a.value)
                self.check_assign(t, BOOL, a.value, None, what="EN")
            return True
        if a.kind == "out" and up == "ENO":
            if a.value is not None:
                t = self.lvalue(a.value)
                if not isinstance(t, ErrorT) and t is not BOOL:
                    self.error(a.value.pos, f"ENO is BOOL, not {t.name}")
            return True
        return False

    def _order(self, c):
        seen_formal = False
        for a in c.args:
            if a.kind == "pos" and seen_formal:
                self.error(a.pos, "positional argument after a formal (name := value) argument")
                return False
            if a.kind != "pos":
                seen_formal = True
        return True

    def std_function(self, c):
        if not self._order(c):
            self.args_exprs(c)
            return ERROR
        args = [a for a in c.args if not self._en_eno(a)]
        positional = [a for a in args if a.kind == "pos"]
        formal = [a for a in args if a.kind != "pos"]
        for a in formal:
            if a.kind == "out":
                self.error(a.pos, f"standard function {c.name.upper()} has no output '{a.name}'")
                return ERROR
        ordered = list(positional)
        if formal:
            names = stdlib.formal_names(c.name, len(args))
            slots: dict[str, ast.Arg] = {}
            for a in formal:
                up = a.name.upper()
                if up not in names:
                    self.error(a.pos, f"{c.name.upper()} has no parameter '{a.name}' "
                                      f"(parameters: {', '.join(names)})")
                    return ERROR
                if up in slots:
                    self.error(a.pos, f"parameter '{a.name}' given twice")
                    return ERROR
                slots[up] = a
            taken = names[:len(positional)]
            for n in taken:
                if n in slots:
                    self.error(slots[n].pos, f"parameter '{n}' already given by position")
                    return ERROR
            for n in names[len(positional):]:
                if n in slots:
                    ordered.append(slots.pop(n))
                elif slots:
                    self.error(c.pos, f"{c.name.upper()}: parameter '{n}' is missing")
                    return ERROR
        for a in ordered:
            if a.value is None:
                self.error(a.pos, f"parameter '{a.name}' has no value")
                return ERROR
        types = [self.expr(a.value) for a in ordered]
        if any(isinstance(t, ErrorT) for t in types):
            return ERROR
        for a, t in zip(ordered, types):
            if isinstance(t, (FBType, ArrayT, StructT)) and c.name.upper() not in ("MOVE", "SEL"):
                self.error(a.value.pos, f"{c.name.upper()} cannot take a {t.name}")
                return ERROR
        try:
            f = stdlib.resolve(c.name, types)
        except stdlib.CallError as exc:
            self.error(c.pos, str(exc))
            return ERROR
        c.target = f
        c.args = [a for a in c.args if a.kind != "pos" and a.name.upper() in ("EN", "ENO")] + \
            ordered
        for a, pt in zip(ordered, f.param_types):
            if isinstance(a.value.type, LiteralT):
                a.value.type = _literal_arg_type(a.value.type, pt)
        if cat(f.result) == "real" or any(cat(t) == "real" for t in f.param_types):
            self.pou.uses_real = True
        return f.result

    def user_function(self, c, pou):
        self.bind_args(c, pou, is_function=True)
        if cat(pou.result) == "real":
            self.pou.uses_real = True
        return pou.result

    def fb_args(self, c, pou):
        self.bind_args(c, pou, is_function=False)

    def bind_args(self, c, pou, is_function):
        """Checks a call's arguments against the callee's interface."""
        if not self._order(c):
            self.args_exprs(c)
            return
        pos_params = [v for v in pou.vars.values() if v.section in ("VAR_INPUT", "VAR_IN_OUT")]
        given = {}
        npos = 0
        what = "function" if is_function else "function block"
        eno_out = pou.var("ENO") is not None and pou.var("ENO").section == "VAR_OUTPUT"
        for a in c.args:
            if not (eno_out and a.kind == "out" and a.name.upper() == "ENO") and \
                    self._en_eno(a):
                continue
            if a.kind == "pos":
                if npos >= len(pos_params):
                    self.error(a.pos, f"too many arguments for {what} {pou.name}: it takes "
                                      f"{len(pos_params)}")
                    self.expr(a.value)
                    npos += 1
                    continue
                param = pos_params[npos]
                npos += 1
                given[param.key] = a
                self.bind_one(a, param, pou)
                continue
            param = pou.var(a.name)
            if a.kind == "in":
                if param is None or param.section not in ("VAR_INPUT", "VAR_IN_OUT"):
                    self.error(a.pos, f"{pou.name} has no input '{a.name}'" +
                               (f" ('{a.name}' is an output: use =>)" if param is not None and
                                param.section == "VAR_OUTPUT" else ""))
                    if a.value is not None:
                        self.expr(a.value)
                    continue
            else:
                if param is None or param.section != "VAR_OUTPUT":
                    self.error(a.pos, f"{pou.name} has no output '{a.name}'" +
                               (f" ('{a.name}' is an input: use :=)" if param is not None else ""))
                    if a.value is not None:
                        self.lvalue(a.value)
                    continue
            if param.key in given:
                self.error(a.pos, f"parameter '{a.name}' given twice")
                continue
            given[param.key] = a
            self.bind_one(a, param, pou)
        for v in pou.inouts:
            if v.key not in given:
                self.error(c.pos, f"VAR_IN_OUT '{v.name}' of {pou.name} must be connected")
        if is_function and npos and npos < len(pos_params) and not any(
                a.kind != "pos" for a in c.args):
            self.error(c.pos, f"{pou.name} takes {len(pos_params)} argument(s), {npos} given")
        c.bound = given

    def bind_one(self, a, param, pou):
        if a.kind == "out":
            if a.value is None:
                return
            tt = self.lvalue(a.value)
            st = param.type
            if a.negate and st is not BOOL:
                self.error(a.pos, "only a BOOL output can be negated")
            self.check_assign(st, tt, a.value, a.value, what=None)
            return
        if a.value is None:
            if param.section == "VAR_IN_OUT":
                self.error(a.pos, f"VAR_IN_OUT '{param.name}' needs a variable")
            return
        if param.section == "VAR_IN_OUT":
            if not isinstance(a.value, ast.Ref):
                self.error(a.value.pos, f"VAR_IN_OUT '{param.name}' of {pou.name} needs a "
                                        "variable, not an expression")
                self.expr(a.value)
                return
            t = self.ref(a.value, write=True)
            bit = any(k == "bit" for k, _, _ in a.value.accessors)
            if bit and not isinstance(t, ErrorT):
                # passed by reference, and a bit has no address of its own
                self.error(a.value.pos, f"VAR_IN_OUT '{param.name}' of {pou.name} needs a variable: "
                                f"the bit access {a.value!r} cannot be passed by reference")
            elif not isinstance(t, ErrorT) and not identical(t, param.type):
                # passed by reference: the argument must have the parameter's
                # type itself (a STRING[8] is not a STRING[11])
                self.error(a.value.pos, f"VAR_IN_OUT '{param.name}' of {pou.name} is "
                                        f"{param.type.name}; {a.value!r} is {t.name}")
            return
        t = self.expr(a.value)
        self.check_assign(t, param.type, a.value, None, what=f"input '{param.name}'")

def _literal_value(e):
    """The value of e when it is integer literal arithmetic (fold.int_arith),
    folded from its operands' const (e's own is set once it is typed)."""
    return fold.node(e) if fold.int_arith(e) else None


def _literal_arg_type(t, pt):
    """The type an untyped argument of a standard call takes: the call's
    parameter type *pt*.  Where that is untyped too (every argument an
    untyped literal: ``MAX(0, 4000000000)``, ``LIMIT(0, 5, 1.5)``), *pt* is
    the arguments' common category (types.common) without a value, and the
    argument keeps its own value in that category: a back end that makes a
    literal concrete where nothing else decides (types.concrete: DINT, LINT
    beyond DINT's range, LREAL) must see 4000000000, not the value-less
    common type, which is DINT (the interpreter stored 4000000000 as a DINT,
    -294967296, where C computed MAX in LINT)."""
    if type(pt) is LiteralT and type(t) is LiteralT:
        v = t.value
        return LiteralT(pt.cat, float(v) if pt.cat == "real" else v)
    return pt


def _describe(node):
    if node is None:
        return "target"
    return f"'{node!r}'"


def _tname(t):
    if isinstance(t, StringT):
        return "WSTRING" if t.wide else "STRING"
    return t.name


def _label_text(low, high):
    return f"{low!r}" + (f"..{high!r}" if high is not None else "")


# operators of other tools that are no IEC 61131-3 functions
_VENDOR_OPERATORS = {
    "SIZEOF": "CODESYS", "ADR": "CODESYS", "ADRINST": "CODESYS", "BITADR": "CODESYS",
    "INDEXOF": "CODESYS", "__NEW": "CODESYS", "__DELETE": "CODESYS",
    "__ISVALIDREF": "CODESYS", "__QUERYINTERFACE": "CODESYS", "__QUERYPOINTER": "CODESYS",
}


def _vendor_note(key: str) -> str:
    tool = _VENDOR_OPERATORS.get(key.upper())
    if tool:
        return f" ({key.upper()} is a {tool} operator, not an IEC 61131-3 function)"
    if key.startswith("__"):
        return " (a name beginning with '__' is no IEC 61131-3 identifier: a vendor's built-in)"
    return ""
