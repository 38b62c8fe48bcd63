"""Is a FUNCTION_BLOCK or PROGRAM type idempotent?  (selective execution,
iec2kmod/codegen/selective.py, rule 8)

One evaluation of a block maps its arguments X (inputs, externals, the
targets of its in-outs) and its state S (every other variable of the
instance, nested instances and their hidden memories included) to a new
state: S1 = f(X, S).  The type is *idempotent* when, for every X and S,
an evaluation that ends without fault leaves a fixpoint for the same
arguments:

    not fault(X, S)  ==>  not fault(X, S1)  and  f(X, S1) = S1
                          (and the second evaluation leaves X as it found it)

Then an evaluation on X settles the block by itself: evaluating it again
on X (the confirm run of rule 4) would read the same values, write the
same values and not fault.  Combinational logic and latches (SR, RS,
a seal-in) are idempotent; an edge detector (R_TRIG: Q falls on the second
evaluation), a counter, an integrator or anything reading a value it
writes later in the same body (a feedback from one cycle to the next) is
not.

The proof runs both evaluations symbolically with the z3 encoding of the
bodies (encode.Encoder: every path, every fault site) on one instance
whose scalars are fresh constants, and asks z3 for a counterexample.  The
answer is "idempotent" only when z3 proves there is none (unsat) within
the time limit.  Refused, hence not idempotent (the confirm run stays):
anything the encoder refuses; a loop at any depth (the loop budget of a
skip is the last evaluation's); REAL/LREAL state (the SMT theory has one
NaN, the machine many: an idempotence proved there may not hold bit for
bit); STRING state (not encoded); directly represented variables (outside
the argument set); writes through a VAR_EXTERNAL or a VAR_IN_OUT, an
in-out next to a body that writes its own inputs (the caller may bind the
in-out to one of them), and externals or in-outs that hold FB instances:
the model gives every argument its own storage, so it must not matter
whether the caller's arguments overlap each other or the instance."""

from __future__ import annotations

from ..checks.types import ArrayT, FBType, StringT, StructT, concrete

# z3's resource limit per check, not a time limit: the same answer on
# every machine, so the generated code (and its token) does not depend on
# how fast the compiler ran.  A proof of the blocks met so far takes well
# under a million.
RLIMIT = 20_000_000
MAX_CHECKS = 32            # per type: the greedy narrowing stops there


class _NoDirects(dict):
    def __getitem__(self, key):
        raise _Refused(f"directly represented variable {key}")

    def __contains__(self, key):
        return False


class _Refused(Exception):
    pass


def _has(t, pred, seen=None):
    """Does type t contain (arrays, structures, user FB variables) a type
    satisfying pred?"""
    seen = set() if seen is None else seen
    t = concrete(t)
    if pred(t):
        return True
    if isinstance(t, ArrayT):
        return _has(t.elem, pred, seen)
    if isinstance(t, StructT):
        return any(_has(ft, pred, seen) for _, ft, _ in t.fields.values())
    if isinstance(t, FBType):
        if t.pou.key in seen:
            return False
        seen.add(t.pou.key)
        return any(_has(v.type, pred, seen) for v in t.pou.vars.values()
                   if v.section not in ("VAR_EXTERNAL", "VAR_IN_OUT", "VAR_TEMP"))
    return False


def _fp_or_string(t):
    from ..checks.types import Elementary
    if isinstance(t, StringT):
        return True
    return isinstance(t, Elementary) and t.name.upper() in ("REAL", "LREAL")


