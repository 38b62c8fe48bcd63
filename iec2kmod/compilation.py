"""One lowering, shared by every command: the stages after checking.

A ``Compilation`` is made once by a driver (the command line, a test, a
benchmark) from the checked project and holds every decision the back ends
act on:

    project      the checked project (checks/)
    selective    the selective plan (codegen/selective.py, ``--selective``)
                 with rule 8 answered by the idempotence analysis below
    plan         where every global, instance and task lives in C and the
                 variable table (codegen/plan.py; each InstancePlan points at
                 its checked ProgramInstance: ``ip.inst``)
    gen          the C of every POU (codegen)
    modules      the split into kernel modules, as data (kmod/split.py)

The writers take it: the kbuild tree (kmod/tree.py), the simulator
(sim.py).  They write; they do not decide.

The generator depends on no solver: whether a block type settles in one
evaluation (selective rule 8) is proved by z3 over the interpreter's model
(verify/idempotent.py), and the answer shapes the instance layout, hence the
interface hash a hot swap checks.  So the proof runs here, in the driver,
and its answers go into the selective plan as data; codegen imports neither
verify nor interp.  The answer depends on the sources, the compiler and the
z3 version (a resource limit, not a time limit, bounds each proof: the same
answer on every machine): pyproject.toml pins z3-solver to Z3_VERSION, the
version the proofs were tested with, and a selective build that needs a
proof refuses to run without z3 or with another version (it would give
another layout, silently)."""

from __future__ import annotations

from functools import cached_property

# The z3 version whose answers the selective layouts were tested with; the
# pin of z3-solver in pyproject.toml (tests/unit/test_compilation.py checks
# that both agree).
Z3_VERSION = "5.4.1"


class CompileError(Exception):
    """The compilation cannot be made as asked (a usage error: exit 2)."""


def settle_answers(project, questions) -> dict:
    """The idempotence analysis (selective rule 8): {POU key: (keep,
    note)} for SelectivePlan.questions."""
    if not questions:
        return {}
    names = ", ".join(sorted(q.pou.name for q in questions))
    try:
        import z3
    except ImportError:
        raise CompileError(
            f"--selective needs z3-solver {Z3_VERSION} to prove which blocks settle in one "
            f"evaluation ({names}); without it the instance layout would differ: "
            f"pip install z3-solver=={Z3_VERSION}") from None
    have = z3.get_version_string()
    if have != Z3_VERSION:
        raise CompileError(
            f"--selective: z3 {have} is installed, the compiler's proofs of which blocks "
            f"settle in one evaluation ({names}) are made with z3 {Z3_VERSION}: another "
            f"version may give another instance layout; pip install z3-solver=={Z3_VERSION}")
    from .verify.idempotent import Prover
    prover = Prover(project)
    return {q.key: prover.settle_set(q.pou, q.externals, q.closure, q.groups)
            for q in questions}


def selective_plan(project, mode):
    """The selective plan for ``--selective[=mode]`` (None or False: plain;
    True: 'all'; a SelectivePlan is taken as it is), rule 8 answered."""
    if not mode:
        return None
    from .codegen.selective import SelectivePlan
    if isinstance(mode, SelectivePlan):
        plan = mode
    else:
        plan = SelectivePlan(project, "all" if mode is True else mode)
    if not plan.settled:
        plan.settle(settle_answers(project, plan.questions))
    return plan


class Compilation:
    """The lowering of one checked project (see the module's docstring).
    The stages run when first asked for, once."""

    def __init__(self, project, selective=None):
        self.project = project
        self.selective = selective_plan(project, selective)

    @classmethod
    def of(cls, what, selective=None) -> "Compilation":
        """*what* itself if it is a Compilation, else one of the project."""
        if isinstance(what, Compilation):
            if selective and what.selective is None:
                raise ValueError("a plain Compilation given where a selective one is asked for")
            return what
        return cls(what, selective)

    @cached_property
    def plan(self):
        """The configuration plan (codegen/plan.py): made here only."""
        from .codegen.plan import build_plan
        return build_plan(self.project)

    @cached_property
    def gen(self):
        """The C of every user POU and the project header."""
        from .codegen import generate
        return generate(self.project, selective=self.selective)

    @cached_property
    def modules(self):
        """The split into kernel modules (kmod/split.py), pure data."""
        from .kmod.split import plan_modules
        return plan_modules(self)

    @cached_property
    def emitter(self):
        """C statements of the configuration: initial values, connections,
        the tasks' run functions (codegen.plan.PlanEmitter)."""
        from .codegen.plan import PlanEmitter
        return PlanEmitter(self.project, self.plan)
