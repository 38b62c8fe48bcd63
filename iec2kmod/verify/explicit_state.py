"""`verify --engine explicit`, inputs and states: which variables are the
free inputs (``input_entries``: computed from the checked AST, on its own,
as explicit.py's docstring states) and the values each takes (``domain``),
and ``Snapshots``: a machine state saved canonically (a running timer by
its elapsed time, REAL by its bit pattern) and restored for the next step.
``VerifyError`` names a construct the explicit engine does not explore.

It imports the checker's types and the interpreter's storage, nothing of
the z3 encoder, and not explicit.py (which imports it)."""

from __future__ import annotations

import struct

from .. import ast
from ..checks.types import EnumT, SubrangeT, concrete
from ..interp.model import Instance
from ..interp.values import base_of, int_range

_TIMERS = {"TON", "TOF", "TP"}
_WORK = 1                       # interp.fbs.WORK
_PACK = struct.Struct("<d").pack


class VerifyError(Exception):
    """A construct the explicit engine does not explore: (src, pos, message);
    src None for a message without a place."""

    def __init__(self, src, pos, message):
        super().__init__(message)
        self.src, self.pos, self.message = src, pos, message


# ------------------------------------------------------------------ inputs
def _closure(project, pou):
    seen, stack = {}, [pou]
    while stack:
        p = stack.pop()
        if p.key in seen:
            continue
        seen[p.key] = p
        for d in getattr(p, "calls", ()) or ():
            if d in project.pous:
                stack.append(project.pous[d])
        for v in p.vars.values():
            t = concrete(v.type)
            while hasattr(t, "elem") and not hasattr(t, "pou"):
                t = concrete(t.elem)
            if hasattr(t, "pou") and not t.pou.standard:
                stack.append(t.pou)
    return list(seen.values())


def _writes_fn():
    from ..codegen.selective import writes
    memo = {}

    def param_written(pou, v):
        key = (pou.key, v.key)
        if key not in memo:
            memo[key] = True
            if not (pou.standard or pou.node is None or getattr(pou, "sfc", None) is not None):
                memo[key] = writes(pou.node.body or [], v, param_written)
        return memo[key]

    def w(pou, v):
        if pou.node is None or getattr(pou, "sfc", None) is not None:
            return True
        return writes(pou.node.body or [], v, param_written)
    return w


def input_entries(m):
    """[(Entry, outside)] of the free inputs of Machine m's configuration,
    outside: written from outside (a READ_WRITE access path)."""
    project, cfg = m.p, m.cfg
    writes = _writes_fn()
    written = set()            # (id(container), key)
    own_written = set()        # (instance path, var key): a program writing its own input
    progs = [pi for r in cfg.resources for pi in r.programs]
    for r in cfg.resources:
        scope = {k: (m.globals, k) for k in cfg.globals}
        scope.update({k: (m.res_globals[r.name], k) for k in r.globals})
        for pi in r.programs:
            if pi.task is None:
                continue
            for q in _closure(project, pi.pou):
                for v in q.vars.values():
                    if v.section == "VAR_EXTERNAL" and v.key in scope and writes(q, v):
                        c, k = scope[v.key]
                        written.add((id(c), k))
            for conn in pi.node.connections:
                param = pi.pou.var(conn.name)
                if param is not None and param.section == "VAR_IN_OUT" and \
                        writes(pi.pou, param):
                    c, k = m.cells[id(conn.value.symbol)]
                    written.add((id(c), k))
            for param, target in pi.outputs:
                if isinstance(target, ast.Direct):
                    written.add((id(m.directs), target.address))
                else:
                    c, k = m.cells[id(target.symbol)]
                    written.add((id(c), k))
            for v in pi.pou.inputs + [v for v in pi.pou.vars.values()
                                      if (v.location or "")[:2] == "%I"]:
                if writes(pi.pou, v):
                    own_written.add((id(pi), v.key))
    table = m.table()
    free_roots = []            # path prefixes (upper) of the free inputs
    for path, v, container in m.global_paths:
        if not v.constant and (id(container), v.key) not in written:
            free_roots.append(path.upper())
    for address in m.directs:
        if (id(m.directs), address) not in written:
            free_roots.append(address.upper())
    for (ipath, _inst), pi in zip(m.instances, progs):
        connected = {c.name.upper() for c in pi.node.connections}
        for v in pi.pou.inputs:
            if v.key not in connected and (id(pi), v.key) not in own_written:
                free_roots.append(f"{ipath}.{v.name}".upper())
        for v in pi.pou.vars.values():          # located %I of the program (z3: model.py)
            if (v.location or "")[:2] == "%I" and (id(pi), v.key) not in own_written:
                free_roots.append(f"{ipath}.{v.name}".upper())
    outside = []
    implicit_one = len(cfg.resources) == 1 and cfg.resources[0].node.name
    for _name, path, _target, direction in cfg.access:
        if direction == "READ_WRITE":
            cands = [path.upper()]
            if implicit_one:
                cands.append(f"{cfg.resources[0].name}.{path}".upper())
            outside.append(cands)
    for (ipath, _inst), pi in zip(m.instances, progs):
        for _name, path, _v, direction in pi.pou.access:
            if direction == "READ_WRITE":
                outside.append([f"{ipath}.{path}".upper()])

    def under(e, prefix):
        p = e.path.upper()
        return p == prefix or p.startswith((prefix + ".", prefix + "["))

    out, seen = [], set()
    for cands in outside:
        hits = []
        for prefix in cands:
            hits = [e for e in table if under(e, prefix)]
            if hits:
                break
        for e in hits:
            if not e.writable:
                raise VerifyError(cfg.src, None, f"verify: the READ_WRITE access path to "
                                  f"{e.path} reaches what an input trace cannot write")
            if e.path not in seen:
                seen.add(e.path)
                out.append((e, True))
    for e in table:
        if e.path in seen:
            continue
        if any(under(e, p) for p in free_roots):
            seen.add(e.path)
            out.append((e, False))
    return out


