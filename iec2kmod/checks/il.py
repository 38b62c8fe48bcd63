"""Pass 'resolve', Instruction List: the type of the current result along
every path (labels and jumps included), each operator and operand checked
against it.  Mixed into checks.body.BodyChecker, whose expression and
assignment checks (checks/expr.py) and call checks (checks/calls.py) it
uses."""

from __future__ import annotations

from .. import ast
from ..diagnostics import Diagnostics
from . import fold, stdlib
from .settle import text, value_type, widest
from .symbols import Var
from .types import (BOOL, ERROR, Elementary, ErrorT, FBType, LiteralT, Type, common, concrete,
                    is_bit, literal_fits)

IL_LOGIC = {"AND": "AND", "ANDN": "AND", "OR": "OR", "ORN": "OR", "XOR": "XOR", "XORN": "XOR"}
IL_ARITH = {"ADD": "ADD", "SUB": "SUB", "MUL": "MUL", "DIV": "DIV", "MOD": "MOD"}
IL_COMPARE = set(stdlib.COMPARE_FAMILIES)
IL_FB_INPUT_OPS = {"S1", "R1", "CLK", "CU", "CD", "PV", "IN", "PT", "S", "R", "LD"}


class ILChecks:
    def check_il(self, instrs):
        labels = self.pou.labels
        self._collect_labels(instrs, labels)
        # first pass, silent: the current result's type at every jump, so
        # that a label knows the type it is reached with
        self.label_cr = {}
        real_diags = self.diags
        self.diags = Diagnostics()
        self.il_list(instrs, None)
        self.diags = real_diags
        self.il_list(instrs, None)
        _type_literal_chains(instrs, self.error)

    def _collect_labels(self, instrs, labels):
        for i in instrs:
            if i.label:
                up = i.label.upper()
                if up in labels:
                    self.error(i.label_pos, f"duplicate label '{i.label}'")
                else:
                    labels[up] = i
            if i.nested:
                for n in i.nested:
                    if n.label:
                        self.error(n.label_pos, "labels are not allowed inside a deferred "
                                                "operation '( ... )'")

    def il_list(self, instrs, cr):
        for i in instrs:
            if i.label:
                jumped = self.label_cr.get(i.label.upper())
                if cr is None:
                    cr = jumped
                elif jumped is not None:
                    cr = _join_cr(i.label, cr, jumped)
            i.cr_in = cr
            cr = self.il_instr(i, cr)
            i.cr_out = cr
        return cr

    def il_operand(self, i):
        if i.operand is None:
            self.error(i.pos, f"{i.op} needs an operand")
            return ERROR
        return self.expr(i.operand)

    def need_cr(self, i, cr):
        if cr is None:
            self.error(i.pos, f"{i.op or i.fn}: no current result (load a value with LD first)")
            return ERROR
        if isinstance(cr, _Conflict):
            self.error(i.pos, f"{i.op or i.fn}: the current result after label '{cr.label}' "
                              f"is {cr.a.name} or {cr.b.name}, depending on the path")
            return ERROR
        return cr

    def il_instr(self, i, cr):
        op = i.op
        if op == "NOP":
            return cr
        if op is None:
            return self.il_function(i, cr)
        if i.deferred:
            inner = None
            if i.operand is not None:
                inner = self.expr(i.operand)
            inner = self.il_list(i.nested, inner)
            if inner is None:
                self.error(i.pos, f"{op}( ... ) computes nothing")
                return cr
            return self.il_apply(i, op, self.need_cr(i, cr), inner, i.pos)
        if op in ("LD", "LDN"):
            t = self.il_operand(i)
            if op == "LDN" and not isinstance(t, ErrorT) and not is_bit(t):
                self.error(i.pos, f"LDN needs BOOL or a bit string, not {t.name}")
            elif op == "LDN" and type(t) is LiteralT:
                return self._literal_bits(i, op, t)     # LDN 5: a bit string, as NOT 5
            return t
        if op in ("ST", "STN"):
            cr = self.need_cr(i, cr)
            if i.operand is None:
                self.error(i.pos, f"{op} needs a variable")
                return cr
            if not isinstance(i.operand, ast.Ref):
                self.error(i.operand.pos, f"{op} needs a variable")
                return cr
            tt = self.lvalue(i.operand)
            stored = cr
            if op == "STN" and not isinstance(cr, ErrorT) and not is_bit(cr):
                self.error(i.pos, f"STN needs BOOL or a bit string, not {cr.name}")
            elif op == "STN" and not isinstance(cr, ErrorT):
                # the type the negation is computed in (and stored from): the
                # current result's, a bit string for an untyped literal
                stored = self._literal_bits(i, op, cr) if type(cr) is LiteralT else concrete(cr)
                if not isinstance(stored, ErrorT):
                    i.sig = (stored, [stored])
            self.check_assign(stored, tt, ast.CR(i.pos, stored), i.operand)
            return cr
        if op in ("S", "R") and isinstance(i.operand, ast.Ref):
            sym = self.lookup(i.operand.name, i.operand.pos, report=False)
            if isinstance(sym, Var) and isinstance(sym.type, FBType) and not i.operand.accessors:
                return self.il_fb_input(i, op, cr)
            cr = self.need_cr(i, cr)
            tt = self.lvalue(i.operand)
            if not isinstance(cr, ErrorT) and cr is not BOOL:
                self.error(i.pos, f"{op} needs a BOOL current result, not {cr.name}")
            if not isinstance(tt, ErrorT) and tt is not BOOL:
                self.error(i.operand.pos, f"{op} needs a BOOL variable, not {tt.name}")
            return cr
        if op in IL_FB_INPUT_OPS:
            return self.il_fb_input(i, op, cr)
        if op == "NOT":
            cr = self.need_cr(i, cr)
            if i.operand is not None:
                self.error(i.operand.pos, "NOT takes no operand")
            if not isinstance(cr, ErrorT) and not is_bit(cr):
                self.error(i.pos, f"NOT needs BOOL or a bit string, not {cr.name}")
            elif type(cr) is LiteralT:
                # an untyped literal (LD 5 NOT): a bit string, as in ST; the
                # back ends compute NOT in the result's type (cr_out)
                return self._literal_bits(i, "NOT", cr)
            return cr
        if op in IL_LOGIC or op in IL_ARITH or op in IL_COMPARE:
            cr = self.need_cr(i, cr)
            t = self.il_operand(i)
            return self.il_apply(i, op, cr, t, i.pos)
        if op in ("JMP", "JMPC", "JMPCN"):
            if op != "JMP":
                cr = self.need_cr(i, cr)
                if not isinstance(cr, ErrorT) and cr is not BOOL:
                    self.error(i.pos, f"{op} needs a BOOL current result, not {cr.name}")
            target = i.operand
            if not isinstance(target, ast.Ref) or target.accessors:
                self.error(i.pos, f"{op} needs a label")
            elif target.name.upper() not in self.pou.labels:
                self.error(target.pos, f"unknown label '{target.name}'")
            elif cr is not None:
                up = target.name.upper()
                prev = self.label_cr.get(up)
                self.label_cr[up] = cr if prev is None else _join_cr(target.name, prev, cr)
            return cr if op != "JMP" else None
        if op in ("RET", "RETC", "RETCN"):
            if op != "RET":
                cr = self.need_cr(i, cr)
                if not isinstance(cr, ErrorT) and cr is not BOOL:
                    self.error(i.pos, f"{op} needs a BOOL current result, not {cr.name}")
            if i.operand is not None:
                self.error(i.operand.pos, f"{op} takes no operand")
            return None if op == "RET" else cr
        if op in ("CAL", "CALC", "CALCN"):
            if op != "CAL":
                cr = self.need_cr(i, cr)
                if not isinstance(cr, ErrorT) and cr is not BOOL:
                    self.error(i.pos, f"{op} needs a BOOL current result, not {cr.name}")
            v = self.lookup(i.fb, i.pos)
            if v is None:
                return cr
            if not isinstance(v, Var) or not isinstance(v.type, FBType):
                self.error(i.pos, f"CAL needs a function block instance; '{i.fb}' is not one")
                return cr
            v.used = True
            self.pou.calls.add(v.type.pou.key)
            args = i.args or []
            if i.operands:
                args = [ast.Arg(o.pos, "pos", None, o) for o in i.operands]
            c = ast.Call(i.pos, i.fb, args)
            c.target = v
            self.bind_args(c, v.type.pou, is_function=False)
            i.call = c
            return cr
        raise AssertionError(op)

    def il_fb_input(self, i, op, cr):
        cr = self.need_cr(i, cr)
        if not isinstance(i.operand, ast.Ref) or i.operand.accessors:
            self.error(i.pos, f"{op} needs a function block instance")
            return cr
        v = self.lookup(i.operand.name, i.operand.pos)
        if v is None:
            return cr
        if not isinstance(v, Var) or not isinstance(v.type, FBType):
            self.error(i.operand.pos, f"{op} needs a function block instance; '{i.operand.name}'"
                                      f" is {getattr(getattr(v, 'type', None), 'name', 'not one')}")
            return cr
        v.used = True
        i.operand.symbol = v
        i.operand.type = v.type
        param = v.type.pou.var(op)
        if param is None or param.section != "VAR_INPUT":
            self.error(i.pos, f"function block {v.type.name} has no input {op}")
            return cr
        self.check_assign(cr, param.type, ast.CR(i.pos, cr), None, what=f"input {op}")
        return cr

    def il_apply(self, i, op, cr, t, pos):
        if isinstance(cr, ErrorT) or isinstance(t, ErrorT):
            return ERROR
        if op in IL_LOGIC:
            if not is_bit(cr) or not is_bit(t):
                self.error(pos, f"{op} needs BOOL or bit string operands, not "
                                f"{(cr if not is_bit(cr) else t).name}")
                return ERROR
            c = common(cr, t)
            if c is None:
                self.error(pos, f"{op}: incompatible operands {cr.name} and {t.name}")
                return ERROR
            if type(c) is LiteralT and c.cat == "int":
                # untyped literals (LD 5 AND 3): a bit string, as in ST
                c = self._literal_bits(i, op, cr, t)
                if isinstance(c, ErrorT):
                    return c
            i.sig = (concrete(c), [concrete(c)] * 2)
            return concrete(c)
        if op in IL_ARITH:
            try:
                f = stdlib.resolve(IL_ARITH[op], [cr, t])
            except stdlib.CallError as exc:
                self.error(pos, f"{op}: {stdlib.operand_message(exc, cr, t)}")
                return ERROR
            # the current result is stored in the operator's type, the
            # literal's own where both operands are untyped (LD 38 SUB 40)
            i.std, i.sig = f, stdlib.call_types(f, concrete(f.result))
            return f.result
        if op in IL_COMPARE:
            if common(cr, t) is None:
                self.error(pos, f"{op}: cannot compare {cr.name} with {t.name}")
                return ERROR
            try:
                f = stdlib.resolve(op, [cr, t])
                i.std, i.sig = f, stdlib.call_types(f, BOOL)
            except stdlib.CallError:     # not elementary: compared as values (interp)
                i.sig = (BOOL, [concrete(common(cr, t))] * 2)
            if type(cr) is LiteralT and type(t) is LiteralT:
                # two literals (LD 3000000000 GT 0): compared in a type that
                # holds both, as in ST (settle.widest)
                w = widest([value_type(cr.value), value_type(t.value)])
                i.sig = (BOOL, [w, w])
            return BOOL
        self.error(pos, f"{op}( ... ) is not a deferrable operation")
        return ERROR

    def il_function(self, i, cr):
        key = i.fn.upper()
        if i.args is not None:
            c = ast.Call(i.pos, i.fn, i.args)
        else:
            args = []
            if cr is not None:
                args.append(ast.Arg(i.pos, "pos", None, ast.CR(i.pos, cr)))
            else:
                self.error(i.pos, f"{i.fn}: no current result to pass as first argument")
                return ERROR
            args += [ast.Arg(o.pos, "pos", None, o) for o in i.operands]
            c = ast.Call(i.pos, i.fn, args)
        i.call = c
        if key in self.p.pous or stdlib.is_std_function(key):
            self.roots.append(c)
            return self.call(c, statement=False)
        self.error(i.pos, f"unknown IL operator or function '{i.fn}'")
        return ERROR