class Prover:
    """One per project: the interpreter's Machine is built once."""

    def __init__(self, project):
        self.project = project
        self._machine = None
        self._failed = None

    def machine(self):
        if self._machine is None and self._failed is None:
            try:
                from ..interp.machine import Machine
                self._machine = Machine(self.project)
            except Exception as exc:          # no configuration, an interpreter refusal
                self._failed = str(exc)
        return self._machine

    def idempotent(self, pou, externals, closure) -> tuple[bool, str]:
        """(proved, why not).  *externals*: [Var] the VAR_EXTERNALs met at
        any depth of the instance (one per name); *closure*: the POUs the
        type uses, itself included (the caller has already checked that
        no loop, timer or SFC is among them and that nothing in them
        writes an external or an in-out)."""
        keep, note = self.settle_set(pou, externals, closure, [])
        return keep == [], note

    def settle_set(self, pou, externals, closure, groups) -> tuple[list | None, str]:
        """The smallest part of the written state whose comparison settles
        a block (rule 8): *groups* is [[leaf path]] (a member of the
        instance: the paths of its leaves, ``$self.<name>...``); the
        answer is the indexes K of the groups to compare, such that for
        every X and S

            not fault(X, S) and S1 = S on the groups of K
                ==>  not fault(X, S1) and f(X, S1) = S1

        (found greedily: each group is left out if the proof still holds
        without it), [] when the type is idempotent, None when not even
        every group proves it (the caller keeps its syntactic rule)."""
        try:
            import z3
        except ImportError:
            return None, "z3 is not installed"
        m = self.machine()
        if m is None:
            return None, f"no model: {self._failed}"
        inouts = [v for v in pou.vars.values() if v.section == "VAR_IN_OUT"]
        for v in externals + inouts:
            if _has(v.type, lambda t: isinstance(t, FBType)):
                return None, f"{v.name} holds function block instances"
        for p in closure:
            for v in p.vars.values():
                if v.section == "VAR_TEMP":
                    continue
                if _has(v.type, _fp_or_string):
                    return None, f"{p.name}.{v.name}: REAL, LREAL or STRING"
        try:
            return self._prove(z3, m, pou, externals, inouts, groups)
        except _Refused as exc:
            return None, str(exc)
        except Exception as exc:               # terms.Refuse and the rest
            msg = getattr(exc, "message", None) or f"{type(exc).__name__}: {exc}"
            return None, msg

    def _prove(self, z3, m, pou, externals, inouts, groups):
        from .encode import Encoder
        from .terms import TRUE, land, lnot, lor, smt_eq
        from .model import SymbolicMachine
        sym = SymbolicMachine.__new__(SymbolicMachine)
        sym.project = self.project
        sym.machine = m
        sym.leaves = []
        sym.by_name = {}
        sym.timers = []
        saved_directs = m.directs
        m.directs = _NoDirects()
        try:
            roles = {}

            def slots(holder, key, t, name, role):
                n = len(sym.leaves)
                sym._slot(holder, key, t, name)
                for leaf in sym.leaves[n:]:
                    roles[leaf.name] = role

            scope = {}
            for v in externals:
                holder = {v.key: m.init.value(v.type, None)}
                slots(holder, v.key, v.type, f"$ext.{v.name}", "arg")
                scope[v.key] = (holder, v.key)
            inst = m.new_instance(pou, scope)
            for v in inouts:
                holder = {v.key: m.init.value(v.type, None)}
                slots(holder, v.key, v.type, f"$inout.{v.name}", "arg")
                inst.r[v.key] = (holder, v.key)
            n = len(sym.leaves)
            sym._instance(inst, "$self", keys=("$self",))
            inputs = {v.key for v in pou.inputs}
            for leaf in sym.leaves[n:]:
                is_input = len(leaf.keys) >= 2 and leaf.keys[1] in inputs
                roles[leaf.name] = "arg" if is_input else "state"
            if not sym.leaves:
                return [], ""
            pre = {leaf.name: leaf.var for leaf in sym.leaves}
            enc1 = Encoder(sym)
            enc1.run_body(pou, inst, TRUE)
            f1 = lor(*[c for c, *_ in enc1.faults])
            post1 = {leaf.name: leaf.c[leaf.k] for leaf in sym.leaves}
            # the second evaluation: the same arguments, the state left
            for leaf in sym.leaves:
                if roles[leaf.name] == "arg":
                    leaf.c[leaf.k] = pre[leaf.name]
            enc2 = Encoder(sym)
            enc2.run_body(pou, inst, TRUE)
            f2 = lor(*[c for c, *_ in enc2.faults])
            eqs = []
            for leaf in sym.leaves:
                now = leaf.c[leaf.k]
                want = pre[leaf.name] if roles[leaf.name] == "arg" else post1[leaf.name]
                if not (z3.is_expr(now) and z3.is_expr(want)):
                    return None, f"{leaf.name} is not a term"
                if now.sort() != want.sort():
                    return None, f"{leaf.name}: sorts differ"
                eqs.append(smt_eq(now, want))
            # the premise a group stands for: its leaves unchanged by the
            # first evaluation
            unchanged = []
            for paths in groups:
                ps = [p.upper() for p in paths]
                leaves = [leaf for leaf in sym.leaves if roles[leaf.name] == "state" and any(
                    leaf.name.upper() == p or leaf.name.upper().startswith(
                        (p + ".", p + "[")) for p in ps)]
                unchanged.append(land(*[smt_eq(post1[leaf.name], pre[leaf.name])
                                        for leaf in leaves]) if leaves else TRUE)
            s = z3.Solver()
            s.set("rlimit", RLIMIT)
            checks = [0]
            s.add(lnot(f1))
            s.add(z3.Not(land(lnot(f2), *eqs)))

            def proved(keep):
                checks[0] += 1
                s.push()
                for i in keep:
                    s.add(unchanged[i])
                r = s.check()
                s.pop()
                return r == z3.unsat, r

            keep = list(range(len(groups)))
            ok, r = proved(keep)
            if not ok and not groups:
                return None, ("the proof ran out of its resource limit" if r != z3.sat else
                              self._what(z3, s, sym, roles, post1, smt_eq, pre))
            if not ok:
                return None, ("the proof ran out of its resource limit" if r != z3.sat else
                              "a second evaluation changes state the comparison misses")
            ok, r = proved([])
            if ok:
                return [], ""
            why = "the proof ran out of its resource limit" if r != z3.sat else \
                self._what(z3, s, sym, roles, post1, smt_eq, pre)
            for i in list(keep):
                if checks[0] >= MAX_CHECKS:
                    break
                trial = [k for k in keep if k != i]
                if proved(trial)[0]:
                    keep = trial
            return keep, why
        finally:
            m.directs = saved_directs

    @staticmethod
    def _what(z3, s, sym, roles, post1, smt_eq, pre):
        """What a counterexample's second evaluation changes."""
        if s.check() != z3.sat:
            return "no counterexample"
        model = s.model()
        diff = [leaf.name for leaf in sym.leaves
                if z3.is_false(model.eval(smt_eq(leaf.c[leaf.k], pre[leaf.name] if roles[
                    leaf.name] == "arg" else post1[leaf.name]), model_completion=True))]
        what = ", ".join(diff[:3]) if diff else "a fault"
        return f"a second evaluation changes {what}"
