"""Pass `verify`: prove properties of a configuration over every input
sequence (`iec2kmod verify`), with counterexamples the simulator replays.

What is encoded (exactly, as the reference interpreter iec2kmod.interp
executes it; the encoder walks the same checked AST and reuses the
interpreter's storage layout and initial values):

  * the scheduler of the configuration's periodic tasks, one instant per
    step: the step is the greatest common divisor of the periods, a hidden
    counter modulo the hyperperiod tells which tasks are released, and the
    released tasks run in priority order (declaration order on ties), each
    running its program instances in declaration order -- connected inputs
    copied in (with their subrange checks), the body, connected outputs
    copied out; with one task a step is one cycle.  Event tasks (SINGLE)
    as the interpreter's scheduler runs them: at each instant the rising
    edges of their variables are looked for before every task run, the
    highest-priority pending task runs, until none is pending (unrolled to
    as many runs as tasks plus event tasks; an instant needing more is
    reported undecided).  The inputs change at the step instants only, so
    an event task triggered between two steps is not modelled (printed as
    a note).  One step is one transition T(state, inputs) over z3 terms
    (model.py, encode.py and its parts encode_*.py, terms.py);
  * state: every variable a cycle can change -- globals, %Q/%M addresses,
    program and FB instance variables at every depth, the hidden state of
    the standard FBs (edge memories, counters' edges, the timers' automaton
    location and elapsed time);
  * inputs (free: any value of their type in every cycle, constrained only
    by --assume and {assume} pragmas): located %I addresses connected to
    programs, globals no cycle writes, program inputs connected to nothing,
    and the variables of READ_WRITE access paths (configuration and program
    VAR_ACCESS) even when cycles write them: an HMI may write them between
    any two cycles, so the next cycle reads whatever it wrote (a path that
    reaches what a trace cannot write -- an FB's output -- is refused).
    Writes by `plc-manager set/force` to other variables are outside the
    proof: they bypass the program's declared interface.
    An enumeration or subrange input ranges over its declared values; a REAL
    input over the finite values (an input trace cannot write NaN or an
    infinity).  Variables no cycle writes and no one else may write are
    constants (their initial value);
  * integers of every width as bit-vectors with two's complement
    wrap-around; division and MOD truncating toward zero; REAL and LREAL as
    IEEE binary32/binary64 (round to nearest even) for + - * / SQRT, the
    comparisons, MIN/MAX/LIMIT/SEL/MUX/ABS, and conversions to and from
    integers (rounded to nearest even and saturated, NaN -> 0; TRUNC);
    TIME/LTIME as signed 64-bit nanoseconds (ADD/SUB/MUL/DIV with integers,
    conversions to and from integers); DATE, TOD and DT arithmetic (ADD/SUB
    with TIME, differences, CONCAT_DATE_TOD); BOOL and the bit strings with
    AND/OR/XOR/NOT, SHL/SHR/ROL/ROR and bit access; enumerations; subranges
    (a store outside the range is a fault); arrays of any element type with
    constant or variable indexes (an index out of range is a fault);
    structures; user FUNCTIONs (EN/ENO included), FUNCTION_BLOCK instances
    at any depth (VAR_IN_OUT, VAR_EXTERNAL, VAR_TEMP instances, R_EDGE and
    F_EDGE inputs, arrays of instances); IF, CASE (an invalid enumeration
    selector is a fault), FOR with constant start/end/step (unrolled, at
    most 4096 iterations a loop and 100000 a cycle; a loop longer than the
    kernel's loop budget is the budget fault), WHILE and REPEAT loops and
    FOR loops with variable bounds (unrolled --unroll times, 16 by default:
    a run that needs more iterations is reported undecided -- "holds up to
    K cycles; undecided at cycle K+1" --, never cut short), EXIT, RETURN;
    IL with its
    current result, deferred operators `OP(`, S/R, the FB input operators,
    CAL/CALC/CALCN, forward jumps JMP/JMPC/JMPCN and RET/RETC/RETCN;
  * the standard FBs SR, RS, R_TRIG, F_TRIG, CTU/CTD/CTUD (every width) and
    the timers TON, TOF, TP as the automata of seed 002 with the task's
    period as the time step: the elapsed time of a running timer grows by
    exactly one period per cycle (it saturates at 2^63-1 ns, 292 years; time
    is a signed 64-bit count in the kernel too);
  * runtime faults -- division by zero, index out of range, subrange,
    invalid enumeration, MUX selector, loop budget -- are violations of the
    implicit property "no runtime error".  As in the kernel and the
    interpreter, a fault stops only its task: the faulting cycle publishes
    none of its writes to globals and %Q/%M, the task never runs again
    (a hidden state bit per task), and the other tasks go on; the
    variables of the faulted task's program instances take any value at
    the fault (the interpreter keeps what the cycle wrote before the
    faulting statement).  The properties are checked on every run, after
    a fault too.

What is refused, with an error naming the construct (never approximated):
STRING/WSTRING values and the string functions -- lazily: they are not
encoded, a non-string value computed from them (FIND, LEN, a comparison) is
a stand-in, and a check whose cone of influence reads a stand-in (the
property, or the runtime-error check through a guard) is decided with every
stand-in free (any value of its type, fresh at every evaluation in every
cycle: an over-approximation, so "proved" and "holds up to N cycles" there
hold for the program, and the report names what was free); when that does
not prove it, the check is refused naming the construct (a violation there
may be one the strings cannot produce); checks that read none are decided
exactly, the strings having no effect on them (the string functions cannot
fault) --, FOR loops whose step is
not constant, IL backward jumps, EXPT and the
transcendental functions (LN LOG EXP SIN COS TAN ASIN ACOS ATAN ATAN2),
conversions between REAL and TIME, of enumerations, and BCD, and
configurations without a periodic task.

Properties are ST boolean expressions over the configuration's variables,
from the command line or from {verify NAME: EXPR} pragmas in the sources
(props.py), checked after every cycle; engine.py decides them by bounded
model checking to --depth cycles and k-induction (proved for every depth),
each property on its cone of influence, with the invariants Houdini proves
among candidates (timers' locations, enumeration ranges, and the intervals
of the bit-vector state found by ranges.py; for a check that does not close
without them, the per-step ranges of the state machines, ``state = S ->
lo <= v <= hi``, ranges.partition_candidates); with REAL, first on sound
over-approximations where floating-point operations are free inputs (a
proof there is a proof; otherwise the exact encoding decides).
A violation writes its input trace (CSV for `iec2kmod sim --inputs`) and a
VCD of the run, replayed in the reference interpreter before it is
reported (cex.py)."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import z3

from ..checks.types import BOOL as _BOOL, StringT, concrete
from ..diagnostics import Diagnostics
from .clockfb import clock_user
from .encode import Encoder
from .engine import System, check
from .model import SymbolicMachine
from .ranges import partition_candidates, range_candidates
from .props import (PropChecker, collect, config_scope, instance_of_path,
                    parse_expr)
from .terms import FALSE, TRUE, Frame, Refuse, const_of, land

__all__ = ["verify", "Refuse", "Outcome", "UsageError"]


class UsageError(Exception):
    """A command-line mistake (exit status 2)."""


@dataclass
class Outcome:
    results: list = field(default_factory=list)
    props: list = field(default_factory=list)     # [Prop] with .scope_path
    system: object = None
    sym: object = None
    state_terms: dict = field(default_factory=dict)   # property name -> term on a state
    invariants: list = field(default_factory=list)
    seconds: float = 0.0
    leaves: int = 0
    inputs: int = 0
    assumptions: list = field(default_factory=list)   # their texts, as the report names them
    runs: object = None       # engine.Runs: how long the runs the assumptions allow are


def _scopes(sym, prop, instance, diags):
    """[(display name, POUInfo, Instance)] a property is checked in."""
    if prop.program is not None:
        out = []
        for (path, inst), pi in zip(sym.machine.instances, sym.programs):
            if pi.pou.key == prop.program and pi.task is not None:
                out.append((f"{path}.{prop.name}", pi.pou, inst))
        return out
    if instance is not None and prop.src.path.startswith("<"):
        hit = instance_of_path(sym, instance)
        if hit is None:
            raise UsageError(f"--instance: no program instance '{instance}' (the instances: "
                             + ", ".join(p for p, _ in sym.machine.instances) + ")")
        return [(prop.name, hit[0], hit[1])]
    pou, inst = config_scope(sym)
    return [(prop.name, pou, inst)]


def build(project, cli_props, cli_assumes, instance, diags, unroll=16):
    """The transition system of the project's configuration with its
    properties; None when diags got errors."""
    sym = SymbolicMachine(project)
    sym.max_iter = unroll
    props = collect(project, cli_props, cli_assumes, diags)
    directs = dict(sym.machine.direct_types)
    checked = []
    for p in props:
        for name, pou, inst in _scopes(sym, p, instance, diags):
            e = parse_expr(p.text, p.src, p.start, diags)
            if e is None:
                continue
            ck = PropChecker(project, diags, pou, p.src, directs)
            if not ck.check_expr(e):
                continue
            checked.append((p, name, pou, inst, e))
    if diags.errors:
        return None
    enc = Encoder(sym)
    enc.lazy_strings = True

    def evaluate(p, pou, inst, e):
        frame = Frame(inst, pou)
        n0 = len(enc.faults)
        r0 = set(enc.refused)
        v = enc.expr_as(e, _BOOL, frame, TRUE)
        for name in set(enc.refused) - r0:      # located in the property's text
            _, pos, msg = enc.refused[name]
            enc.refused[name] = (p.src, pos, msg)
        if len(enc.faults) > n0:
            del enc.faults[n0:]
            raise Refuse(p.src, e.pos, "verify: a property that can fault (an index out of "
                                       "range or a division by zero in it)")
        return v

    # the properties as functions of a state (cex.replay evaluates them on
    # the interpreter's state after cycle K)
    state_terms = {}
    assume_terms = []
    for p, name, pou, inst, e in checked:
        if p.kind == "property":
            state_terms[name] = evaluate(p, pou, inst, e)
        else:
            assume_terms.append((" ".join(p.text.split()), evaluate(p, pou, inst, e)))
    sym.run_cycle(enc)
    # properties AND assumptions at one time point: the state after the
    # step (every released task's copy-out done), with the inputs the step
    # read -- a program input connected to an address holds the value the
    # step copied in.  (Assumptions were evaluated on the state before the
    # step, where such an input still held the previous step's copy.)
    post_props = []
    assumes = []
    for p, name, pou, inst, e in checked:
        v = evaluate(p, pou, inst, e)
        if p.kind == "assume":
            assumes.append(v)
        else:
            post_props.append((name, v))
    # classify the leaves
    outside = _written_from_outside(sym)
    state, inputs, consts = [], [], []
    for leaf in sym.leaves:
        post = leaf.c[leaf.k]
        if id(leaf) in outside:
            # whatever the cycle leaves there, the next cycle reads what
            # the outside wrote: a free input of every step
            leaf.outside = True
            leaf.role = "input"
            inputs.append(leaf)
        elif z3.is_expr(post) and post.eq(leaf.var):
            if leaf.candidate:
                leaf.role = "input"
                inputs.append(leaf)
            else:
                leaf.role = "const"
                consts.append(leaf)
        else:
            leaf.role = "state"
            state.append(leaf)
    cpairs = [(leaf.var, const_of(leaf.init, leaf.type)) for leaf in consts]

    # the placeholders "task T faults in this step": their conditions (a
    # later task's may read what an earlier one's fault restored), or FALSE
    resolved = []
    for flag, cond in sym.fault_flags:
        resolved.append((flag, z3.substitute(cond, *resolved) if resolved else cond))
    no_faults = [(flag, FALSE) for flag, _ in sym.fault_flags]

    def system(flags):
        def fix(t):
            # the flags first: their conditions read constants too
            t = z3.substitute(t, *flags) if flags else t
            t = z3.substitute(t, *cpairs) if cpairs else t
            return z3.simplify(t)
        ts = System(
            state=[(leaf, leaf.var, const_of(leaf.init, leaf.type), fix(leaf.c[leaf.k]))
                   for leaf in state],
            inputs=[(leaf, leaf.var, sym.domain(leaf, leaf.var)) for leaf in inputs]
            + ([(None, h, dom) for h, dom in sym.havoc] if flags is resolved else []),
            faults=[(fix(c), kind, pou, src, pos) for c, kind, pou, src, pos in enc.faults],
            props=[(n, fix(t)) for n, t in post_props],
            assume=fix(land(*assumes)) if assumes else TRUE,
            refused=dict(enc.refused))
        ts.stand_ins = list(enc.stand_ins)
        ts.invariants = ([(n, fix(t)) for n, t in sym.invariant_candidates(lambda lf: lf.var)]
                         + range_candidates(ts.state))
        ts.extra = partition_candidates(ts.state)
        return ts

    ts = system(resolved)
    # once 'no runtime error' is proved no task ever stops: the properties
    # are decided on the system without the stopping (engine.check), whose
    # interval invariants the free values of a faulted task do not spoil
    ts.nofault = system(no_faults) if sym.fault_flags else None
    out = Outcome(props=[c[1] for c in checked if c[0].kind == "property"], system=ts,
                  sym=sym, state_terms={n: fix_all(t, cpairs) for n, t in state_terms.items()})
    out.assume_terms = [(t, fix_all(v, cpairs + resolved)) for t, v in assume_terms]
    out.leaves = len(state)
    out.inputs = len(inputs)
    out.assumptions = [" ".join(p.text.split()) + (f" (in {name[:-len(p.name) - 1]})"
                                                   if p.program is not None else "")
                       for p, name, pou, inst, e in checked if p.kind == "assume"]
    out.cpairs = cpairs
    return out


def _access_decl(blocks, name):
    """The position of the access path declaration NAME among VAR_ACCESS blocks."""
    for b in blocks or ():
        if getattr(b, "kind", "") != "VAR_ACCESS":
            continue
        for d in b.decls:
            if d.name.upper() == name.upper():
                return d.pos
    return None


def _written_from_outside(sym):
    """{id(Leaf)} of the variables an HMI may write between two cycles:
    those named by a READ_WRITE access path, of the configuration
    (VAR_ACCESS) or of a program (its VAR_ACCESS, for every instance).
    Such a variable is a free input of every step, even when cycles write
    it: a property proved with it holds whatever the HMI writes, whenever.
    A path whose variables a trace cannot write (an FB instance's hidden
    state, an output of an FB inside a program) is refused: a
    counterexample through it could not be replayed."""
    m = sym.machine
    cfg = sym.cfg
    writable = {e.path.upper() for e in m.table() if e.writable}
    by_cell = {}
    for leaf in sym.leaves:
        by_cell.setdefault(id(leaf.c), []).append(leaf)
    wanted = []       # (leaves, src, pos, access name)
    cfg_blocks = getattr(cfg.node, "access", None)
    for name, path, target, direction in cfg.access:
        if direction != "READ_WRITE" or target is None:
            continue
        pos = _access_decl(cfg_blocks, name)
        if path.startswith("%"):
            hits = [lf for lf in sym.leaves if lf.keys == ("%", path.upper())]
        elif id(target) in m.cells:
            c, k = m.cells[id(target)]
            root = sym._root_of(c)
            hits = [lf for lf in sym.leaves if lf.keys[:2] == (root, k)]
        else:
            hits = _leaves_under(sym, _instance_path(m, cfg, path))
        wanted.append((hits, target, cfg.src, pos, name))
    for (ipath, _inst), pi in zip(m.instances, sym.programs):
        for name, path, v, direction in pi.pou.access:
            if direction != "READ_WRITE":
                continue
            pos = _access_decl(getattr(pi.pou.node, "blocks", None), name)
            wanted.append((_leaves_under(sym, f"{ipath}.{path}"), v, pi.pou.src, pos, name))
    out = set()
    for hits, target, src, pos, name in wanted:
        if not hits:
            if isinstance(concrete(target.type), StringT):
                continue    # strings are not encoded (a check reading one is refused)
            raise Refuse(src, pos, f"verify: the READ_WRITE access path '{name}' names no "
                                   "variable of the encoding")
        for leaf in hits:
            if leaf.hidden or leaf.name.upper() not in writable:
                raise Refuse(src, pos, f"verify: the READ_WRITE access path '{name}' reaches "
                                       f"{leaf.name}, which an input trace cannot write (an "
                                       "FB's output or internal state): declare it READ_ONLY")
            out.add(id(leaf))
    return out


def _instance_path(m, cfg, path):
    """RES.INST.VAR... (or INST.VAR... with one resource) as the
    interpreter names it."""
    names = [p for p, _ in m.instances]
    up = path.upper()
    for p in names:
        if up.startswith(p.upper() + "."):
            return path
    if len(cfg.resources) == 1 and cfg.resources[0].node.name:
        return f"{cfg.resources[0].name}.{path}"
    return path


def _leaves_under(sym, prefix):
    up = prefix.upper()
    return [lf for lf in sym.leaves
            if lf.name.upper() == up or lf.name.upper().startswith((up + ".", up + "["))]


def fix_all(t, pairs):
    return z3.substitute(t, *pairs) if pairs else t


def verify(project, cli_props=(), cli_assumes=(), depth=20, instance=None, diags=None,
           timeout_ms=60000, unroll=16, on_built=None, on_result=None, deadline=None):
    """Builds and checks; returns an Outcome (None on source errors, in
    diags).  Raises Refuse for a construct that cannot be encoded.
    on_built(outcome) once the system is built, on_result(result) as each
    check is decided; deadline (time.monotonic()): the checks not decided
    by then are unknown (timeout)."""
    diags = diags if diags is not None else Diagnostics()
    t0 = time.perf_counter()
    if (clock := clock_user(project)) is not None:
        raise Refuse(*clock)
    out = build(project, list(cli_props), list(cli_assumes), instance, diags, unroll)
    if out is None:
        return None
    if on_built is not None:
        on_built(out)
    info = {}
    out.results, out.invariants = check(out.system, depth, timeout_ms, info=info,
                                        on_result=on_result, deadline=deadline)
    out.runs = info.get("runs")
    out.seconds = time.perf_counter() - t0
    return out
