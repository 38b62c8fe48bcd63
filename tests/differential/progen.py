"""A type-directed generator of valid random IEC 61131-3 projects.

``generate_unit(seed, k)`` returns a :class:`Unit`: the declarations of one
random project (TYPEs, FUNCTIONs, FUNCTION_BLOCKs, PROGRAMs in ST and IL)
and its share of a configuration (globals, located variables, resources,
periodic and event tasks, program instances with connections), plus a random
input trace.  Every name a unit declares starts with ``u<k>_`` (local
variable names excepted), and its direct addresses come from its own range,
so several units merge into one configuration -- one simulator build for
many projects -- and each one still runs alone, with the same file and the
same line numbers, when a disagreement has to be minimised.

The generator is deterministic for a given seed (``random.Random(seed)``
only).  What it keeps in mind so that engines can be compared exactly:

- a REAL/LREAL value computed by a transcendental function (SIN, LN, EXP,
  EXPT, ``**``, ...) may differ in the last bits between libms: such values
  go only into *sink* variables (``fz*``) that nothing reads, so a last-ULP
  difference can never reach control flow, an index or an integer;
- loops are bounded by construction (constant-range FOR loops, WHILE/REPEAT
  on a dedicated counter), except for a rare deliberate endless loop that
  the per-cycle loop budget turns into a runtime fault;
- runtime faults (division by zero, index out of range, a subrange
  violation, MUX out of range) are rare on purpose, so most traces are long.
"""

from __future__ import annotations

import random
import re
from dataclasses import dataclass, field


# ----------------------------------------------------------------- types
class Ty:
    def __init__(self, kind, name, bits=0, signed=False, **kw):
        self.kind = kind        # bool int bit real time string enum sub array struct fb
        self.name = name        # how a declaration spells it
        self.bits = bits
        self.signed = signed
        self.__dict__.update(kw)

    def __repr__(self):
        return self.name

    @property
    def elementary(self):
        return self.kind in ("bool", "int", "bit", "real", "time")

    @property
    def scalar(self):
        return self.kind in ("bool", "int", "bit", "real", "time", "string", "enum", "sub")


BOOL = Ty("bool", "BOOL", 1)
INTS = [Ty("int", n, b, s) for n, b, s in (("SINT", 8, True), ("INT", 16, True),
                                              ("DINT", 32, True), ("LINT", 64, True),
                                              ("USINT", 8, False), ("UINT", 16, False),
                                              ("UDINT", 32, False), ("ULINT", 64, False))]
BITS = [Ty("bit", n, b) for n, b in (("BYTE", 8), ("WORD", 16), ("DWORD", 32), ("LWORD", 64))]
REAL = Ty("real", "REAL", 32)
LREAL = Ty("real", "LREAL", 64)
REALS = [REAL, LREAL]
TIME = Ty("time", "TIME", 64)
T = {t.name: t for t in [BOOL, *INTS, *BITS, *REALS, TIME]}
INT, DINT = T["INT"], T["DINT"]
WIDEN = {"SINT": ["INT", "DINT", "LINT"], "INT": ["DINT", "LINT"], "DINT": ["LINT"],
         "USINT": ["UINT", "UDINT", "ULINT", "INT", "DINT"], "UINT": ["UDINT", "ULINT", "DINT"],
         "UDINT": ["ULINT", "LINT"], "BYTE": ["WORD", "DWORD"], "WORD": ["DWORD", "LWORD"],
         "DWORD": ["LWORD"], "REAL": ["LREAL"]}


def string_t(n=None):
    return Ty("string", f"STRING[{n}]" if n else "STRING", length=n or 254)


def rng_of(t):
    if t.kind == "sub":
        return t.lo, t.hi
    if t.kind == "bool":
        return 0, 1
    if t.kind == "int" and t.signed:
        return -(1 << (t.bits - 1)), (1 << (t.bits - 1)) - 1
    return 0, (1 << t.bits) - 1


def same_type(a, b):
    if a is b:
        return True
    if a.kind == b.kind == "string":
        return True
    return a.kind in ("bool", "int", "bit", "real", "time") and a.name == b.name


# ------------------------------------------------------------- variables
@dataclass
class Var:
    name: str
    ty: Ty
    sec: str                 # in out inout ext var temp const global
    ro: bool = False         # input or constant: not assignable
    sink: bool = False       # receives inexact REAL values; never read
    wo: bool = False         # write-only (a function's result variable)
    reserved: bool = False   # a loop counter or FOR variable: not assignable
    init: str | None = None
    edge: str | None = None
    loc: str | None = None


@dataclass
class Pou:
    kind: str                # FUNCTION FUNCTION_BLOCK PROGRAM
    name: str
    vars: list = field(default_factory=list)
    result: Ty | None = None
    lang: str = "ST"
    body: list = field(default_factory=list)     # lines
    depth: int = 0           # FB nesting depth under it
    has_ext: bool = False    # it or an FB inside uses VAR_EXTERNAL
    home: str | None = None  # resource whose globals a program may use
    consts: list = field(default_factory=list)  # named constants (VAR CONSTANT) of bounds
    ext_consts: list = field(default_factory=list)  # VAR_EXTERNAL CONSTANTs of bounds

    def section(self, sec):
        return [v for v in self.vars if v.sec == sec]


@dataclass
class Unit:
    seed: int
    k: int
    prefix: str
    decl_text: str                      # TYPEs and POUs
    globals_text: list                  # lines inside the configuration's VAR_GLOBAL
    resources_text: str
    inputs: list                        # (path, Ty) the trace may write
    addresses: set
    trace: list                         # (t_ns, path, literal)
    features: set
    cycles: int
    interval_ns: int = 10_000_000
    const_globals: list = field(default_factory=list)

    def standalone(self) -> str:
        """The unit as one file with its own configuration (same line numbers)."""
        return self.decl_text + config_text(f"{self.prefix}cfg", [self])

    def trace_csv(self) -> str:
        return "".join(f"{t}ns,{p},{v}\n" for t, p, v in self.trace)


def config_text(name, units) -> str:
    lines = [f"CONFIGURATION {name}"]
    g = [ln for u in units for ln in u.globals_text]
    if g:
        lines += ["VAR_GLOBAL"] + ["    " + ln for ln in g] + ["END_VAR"]
    c = [ln for u in units for ln in u.const_globals]
    if c:
        lines += ["VAR_GLOBAL CONSTANT"] + ["    " + ln for ln in c] + ["END_VAR"]
    for u in units:
        lines.append(u.resources_text.rstrip("\n"))
    lines.append("END_CONFIGURATION")
    return "\n".join(lines) + "\n"


# ------------------------------------------------------------ generator
STD_FBS = {
    "TON": ([("IN", "bool"), ("PT", "time")], [("Q", BOOL), ("ET", TIME)]),
    "TOF": ([("IN", "bool"), ("PT", "time")], [("Q", BOOL), ("ET", TIME)]),
    "TP": ([("IN", "bool"), ("PT", "time")], [("Q", BOOL), ("ET", TIME)]),
    "R_TRIG": ([("CLK", "bool")], [("Q", BOOL)]),
    "F_TRIG": ([("CLK", "bool")], [("Q", BOOL)]),
    "SR": ([("S1", "bool"), ("R", "bool")], [("Q1", BOOL)]),
    "RS": ([("S", "bool"), ("R1", "bool")], [("Q1", BOOL)]),
}
for _sfx, _t in (("", "INT"), ("_DINT", "DINT"), ("_LINT", "LINT"), ("_UDINT", "UDINT"),
                 ("_ULINT", "ULINT")):
    STD_FBS["CTU" + _sfx] = ([("CU", "bool"), ("R", "bool"), ("PV", _t)],
                             [("Q", BOOL), ("CV", T[_t])])
    STD_FBS["CTD" + _sfx] = ([("CD", "bool"), ("LD", "bool"), ("PV", _t)],
                             [("Q", BOOL), ("CV", T[_t])])
    STD_FBS["CTUD" + _sfx] = ([("CU", "bool"), ("CD", "bool"), ("R", "bool"), ("LD", "bool"),
                               ("PV", _t)], [("QU", BOOL), ("QD", BOOL), ("CV", T[_t])])

# Patterns of bugs found by this campaign and reported, which the generator
# avoids so that the campaign keeps finding others.  Each entry names the
# regression case that shows the bug; delete the entry once it is fixed.
AVOID: set = set()
_ZERO = re.compile(r"^\(*(?:[A-Z]+#)?(?:16#)?0+\)*$")


def _norm(e):
    return re.sub(r"MOVE\(|[() ]", "", e)


def clash(a, b, t):
    """Would comparing a with b hit a bug listed in AVOID?"""
    if "self_compare" in AVOID and _norm(a) == _norm(b):
        return True
    if "unsigned_zero" in AVOID and (t.kind == "bit" or t.kind == "int" and not t.signed) \
            and (_ZERO.match(a) or _ZERO.match(b)):
        return True
    return False


FUZZY_FNS = ["SIN", "COS", "TAN", "ASIN", "ACOS", "ATAN", "LN", "LOG", "EXP"]
WORDS = ["a", "b", "ab", "xyz", "Hello", "PLC", " ", "", "12", "-7", "abcabc", "$$", "$'q",
         "q$'", "$N", "z z", "3.5", "TRUE"]


