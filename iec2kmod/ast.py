"""The syntax tree every later pass reads: expressions, statements,
declarations, POUs and the configuration.

The parser (parse/parser.py) turns textX's model into these nodes in one
conversion after the parse, and parse/stfast.py builds the same nodes
directly for the statements it parses by hand; no textX object survives
past parse/.  Expressions are rebuilt from the grammar's flat
operand/operator sequences into precedence trees.  Every node keeps the
character offset it starts at (``pos``); the checker (checks/) fills an
expression's ``type``, ``const`` (checks/fold.py) and, for a standard call or
operator, ``sig``/``fn`` (checks/settle.py); parse/lexical.attach attaches
each pragma to the node it applies to.
"""

from __future__ import annotations


class Expr:
    __slots__ = ("pos", "type", "const")

    def __init__(self, pos):
        self.pos = pos
        self.type = None   # filled by the type checker
        self.const = None  # folded constant value, when known


class BinOp(Expr):
    """``left op right``.  For an arithmetic operator (+ - * / MOD **) the
    checker sets ``fn``, the standard function it is (a StdFunc), and
    ``sig`` as on a Call; for a comparison ``sig`` is (BOOL, [t, t]), t the
    type both operands are compared in."""

    __slots__ = ("op", "left", "right", "fn", "sig")

    def __init__(self, pos, op, left, right):
        super().__init__(pos)
        self.op = op
        self.left = left
        self.right = right
        self.fn = None
        self.sig = None

    def __repr__(self):
        return f"({self.left!r} {self.op} {self.right!r})"


class UnOp(Expr):
    __slots__ = ("op", "operand")

    def __init__(self, pos, op, operand):
        super().__init__(pos)
        self.op = op
        self.operand = operand

    def __repr__(self):
        return f"({self.op} {self.operand!r})"


class Lit(Expr):
    """A literal: ``kind`` is int, real, bool, time, date, tod, dt, string,
    wstring or enum; ``value`` its Python value; ``type_name`` the explicit
    type prefix (``INT#5``) or None."""

    __slots__ = ("text", "kind", "value", "type_name")

    def __init__(self, pos, text, kind, value, type_name=None):
        super().__init__(pos)
        self.text = text
        self.kind = kind
        self.value = value
        self.type_name = type_name

    def __repr__(self):
        return self.text


class Ref(Expr):
    """A variable access: ``name`` then accessors: ('index', [exprs], pos),
    ('member', name, pos) or ('bit', n, pos)."""

    __slots__ = ("name", "accessors", "symbol")

    def __init__(self, pos, name, accessors):
        super().__init__(pos)
        self.name = name
        self.accessors = accessors
        self.symbol = None

    def __repr__(self):
        out = self.name
        for kind, val, _ in self.accessors:
            if kind == "index":
                out += "[" + ", ".join(map(repr, val)) + "]"
            else:
                out += f".{val}"
        return out


class Direct(Expr):
    """A directly represented variable such as %IX0.1."""

    __slots__ = ("address",)

    def __init__(self, pos, address):
        super().__init__(pos)
        self.address = address

    def __repr__(self):
        return self.address


class Arg:
    """A call argument: ``kind`` is 'pos', 'in' (name := value) or
    'out' (name => target)."""

    __slots__ = ("pos", "kind", "name", "value", "negate")

    def __init__(self, pos, kind, name, value, negate=False):
        self.pos = pos
        self.kind = kind
        self.name = name
        self.value = value
        self.negate = negate

    def __repr__(self):
        if self.kind == "pos":
            return repr(self.value)
        return f"{self.name} {':=' if self.kind == 'in' else '=>'} {self.value!r}"


class Call(Expr):
    """A call.  For a standard function the checker sets ``target`` (a
    StdFunc) and ``sig``: (result type, [parameter types]) the call is
    computed in once its context is known (checks/settle.py); every back end
    reads it.  A result still a LiteralT means: computed exactly on the
    literals' values."""

    __slots__ = ("name", "args", "target", "bound", "ref", "sig")

    def __init__(self, pos, name, args, ref=None):
        super().__init__(pos)
        self.name = name
        self.args = args
        self.target = None  # resolved POU, FB instance Var or standard function
        self.bound = None   # upper parameter name -> Arg, for user POUs
        # the instance called when it is an element of an array of FB
        # instances (t[i](IN := x)): a Ref with accessors; target is then
        # the array variable and ref.type the instance's FBType
        self.ref = ref
        self.sig = None

    def __repr__(self):
        return f"{self.name}({', '.join(map(repr, self.args))})"


# --------------------------------------------------------------------------
# Declarations, statements and POUs.  Plain picklable objects, so parsed
# files can travel between worker processes and into the parse cache.


class CR(Expr):
    """The current result of an IL instruction list used as an expression
    (IL's ``ADD x`` is ``CR + x``): made by the IL checker, read by every
    back end."""

    __slots__ = ("cr_type",)

    def __init__(self, pos, t):
        super().__init__(pos)
        self.cr_type = t
        self.type = t


class Node:
    __slots__ = ("pos",)
    fields: tuple = ()

    def __init__(self, pos=None, **kw):
        self.pos = pos
        for name in self.__slots__:
            if name != "pos":
                setattr(self, name, kw.get(name))

    def __repr__(self):
        inner = ", ".join(f"{k}={getattr(self, k)!r}" for k in self.__slots__
                          if k not in ("pos",) and getattr(self, k) not in (None, [], ()))
        return f"{type(self).__name__}({inner})"


# type specifications
class NamedSpec(Node):
    __slots__ = ("name",)