def _type_literal_chains(instrs, error):
    """An untyped current result takes the type of the variable it is stored
    in, as an untyped ST expression takes its target's (settle.py): ``LD
    2147483647 ADD 1 ST x`` into a LINT adds in LINT (2147483648), as
    ``x := 2147483647 + 1`` does and as MatIEC computes it (its IL default
    variable of the store's type); it was computed in the literal's own type
    (DINT: -2147483648).  A chain is an LD of an untyped literal and the
    arithmetic on untyped operands after it, on a straight line (no label);
    it takes the type when every ST that reads it stores into the same
    integer or real type and nothing else reads it but a comparison with an
    untyped literal after the stores (compared in that type, as MatIEC
    does); read by anything else (a function, a jump, a label's other
    paths) it keeps the literal's own type.  A chain whose exact value
    leaves the integer type it takes (``LD 100 ADD 100 ST s``, s a SINT) is
    refused through *error*, as the ST assignment of the same expression
    is (_chain_overflow)."""
    chain = []
    stores = []
    compare = []

    def close():
        types = {id(concrete(st.operand.type)): concrete(st.operand.type) for st in stores}
        typed = False
        if len(chain) > 1 and len(types) == 1:     # LD 99 ST i alone computes nothing
            tt = next(iter(types.values()))
            if isinstance(tt, Elementary) and tt.cat in ("sint", "uint", "real") and all(
                    c.op == "LD" or tt.cat in stdlib.NUMERIC_CONTEXT.get(c.std.family, ())
                    for c in chain):
                try:        # a comparison after the stores compares in their type
                    cmp = [(c, stdlib.resolve(c.op, [tt, c.operand.type])) for c in compare]
                except stdlib.CallError:
                    cmp = None
                if cmp is not None:
                    for c in chain:
                        c.cr_out = tt
                        if c.op != "LD":
                            c.sig = stdlib.call_types(c.std, tt)
                    for c in chain[1:] + stores:
                        c.cr_in = tt
                    for c in stores:
                        c.cr_out = tt
                    for c, f in cmp:
                        c.cr_in = tt
                        c.std, c.sig = f, stdlib.call_types(f, BOOL)
                    typed = True
                    wrap = _chain_overflow(chain, tt)
                    if wrap is not None:
                        error(*wrap)
        if len(chain) > 1 and not typed:
            # computed in the literal's own type, then stored (LD 0 SUB 1 ST
            # w, w a WORD; LD 100 ADD 100 ST s ST i): the value each store
            # keeps must be the exact one, as for w := 0 - 1 in ST
            for st in stores:
                wrap = _chain_overflow(chain, concrete(st.operand.type), st)
                if wrap is not None:
                    error(*wrap)
        chain.clear()
        stores.clear()
        compare.clear()

    for i in instrs:
        if i.op == "LD" and not i.deferred and type(i.cr_out) is LiteralT and \
                i.operand is not None and type(i.operand.type) is LiteralT:
            close()
            chain.append(i)
        elif chain and not stores and not i.label and i.op in IL_ARITH and not i.deferred \
                and type(i.cr_in) is LiteralT and type(i.cr_out) is LiteralT and \
                i.operand is not None and type(i.operand.type) is LiteralT and \
                getattr(i, "std", None) is not None:
            chain.append(i)
        elif chain and not i.label and i.op == "ST" and \
                isinstance(getattr(i.operand, "type", None), Type):
            stores.append(i)
        elif chain and stores and not i.label and i.op in IL_COMPARE and not i.deferred \
                and i.operand is not None and type(i.operand.type) is LiteralT:
            compare.append(i)       # LD 1 ADD 2 ST x GT 0: compared in x's type (MatIEC)
            close()
        elif i.op == "LD" and not i.label:
            close()             # a new current result: the chain's stores are all
        else:
            # anything else reads or carries the current result (a
            # comparison, a function, a jump, a label's other paths): the
            # chain keeps the literal's own type
            chain.clear()
            stores.clear()
    close()


