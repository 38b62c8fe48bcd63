"""The execution model: the facts about running a configuration that the C
runtime (kernel and simulator), the reference interpreter and the verifier
must agree on.  One source of truth; the C side's copies are checked
against it by tests (tests/unit/test_compilation.py, test_watchdog.py)."""

from __future__ import annotations

from .checks.types import Elementary, EnumT, StringT, SubrangeT, concrete

# Loop iterations a task may run in one cycle before it faults with
# IEC_FAULT_LOOP: every task of the kernel modules and of the simulator is
# given this budget (kmod_templates/runtime/iec_fault.h
# IEC_LOOP_BUDGET_DEFAULT is the same number, for a context initialised
# without one); the interpreter counts iterations against it and the
# verifier's unrolling stays below it.
LOOP_BUDGET = 1_000_000

# The simulated clock (`iec2kmod sim`, both engines): a cycle takes no time
# on the clock that releases the tasks, but for the watchdog each loop
# iteration costs SIM_ITERATION_NS of simulated execution time (everything
# else costs nothing).  The watchdog faults the iteration that would end
# past the watchdog time; a cycle whose simulated time exceeds the task's
# INTERVAL is an overrun.  Deterministic, and the same in both engines: they
# count iterations as the loop budget does (kmod_templates/sim/sim_main.c
# SIM_ITERATION_NS is the same number).
SIM_ITERATION_NS = 100

# Elements of an array or structure listed per variable in the variable
# table (the manager's, the simulator's and the interpreter's).
MAX_TABLE_ELEMENTS = 256


def element_path(path: str, dims, n: int) -> str:
    """The variable table's path of element *n* (row-major, the last index
    fastest, as in C) of array *path* with dimensions *dims* [(lo, hi)]:
    ``a[1,0]``.  Both engines' tables name elements this way."""
    parts = []
    for lo, hi in reversed(dims):
        size = hi - lo + 1
        parts.append(lo + n % size)
        n //= size
    parts.reverse()
    return f"{path}[{','.join(map(str, parts))}]"


def kind_of(t) -> str | None:
    """The value kind of a variable table entry of type *t*: b (BOOL),
    i (signed), u (unsigned, bit strings), f (real), t (time-like),
    e (enumeration), s (STRING), w (WSTRING); None for a type that is not
    one value (array, structure, FB instance)."""
    t = concrete(t)
    if isinstance(t, EnumT):
        return "e"
    if isinstance(t, SubrangeT):
        t = t.elem
    if isinstance(t, StringT):
        return "w" if t.wide else "s"
    if not isinstance(t, Elementary):
        return None
    return {"bool": "b", "sint": "i", "uint": "u", "bit": "u", "real": "f", "time": "t",
            "date": "t", "tod": "t", "dt": "t"}[t.cat]
