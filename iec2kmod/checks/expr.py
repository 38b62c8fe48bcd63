"""Pass 'resolve', expressions: the type of every expression of a body and
whether a typed value may go where it is written.

``ExprChecks`` is mixed into checks.body.BodyChecker, whose state it uses
(``p``, ``decl``, ``pou``, ``src``, ``error``, ``warning``, ``roots``,
``depth``, ``loop_vars``) and whose calls it reaches through ``call``
(checks/calls.py).  It holds:

- assignment compatibility, ``check_assign``: a value's type against its
  target's (statements, FOR bounds, call arguments and IL share it);
- names: a variable or an enumeration value (``lookup``, ``ref``), its
  accessors (index, member, bit), whether it may be written;
- expressions: literals, binary and unary operators, each typed and folded
  (``Expr.const``, checks/fold.py)."""

from __future__ import annotations

from .. import ast
from ..diagnostics import INPUT_WRITE_RULE
from . import fold, stdlib
from .eno import fb_eno
from .symbols import EnumValue, Var
from .types import (BOOL, ELEMENTARY, ERROR, AnyIntResult, ArrayT, Elementary, EnumT, ErrorT, FBType,
                    LiteralT, StringT, StructT, SubrangeT, assignable, cat, common,
                    concrete, concrete_bits, is_bit, is_int, literal_fits, not_bit_value)

ARITH = {"+": "ADD", "-": "SUB", "*": "MUL", "/": "DIV", "MOD": "MOD"}
COMPARE = {"=": "EQ", "<>": "NE", "<": "LT", ">": "GT", "<=": "LE", ">=": "GE"}
LOGIC = {"AND", "OR", "XOR"}


class ExprChecks:
    # ------------------------------------------------------- assignment
    def check_assign(self, vt, tt, value, target_node, what=None):
        if isinstance(vt, ErrorT) or isinstance(tt, ErrorT) or tt is None or vt is None:
            return
        if isinstance(tt, FBType) or isinstance(vt, FBType):
            self.error(value.pos, "function block instances cannot be assigned")
            return
        if isinstance(tt.base, Elementary) and tt.base.cat == "bit" and \
                isinstance(value, (ast.UnOp, ast.BinOp, ast.Call)) and _literal_bits(value):
            # NOT, AND, OR, XOR, SHL, SHR, ROL, ROR on untyped literals into a
            # bit string: computed in it (l := SHL(1, 40) into an LWORD,
            # b := NOT 0 into a BYTE: 255), as MatIEC computes them
            # (SHL__LWORD__LWORD__SINT), where every literal fits it
            hi = tt.base.range[1]
            bad = next((v for v in _bit_literal_values(value) if not 0 <= v <= hi), None)
            if bad is not None:
                self.error(value.pos, f"{bad} is out of range for {tt.name}")
                return
            _bits_in(value, tt.base)
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
            # an untyped index takes its own type when settled (settle.settle_root)
            self.own_roots.add(id(e))
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
            if v is None and name.upper() == "ENO":
                # the implicit output, kept in the instance once read
                v = fb_eno(t)
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
            self.error(e.pos, not_bit_value(f"operator {op}", lits))
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


_SHIFTS = ("SHL", "SHR", "ROL", "ROR")


def _untyped_int(e):
    return isinstance(e, ast.Lit) and e.kind == "int" and not e.type_name


def _shift_args(e):
    """(IN, N) of a call of SHL, SHR, ROL or ROR, else None."""
    if isinstance(e, ast.Call) and isinstance(e.target, stdlib.StdFunc) and \
            e.target.family in _SHIFTS:
        pos = [a.value for a in e.args if a.kind == "pos" or
               (a.name or "").upper() not in ("EN", "ENO")]
        if len(pos) == 2 and len(pos) == len(e.args):     # no EN, no ENO
            return pos
    return None


def _literal_bits(e, root=True):
    """Whether e is NOT, AND, OR, XOR, SHL, SHR, ROL or ROR on untyped integer
    literals (the bit string it is computed in is its context's)."""
    if not root and _untyped_int(e):
        return True
    if isinstance(e, ast.UnOp):
        return e.op == "NOT" and _literal_bits(e.operand, False)
    if isinstance(e, ast.BinOp):
        return e.op in LOGIC and _literal_bits(e.left, False) and _literal_bits(e.right, False)
    args = _shift_args(e)
    return args is not None and _literal_bits(args[0], False)


def _bit_literal_values(e):
    """The values of the literals a bit string computes _literal_bits' e on
    (a shift's N is a count, not one)."""
    if _untyped_int(e):
        return [e.value]
    if isinstance(e, ast.UnOp):
        return _bit_literal_values(e.operand)
    if isinstance(e, ast.BinOp):
        return _bit_literal_values(e.left) + _bit_literal_values(e.right)
    return _bit_literal_values(_shift_args(e)[0])


def _bits_in(e, t):
    """Types _literal_bits' e in bit string t."""
    if _untyped_int(e):
        e.type = t          # a shift's IN (a DWORD by the call's parameter type)
        return
    e.type = t
    if isinstance(e, ast.UnOp):
        _bits_in(e.operand, t)
    elif isinstance(e, ast.BinOp):
        _bits_in(e.left, t)
        _bits_in(e.right, t)
    else:
        arg, n = _shift_args(e)
        _bits_in(arg, t)
        e.target = stdlib.resolve(e.target.name, [t, n.type])


def _literal_value(e):
    """The value of e when it is integer literal arithmetic (fold.int_arith),
    folded from its operands' const (e's own is set once it is typed)."""
    return fold.node(e) if fold.int_arith(e) else None


def _describe(node):
    if node is None:
        return "target"
    return f"'{node!r}'"


def _tname(t):
    if isinstance(t, StringT):
        return "WSTRING" if t.wide else "STRING"
    return t.name
