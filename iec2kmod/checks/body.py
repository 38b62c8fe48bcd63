"""Pass 'resolve': name resolution and strong typing of every POU body, ST,
IL and SFC.  Every expression gets ``.type``; every variable access gets
``.symbol``; every call gets ``.target``.

This file holds the pass itself, ``BodyChecker``: its entry (which body
language), the ST statements (IF, CASE and its labels, FOR, WHILE, REPEAT,
EXIT, CONTINUE) and the settling of the standard calls at the end.  The rest
of the checker is mixed in, each part in its file, all of them on the state
``BodyChecker`` sets up (``p``, ``decl``, ``pou``, ``src``, ``error``,
``warning``, ``roots``, ``depth``, ``loop_vars``):

- checks/expr.py ``ExprChecks``: names, accessors, literals, operators, and
  whether a typed value may be assigned to a target (``check_assign``);
- checks/calls.py ``CallChecks``: calls and the binding of their arguments;
- checks/il.py ``ILChecks``: Instruction List bodies;
- an SFC body is checked by checks/sfc.py's ``SFCChecker`` through this
  checker."""

from __future__ import annotations

from .. import ast
from .calls import CallChecks
from .expr import ExprChecks
from .il import ILChecks
from .settle import overflows, settle, settle_root
from .sfc import SFCChecker
from .symbols import EnumValue, POUInfo, Var
from .types import ERROR, Elementary, EnumT, ErrorT, SubrangeT, is_bool, is_int


class BodyChecker(ExprChecks, CallChecks, ILChecks):
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
        self.own_roots: set = set()     # ids of those used in their own type (settle_root)

    def error(self, pos, msg):
        self.diags.error(self.src, pos, msg)

    def error_once(self, pos, msg):
        """An error, unless one is reported at *pos* already (check_assign's
        '200 is out of range for SINT' where the checker's own says 100 +
        100 is 200)."""
        if self.src is not None:
            line, col = self.src.linecol(pos or 0)
            if any(d.path == self.src.path and (d.line, d.col) == (line, col)
                   for d in self.diags.errors):
                return
        self.error(pos, msg)

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
            if id(e) in self.own_roots:
                settle_root(e)      # a CASE selector, an index: no context types it
            else:
                settle(e)
            for pos, msg in overflows(e):   # 100 + 100 settled into a SINT
                self.error_once(pos, msg)
        self.roots = []
        self.own_roots = set()

    def _check(self):
        node = self.pou.node
        if node.language == "SFC":
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

    def case(self, s):
        st = self.expr(s.selector)
        self.own_roots.add(id(s.selector))
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


def _label_text(low, high):
    return f"{low!r}" + (f"..{high!r}" if high is not None else "")