def _chain_overflow(chain, tt, store=None):
    """(position, message) of the first value of IL chain *chain* (an LD of
    an untyped literal and arithmetic on untyped literals) that integer
    type *tt*, the type it is computed in, cannot hold, exactly computed
    (integer division truncates); None where every value fits or *tt* is
    a real (rounding is no error).  With *store*, an ST of the chain
    computed in the literal's own type: only the value it stores into a
    variable of integer or bit-string type *tt*."""
    ranged = ("sint", "uint", "bit") if store is not None else ("sint", "uint")
    if not isinstance(tt, Elementary) or tt.cat not in ranged:
        return None
    lo, hi = tt.range
    shown = f"LD {chain[0].operand.text}" if isinstance(chain[0].operand, ast.Lit) else "LD"
    v = getattr(chain[0].operand, "const", None)
    for c in chain:
        w = getattr(c.operand, "const", None)
        if not isinstance(w, int) or isinstance(w, bool):
            return None
        if store is None and not lo <= w <= hi:
            return (c.operand.pos, f"{w} is out of range for {tt.name}, the type the current "
                                   "result is computed in (the type of the variable it is stored "
                                   "in); write the value or convert explicitly")
        if c.op == "LD":
            continue
        shown += f" {c.op} {getattr(c.operand, 'text', w)}"
        try:
            v = fold.binary({"ADD": "+", "SUB": "-", "MUL": "*", "DIV": "/", "MOD": "MOD"}[c.op],
                            v, w)
        except (ArithmeticError, KeyError):
            return None
        if store is None and not lo <= v <= hi:
            return (c.pos, f"{shown} is {v}, out of range for {tt.name} (the type of the variable "
                           "it is stored in); write the value or convert explicitly")
    if store is not None and not lo <= v <= hi:
        return (store.pos, f"{shown} is {v}, out of range for {tt.name}, the type of "
                           f"'{text(store.operand)}' it is stored in; write the value or convert "
                           "explicitly")
    return None


def _join_cr(label, a, b):
    """The current result's type at a label reached with types a and b: the
    same type, or an untyped literal's path taking the other path's type when
    the literal fits it (a literal takes the type its context requires: ed.2
    2.2.1, ed.3 6.3.3); otherwise a conflict, an error only if an instruction
    reads the current result (LD replaces it)."""
    if isinstance(a, _Conflict) or isinstance(b, _Conflict):
        return a if isinstance(a, _Conflict) else b
    if isinstance(a, ErrorT) or isinstance(b, ErrorT):
        return a if isinstance(b, ErrorT) else b
    if concrete(a) is concrete(b):
        return b if isinstance(a, LiteralT) else a
    if isinstance(a, LiteralT) and not isinstance(b, LiteralT) and literal_fits(a, b):
        return b
    if isinstance(b, LiteralT) and not isinstance(a, LiteralT) and literal_fits(b, a):
        return a
    return _Conflict(label, concrete(a), concrete(b))


class _Conflict(ErrorT):
    """The current result at a label reached with two different types."""

    def __init__(self, label, a, b):
        self.label = label
        self.a = a
        self.b = b