class StringSpec(Node):
    __slots__ = ("wide", "length")


class SubrangeSpec(Node):
    __slots__ = ("base", "low", "high")


class EnumSpec(Node):
    __slots__ = ("base", "values")  # values: [(name, expr|None, pos)]


class ArraySpec(Node):
    __slots__ = ("ranges", "element")  # ranges: [(low expr, high expr)]


class StructSpec(Node):
    __slots__ = ("members",)  # [VarDecl] with one name each


class ArrayInit(Node):
    __slots__ = ("items",)  # [(count|None, value|None)]


class StructInit(Node):
    __slots__ = ("fields",)  # [(name, value, pos)]


class TypeDef(Node):
    __slots__ = ("name", "spec", "init", "src")


class VarDecl(Node):
    # names: [(name, pos)]; pragmas: the {selective} in front of it, for
    # every name (parse/lexical.attach; None outside a POU's VAR blocks)
    __slots__ = ("names", "location", "edge", "spec", "init", "pragmas")


class AccessDecl(Node):
    __slots__ = ("name", "path", "spec", "direction")


class ConfigDecl(Node):
    __slots__ = ("path", "location", "spec", "init")


class VarBlock(Node):
    __slots__ = ("kind", "qualifiers", "decls")


class POU(Node):
    """A FUNCTION, FUNCTION_BLOCK or PROGRAM.  ``language`` is ST, IL or SFC;
    an SFC body is in ``sfc`` (``body`` is then empty)."""

    # pragmas: the {verify}/{assume} inside it and the {selective} in front
    # of it, in order (parse/lexical.attach); readers pick theirs by kind
    __slots__ = ("kind", "name", "result", "blocks", "body", "language", "src", "end_pos", "sfc",
                 "pragmas")


# statements
class Assign(Node):
    __slots__ = ("target", "value")


class CallStmt(Node):
    __slots__ = ("call",)


class If(Node):
    __slots__ = ("branches", "else_")  # branches: [(cond, [stmt])]


class Case(Node):
    __slots__ = ("selector", "elements", "else_", "values")  # elements: [([(low, high|None)], [stmt])]


class For(Node):
    __slots__ = ("var", "var_pos", "start", "end", "step", "body")


class While(Node):
    __slots__ = ("cond", "body")


class Repeat(Node):
    __slots__ = ("body", "cond")


class Exit(Node):
    __slots__ = ()


class Continue(Node):
    """CONTINUE (ed.3): the rest of the innermost loop's iteration is
    skipped; a FOR loop steps its variable, a WHILE and a REPEAT test their
    condition."""

    __slots__ = ()


class Return(Node):
    __slots__ = ()


class Empty(Node):
    __slots__ = ()


class ILInstr(Node):
    """One IL instruction.  ``op`` is the upper-case operator (LD, ADD, CAL,
    ...), or None for a function call (``fn``); ``nested`` holds the
    instructions of a deferred ``op(`` ... ``)`` whose first operand is
    ``operand``; ``args`` are formal arguments of CAL or a function."""

    __slots__ = ("label", "label_pos", "op", "operand", "deferred", "nested", "fb",
                 "fn", "args", "operands", "call", "cr_in", "cr_out", "std", "sig")
    # std, sig: for an arithmetic or comparison operator (ADD, GT, ...), the
    # standard function it is and the types it is computed in (the checker's)


# textual SFC (IEC 61131-3 ed.2 2.6); checked by iec2kmod/checks/sfc.py
class SFC(Node):
    """The SFC body of a POU: its elements in source order."""

    __slots__ = ("steps", "transitions", "actions")


class Step(Node):
    __slots__ = ("name", "initial", "assocs")  # assocs: [ActionAssoc]


class ActionAssoc(Node):
    """``action(qualifier, time, indicators...)``: ``qualifier`` upper case
    or None (N); ``args`` the expressions after it (a time first for L, D,
    SD, DS, SL; then indicator variables), ``time`` and ``indicators`` set by
    the checks."""

    __slots__ = ("action", "qualifier", "qual_pos", "args", "time", "indicators")


class Transition(Node):
    """``sources`` and ``targets``: [(step name, pos)]; the condition is
    ``cond`` (ST expression) or ``il`` (IL instructions, the condition is the
    current result at their end)."""

    __slots__ = ("name", "priority", "sources", "targets", "cond", "il", "index")


class Action(Node):
    __slots__ = ("name", "language", "body")


# configuration
class Task(Node):
    # props: {KEY: (expr, pos)}; pragmas: the {watchdog} in front of it (lexical.attach)
    __slots__ = ("name", "props", "pragmas")


class Connection(Node):
    __slots__ = ("name", "direction", "value")  # direction: 'in' | 'out'


class ProgramConfig(Node):
    # pragmas: the {selective} in front of it (parse/lexical.attach)
    __slots__ = ("name", "retain", "task", "task_pos", "type", "type_pos", "connections",
                 "pragmas")


class Resource(Node):
    __slots__ = ("name", "processor", "blocks", "tasks", "programs")


class Configuration(Node):
    __slots__ = ("name", "blocks", "resources", "access", "src")


class SourceUnit(Node):
    """One parsed file: its types, POUs and configurations in order;
    ``pragmas`` every pragma of the file in order, ``outside`` the {verify}
    and {assume} written outside any POU, ``unattached`` the {selective}
    in front of nothing they can apply to (parse/lexical.attach; the
    selective pass warns at each)."""

    __slots__ = ("src", "types", "pous", "configurations", "pragmas", "outside", "unattached")
