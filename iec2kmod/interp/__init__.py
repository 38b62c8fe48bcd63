"""The reference interpreter: a second, independent execution of IEC
61131-3 semantics (`iec2kmod sim --engine vm`).

It runs the checked AST of the front end directly, in Python, and shares
nothing with the C code generator (not its plan, not its naming, not its
runtime library).  Its purpose is to be an oracle: the same project run by
the compiled C simulator and by this interpreter must give the same
traces, faults included.

A pipeline a person can read, one module per stage:

    values.py    how each IEC type's values are held; wrap-around, REAL
                 rounding to binary32
    model.py     storage: instances, frames, initial values, copies, the
                 binding of VAR_EXTERNAL (by name, at every FB depth)
    std.py       the standard functions (numeric, bit string, selection,
                 comparison, string, time)
    conv.py      the type conversions and the textual forms of values
    fbs.py       the standard function blocks (bistables, edges, counters,
                 timers after seed 002's automata)
    compiler.py  expressions, statements, calls and IL (with its current
                 result) turned into closures, once
    machine.py   configuration, variable table, input traces and the
                 scheduler on the simulated clock (the cycle model)
    errors.py    runtime faults

Where the interpreter's results may legitimately differ from the C
simulator's: the transcendental REAL/LREAL functions listed in
std.ULP_TOLERANT (libm differences in the last ULP or two)."""

from .errors import Fault, VMError
from .machine import LOOP_BUDGET, Machine, VMResult, run

__all__ = ["run", "Machine", "VMResult", "VMError", "Fault", "LOOP_BUDGET"]
