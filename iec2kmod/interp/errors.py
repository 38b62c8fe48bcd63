"""Runtime faults: the defined outcomes of the operations IEC 61131-3 leaves
as errors.  A fault stops the task; its message names the fault, the POU
and the source line where it happened."""

from __future__ import annotations

DIV_ZERO = "division by zero"
INDEX = "array index out of range"
RANGE = "subrange value out of range"
ENUM = "invalid enumerated value"
LOOP = "endless loop (loop budget exhausted)"
MUX = "MUX selector out of range"
WATCHDOG = "watchdog (cycle longer than the task's watchdog time)"
OVERRUN = "overruns (cycles in a row that ended after the next release)"


class Fault(Exception):
    """A runtime error.  ``pou``/``line`` are filled in by the innermost
    statement that sees it (the POU whose statement failed)."""

    def __init__(self, kind):
        super().__init__(kind)
        self.kind = kind
        self.pou = None
        self.line = 0


class InterpError(Exception):
    """A usage error (unknown variable, bad trace): exit code 2."""