class Gen:
    def __init__(self, seed: int, k: int = 0, size: float = 1.0):
        self.r = random.Random(seed)
        self.seed = seed
        self.k = k
        self.p = f"u{k}_"
        self.size = size
        self.types = []          # (Ty, decl text)
        self.funcs = []          # Pou
        self.fbs = []            # Pou
        self.progs = []          # Pou
        self.cglobals = []       # Var (configuration level)
        self.rglobals = {}       # resource name -> [Var]
        self.features = set()
        self.n = 0
        self.addr_base = 64 * k + 8
        self.addr_next = 0
        self.addresses = set()
        self.inputs = []         # (path, Ty)
        self.safe = False        # no operation that can fault (AVOID)
        self.named_strings = []
        self.enums, self.subs, self.structs, self.arrays = [], [], [], []
        self.nres = 1
        self.sfc_r = random.Random(f"sfc{seed}")
        self.sfc = True
        # the constructs of issue 10 are decided by a generator of their own:
        # with them off (generate_unit(fidelity=False)) a seed gives the
        # project it gave before they were added
        self.fid_r = random.Random(f"fid{seed}")
        self.fid = True
        # the real-code forms of issue 25 (located variables in programs,
        # writes to inputs) likewise: with real_code=False a seed gives the
        # project it gave before
        self.real_r = random.Random(f"real{seed}")
        self.real = True
        self.loc_next = 0
        self.located_progs = set()
        # named constants in array bounds and CASE labels: a generator of
        # their own, kept out of the variables the bodies draw from, so a
        # seed's project is the one it gave before, with names for numbers
        self.nc_r = random.Random(f"nc{seed}")
        self.nc = True
        # CONTINUE (ed.3) in loops: likewise a generator of its own; its
        # condition reads only the loop's variable
        self.ct_r = random.Random(f"ct{seed}")
        self.cont = True
        # boundary values (issue 29): type limits and their neighbours in
        # literals, input traces and comparisons of unsigned types, decided
        # by a generator of their own (boundary_lit, boundary_input,
        # boundary_compare_type); with them off a seed gives the project it
        # gave before
        self.bd_r = random.Random(f"bd{seed}")
        self.bd = True
        # constant expressions as initial values (k : INT := (7 - 2)): the
        # same value as the literal drawn, written as a sum or difference
        # the checker folds, decided by a generator of its own so a seed's
        # project keeps its values (issue 24: such an initial value stopped
        # the C engine and no campaign wrote one)
        self.ie_r = random.Random(f"ie{seed}")
        self.init_expr = True
        self.cur_pou = None
        # strings=False (generate_unit): no STRING type, value or function,
        # for engines that have none (the verifier); True leaves every seed's
        # project as it was
        self.strings = True

    # ------------------------------------------------------------ helpers
    def uid(self, stem):
        self.n += 1
        return f"{stem}{self.n}"

    def fid_chance(self, p):
        return self.fid and self.fid_r.random() < p

    def nc_chance(self, p):
        return self.nc and self.nc_r.random() < p

    def continue_if(self, var, ind):
        """`IF <a test of the loop's variable> THEN CONTINUE; END_IF;`"""
        k = self.ct_r.randint(-2, 8)
        cond = self.ct_r.choice([f"{var} = {k}", f"{var} MOD 2 = 0", f"{var} > {k}",
                                 f"{var} < {k}"])
        if self.ct_r.random() < 0.3:
            self.feat("continue_case")
            return [f"{ind}CASE {var} OF", f"{ind}    {abs(k)}, {abs(k) + 2}: CONTINUE;",
                    f"{ind}END_CASE;"]
        return [f"{ind}IF {cond} THEN", f"{ind}    CONTINUE;", f"{ind}END_IF;"]

    def named_constant(self, pou, value):
        """The name of a new VAR CONSTANT of *pou* worth *value* (a bound
        or a CASE label), declared from another one at times."""
        name = f"k{self.nc_r.randrange(1 << 30):x}_{len(pou.consts)}"
        init = str(value)
        if pou.consts and self.nc_r.random() < 0.4:
            other = self.nc_r.choice(pou.consts)
            init = f"{other.name} + ({value - int(other.value)})"
            self.feat("named_const_from_const")
        v = Var(name, INT, "const", ro=True, init=init)
        v.value = value
        pou.consts.append(v)
        return name

    def named_bounds(self, pou, t):
        """An unnamed array type of *pou* with some bounds named by
        constants (ed.3: a bound is a constant expression): a local VAR
        CONSTANT, or an expression of a VAR_EXTERNAL CONSTANT of the POU
        (the configuration's VAR_GLOBAL CONSTANT) worth the same bound."""
        if t.kind != "array" or t.named or not self.nc_chance(0.3):
            return t
        # the configuration's integer constants; a PROGRAM or FUNCTION_BLOCK
        # reaches one through a VAR_EXTERNAL CONSTANT of its own (declared
        # apart from the variables its body draws from)
        exts = [(g.name, int(g.init), g.ty) for g in self.cglobals
                if getattr(g, "const", False) and g.ty.kind == "int"
                and re.fullmatch(r"-?\d+", g.init or "")] if pou.kind != "FUNCTION" else []
        dims = []
        for lo, hi in t.dims:
            a, b = str(lo), str(hi)
            if exts and self.nc_r.random() < 0.5:
                n, val, gt = self.nc_r.choice(exts)
                b = n if val == hi else f"{n} + ({hi - val})"
                if not any(v.name == n and v.sec == "ext" for v in pou.vars + pou.ext_consts):
                    pou.ext_consts.append(Var(n, gt, "ext", ro=True))
                self.feat("named_const_external_bound")
            elif self.nc_r.random() < 0.6:
                b = self.named_constant(pou, hi)
                self.feat("named_const_bound")
            if self.nc_r.random() < 0.3:
                a = self.named_constant(pou, lo)
            dims.append(f"{a}..{b}")
        es = t.elem.name if t.elem.kind != "array" else t.elem.spec
        spec = "ARRAY[" + ", ".join(dims) + f"] OF {es}"
        return Ty("array", t.name, dims=t.dims, elem=t.elem, spec=spec, named=False)

    def chance(self, p):
        return self.r.random() < p

    def risky(self, p):
        """Shall an operation that can fault at run time be generated?"""
        return not self.safe and self.chance(p)

    def pick(self, seq):
        return self.r.choice(seq)

    def feat(self, name):
        self.features.add(name)

    # --------------------------------------------------------- literals
    def lit(self, t, small=True, bare=True):
        """A literal of type t; typed (INT#5) unless bare and the context
        types it (an untyped literal alone in a function call is DINT/LREAL)."""
        s = self._lit(t, small)
        if not bare and t.kind in ("int", "bit", "real") and t.name not in ("DINT", "LREAL") \
                and "#" not in s.replace("16#", ""):
            s = f"{t.name}#{s}"
        return s

    def _lit(self, t, small=True):
        r = self.r
        b = self.boundary_lit(t)
        if b is not None:
            return b
        if t.kind == "bool":
            return self.pick(["TRUE", "FALSE"])
        if t.kind == "sub":
            return str(r.randint(t.lo, t.hi))
        if t.kind == "enum":
            return f"{t.name}#{self.pick(t.values)}"
        if t.kind in ("int", "bit"):
            lo, hi = rng_of(t)
            if not small and self.chance(0.3):
                v = self.pick([lo, hi, lo + 1, hi - 1, 0, 1])
                if v < 0:
                    return f"{t.name}#{v}"
                return f"{t.name}#{v}" if self.chance(0.5) else str(v)
            v = r.randint(max(lo, -20), min(hi, 40))
            if t.kind == "bit" and self.chance(0.4):
                return f"16#{v:X}"
            if v < 0 and self.chance(0.5):
                return f"{t.name}#{v}"
            return str(v)
        if t.kind == "real":
            v = self.pick([0.0, 0.5, 1.0, 1.5, 2.0, -2.5, 10.0, 0.25, 100.0, -0.125, 3.0, 7.75])
            if self.chance(0.3):
                return f"{t.name}#{v}"
            return repr(v)
        if t.kind == "time":
            return f"T#{r.randint(0, 300)}ms"
        if t.kind == "string":
            w = self.pick(WORDS)
            return f"'{w}'"
        raise AssertionError(t)

    # ------------------------------------------------ boundary values (issue 29)
    def bd_chance(self, p):
        return self.bd and self.bd_r.random() < p

    def boundary_ints(self, t):
        """The limits of an integer or bit string type and their neighbours:
        0, 1, -1, MIN, MIN+1, MAX, MAX-1, 2^(n-1) and its neighbours."""
        lo, hi = rng_of(t)
        h = 1 << (t.bits - 1)
        return sorted(v for v in {0, 1, -1, 2, lo, lo + 1, hi, hi - 1, h, h - 1, h + 1}
                      if lo <= v <= hi)

    def boundary_lit(self, t, p=0.2):
        """A boundary literal of an elementary or string type with
        probability p, or None (the ordinary literal then)."""
        if t.kind not in ("int", "bit", "real", "time", "string") or not self.bd_chance(p):
            return None
        r = self.bd_r
        if t.kind in ("int", "bit"):
            self.feat("boundary_" + t.kind)
            v = r.choice(self.boundary_ints(t))
            if v < 0:
                return f"{t.name}#{v}"
            if t.kind == "bit" and r.random() < 0.5:
                return f"{t.name}#16#{v:X}"
            return f"{t.name}#{v}"
        if t.kind == "real":
            self.feat("boundary_real")
            big = ["3.4E38", "-3.4E38", "1.0E-38", "1.4E-45"] if t.bits == 32 else \
                ["1.7E308", "-1.7E308", "2.2E-308", "4.9E-324"]
            return f"{t.name}#" + r.choice(["0.0", "-0.0", "1.0", "-1.0",
                                             "9.2233720368547758E18", "1.8446744073709552E19",
                                             "2147483647.5", "-2147483648.5"] + big)
        if t.kind == "time":
            self.feat("boundary_time")
            return r.choice(["T#0ms", "T#1ms", "T#-1ms", "T#24d20h31m23s647ms",
                             "T#-24d20h31m23s648ms"])
        if not self.strings:
            return None
        self.feat("boundary_string")
        n = min(t.length, 254)
        return "''" if r.random() < 0.4 else "'" + ("abcdefghij" * 26)[:n] + "'"

    def boundary_input(self, t, p=0.3):
        """A boundary value for an input trace (integers, bit strings, reals
        and times) with probability p, or None."""
        if not self.bd_chance(p):
            return None
        r = self.bd_r
        if t.kind in ("int", "bit"):
            self.feat("boundary_input")
            return str(r.choice(self.boundary_ints(t)))
        if t.kind == "real":
            big = ["3.4E38", "-3.4E38", "1.4E-45"] if t.bits == 32 else \
                ["1.7E308", "-1.7E308", "4.9E-324"]
            return r.choice(["0.0", "-0.0", "9.2233720368547758E18"] + big)
        if t.kind == "time":
            return r.choice(["T#0ms", "T#24d20h31m23s647ms"])
        return None

    def boundary_compare_type(self, ct, p=0.25):
        """The operand type of a comparison: with probability p an unsigned
        integer or a wide bit string instead (the ordinary choice has none:
        issue 29's M21 compared them as signed)."""
        if ct.kind in ("int", "bit") and self.bd_chance(p):
            self.feat("boundary_compare_unsigned")
            return self.bd_r.choice([*INTS[4:], *BITS[2:]])
        return ct

    # --------------------------------------------------------------- types
    def make_types(self):
        r = self.r
        p = self.p
        self.enums, self.subs, self.structs, self.arrays = [], [], [], []
        for _ in range(r.randint(0, 2)):
            name = self.uid(p + "E")
            vals = [f"{name}_v{j}" for j in range(r.randint(2, 5))]
            t = Ty("enum", name, values=vals)
            if self.chance(0.4):
                base = self.pick(["INT", "DINT", "USINT"])
                nums = sorted(r.sample(range(0, 90), len(vals)))
                spec = f"{base}(" + ", ".join(f"{v} := {n}" for v, n in zip(vals, nums)) + ")"
                self.feat("enum_valued")
            else:
                spec = "(" + ", ".join(vals) + ")"
            init = f" := {self.pick(vals)}" if self.chance(0.4) else ""
            self.types.append(f"TYPE {name} : {spec}{init}; END_TYPE")
            self.enums.append(t)
            self.feat("enum")
        for _ in range(r.randint(0, 2)):
            name = self.uid(p + "S")
            base = self.pick([T["INT"], T["DINT"], T["SINT"], T["UINT"]])
            lo = r.randint(-5, 5) if base.signed else r.randint(0, 5)
            hi = lo + r.randint(0, 20)
            t = Ty("sub", name, base=base, lo=lo, hi=hi)
            self.types.append(f"TYPE {name} : {base.name}({lo}..{hi}); END_TYPE")
            self.subs.append(t)
            self.feat("subrange")
        for _ in range(r.randint(0, 2)):
            name = self.uid(p + "A")
            t = self.array_type(named=name)
            self.types.append(f"TYPE {name} : {t.spec}; END_TYPE")
            self.arrays.append(t)
        for _ in range(r.randint(0, 2)):
            name = self.uid(p + "R")
            fields = []
            for j in range(r.randint(1, 4)):
                ft = self.pick_type(allow_struct=True, allow_array=True)
                fields.append((f"f{j}", ft))
            t = Ty("struct", name, fields=fields)
            body = " ".join(f"{fn} : {ft.name if ft.kind != 'array' or ft.named else ft.spec}"
                            f"{self.init_for(ft)};" for fn, ft in fields)
            self.types.append(f"TYPE {name} : STRUCT {body} END_STRUCT; END_TYPE")
            self.structs.append(t)
            self.feat("struct")
        if self.chance(0.3):
            name = self.uid(p + "Str")
            n = r.randint(1, 12)
            t = Ty("string", name, length=n)
            self.types.append(f"TYPE {name} : STRING[{n}]; END_TYPE")
            self.named_strings = [t]
        else:
            self.named_strings = []

    def array_type(self, named=None):
        r = self.r
        dims = []
        for _ in range(1 if self.chance(0.7) else r.randint(2, 3)):
            lo = self.pick([0, 1, 1, -2, 5])
            dims.append((lo, lo + r.randint(0, 5)))
        elem = self.pick_type(allow_struct=bool(named), allow_array=False)
        es = elem.name if elem.kind != "array" else elem.spec
        spec = "ARRAY[" + ", ".join(f"{a}..{b}" for a, b in dims) + f"] OF {es}"
        if len(dims) > 1:
            self.feat("array_multidim")
        self.feat("array")
        return Ty("array", named or spec, dims=dims, elem=elem, spec=spec, named=bool(named))

    def pick_type(self, allow_struct=False, allow_array=False, scalar_only=False):
        r = self.r.random()
        if r < 0.12:
            return BOOL
        if r < 0.45:
            return self.pick(INTS[:4] if self.chance(0.7) else INTS)
        if r < 0.52:
            return self.pick(BITS)
        if r < 0.60:
            return self.pick(REALS)
        if r < 0.66:
            return TIME
        if r < 0.72:
            if not self.strings:
                return INT
            if self.named_strings and self.chance(0.3):
                return self.named_strings[0]
            return string_t(self.pick([None, 4, 8, 16]))
        if r < 0.78 and self.enums:
            return self.pick(self.enums)
        if r < 0.82 and self.subs:
            return self.pick(self.subs)
        if scalar_only:
            return INT
        if r < 0.90 and allow_array:
            if self.arrays and self.chance(0.6):
                return self.pick(self.arrays)
            return self.array_type()
        if allow_struct and self.structs:
            return self.pick(self.structs)
        return self.pick(INTS[:4])

    def init_for(self, t, p=0.3):
        if not self.chance(p):
            return ""
        if t.scalar:
            self.feat("init")
            return f" := {self.init_expression(t, self.lit(t))}"
        if t.kind == "array":
            n = 1
            for a, b in t.dims:
                n *= b - a + 1
            if not t.elem.scalar or n > 12:
                return ""
            items = [self.lit(t.elem) for _ in range(self.r.randint(1, n))]
            if len(items) < n and self.chance(0.5):
                items.append(f"{n - len(items)}({self.lit(t.elem)})")
            self.feat("init_array")
            return " := [" + ", ".join(items) + "]"
        if t.kind == "struct":
            fs = [(fn, ft) for fn, ft in t.fields if ft.scalar]
            if not fs:
                return ""
            self.feat("init_struct")
            return " := (" + ", ".join(f"{fn} := {self.lit(ft)}" for fn, ft in fs) + ")"
        return ""

    def init_expression(self, t, text):
        """*text*, an initial value of type t, or now and then an integer
        literal of it as a constant expression of the same value (untyped
        literals the checker folds in t's type: no step leaves t's range)."""
        if not self.init_expr or t.kind not in ("int", "bit") or self.ie_r.random() >= 0.3:
            return text
        try:
            v = int(text.split("#", 1)[1] if text.startswith(t.name + "#") else text)
        except ValueError:
            return text                     # 16#.., a boundary literal's other forms
        lo, hi = rng_of(t)
        k = self.ie_r.randint(1, 9)
        if v - k >= lo and (v - k >= 0 or t.signed):
            a, op = v - k, "+"              # (a + k) = v
        elif v + k <= hi:
            a, op = v + k, "-"              # (a - k) = v
        else:
            return text
        self.feat("init_expr")
        return f"({a} {op} {k})"

    def decl(self, v):
        t = v.ty
        spec = t.name if t.kind not in ("array",) or t.named else t.spec
        loc = f" AT {v.loc}" if v.loc else ""
        edge = f" {v.edge}" if v.edge else ""
        init = f" := {v.init}" if v.init else ""
        return f"{v.name}{loc} : {spec}{edge}{init};"

    # ------------------------------------------------------------ globals
    def make_globals(self):
        r = self.r
        p = self.p
        for _ in range(r.randint(2, 6)):
            t = self.pick_type(allow_struct=True, allow_array=True)
            v = Var(self.uid(p + "g"), t, "global")
            if self.chance(0.3):
                v.init = self.init_for(t, 1.0)[4:] or None
            self.cglobals.append(v)
        for _ in range(r.randint(1, 4)):                  # trace-driven inputs
            t = self.pick_type(scalar_only=True)
            if t.kind == "string":
                t = INT
            v = Var(self.uid(p + "in"), t, "global")
            self.cglobals.append(v)
            self.inputs.append((v.name, t))
        if self.chance(0.5):                             # constants
            t = self.pick([INT, DINT, T["UINT"], BOOL, TIME, REAL])
            v = Var(self.uid(p + "k"), t, "global", ro=True, init=self.lit(t))
            v.const = True
            self.cglobals.append(v)
            self.feat("global_constant")
        if self.chance(0.6):                             # located
            for _ in range(r.randint(1, 3)):
                kind = self.pick("IQM")
                t, addr = self.address(kind)
                v = Var(self.uid(p + "io"), t, "global", loc=addr)
                self.cglobals.append(v)
                if kind == "I":
                    self.inputs.append((v.name, t))
                self.feat("located_" + kind)

    def next_byte(self):
        """Four bytes of the unit's own range (addresses are byte offsets:
        %IW n is bytes 2n, 2n+1; %ID n bytes 4n .. 4n+3)."""
        o = (self.addr_base + self.addr_next) * 4
        self.addr_next += 1
        return o

    @staticmethod
    def addr_text(kind, size, o, bit=0):
        if size == "X":
            return f"%{kind}X{o}.{bit}"
        return f"%{kind}{size}{o // {'B': 1, 'W': 2, 'D': 4}[size]}"

    def address(self, kind):
        o = self.next_byte()
        size = self.pick("XBWD")
        if size == "X":
            return BOOL, self.addr_text(kind, "X", o, self.r.randint(0, 7))
        t = {"B": self.pick(["BYTE", "SINT", "USINT"]), "W": self.pick(["WORD", "INT", "UINT"]),
             "D": self.pick(["DWORD", "DINT", "UDINT"])}[size]
        return T[t], self.addr_text(kind, size, o)

    # ------------------------------------------------------------ scopes
    def readable(self, scope, want, exact=True, writable=False):
        """(path, Ty) pairs of scope that give a value of type want."""
        out = []
        for v in scope:
            if v.sink or v.wo or (writable and (v.ro or v.reserved)):
                continue
            for path, t, w in self.paths(v.name, v.ty, 0):
                if writable and not w:
                    continue
                if self.fits(t, want, writable):
                    out.append((path, t))
        return out

    def fits(self, t, want, exact_target=False):
        if want.kind == "sub":
            return t is want or (not exact_target and False)
        if t.kind == "sub":
            return (not exact_target) and want.kind == "int" and want.name == t.base.name
        if want.kind in ("enum", "struct", "array"):
            return t is want
        return same_type(t, want)

    def paths(self, name, t, depth):
        """Every (path template, Ty, writable) reachable in a value of type t.
        A template is a tuple of text parts and ("idx", dims) slots."""
        base = name if isinstance(name, tuple) else (name,)
        out = [(base, t, True)]
        if depth > 3:
            return out
        if t.kind == "array":
            sub = base + ("[", ("idx", tuple(t.dims)), "]")
            out += self.paths(sub, t.elem, depth + 1)
        elif t.kind == "struct":
            for fn, ft in t.fields:
                out += self.paths(base + ("." + fn,), ft, depth + 1)
        elif t.kind == "fb":
            out = [(base, t, False)]
            for on, ot in t.outputs:
                out.append((base + ("." + on,), ot, False))
        elif t.kind == "bit" and depth == 0 and self.chance(0.2):
            out.append((base + (f".{self.r.randint(0, t.bits - 1)}",), BOOL, True))
            self.feat("bit_access")
        return out

    @staticmethod
    def plain(path):
        """A template without index slots (IL operands)."""
        return all(isinstance(p, str) for p in path)

    def render_path(self, path, scope, d):
        out = []
        for part in path:
            if isinstance(part, str):
                out.append(part)
            else:
                out.append(", ".join(self.index(lo, hi, scope, d) for lo, hi in part[1]))
        return "".join(out)

    def index(self, lo, hi, scope, d):
        r = self.r.random()
        n = hi - lo + 1
        fors = [v for v in self.for_ranges if v[1] >= lo and v[2] <= hi]
        if fors and r < 0.3:
            return self.pick(fors)[0]
        if r < 0.6:
            return str(self.r.randint(lo, hi))
        if r < 0.97 or self.safe:
            e = self.expr(INT, scope, d + 1)
            self.feat("index_computed")
            return f"ABS({e} MOD {n}) + {lo}" if lo else f"ABS({e} MOD {n})"
        vs = [p for p, _ in self.readable(scope, INT) if self.plain(p)]
        if not vs:
            return str(lo)
        self.feat("index_risky")
        return f"ABS({''.join(self.pick(vs))} MOD {n + 1}) + {lo}"

    # --------------------------------------------------------- expressions
    def expr(self, t, scope, d=0, fuzzy=False):
        """An expression of type t (assignable to t)."""
        if t.kind == "sub":
            base = t.base
            e = self.expr(base, scope, d + 1)
            if not self.risky(0.03):
                return f"LIMIT({t.lo}, {e}, {t.hi})"
            vs = [p for p, tt in self.readable(scope, base) if self.plain(p)]
            if not vs:
                return f"LIMIT({t.lo}, {e}, {t.hi})"
            self.feat("subrange_risky")
            k = self.r.randint(0 if not base.signed else -2, 2)
            return f"({''.join(self.pick(vs))} + {k})"
        leaf = d >= 3 or self.chance(0.25 + 0.15 * d)
        cands = self.readable(scope, t)
        # implicit widening only where the expression's type is the target's:
        # inside an operation an untyped constant would be typed by the
        # narrower operand (the front end's rule) and may not fit it
        if t.kind in ("int", "bit", "real", "time") and d == 0 and self.chance(0.15):
            for w, targets in WIDEN.items():
                if t.name in targets and (T[w].signed or not t.signed):
                    cands += self.readable(scope, T[w])
                    self.feat("implicit_widen")
        if leaf:
            if cands and self.chance(0.7):
                return self.render_path(self.pick(cands)[0], scope, d)
            return self.lit(t, small=d > 0 or self.chance(0.8), bare=(d == 0))
        m = getattr(self, "e_" + t.kind)
        return m(t, scope, d + 1, fuzzy)

    def call_user_fn(self, t, scope, d):
        if self.safe:       # its body may fault
            return None
        fns = [f for f in self.funcs if f.result is not None and same_type(f.result, t)
               and f.name != getattr(self, "cur_name", None)]
        if not fns:
            return None
        f = self.pick(fns)
        args = []
        formal = self.chance(0.4)
        was, self.safe = self.safe, self.safe or "fault_in_call_arg" in AVOID
        try:
            return self._call_user_fn(f, args, formal, scope, d)
        finally:
            self.safe = was

    def _call_user_fn(self, f, args, formal, scope, d):
        for v in f.vars:
            if v.sec == "in":
                e = self.arg_expr(v.ty, scope, d)
                if e is None:
                    return None
                args.append(f"{v.name} := {e}" if formal else e)
            elif v.sec == "inout":
                c = self.inout_args(scope, v.ty)
                if not c:
                    return None
                pth = self.render_path(self.pick(c)[0], scope, d)
                args.append(f"{v.name} := {pth}" if formal else pth)
                self.feat("function_inout")
            elif v.sec == "out" and formal and self.chance(0.5):
                c = [x for x in self.readable(scope, v.ty, writable=True) if x[1].kind != "sub"]
                if c:
                    args.append(f"{v.name} => {self.render_path(self.pick(c)[0], scope, d)}")
                    self.feat("function_output")
        if formal and getattr(f, "eno", False) and self.fid_chance(0.6):
            c = [x for x in self.readable(scope, BOOL, writable=True) if x[1] is BOOL]
            if c:
                args.append(f"ENO => {self.render_path(self.pick(c)[0], scope, d)}")
                self.feat("function_eno_out")
        self.feat("user_function")
        return f"{f.name}({', '.join(args)})"

    def inout_args(self, scope, want):
        """Variables that can be passed to a VAR_IN_OUT of type want."""
        if want.kind == "fb":
            return [((v.name,), v.ty) for v in scope if v.ty.kind == "fb" and
                    not v.ty.is_array and v.ty.name == want.name]
        out = []
        for p, t in self.readable(scope, want, writable=True):
            if t is not want and not (want.scalar and same_type(t, want) and t.kind != "sub"):
                continue
            # a reference: a string of the parameter's own length, and not a
            # bit of a word (no address); the front end rejects both
            # (tests/errors/references.st)
            if want.kind == "string" and t.length != want.length:
                continue
            if want.kind == "bool" and \
                    re.search(r"\.[0-9]+$", p[-1] if isinstance(p[-1], str) else ""):
                continue
            out.append((p, t))
        return out

    def arg_expr(self, t, scope, d):
        if t.scalar:
            return self.expr(t, scope, d)
        c = [x for x in self.readable(scope, t)]
        if not c:
            return None
        return self.render_path(self.pick(c)[0], scope, d)

    def e_int(self, t, scope, d, fuzzy):
        r = self.r.random()
        x = lambda: self.expr(t, scope, d)   # noqa: E731
        if r < 0.30:
            op = self.pick(["+", "-", "*"])
            self.feat("arith")
            return f"({x()} {op} {x()})"
        if r < 0.40:
            op = self.pick(["/", "MOD"])
            if not self.risky(0.1):
                lo, hi = rng_of(t)
                k = self.r.randint(1, min(hi, 9))
                if t.signed and self.chance(0.3):
                    k = -k
                if op == "MOD" and self.fid_chance(0.3):
                    self.feat("fn_form_MOD")        # the function form (issue 10)
                    return f"MOD({x()}, {k})"
                return f"({x()} {op} {k})"
            self.feat("div_risky")
            return f"({x()} {op} {x()})"
        if r < 0.45 and t.signed:
            return f"-{x()}" if self.chance(0.5) else f"ABS({x()})"
        if r < 0.55:
            f = self.pick(["MAX", "MIN", "LIMIT", "SEL", "MUX", "MOVE"])
            self.feat("std_" + f)
            if f == "LIMIT":
                return f"LIMIT({x()}, {x()}, {x()})"
            if f == "SEL":
                return f"SEL({self.expr(BOOL, scope, d)}, {x()}, {x()})"
            if f == "MUX":
                k = self.expr(INT, scope, d)
                if not self.risky(0.1):
                    k = f"ABS({k} MOD 3)"
                return f"MUX({k}, {x()}, {x()}, {x()})"
            if f == "MOVE":
                return f"MOVE({x()})"
            return f"{f}({', '.join(x() for _ in range(self.r.randint(2, 3)))})"
        if r < 0.70:
            src = self.pick([*INTS, *BITS, BOOL, REAL, LREAL] +
                            ([TIME] if t.name in ("DINT", "LINT", "UDINT", "ULINT") else []))
            if src.name == t.name:
                return x()
            self.feat("conv")
            return f"{src.name}_TO_{t.name}({self.expr(src, scope, d)})"
        if r < 0.76 and t.name == "INT" and self.strings:
            s = self.expr(string_t(), scope, d)
            if self.chance(0.5):
                self.feat("std_LEN")
                return f"LEN({s})"
            self.feat("std_FIND")
            return f"FIND({s}, {self.expr(string_t(), scope, d)})"
        if r < 0.80 and t.name == "DINT":
            self.feat("std_TRUNC")
            return f"TRUNC({self.expr(LREAL, scope, d)})"
        if r < 0.84 and t.name in ("SINT", "INT", "DINT") and self.chance(0.5):
            self.feat("real_trunc_conv")
            return f"REAL_TRUNC_{t.name}({self.expr(REAL, scope, d)})"
        if r < 0.92:
            e = self.call_user_fn(t, scope, d)
            if e:
                return e
        if r < 0.96 and t.name in ("INT", "DINT"):
            tt = self.pick([INT, DINT, TIME])
            if tt.name != t.name and tt.kind == "int":
                return f"{tt.name}_TO_{t.name}({self.expr(tt, scope, d)})"
        return x() if self.chance(0.3) else self.lit(t, bare=False)

    def e_bit(self, t, scope, d, fuzzy):
        r = self.r.random()
        x = lambda: self.expr(t, scope, d)   # noqa: E731
        if r < 0.35:
            self.feat("bitwise")
            if self.fid_chance(0.2):
                self.feat("fn_form_bitwise")    # AND(a, b, ...) (issue 10)
                return f"{self.pick(['AND', 'OR', 'XOR'])}" \
                    f"({', '.join(x() for _ in range(self.r.randint(2, 3)))})"
            return f"({x()} {self.pick(['AND', 'OR', 'XOR', '&'])} {x()})"
        if r < 0.45:
            return f"NOT {x()}"
        if r < 0.65:
            f = self.pick(["SHL", "SHR", "ROL", "ROR"])
            self.feat("std_" + f)
            n = self.r.randint(0, t.bits + 2) if self.chance(0.8) else \
                self.expr(self.pick([INT, T["USINT"]]), scope, d)
            return f"{f}({x()}, {n})"
        if r < 0.75:
            f = self.pick(["MAX", "MIN", "MOVE"])
            return f"MOVE({x()})" if f == "MOVE" else f"{f}({x()}, {x()})"
        if r < 0.88:
            src = self.pick([*INTS, *BITS, BOOL])
            if src.name == t.name:
                return x()
            self.feat("conv")
            return f"{src.name}_TO_{t.name}({self.expr(src, scope, d)})"
        e = self.call_user_fn(t, scope, d)
        return e or self.lit(t, bare=False)

    def e_real(self, t, scope, d, fuzzy):
        r = self.r.random()
        x = lambda: self.expr(t, scope, d, fuzzy)   # noqa: E731
        if fuzzy and r < 0.3:
            f = self.pick(FUZZY_FNS + ["EXPT", "**"])
            self.feat("std_" + f)
            if f == "EXPT":
                return f"EXPT({x()}, {self.pick([x(), self.lit(INT)])})"
            if f == "**":
                return f"(({x()}) ** ({x()}))"
            return f"{f}({x()})"
        if r < 0.40:
            return f"({x()} {self.pick(['+', '-', '*', '/'])} {x()})"
        if r < 0.50:
            return f"-{x()}" if self.chance(0.5) else f"ABS({x()})"
        if r < 0.58:
            self.feat("std_SQRT")
            if self.fid_chance(0.3):
                # an untyped real literal typed by its context (issue 10):
                # SQRT on REAL where t is REAL (sqrt is exact in both engines)
                self.feat("real_literal_context")
                return f"SQRT({self.fid_r.randint(0, 400) / 4.0!r})"
            return f"SQRT({x()})"
        if r < 0.66:
            f = self.pick(["MAX", "MIN", "LIMIT", "SEL"])
            if f == "LIMIT":
                return f"LIMIT({x()}, {x()}, {x()})"
            if f == "SEL":
                return f"SEL({self.expr(BOOL, scope, d)}, {x()}, {x()})"
            return f"{f}({x()}, {x()})"
        if r < 0.85:
            src = self.pick([*INTS, REAL, LREAL])
            if src.name == t.name:
                return x()
            self.feat("conv_to_real")
            return f"{src.name}_TO_{t.name}({self.expr(src, scope, d, fuzzy)})"
        e = self.call_user_fn(t, scope, d)
        return e or self.lit(t, bare=False)

    def e_time(self, t, scope, d, fuzzy):
        r = self.r.random()
        x = lambda: self.expr(t, scope, d)   # noqa: E731
        if r < 0.4:
            self.feat("time_arith")
            return f"({x()} {self.pick(['+', '-'])} {x()})"
        if r < 0.5:
            return f"({x()} * {self.r.randint(0, 5)})"
        if r < 0.6:
            return f"({x()} / {self.r.randint(1, 5)})"
        if r < 0.75:
            f = self.pick(["MAX", "MIN", "LIMIT", "SEL"])
            if f == "LIMIT":
                return f"LIMIT({x()}, {x()}, {x()})"
            if f == "SEL":
                return f"SEL({self.expr(BOOL, scope, d)}, {x()}, {x()})"
            return f"{f}({x()}, {x()})"
        if r < 0.9:
            self.feat("conv_time")
            return f"DINT_TO_TIME({self.expr(DINT, scope, d)})"
        e = self.call_user_fn(t, scope, d)
        return e or self.lit(t, bare=False)

    def e_string(self, t, scope, d, fuzzy):
        r = self.r.random()
        S = string_t()
        s = lambda: self.expr(S, scope, d)   # noqa: E731

        def n():
            if self.chance(0.85):
                return str(self.r.randint(-1, 10))
            return self.expr(INT, scope, d)
        if r < 0.25:
            self.feat("std_CONCAT")
            return f"CONCAT({', '.join(s() for _ in range(self.r.randint(2, 3)))})"
        if r < 0.6:
            f = self.pick(["LEFT", "RIGHT", "MID", "INSERT", "DELETE", "REPLACE"])
            self.feat("std_" + f)
            if f in ("LEFT", "RIGHT"):
                return f"{f}({s()}, {n()})"
            if f == "MID":
                return f"MID({s()}, {n()}, {n()})"
            if f == "INSERT":
                return f"INSERT({s()}, {s()}, {n()})"
            if f == "DELETE":
                return f"DELETE({s()}, {n()}, {n()})"
            return f"REPLACE({s()}, {s()}, {n()}, {n()})"
        if r < 0.8:
            src = self.pick([*INTS, *BITS, BOOL, REAL, LREAL, TIME])
            self.feat("conv_to_string")
            return f"{src.name}_TO_STRING({self.expr(src, scope, d)})"
        if r < 0.85:
            return f"SEL({self.expr(BOOL, scope, d)}, {s()}, {s()})"
        e = None if "string_fn_in_concat" in AVOID and d > 1 else self.call_user_fn(t, scope, d)
        return e or self.lit(t, bare=False)

    def e_enum(self, t, scope, d, fuzzy):
        if self.chance(0.4):
            return f"SEL({self.expr(BOOL, scope, d)}, {self.expr(t, scope, d)}, " \
                   f"{self.expr(t, scope, d)})"
        e = self.call_user_fn(t, scope, d)
        return e or self.lit(t, bare=False)

    def e_bool(self, t, scope, d, fuzzy):
        r = self.r.random()
        x = lambda: self.expr(BOOL, scope, d)   # noqa: E731
        if r < 0.25:
            if self.fid_chance(0.15):
                self.feat("fn_form_bitwise")
                return f"{self.pick(['AND', 'OR', 'XOR'])}" \
                    f"({', '.join(x() for _ in range(self.r.randint(2, 3)))})"
            return f"({x()} {self.pick(['AND', 'OR', 'XOR', '&'])} {x()})"
        if r < 0.32:
            return f"NOT {x()}"
        if r < 0.7:
            ct = self.pick([*INTS[:4], INT, INT, DINT, *BITS[:2], REAL, LREAL, TIME, string_t()]
                           + self.enums)
            if ct.kind == "string" and not self.strings:
                ct = INT
            ct = self.boundary_compare_type(ct)
            a, b = self.expr(ct, scope, d), self.expr(ct, scope, d)
            while clash(a, b, ct):
                a, b = self.expr(ct, scope, d), self.lit(ct, bare=False)
            ops = ["=", "<>"] if ct.kind == "enum" else ["=", "<>", "<", ">", "<=", ">="]
            self.feat("compare_" + ct.kind)
            if self.chance(0.15) and ct.kind not in ("enum", "string"):
                f = self.pick(["GT", "GE", "EQ", "LE", "LT", "NE"])
                return f"{f}({a}, {b})"
            return f"({a} {self.pick(ops)} {b})"
        if r < 0.8:
            src = self.pick([*INTS, *BITS])
            self.feat("conv_to_bool")
            return f"{src.name}_TO_BOOL({self.expr(src, scope, d)})"
        e = self.call_user_fn(t, scope, d)
        return e or self.lit(t, bare=False)

    # ---------------------------------------------------------- statements
    def lvalues(self, scope, t=None):
        out = []
        for v in scope:
            if v.ro or v.reserved or v.ty.kind == "fb" or \
                    v.ty.kind == "array" and v.ty.elem.kind == "fb":
                continue
            for path, tt, w in self.paths(v.name, v.ty, 0):
                if w and (t is None or tt is t or (t.scalar and same_type(tt, t))):
                    out.append((path, tt, v))
        return out

    def assignment(self, scope, d):
        lv = self.lvalues(scope)
        if not lv:
            return None
        path, t, v = self.pick(lv)
        if t.kind in ("string", "array", "struct") and "fault_in_string_store" in AVOID:
            was, self.safe = self.safe, True
            try:
                return self._assignment(path, t, v, scope, d)
            finally:
                self.safe = was
        return self._assignment(path, t, v, scope, d)

    def _assignment(self, path, t, v, scope, d):
        lhs = self.render_path(path, scope, d)
        if v.sink:
            self.feat("fuzzy_real")
            return f"{lhs} := {self.expr(t, scope, 0, fuzzy=True)};"
        if t.kind in ("array", "struct"):
            same = [x for x in self.readable(scope, t) if x[0] != path and self.plain(x[0])]
            if not same:
                return None
            self.feat("aggregate_assign")
            return f"{lhs} := {self.render_path(self.pick(same)[0], scope, d)};"
        rhs = self.expr(t, scope)
        if "string_alias" in AVOID and t.kind == "string" and "[" in lhs and \
                re.search(rf"\b{re.escape(lhs.split('[')[0])}\[", rhs):
            rhs = self.lit(t)
        return f"{lhs} := {rhs};"

    def stmts(self, scope, d, n, ctx):
        out = []
        for _ in range(n):
            s = self.stmt(scope, d, ctx)
            if s:
                out += s if isinstance(s, list) else [s]
        return out

    def stmt(self, scope, d, ctx):
        r = self.r.random()
        ind = "    " * (d + 1)
        deep = d >= 3
        if r < 0.40 or deep and r < 0.8:
            s = self.assignment(scope, d)
            return [ind + s] if s else None
        if r < 0.50:
            self.feat("if")
            out = [f"{ind}IF {self.expr(BOOL, scope)} THEN"]
            out += self.stmts(scope, d + 1, self.r.randint(1, 3), ctx)
            for _ in range(self.r.randint(0, 2)):
                self.feat("elsif")
                out.append(f"{ind}ELSIF {self.expr(BOOL, scope)} THEN")
                out += self.stmts(scope, d + 1, self.r.randint(1, 2), ctx)
            if self.chance(0.5):
                out.append(f"{ind}ELSE")
                out += self.stmts(scope, d + 1, self.r.randint(1, 2), ctx)
            out.append(f"{ind}END_IF;")
            return out
        if r < 0.57:
            return self.case_stmt(scope, d, ctx)
        if r < 0.66:
            return self.for_stmt(scope, d, ctx)
        if r < 0.71:
            return self.while_stmt(scope, d, ctx)
        if r < 0.80:
            return self.fb_call(scope, d)
        if r < 0.83 and ctx.get("loop"):
            self.feat("exit")
            return [f"{ind}IF {self.expr(BOOL, scope)} THEN", f"{ind}    EXIT;", f"{ind}END_IF;"]
        if r < 0.85:
            self.feat("return")
            return [f"{ind}IF {self.expr(BOOL, scope)} THEN", f"{ind}    RETURN;",
                    f"{ind}END_IF;"]
        if r < 0.86:
            self.feat("empty_stmt")
            return [f"{ind};"]
        if r < 0.88 and self.chance(0.05) and not ctx.get("fn"):
            self.feat("endless_loop")
            return [f"{ind}IF {self.expr(BOOL, scope)} AND {self.expr(BOOL, scope)} THEN",
                    f"{ind}    WHILE TRUE DO", f"{ind}        ;", f"{ind}    END_WHILE;",
                    f"{ind}END_IF;"]
        s = self.assignment(scope, d)
        return [ind + s] if s else None

    def case_stmt(self, scope, d, ctx):
        ind = "    " * (d + 1)
        sels = [t for t in [INT, DINT, T["USINT"], T["SINT"]] + self.enums + self.subs]
        st = self.pick(sels)
        if st.kind == "sub":
            c = self.readable(scope, st)
            if c:
                sel = self.render_path(self.pick(c)[0], scope, d)
            else:
                st = st.base
                sel = self.expr(st, scope)
        else:
            sel = self.expr(st, scope)
        out = [f"{ind}CASE {sel} OF"]
        self.feat("case")
        if st.kind == "enum":
            vals = list(st.values)
            self.r.shuffle(vals)
            self.feat("case_enum")
            while vals:
                k = self.r.randint(1, min(2, len(vals)))
                labels, vals = vals[:k], vals[k:]
                if self.chance(0.3) and vals:
                    continue
                out.append(f"{ind}{', '.join(f'{st.name}#{v}' for v in labels)}:")
                out += self.stmts(scope, d + 1, self.r.randint(1, 2), ctx) or [ind + "    ;"]
        else:
            lo, hi = rng_of(st)
            lo, hi = max(lo, -5), min(hi, 20)
            pts = sorted(self.r.sample(range(lo, hi + 1), min(hi - lo + 1, self.r.randint(1, 5))))
            used = set()
            for pt in pts:
                if pt in used:
                    continue
                if self.chance(0.3) and pt + 2 <= hi and not ({pt + 1, pt + 2} & set(pts)):
                    lab = f"{pt}..{pt + 2}"
                    used |= {pt, pt + 1, pt + 2}
                    self.feat("case_range")
                    if self.cur_pou is not None and self.nc_chance(0.25):
                        lab = f"{self.named_constant(self.cur_pou, pt)}..{pt + 2}"
                        self.feat("named_const_case")
                else:
                    lab = str(pt)
                    used.add(pt)
                    if self.cur_pou is not None and self.nc_chance(0.25):
                        lab = self.named_constant(self.cur_pou, pt)
                        self.feat("named_const_case")
                out.append(f"{ind}{lab}:")
                out += self.stmts(scope, d + 1, self.r.randint(1, 2), ctx) or [ind + "    ;"]
        if self.chance(0.5):
            out.append(f"{ind}ELSE")
            out += self.stmts(scope, d + 1, self.r.randint(1, 2), ctx)
        out.append(f"{ind}END_CASE;")
        return out

    def loop_var(self, scope, t=None):
        free = [v for v in scope if v.sec in ("var", "temp") and v.ty.kind == "int"
                and not v.reserved and v.ty.name in ("INT", "DINT", "SINT", "LINT")
                and (t is None or v.ty.name == t)]
        return self.pick(free) if free else None

    def for_stmt(self, scope, d, ctx):
        ind = "    " * (d + 1)
        v = self.loop_var(scope)
        if v is None:
            return None
        self.feat("for")
        lo, hi = self.r.randint(-3, 5), self.r.randint(-3, 12)
        step = self.pick([None, 1, 2, 3, -1, -2])
        if step is not None and step < 0 or step is None and self.chance(0.2):
            lo, hi = max(lo, hi), min(lo, hi)
            step = step if step is not None else -1
            self.feat("for_down")
        a, b = str(lo), str(hi)
        was, self.safe = self.safe, self.safe or "fault_in_for_head" in AVOID
        if self.chance(0.3):
            self.feat("for_variable_bounds")
            e = self.expr(v.ty, scope)
            a = f"({e} MOD 4) + {lo}"
        st = f" BY {step}" if step is not None else ""
        if step is not None and self.chance(0.25):
            self.feat("for_variable_step")
            e = self.expr(v.ty, scope)
            st = f" BY {'-' if step < 0 else ''}(ABS({e} MOD 3) + 1)"
        elif step is not None:
            self.feat("for_const_step")
        self.safe = was
        v.reserved = True
        rng = (v.name, min(lo, hi), max(lo, hi))
        ranged = not a.startswith("(")
        if ranged:
            self.for_ranges.append(rng)
        body = self.stmts(scope, d + 1, self.r.randint(1, 3), dict(ctx, loop=True))
        if ranged:
            self.for_ranges.remove(rng)
        v.reserved = False
        if self.cont and self.ct_r.random() < 0.2:
            # at the start or after the first statement of the body
            at = 0 if not body or self.ct_r.random() < 0.5 else len(body)
            body = body[:at] + self.continue_if(v.name, ind + "    ") + body[at:]
            self.feat("continue_for")
        return [f"{ind}FOR {v.name} := {a} TO {b}{st} DO"] + (body or [ind + "    ;"]) + \
            [f"{ind}END_FOR;"]

    def while_stmt(self, scope, d, ctx):
        ind = "    " * (d + 1)
        v = self.loop_var(scope)
        if v is None:
            return None
        v.reserved = True
        n = self.r.randint(0, 8)
        body = self.stmts(scope, d + 1, self.r.randint(1, 3), dict(ctx, loop=True))
        v.reserved = False
        step = [f"{ind}    {v.name} := {v.name} + 1;"]
        head, tail = [], step
        if self.cont and self.ct_r.random() < 0.2:
            # the counter first, so that CONTINUE cannot skip it
            head, tail = step + self.continue_if(v.name, ind + "    "), []
            self.feat("continue_while")
        if self.chance(0.5):
            self.feat("while")
            return [f"{ind}{v.name} := 0;", f"{ind}WHILE {v.name} < {n} DO"] + head + body + \
                tail + [f"{ind}END_WHILE;"]
        self.feat("repeat")
        return [f"{ind}{v.name} := 0;", f"{ind}REPEAT"] + head + body + tail + \
            [f"{ind}UNTIL {v.name} >= {n}", f"{ind}END_REPEAT;"]

    def fb_call(self, scope, d):
        ind = "    " * (d + 1)
        insts = [v for v in scope if v.ty.kind == "fb" and not v.ty.is_array]
        arrays = [v for v in scope if v.ty.kind == "array" and v.ty.elem.kind == "fb" and
                  len(v.ty.dims) == 1]
        if arrays and self.fid_chance(1.0 if not insts else 0.3):
            v = self.pick(arrays)
            t = v.ty.elem
            (lo, hi), = v.ty.dims
            callee = f"{v.name}[{self.index(lo, hi, scope, d)}]"
            self.feat("fb_array_call")          # t[i](...) (issue 10)
        elif not insts:
            return None
        else:
            v = self.pick(insts)
            t = v.ty
            callee = v.name
        args = []
        self.safe = "fault_in_call_arg" in AVOID
        for name, it in t.inputs:
            if self.chance(0.8):
                args.append(f"{name} := {self.expr(it, scope)}")
        self.safe = False
        for name, ot in t.inout:
            c = self.inout_args(scope, ot)
            if not c:
                return None
            args.append(f"{name} := {self.render_path(self.pick(c)[0], scope, d)}")
            if ot.kind == "fb":
                self.feat("fb_inout_instance_call")
        for name, ot in t.outputs:
            if self.chance(0.3):
                c = [x for x in self.readable(scope, ot, writable=True)
                     if same_type(x[1], ot) and x[1].kind != "sub" and ot.scalar]
                if c:
                    was, self.safe = self.safe, self.safe or "output_index_call" in AVOID
                    args.append(f"{name} => {self.render_path(self.pick(c)[0], scope, d)}")
                    self.safe = was
                    self.feat("fb_output_binding")
        self.feat("fb_call_std" if t.std else "fb_call_user")
        self.feat("std_fb_" + t.name) if t.std else None
        return [f"{ind}{callee}({', '.join(args)});"]

    # ----------------------------------------------------------------- IL
    def il_operand(self, t, scope):
        c = [x for x in self.readable(scope, t) if self.plain(x[0]) and x[1].kind != "sub"]
        if c and self.chance(0.6):
            return "".join(self.pick(c)[0])
        return self.lit(t)

    def il_target(self, t, scope):
        c = [(p, tt, v) for p, tt, v in self.lvalues(scope, t) if self.plain(p) and not v.sink
             and tt.kind != "sub" and same_type(tt, t)]
        return "".join(self.pick(c)[0]) if c else None

    def il_body(self, scope, pou):
        """Lines of an IL body: segments that each start with LD, forward
        jumps to labels at segment starts, deferred operations, CAL."""
        segs = []
        for _ in range(self.r.randint(3, int(9 * self.size) + 3)):
            s = self.il_segment(scope, pou)
            if s:
                segs.append(s)
        if not segs:
            segs = [["LD TRUE", "NOT"]]
        # forward jumps
        labels = {}
        for i in range(len(segs) - 1):
            if self.chance(0.2):
                j = self.r.randint(i + 1, len(segs) - 1)
                lab = labels.setdefault(j, self.uid("L"))
                cond = self.expr_il_bool(scope)
                segs[i] = segs[i] + cond + [f"{self.pick(['JMPC', 'JMPCN'])} {lab}"]
                self.feat("il_jump")
            elif self.chance(0.05):
                j = self.r.randint(i + 1, len(segs) - 1)
                lab = labels.setdefault(j, self.uid("L"))
                segs[i] = segs[i] + [f"JMP {lab}"]
                self.feat("il_jmp")
        out = []
        for i, s in enumerate(segs):
            if i in labels:
                out.append(f"{labels[i]}:")
            out += s
        if self.chance(0.1):
            out += ["LD FALSE", "RETC"]
            self.feat("il_ret")
        return ["        " + ln if not ln.endswith(":") else ln for ln in out]

    def expr_il_bool(self, scope):
        a = self.il_operand(BOOL, scope)
        out = [f"LD {a}"]
        if self.chance(0.5):
            out.append(f"{self.pick(['AND', 'OR', 'XOR', 'ANDN', 'ORN'])} "
                       f"{self.il_operand(BOOL, scope)}")
        return out

    def il_segment(self, scope, pou):
        r = self.r.random()
        if r < 0.45:
            t = self.pick([INT, DINT, INT, T["SINT"], T["UINT"], T["LINT"], REAL, LREAL])
            tgt = self.il_target(t, scope)
            if tgt is None:
                return None
            first = self.il_operand(t, scope)
            if "il_literal_cr" in AVOID and re.match(r"^[-+]?[0-9]", first):
                first = f"{t.name}#{first}"
            out = [f"LD {first}"]
            for _ in range(self.r.randint(0, 3)):
                op = self.pick(["ADD", "SUB", "MUL", "DIV", "MOD"] if t.kind == "int"
                               else ["ADD", "SUB", "MUL"])
                if op in ("DIV", "MOD"):
                    opd = str(self.r.randint(1, 7)) if self.chance(0.9) else \
                        self.il_operand(t, scope)
                    out.append(f"{op} {opd}")
                elif self.chance(0.25):
                    self.feat("il_deferred")
                    out.append(f"{op}( {self.il_operand(t, scope)}")
                    out.append(f"{self.pick(['ADD', 'SUB', 'MUL'])} {self.il_operand(t, scope)}")
                    out.append(")")
                else:
                    out.append(f"{op} {self.il_operand(t, scope)}")
            if t.kind == "int" and self.chance(0.2):
                f = self.pick(["MAX", "MIN", "LIMIT", "ABS"] if t.signed else ["MAX", "MIN"])
                out.append(f"LIMIT {self.lit(t)}, {self.lit(t)}" if f == "LIMIT" else
                           "ABS" if f == "ABS" else f"{f} {self.il_operand(t, scope)}")
                self.feat("il_function")
            out.append(f"ST {tgt}")
            self.feat("il_arith")
            return out
        if r < 0.70:
            tgt = self.il_target(BOOL, scope)
            if tgt is None:
                return None
            out = [f"{self.pick(['LD', 'LDN'])} {self.il_operand(BOOL, scope)}"]
            for _ in range(self.r.randint(0, 3)):
                op = self.pick(["AND", "OR", "XOR", "ANDN", "ORN", "XORN"])
                if self.chance(0.3):
                    self.feat("il_deferred")
                    out.append(f"{op}( {self.il_operand(BOOL, scope)}")
                    out.append(f"{self.pick(['AND', 'OR'])} {self.il_operand(BOOL, scope)}")
                    out.append(")")
                else:
                    out.append(f"{op} {self.il_operand(BOOL, scope)}")
            if self.chance(0.2):
                out.append("NOT")
            out.append(f"{self.pick(['ST', 'STN', 'S', 'R'])} {tgt}")
            self.feat("il_logic")
            return out
        if r < 0.82:
            t = self.pick([INT, DINT, TIME, REAL])
            tgt = self.il_target(BOOL, scope)
            if tgt is None:
                return None
            self.feat("il_compare")
            a, b = self.il_operand(t, scope), self.il_operand(t, scope)
            while clash(a, b, t):
                a, b = self.il_operand(t, scope), self.lit(t)
            return [f"LD {a}", f"{self.pick(['GT', 'GE', 'EQ', 'NE', 'LE', 'LT'])} {b}",
                    f"ST {tgt}"]
        if r < 0.88:
            src, dst = self.pick([(INT, REAL), (INT, DINT), (DINT, INT), (REAL, INT),
                                  (T["UINT"], T["WORD"]), (BOOL, INT)])
            tgt = self.il_target(dst, scope)
            if tgt is None:
                return None
            self.feat("il_conv")
            return [f"LD {self.il_operand(src, scope)}", f"{src.name}_TO_{dst.name}", f"ST {tgt}"]
        insts = [v for v in scope if v.ty.kind == "fb" and not v.ty.is_array]
        if not insts:
            return None
        v = self.pick(insts)
        t = v.ty
        if t.std and self.chance(0.5):
            out = []
            for name, it in t.inputs:
                if name in ("S1", "R", "CLK", "CU", "CD", "PV", "IN", "PT"):
                    out += [f"LD {self.il_operand(it, scope)}", f"{name} {v.name}"]
            out.append(f"CAL {v.name}")
            self.feat("il_fb_operators")
            return out
        args = []
        for name, it in t.inputs:
            if self.chance(0.7):
                args.append(f"{name} := {self.il_operand(it, scope)}")
        for name, ot in t.inout:
            c = [x for x in self.inout_args(scope, ot) if self.plain(x[0])]
            if not c:
                return None
            args.append(f"{name} := {''.join(self.pick(c)[0])}")
        op = self.pick(["CAL", "CAL", "CALC", "CALCN"])
        out = []
        if op != "CAL":
            out = self.expr_il_bool(scope)
        self.feat("il_" + op)
        return out + [f"{op} {v.name}({', '.join(args)})"]

    # ------------------------------------------------------------ POUs
    def locals_for(self, pou, n):
        for _ in range(n):
            t = self.pick_type(allow_struct=True, allow_array=True)
            init = self.init_for(t)[4:] or None
            pou.vars.append(Var(self.uid("v"), self.named_bounds(pou, t), "var", init=init))
        for name in ("i", "j"):
            pou.vars.append(Var(f"{name}{self.uid('')}", self.pick([INT, DINT]), "var"))
        if self.chance(0.5):
            t = self.pick([INT, BOOL, REAL, string_t(8)])
            if t.kind == "string" and not self.strings:
                t = INT
            pou.vars.append(Var(self.uid("tmp"), t, "temp"))
            self.feat("var_temp")
            pou.vars.append(Var(self.uid("ti"), INT, "temp"))
        if self.chance(0.3):
            t = self.pick([INT, DINT, BOOL, REAL])
            pou.vars.append(Var(self.uid("c"), t, "const", ro=True, init=self.lit(t)))
            self.feat("var_constant")
        if self.chance(0.5):
            pou.vars.append(Var(self.uid("fz"), self.pick(REALS), "var", sink=True))

    # ------------------------------------------------------------- SFC
    QUALIFIERS = ("N", "N", "", "R", "S", "P", "P0", "P1", "L", "D", "SD", "DS", "SL")

    def sfc_condition(self, scope, steps):
        """The lines of a transition condition, ST (``:= e;``) or IL (``:``
        and a simple instruction list), sometimes on a step's X or T."""
        r = self.r
        st = self.pick(steps)
        on_step = self.chance(0.3)
        ms = r.randint(0, 6) * 10
        if self.chance(0.3):
            self.feat("sfc_il_condition")
            if not on_step:
                return [" :"] + ["    " + ln for ln in self.expr_il_bool(scope)]
            self.feat("sfc_step_t")
            lines = [f"    LD {st}.T", f"    GE T#{ms}ms"] if self.chance(0.6) else \
                [f"    LDN {st}.X"]
            if self.chance(0.5):
                lines.append(f"    {self.pick(['AND', 'OR'])} {self.il_operand(BOOL, scope)}")
            return [" :"] + lines
        if not on_step:
            return [f" := {self.expr(BOOL, scope)};"]
        self.feat("sfc_step_t")
        cond = f"{st}.T >= T#{ms}ms" if self.chance(0.6) else f"NOT {st}.X"
        if self.chance(0.5):
            cond = f"({cond}) {self.pick(['AND', 'OR'])} ({self.expr(BOOL, scope)})"
        return [f" := {cond};"]

    def sfc_body(self, scope, pou):
        """An SFC body: a ring of steps from the initial one (every step
        reachable), extra divergent transitions (some with PRIORITY), a
        simultaneous divergence and its convergence, ACTIONs in ST and IL,
        BOOL variables as actions, every qualifier with literal or variable
        times."""
        r = self.r
        ring = [self.uid("st") for _ in range(r.randint(2, 5))]
        steps = list(ring)
        trans = []                        # (name|None, priority|None, [from], [to])
        for i, st in enumerate(ring):
            trans.append((None, None, [st], [ring[(i + 1) % len(ring)]]))
        for _ in range(r.randint(0, 2)):
            a, b = self.pick(ring), self.pick(ring)
            prio = r.randint(0, 3) if self.chance(0.5) else None
            trans.append((self.uid("tr") if self.chance(0.5) else None, prio, [a], [b]))
            self.feat("sfc_divergence")
            if prio is not None:
                self.feat("sfc_priority")
        if self.chance(0.5):
            k = r.randint(0, len(ring) - 1)
            pa, pb = self.uid("st"), self.uid("st")
            steps += [pa, pb]
            trans.append((None, None, [ring[k]], [pa, pb]))
            trans.append((None, None, [pa, pb], [ring[(k + 1) % len(ring)]]))
            self.feat("sfc_simultaneous")
        actions = []
        for _ in range(r.randint(1, 3)):
            name = self.uid("ac")
            self.for_ranges = []
            if self.chance(0.3):
                body = self.il_body(scope, pou)
                self.feat("sfc_il_action")
            else:
                body = self.stmts(scope, 0, r.randint(1, int(4 * self.size) + 1), {})
            actions.append((name, body))
        bool_vars = [v.name for v in scope if v.ty is BOOL and v.sec in ("var", "out")
                     and not v.ro and not v.reserved and not v.sink]
        # action_time ::= duration | variable_name (no member, no index)
        times = [p for p, t in self.readable(scope, TIME) if len(p) == 1]
        assocs = {st: [] for st in steps}
        for st in steps:
            for _ in range(r.randint(0, 3)):
                if bool_vars and self.chance(0.2):
                    target = self.pick(bool_vars)
                    self.feat("sfc_variable_action")
                else:
                    target = self.pick(actions)[0]
                q = self.pick(self.QUALIFIERS)
                self.feat(f"sfc_q_{q or 'none'}")
                if q in ("L", "D", "SD", "DS", "SL"):
                    tm = "".join(self.pick(times)) if times and self.chance(0.3) else \
                        f"T#{r.randint(0, 5) * 10}ms"
                    assocs[st].append(f"{target}({q}, {tm})")
                else:
                    assocs[st].append(f"{target}({q})")
        out = []
        for i, st in enumerate(steps):
            kw = "INITIAL_STEP" if i == 0 else "STEP"
            out.append(f"{kw} {st}:")
            out += [f"    {a};" for a in assocs[st]]
            out.append("END_STEP")
        for name, prio, src, dst in trans:
            head = "TRANSITION"
            if name:
                head += f" {name}"
            if prio is not None:
                head += f" (PRIORITY := {prio})"
            fr = src[0] if len(src) == 1 else f"({', '.join(src)})"
            to = dst[0] if len(dst) == 1 else f"({', '.join(dst)})"
            cond = self.sfc_condition(scope, steps)
            out.append(f"{head} FROM {fr} TO {to}{cond[0]}")
            out += cond[1:]
            out.append("END_TRANSITION")
        for name, body in actions:
            out.append(f"ACTION {name}:")
            out += body
            out.append("END_ACTION")
        return out

    def make_function(self):
        r = self.r
        name = self.uid(self.p + "fn")
        res = self.pick_type(scalar_only=True)
        if res.kind == "sub":
            res = res.base
        f = Pou("FUNCTION", name, result=res)
        ptype = self.pick_type
        for _ in range(r.randint(1, 3)):
            t = ptype(allow_struct=True, allow_array=self.chance(0.3))
            f.vars.append(Var(self.uid("a"), t, "in", ro=True))
        if self.chance(0.3):
            f.vars.append(Var(self.uid("io"), ptype(scalar_only=True), "inout"))
        if self.chance(0.3):
            f.vars.append(Var(self.uid("o"), self.pick_type(scalar_only=True), "out"))
        self.input_writes(f)
        self.locals_for(f, r.randint(0, 2))
        scope = list(f.vars) + [Var(name, res, "result", wo=True)]
        self.for_ranges = []
        self.cur_name = name
        self.cur_pou = f
        body = self.stmts(scope, 0, r.randint(2, int(6 * self.size) + 2), {"fn": True})
        if self.fid_chance(0.3):
            # ENO inside the body: the implicit output, TRUE when the body
            # starts, received by a call's ENO => (issue 10)
            line = f"    IF {self.expr(BOOL, scope)} THEN ENO := FALSE; END_IF;"
            # before or after the statements (a statement may span lines)
            body.insert(0, line) if self.fid_chance(0.5) else body.append(line)
            f.eno = True
            self.feat("function_eno")
        body.append(f"    {name} := {self.expr(res, scope)};")
        self.cur_name = None
        f.body = body
        self.funcs.append(f)
        self.feat("function")

    def fb_type(self, pou):
        ins = [(v.name, v.ty) for v in pou.vars if v.sec == "in"]
        outs = [(v.name, v.ty) for v in pou.vars if v.sec == "out"]
        inout = [(v.name, v.ty) for v in pou.vars if v.sec == "inout"]
        return Ty("fb", pou.name, inputs=ins, outputs=outs, inout=inout, std=False,
                  is_array=False, pou=pou)

    def std_fb_type(self, name):
        ins, outs = STD_FBS[name]
        ins = [(n, BOOL if k == "bool" else TIME if k == "time" else T[k]) for n, k in ins]
        return Ty("fb", name, inputs=ins, outputs=outs, inout=[], std=True, is_array=False)

    def add_instances(self, pou):
        r = self.r
        for _ in range(r.randint(0, 3)):
            name = self.pick(list(STD_FBS))
            pou.vars.append(Var(self.uid("sfb"), self.std_fb_type(name), "var"))
        if self.fbs:
            for _ in range(r.randint(1, 2)):
                sub = self.pick(self.fbs)
                t = self.fb_type(sub)
                pou.vars.append(Var(self.uid("fb"), t, "var"))
                pou.depth = max(pou.depth, sub.depth + 1)
                pou.has_ext |= sub.has_ext
            if self.chance(0.15):
                sub = self.pick(self.fbs)
                t = Ty("array", f"ARRAY[1..2] OF {sub.name}", dims=[(1, 2)],
                       elem=self.fb_type(sub), spec=f"ARRAY[1..2] OF {sub.name}", named=False)
                t.elem.is_array = True
                pou.vars.append(Var(self.uid("fba"), t, "var"))
                self.feat("array_of_fb")

    def externals_for(self, pou, pool):
        for g in self.r.sample(pool, min(len(pool), self.r.randint(1, 3))):
            const = getattr(g, "const", False)
            pou.vars.append(Var(g.name, g.ty, "ext", ro=const))
            pou.has_ext = True
            self.feat("external_const" if const else "external")
            if g.ty.kind in ("array", "struct", "string"):
                self.feat("external_" + g.ty.kind)

    def make_fb(self):
        r = self.r
        name = self.uid(self.p + "FB")
        fb = Pou("FUNCTION_BLOCK", name)
        for _ in range(r.randint(1, 3)):
            t = self.pick_type(scalar_only=True)
            v = Var(self.uid("in"), t, "in", ro=True)
            if t is BOOL and self.chance(0.3):
                v.edge = self.pick(["R_EDGE", "F_EDGE"])
                self.feat("edge_input")
            fb.vars.append(v)
        for _ in range(r.randint(1, 3)):
            t = self.pick_type(scalar_only=True)
            fb.vars.append(Var(self.uid("out"), t, "out"))
        if self.chance(0.3):
            t = self.pick_type(allow_struct=True, allow_array=True)
            fb.vars.append(Var(self.uid("io"), t, "inout"))
            self.feat("fb_inout")
        if self.fbs and self.chance(0.2):
            # an instance of another block by reference
            fb.vars.append(Var(self.uid("iof"), self.fb_type(self.pick(self.fbs)), "inout"))
            self.feat("fb_inout_instance")
        if self.chance(0.6):
            self.externals_for(fb, [g for g in self.cglobals if not g.loc])
        self.add_instances(fb)
        self.input_writes(fb)
        self.locals_for(fb, r.randint(1, 3))
        self.pou_body(fb)
        self.fbs.append(fb)
        if fb.has_ext:
            self.feat(f"fb_external_depth{fb.depth + 1}")

    def pou_body(self, pou):
        self.cur_pou = pou
        scope = list(pou.vars)
        self.for_ranges = []
        # SFC is decided by a generator of its own, so that projects without
        # SFC stay those the seeds gave before SFC was added
        if self.sfc and self.sfc_r.random() < 0.12:
            pou.lang = "SFC"
            self.feat("sfc")
            pou.body = self.sfc_body(scope, pou)
        elif self.chance(0.25):
            pou.lang = "IL"
            self.feat("il_body")
            pou.body = self.il_body(scope, pou)
        else:
            pou.body = self.stmts(scope, 0, self.r.randint(3, int(10 * self.size) + 3), {})

    def make_program(self, home):
        r = self.r
        name = self.uid(self.p + "P")
        prog = Pou("PROGRAM", name, home=home)
        for _ in range(r.randint(0, 3)):
            t = self.pick([*INTS[:4], BOOL, T["WORD"], T["BYTE"], REAL, TIME])
            prog.vars.append(Var(self.uid("pin"), t, "in", ro=True))
        for _ in range(r.randint(0, 3)):
            t = self.pick([*INTS[:4], BOOL, T["WORD"], T["UINT"], REAL, TIME])
            prog.vars.append(Var(self.uid("pout"), t, "out"))
        pool = [g for g in self.cglobals if not g.loc or self.nres == 1] + \
            list(self.rglobals.get(home, []))
        self.externals_for(prog, pool)
        self.add_instances(prog)
        if self.chance(0.15):
            prog.vars.append(Var(self.uid("pg"), INT, "pglobal"))
            self.feat("program_var_global")
        self.program_located(prog)
        self.locals_for(prog, r.randint(2, 5))
        self.pou_body(prog)
        self.progs.append(prog)
        self.feat("program")

    # ------------------------------------------- real-code forms (issue 25)
    def real_chance(self, p):
        return self.real and self.real_r.random() < p

    def program_located(self, prog):
        """Located variables in the program's VAR, as OpenPLC programs declare
        their I/O (addresses from the last quarter of the unit's range, which
        nothing else takes); the trace writes the %I ones by address."""
        if not self.real_chance(0.35):
            return
        for _ in range(self.real_r.randint(1, 3)):
            if self.loc_next >= 16:
                break
            o = (self.addr_base + 48 + self.loc_next) * 4
            self.loc_next += 1
            kind = self.real_r.choice("IQM")
            size = self.real_r.choice("XBWD")
            if size == "X":
                t, addr = BOOL, self.addr_text(kind, "X", o, self.real_r.randint(0, 7))
            else:
                t = T[self.real_r.choice({"B": ["BYTE", "SINT", "USINT"],
                                          "W": ["WORD", "INT", "UINT"],
                                          "D": ["DWORD", "DINT", "UDINT"]}[size])]
                addr = self.addr_text(kind, size, o)
            prog.vars.append(Var(self.uid("lv"), t, "var", loc=addr))
            if kind == "I":
                self.inputs.append((addr, t))
            self.located_progs.add(prog.name)
            self.feat("located_in_program_" + kind)

    def input_writes(self, pou):
        """Inputs the body may assign (OSCAT does; a warning, not an error)."""
        if not self.real_chance(0.3):
            return
        # a function's ARRAY, STRUCT and STRING inputs too: the function
        # works on a copy (codegen/pou.py param_name)
        ins = [v for v in pou.vars if v.sec == "in" and not v.edge]
        for v in ins:
            if self.real_r.random() < 0.6:
                v.ro = False
                self.feat("input_write")
                if pou.kind == "FUNCTION" and v.ty.kind in ("array", "struct", "string"):
                    self.feat("function_aggregate_input_write")

    # ------------------------------------------------------------ render
    SEC = {"in": "VAR_INPUT", "out": "VAR_OUTPUT", "inout": "VAR_IN_OUT", "ext": "VAR_EXTERNAL",
           "var": "VAR", "temp": "VAR_TEMP", "const": "VAR CONSTANT", "pglobal": "VAR_GLOBAL"}

    def render_pou(self, pou):
        head = f"{pou.kind} {pou.name}"
        if pou.kind == "FUNCTION":
            head += f" : {pou.result.name}"
        lines = [head]
        order = ["in", "out", "inout", "ext", "var", "const", "temp", "pglobal"]
        for sec in order:
            vs = [v for v in pou.vars if v.sec == sec] + (
                pou.consts if sec == "const" else pou.ext_consts if sec == "ext" else [])
            if not vs:
                continue
            kw = self.SEC[sec]
            if sec == "ext" and all(v.ro for v in vs) and vs:
                kw = "VAR_EXTERNAL CONSTANT"
            elif sec == "ext" and any(v.ro for v in vs):
                lines.append("VAR_EXTERNAL CONSTANT")
                lines += ["    " + self.decl(Var(v.name, v.ty, "ext")) for v in vs if v.ro]
                lines.append("END_VAR")
                vs = [v for v in vs if not v.ro]
            lines.append(kw)
            for v in vs:
                if sec == "ext":
                    lines.append("    " + self.decl(Var(v.name, v.ty, "ext")))
                else:
                    lines.append("    " + self.decl(v))
            lines.append("END_VAR")
        lines += pou.body
        lines.append(f"END_{pou.kind}")
        return "\n".join(lines) + "\n"

    def render_global(self, v):
        s = self.decl(v)
        return s

    # ------------------------------------------------------------- unit
    def unit(self, cycles=100) -> Unit:
        r = self.r
        p = self.p
        self.make_types()
        self.make_globals()
        nres = self.nres = 1 if self.chance(0.6) else 2
        resources = [f"{p}R{j}" for j in range(nres)]
        for res in resources:
            if self.chance(0.4):
                gs = []
                for _ in range(r.randint(1, 2)):
                    t = self.pick_type(allow_struct=True, allow_array=True)
                    gs.append(Var(self.uid(p + "rg"), t, "global"))
                self.rglobals[res] = gs
                self.feat("resource_global")
        for _ in range(r.randint(0, 3)):
            self.make_function()
        nfb = r.randint(0, 4)
        for _ in range(nfb):
            self.make_fb()
        # an FB chain with an external at depth 3 now and then
        if self.chance(0.35):
            f1 = Pou("FUNCTION_BLOCK", self.uid(p + "FB"))
            f1.vars.append(Var(self.uid("in"), INT, "in", ro=True))
            f1.vars.append(Var(self.uid("out"), INT, "out"))
            self.externals_for(f1, [g for g in self.cglobals if not g.loc])
            self.locals_for(f1, 1)
            self.pou_body(f1)
            self.fbs.append(f1)
            prev = f1
            for _ in range(2):
                f = Pou("FUNCTION_BLOCK", self.uid(p + "FB"), depth=prev.depth + 1,
                        has_ext=True)
                f.vars.append(Var(self.uid("out"), INT, "out"))
                f.vars.append(Var(self.uid("fb"), self.fb_type(prev), "var"))
                self.locals_for(f, 1)
                self.pou_body(f)
                self.fbs.append(f)
                prev = f
            self.feat("fb_external_depth3")
        nprog = r.randint(nres, 3)
        for j in range(nprog):
            self.make_program(resources[j % nres])
        # event trigger
        trig = None
        if self.chance(0.4):
            trig = Var(self.uid(p + "trig"), BOOL, "global")
            self.cglobals.append(trig)
            self.inputs.append((trig.name, BOOL))
        # resources, tasks, instances
        res_lines = []
        rinst = {}
        for res in resources:
            lines = [f"RESOURCE {res} ON CPU{self.pick([0, 0, 1])}"]
            gs = self.rglobals.get(res, [])
            if gs:
                lines += ["    VAR_GLOBAL"] + ["        " + self.decl(v) for v in gs] + \
                    ["    END_VAR"]
            tasks = []
            for _ in range(r.randint(1, 3)):
                tn = self.uid("t")
                if trig is not None and self.chance(0.3) and not any(e for _, e in tasks):
                    lines.append(f"    TASK {tn} (SINGLE := {trig.name}, "
                                 f"PRIORITY := {r.randint(0, 4)});")
                    tasks.append((tn, True))
                    self.feat("event_task")
                else:
                    iv = self.pick([10, 10, 20, 30, 50])
                    lines.append(f"    TASK {tn} (INTERVAL := T#{iv}ms, "
                                 f"PRIORITY := {r.randint(0, 4)});")
                    tasks.append((tn, False))
            if all(e for _, e in tasks):
                tn = self.uid("t")
                lines.append(f"    TASK {tn} (INTERVAL := T#10ms, PRIORITY := 3);")
                tasks.append((tn, False))
            if len(tasks) > 1:
                self.feat("several_tasks")
            rinst[res] = (lines, tasks, [])
        if nres > 1:
            self.feat("several_resources")
        for prog in self.progs:
            res = prog.home
            lines, tasks, insts = rinst[res]
            n_inst = 1 if self.chance(0.7) else 2
            if prog.name in self.located_progs:
                n_inst = 1           # one address, one variable: one instance
            for _ in range(n_inst):
                iname = self.uid(p + "i")
                tn, _ = self.pick(tasks)
                conns = self.connections(prog, res)
                c = f" ({', '.join(conns)})" if conns else ""
                insts.append(f"    PROGRAM {iname} WITH {tn} : {prog.name}{c};")
                for v in prog.vars:
                    if v.sec == "in" and not any(x.startswith(v.name + " ") for x in conns) \
                            and v.ty.kind != "string":
                        self.inputs.append((f"{res}.{iname}.{v.name}", v.ty))
        for res in resources:
            lines, tasks, insts = rinst[res]
            res_lines.append("\n".join(lines + insts + ["END_RESOURCE"]))
        decl = []
        if self.types:
            decl += self.types
        for f in self.funcs:
            decl.append(self.render_pou(f))
        for f in self.fbs:
            decl.append(self.render_pou(f))
        for pr in self.progs:
            decl.append(self.render_pou(pr))
        decl_text = f"(* generated by progen: seed {self.seed} *)\n" + "\n".join(decl) + "\n"
        gl = []
        for g in self.cglobals:
            if getattr(g, "const", False):
                continue
            gl.append(self.render_global(g))
        consts = [g for g in self.cglobals if getattr(g, "const", False)]
        globals_text = gl
        if consts:
            self.const_text = consts
        u = Unit(self.seed, self.k, p, decl_text, globals_text,
                 "\n".join(res_lines) + "\n", self.inputs, self.addresses, [], self.features,
                 cycles)
        u.const_globals = [self.render_global(g) for g in consts]
        u.trace = self.make_trace(cycles)
        return u

    def connections(self, prog, res):
        out = []
        pool = [g for g in self.cglobals if not g.loc or self.nres == 1] + \
            list(self.rglobals.get(res, []))
        for v in prog.vars:
            if v.sec == "in" and self.chance(0.5):
                r = self.r.random()
                gs = [g for g in pool if same_type(g.ty, v.ty) and g.ty.kind == v.ty.kind]
                if r < 0.5 and gs:
                    out.append(f"{v.name} := {self.pick(gs).name}")
                    self.feat("connection_in_global")
                elif r < 0.75 and v.ty.kind in ("int", "bit", "bool") and v.ty.bits <= 32:
                    addr = self.direct_for(v.ty, "I")
                    out.append(f"{v.name} := {addr}")
                    self.inputs.append((addr, v.ty))
                    self.feat("connection_in_direct")
                else:
                    out.append(f"{v.name} := {self.lit(v.ty)}")
                    self.feat("connection_in_const")
            elif v.sec == "out" and self.chance(0.5):
                gs = [g for g in pool if same_type(g.ty, v.ty) and not getattr(g, "const", False)
                      and not (g.loc or "").startswith("%I")]
                if gs and self.chance(0.6):
                    out.append(f"{v.name} => {self.pick(gs).name}")
                    self.feat("connection_out_global")
                elif v.ty.kind in ("int", "bit", "bool") and v.ty.bits <= 32:
                    out.append(f"{v.name} => {self.direct_for(v.ty, 'Q')}")
                    self.feat("connection_out_direct")
        return out

    def direct_for(self, t, kind):
        o = self.next_byte()
        if t.kind == "bool":
            a = self.addr_text(kind, "X", o, self.r.randint(0, 7))
        else:
            a = self.addr_text(kind, {8: 'B', 16: 'W', 32: 'D'}[t.bits], o)
        self.addresses.add(a)
        return a

    def make_trace(self, cycles):
        ev = []
        iv = 10_000_000
        for c in range(cycles):
            for path, t in self.inputs:
                if c == 0 and self.chance(0.5) or self.chance(0.15):
                    if t is BOOL and "trig" in path:
                        ev.append((c * iv, path, self.pick(["TRUE", "FALSE"])))
                        continue
                    ev.append((c * iv, path, self.trace_value(t)))
        return ev

    def trace_value(self, t):
        r = self.r
        b = self.boundary_input(t)
        if b is not None:
            return b
        if t.kind == "bool":
            return self.pick(["TRUE", "FALSE"])
        if t.kind == "sub":
            return str(r.randint(t.lo, t.hi))
        if t.kind == "enum":
            return self.pick(t.values)
        if t.kind in ("int", "bit"):
            lo, hi = rng_of(t)
            x = r.random()
            if x < 0.1:
                return str(self.pick([lo, hi, 0, 1]))
            if x < 0.7:
                return str(max(lo, min(hi, r.randint(-20, 30))))
            return str(r.randint(lo, hi))
        if t.kind == "real":
            return repr(round(r.uniform(-100, 100), 2)) if self.chance(0.8) else \
                self.pick(["0.0", "0.5", "-1.5", "1000000.0"])
        if t.kind == "time":
            return f"T#{r.randint(0, 500)}ms"
        raise AssertionError(t)


