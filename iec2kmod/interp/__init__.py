"""The reference interpreter: a second, independent execution of IEC
61131-3 semantics (`iec2kmod sim --engine interp`).

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
    sfc.py       SFC bodies: steps, transitions, ACTION_CONTROL, actions
    compiler.py  expressions, statements, calls and IL (with its current
                 result) turned into closures, once: statements and POU
                 bodies there, variable access and expressions in
                 compile_expr.py, calls in compile_calls.py, IL in
                 compile_il.py, what they share in closures.py
    machine.py   configuration, variable table, input traces and the
                 scheduler on the simulated clock (the cycle model)
    errors.py    runtime faults

Where the interpreter's results may legitimately differ from the C
simulator's: the transcendental REAL/LREAL functions listed in
std.ULP_TOLERANT -- LN LOG EXP SIN COS TAN ASIN ACOS ATAN ATAN2 EXPT --
computed with Python's math module (the platform libm), where the C runtime
has its own libm within 1-2 ULP of correctly rounded: they may differ in the
last ULP or two.  + - * / and SQRT are exact IEEE operations in both.

Readings of the standard where it leaves room (each one a decision, so the
oracle is explicit about what it checks):

  * A runtime error (division by zero, index or subrange violation, MUX
    selector, loop budget) stops the task at the faulting operation: the
    statement does not complete and nothing is stored; the fault names the
    innermost POU and the line of the statement (of the condition, for
    IF/ELSIF/WHILE/UNTIL).  The programs after it in the task's cycle do not
    run, the other tasks go on.
  * Every loop iteration -- WHILE, REPEAT, FOR, and an IL jump backwards --
    costs one unit of the per-cycle loop budget (the kernel's,
    LOOP_BUDGET), counted as the iteration starts.
  * The inputs of a function are all evaluated before it runs (SEL and MUX
    included), and both operands of AND/OR/XOR.
  * EN = FALSE: the function or FB does not run, ENO is FALSE, a function
    gives its result type's default value.
  * Default initial values: 0, FALSE, '', T#0s, D#1970-01-01, an
    enumeration's first value (or its declared initial value), a subrange's
    lower limit.
  * F_TRIG's memory starts as "CLK was FALSE" (M := 1), so a FALSE CLK on
    the first call is no edge; R_EDGE/F_EDGE inputs of user blocks likewise.
  * Conversions between time types and numbers count TIME and TOD in
    milliseconds, DATE and DT in seconds, the L forms in nanoseconds.
  * SFC bodies (sfc.py): transitions first, on the situation at the start
    of the call, cleared together (PRIORITY, then source order, decides a
    divergence), then every action's ACTION_CONTROL (no final scan), then
    the bodies of the actions whose Q is TRUE; the cycle model is written
    out in iec2kmod/codegen/sfc.py and implemented here on its own."""

from .errors import Fault, InterpError
from .machine import LOOP_BUDGET, Machine, InterpResult, run

__all__ = ["run", "Machine", "InterpResult", "InterpError", "Fault", "LOOP_BUDGET"]
