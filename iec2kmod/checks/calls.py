"""Pass 'resolve', calls: what a call names and how its arguments bind.

``CallChecks`` is mixed into checks.body.BodyChecker, whose state it uses
(``p``, ``pou``, ``error``, ``roots``) and whose expression checks it calls
(``expr``, ``lvalue``, ``ref``, ``check_assign``: checks/expr.py).  A call
is of a function block instance (also an element of an array of them), a
user function or a standard function (checks/stdlib.py resolves its
overload); its arguments are bound by position or name (EN and ENO on every
call), each checked against its parameter."""

from __future__ import annotations

from .. import ast
from . import stdlib
from .types import BOOL, ERROR, ArrayT, ErrorT, FBType, LiteralT, StructT, cat, identical


class CallChecks:
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