def generate_unit(seed: int, k: int = 0, cycles: int = 100, size: float = 1.0,
                  sfc: bool = True, fidelity: bool = True, strings: bool = True,
                  named_constants: bool = True, continue_stmt: bool = True,
                  boundary: bool = True, real_code: bool = True) -> Unit:
    """``sfc=False``: no SFC bodies -- the same project the seed gave before
    the generator knew SFC (SFC is decided by a random generator of its own).
    ``fidelity=False``: none of the constructs of issue 10 (function forms,
    context-typed real literals, calls on array elements, ENO in functions),
    likewise decided by a generator of their own.  ``strings=False``: no
    STRING type, value or function (benchmarks/verify_fuzz.py: the verifier
    refuses them); True gives every seed's project as before.
    ``named_constants=False``: no VAR CONSTANT naming an array bound or a
    CASE label (decided by a generator of its own as well).
    ``continue_stmt=False``: no CONTINUE (ed.3) in loops (likewise).
    ``boundary=False``: no boundary values (Gen.boundary_lit, issue 29).
    ``real_code=False``: no located variables in programs and no writes to
    inputs (issue 25; likewise)."""
    g = Gen(seed, k, size)
    g.sfc = sfc
    g.fid = fidelity
    g.strings = strings
    g.nc = named_constants
    g.cont = continue_stmt
    g.bd = boundary
    g.real = real_code
    g._dims = {}
    g.for_ranges = []
    return g.unit(cycles)
