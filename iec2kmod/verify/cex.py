"""Counterexamples: the input trace of a violating run as an `iec2kmod sim
--inputs` CSV (time,variable,value), the run itself as a VCD, and the
replay of that trace in the reference interpreter that confirms the
violation before it is reported.

Cycle k (1-based) of the task runs at (k-1) * period; the inputs of cycle k
are written at that time, before the cycle runs, so `sim --inputs` applies
them exactly when the verifier's cycle k reads them.  A variable of a
READ_WRITE access path is written before every cycle (the value the
verifier chose, over whatever the previous cycle left there)."""

from __future__ import annotations

import math

import z3

from ..interp.model import Instance
from ..traces import input_literal, write_inputs
from .terms import const_of, py_value


def input_values(out, result):
    """[(cycle, {leaf name: Python value})] of a violating BMC path."""
    model = result.model
    # an input outside the property's cone of influence is not in the
    # query, so not in the model: model completion would give it any value
    # of its sort (a REAL NaN, an enumeration or subrange value out of its
    # domain) that a trace cannot write; it keeps its initial value
    given = {d.name() for d in model.decls()}
    rows = []
    for k in range(1, result.cycle + 1):
        vals = {}
        for leaf, var, _ in out.system.inputs:
            if leaf is None:        # a stand-in (never read by a check that got a verdict)
                continue
            name = f"{var}@b{k}"
            if name not in given:
                if not leaf.outside:
                    vals[leaf.name] = leaf.init
                # a variable written from outside (READ_WRITE access path)
                # the check does not read: not written, the cycles' own
                # value stays (one of the behaviours the proof covers)
                continue
            term = model.eval(z3.Const(name, var.sort()), model_completion=True)
            vals[leaf.name] = py_value(term, leaf.type)
        rows.append((k, vals))
    return rows


def write_trace(out, result, path):
    period = out.sym.period
    leaves = {leaf.name: leaf for leaf, _, _ in out.system.inputs if leaf is not None}
    last = {}
    rows = []
    for k, vals in input_values(out, result):
        t = (k - 1) * period
        for name in sorted(vals):
            v = vals[name]
            if name in last and _same(last[name], v) and not leaves[name].outside:
                continue    # written from outside: again, over what the cycle wrote
            last[name] = v
            rows.append((f"{t}ns", name, input_literal(leaves[name].type, v)))
    return write_inputs(path, rows)


def _same(a, b):
    if isinstance(a, float) and isinstance(b, float):
        return a == b and math.copysign(1, a) == math.copysign(1, b) or (a != a and b != b)
    return a == b


def lookup(machine, keys):
    """The (container, key) of a leaf in another Machine of the project."""
    root, *rest = keys
    if root == "G":
        c = machine.globals
    elif root.startswith("R:"):
        c = machine.res_globals[root[2:]]
    elif root == "%":
        c = machine.directs
    else:
        c = dict(machine.instances)[rest[0]]
        rest = rest[1:]
    for k in rest[:-1]:
        c = c.v[k] if isinstance(c, Instance) else c[k]
    k = rest[-1]
    if isinstance(k, tuple):
        # ("e", key): the memory of an FB instance's R_EDGE/F_EDGE input
        return c.e, k[1]
    return (c.v if isinstance(c, Instance) else c), k


def leaf_value(machine, leaf, now, stopped=()):
    """A leaf's value in an interpreter Machine (the hidden elapsed time of
    a timer from its start time T0, as the encoding holds it; stopped: the
    names of the tasks a fault stopped)."""
    if leaf.keys[0] == "S":
        return leaf.keys[1] in stopped
    if leaf.keys[0] == "E":
        # the SINGLE variable as the last edge detection of the instant saw it
        c, k = lookup(machine, leaf.single_keys)
        return bool(c[k])
    if leaf.keys == ("T",):
        return ((now // out_period(leaf)) + 1) % leaf.ticks
    if leaf.name.endswith(".$EL") and leaf.hidden:
        c, _ = lookup(machine, leaf.keys[:-1] + ("$S",))
        return now - c["$T0"] if c["$S"] == 1 else 0
    c, k = lookup(machine, leaf.keys)
    if isinstance(leaf.keys[-1], tuple):
        # the interpreter creates an edge memory at the instance's first
        # call: FALSE until then
        return bool(c.get(k, False))
    return c[k]


def out_period(leaf):
    return leaf.period


def state_pairs(out, machine, now, stopped=()):
    pairs = []
    for leaf in out.sym.leaves:
        if leaf.role == "const":
            continue
        pairs.append((leaf.var, const_of(leaf_value(machine, leaf, now, stopped), leaf.type)))
    return pairs


def replay(out, result, trace_path, vcd_path=None):
    """Runs the trace in the reference interpreter; returns (confirmed,
    message).  Confirmed: the interpreter faults in cycle K (a runtime
    error) or the property is FALSE after cycle K."""
    from .. import interp
    from ..interp.machine import Machine
    from ..traces import write_vcd
    project = out.sym.project
    period = out.sym.period
    end = (result.cycle - 1) * period
    m = Machine(project)
    table = m.table()
    watch = [e.path for e in table]
    res = interp.run(project, end, watch=watch, inputs=trace_path, machine=m)
    if vcd_path:
        write_vcd(res, vcd_path, table)
    if result.name == "no runtime error":
        hits = [f for f in res.faults if f[0] == end]
        if hits:
            t, task, kind_, pou, file, line = hits[0]
            return True, f"{file}:{line}: runtime error: {kind_} in {pou}"
        return False, "the interpreter ran the trace without a runtime error"
    # the trace satisfies the assumptions at every step, as the interpreter
    # runs it (independently of the encoding: the time point is the same)
    for k in range(1, result.cycle + 1):
        at = (k - 1) * period
        mk = Machine(project)
        rk = interp.run(project, at, watch=[], inputs=trace_path, machine=mk)
        pairs = state_pairs(out, mk, at, {f[1] for f in rk.faults})
        for text, term in getattr(out, "assume_terms", ()):
            v = z3.simplify(z3.substitute(term, *pairs))
            if not z3.is_true(v):
                return False, f"the trace breaks the assumption '{text}' at step {k} ({v})"
    # a fault stops its task; the property is checked after it too
    stopped = {f[1] for f in res.faults}
    term = out.state_terms[result.name]
    v = z3.simplify(z3.substitute(term, *state_pairs(out, m, end, stopped)))
    if z3.is_false(v):
        return True, "the property is FALSE after that cycle"
    return False, f"the interpreter's state satisfies the property ({v})"