def domain(e):
    """The values an input of Entry e's type takes, or (None, how many)."""
    t = concrete(e.type)
    if isinstance(t, EnumT):
        return [v for _, v in t.values.values()], None
    if isinstance(t, SubrangeT):
        return list(range(t.low, t.high + 1)), None
    b = base_of(t)
    if getattr(b, "cat", None) == "bool":
        return [False, True], None
    rng = int_range(t) if getattr(b, "cat", None) in ("sint", "uint", "bit") else None
    if rng is not None:
        n = rng[1] - rng[0] + 1
        if n > 1 << 20:
            return None, f"2^{n.bit_length() - 1}"
        return list(range(rng[0], rng[1] + 1)), None
    return None, f"every value of {t.name}"


# ------------------------------------------------------------ state
class Snapshots:
    """Saves the machine's whole state as a hashable value and restores it
    in place (every reference into the storage stays valid)."""

    def __init__(self, m, inputs, period):
        self.m = m
        self.period = period
        self.inputs = inputs
        self.temps = {}
        for pou in m.p.pous.values():
            self.temps[pou.key] = frozenset(v.key for v in pou.vars.values()
                                            if v.section == "VAR_TEMP")
        self.roots = [m.globals] + [m.res_globals[k] for k in sorted(m.res_globals)] + \
            [m.directs]
        self.insts = [inst for _, inst in m.instances]

    # encoding: scalars as they are (floats by their bits), containers as tuples
    def _enc(self, x, now):
        t = type(x)
        if t is bool or t is int or t is str:
            return x
        if t is Instance:
            return self._inst(x, now)
        if t is list:
            return tuple([self._enc(y, now) for y in x])
        if t is dict:
            return tuple([self._enc(y, now) for y in x.values()])
        if t is float:
            return ("f", _PACK(x))
        return x

    def _inst(self, inst, now):
        pou = inst.pou
        if "$SFC" in inst.e:
            raise VerifyError(pou.src, None, "verify --engine explicit: an SFC body (its "
                              "steps' times are absolute) is not explored")
        v = inst.v
        if pou.standard:
            if pou.name.upper() in _TIMERS:
                rel = now - v["$T0"] if v["$S"] == _WORK else 0
                return tuple([(rel if k == "$T0" else self._enc(x, now)) for k, x in v.items()])
            return tuple([self._enc(x, now) for x in v.values()])
        temps = self.temps.get(pou.key, ())
        vals = tuple([self._enc(x, now) for k, x in v.items() if k not in temps])
        edges = tuple(sorted(inst.e.items())) if inst.e else ()
        cr = self._enc(inst.cr, now) if inst.cr is not None else None
        return (vals, edges, cr)

    def save(self, sched, now, tick):
        for e, _ in self.inputs:          # not state: every step overwrites them
            e.set(e.canon)
        faulted, prev, late = sched
        return (tick, tuple(faulted), tuple(prev), tuple(late),
                tuple([self._enc(r, now) for r in self.roots]),
                tuple([self._inst(i, now) for i in self.insts]))

    def _dec(self, holder, key, enc, now):
        if type(enc) is not tuple:          # a scalar
            holder[key] = enc
            return
        x = holder[key]
        t = type(x)
        if t is Instance:
            self._dec_inst(x, enc, now)
        elif t is list:
            for i, y in enumerate(enc):
                self._dec(x, i, y, now)
        elif t is dict:
            for k, y in zip(list(x.keys()), enc):
                self._dec(x, k, y, now)
        else:                               # a float, by its bits
            holder[key] = struct.unpack("<d", enc[1])[0]

    def _dec_inst(self, inst, enc, now):
        v = inst.v
        pou = inst.pou
        if pou.standard:
            timer = pou.name.upper() in _TIMERS
            for k, y in zip(list(v.keys()), enc):
                if timer and k == "$T0":
                    v[k] = now - y
                else:
                    self._dec(v, k, y, now)
            return
        vals, edges, cr = enc
        temps = self.temps.get(pou.key, ())
        for k, y in zip([k for k in v if k not in temps], vals):
            self._dec(v, k, y, now)
        inst.e.clear()
        inst.e.update(edges)
        inst.cr = None if cr is None else (struct.unpack("<d", cr[1])[0]
                                           if isinstance(cr, tuple) else cr)

    def restore(self, snap, now):
        """Restores snap for a step at time now (the snapshot was taken one
        step before)."""
        tick, faulted, prev, late, roots, insts = snap
        before = now - self.period
        for r, enc in zip(self.roots, roots):
            for k, y in zip(list(r.keys()), enc):
                self._dec(r, k, y, before)
        for inst, enc in zip(self.insts, insts):
            self._dec_inst(inst, enc, before)
        return list(faulted), list(prev), list(late)
