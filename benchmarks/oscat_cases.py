"""Expected outputs of OSCAT BASIC functions and function blocks, written
from OSCAT's documentation, never from iec2kmod's output: the
<documentation> text of the translation's plc.xml, quoted in ``doc``, and
the function's published meaning (its name, the mathematics or the
calendar); and, in the cases named "... (manual)", the examples of the
OSCAT BASIC manual (github.com/franz-hoepfinger-oscat/oscat-basic-docs,
docs/en/<page>, the page in ``doc``).  A manual example with the same
function and inputs as a plc.xml case is kept once (the plc.xml one).
The data module of benchmarks/oscat.py (it runs nothing itself); this
text is ours, no OSCAT source is in it.  MINUTE_OF_DT has no case: the
translation declares its parameter XDT in VAR_OUTPUT, so no call can pass
a date to it.  SINH and SQRTN have none yet: some of their copies declare
the parameters in VAR (benchmarks/oscat.py reports the conflict and keeps
the copy that declares them).

Conventions of the OpenPLC translation (wonka929/OSCAT_OpenPLC) the values
follow: DATE and DT are UDINT seconds since 1970-01-01 (CODESYS's
representation), TOD is UDINT milliseconds since midnight.  Reference
values of transcendental functions are the mathematical ones (Python's
math module, to 8 digits); ``tol`` is absolute and relative.

``known`` is filled in only after a disagreement was investigated by
reading the translation's code: it says why the code differs from the
documentation (the expected value stays the documented one).

A case is a FUNCTION call (``outputs``: expression, result type, expected)
or a FUNCTION_BLOCK instance called once a cycle with ``calls`` (the
arguments of each call), its outputs read after the last call.  ``note``
says where the documentation is ambiguous and which reading the value
takes.
"""

from __future__ import annotations

import datetime as _dt
import re
from dataclasses import dataclass, field


@dataclass
class Case:
    name: str
    pou: str
    outputs: list            # [(expression or FB output, IEC type, expected value)]
    doc: str                 # the documentation sentence the values come from
    calls: list = field(default_factory=list)   # FB: one argument list a cycle
    tol: float = 1e-5
    note: str = ""
    needs: tuple = ()        # other POUs the case's expressions call
    known: str = ""          # why the translation's code disagrees (found by reading it)
    vars: tuple = ()         # declarations of the case program the arguments need
                             # (an ARRAY argument), names unique across the cases

    @property
    def kind(self):
        return "FB" if self.calls else "F"


PI = 3.14159265


def d(y, m, day, h=0, mi=0, s=0) -> int:
    """A DATE or DT as the translation holds it: UDINT seconds since 1970."""
    return int(_dt.datetime(y, m, day, h, mi, s, tzinfo=_dt.timezone.utc).timestamp())


def tod(h, m, s=0.0) -> int:
    """A TOD as the translation holds it: UDINT milliseconds since midnight."""
    return int(round((h * 3600 + m * 60 + s) * 1000))


def t(text: str) -> int:
    """A TIME literal of the manual (T#1d2h24m) in nanoseconds."""
    unit = {"d": 86400e9, "h": 3600e9, "m": 60e9, "s": 1e9, "ms": 1e6}
    return int(round(sum(float(n) * unit[u]
                         for n, u in re.findall(r"(\d+(?:\.\d+)?)(ms|d|h|m|s)", text[2:]))))


def manual(page: str) -> str:
    return f"OSCAT BASIC manual, {page} (oscat-basic-docs, docs/en/{page.lower()})"

CASES = [
    # ---------------------------------------------------------- 5 Mathematics
    Case("FACT", "FACT", [("FACT(5)", "DINT", 120), ("FACT(13)", "DINT", -1),
                          ("FACT(-1)", "DINT", -1)],
         "this function calculates the factorial of x if the input is negative or higher then "
         "12 the output will be -1"),
    Case("FIB", "FIB", [("FIB(10)", "DINT", 55), ("FIB(1)", "DINT", 1)],
         "calculates the fibonacci sequence",
         note="F(0)=0, F(1)=1 (the usual indexing; the text does not say)"),
    Case("GCD", "GCD", [("GCD(12, 18)", "INT", 6), ("GCD(17, 5)", "INT", 1)],
         "this function calculates the gretaest common divisor of two numbers A and B",
         known="the translation's binary (Stein) GCD halves its result, GCD := SHR(GCD, 1), "
               "where the algorithm doubles it for every factor 2 common to A and B: with "
               "both inputs even the result is 0 (odd inputs are right)"),
    Case("POLYNOM_INT", "POLYNOM_INT",
         [("POLYNOM_INT(X := 3.0, XY := pi_xy, Pts := 3)", "REAL", 9.0),
          ("POLYNOM_INT(X := 1.5, XY := pi_xy, Pts := 3)", "REAL", 2.25),
          ("pi_xy[3, 1]", "REAL", 4.0)],
         "POLYNOM_INT calculates an output based on a Polynom interpolation of up to 5 "
         "coordinates given in an array the indut coordinates have to start at the lowest "
         "array position and must be sorted ba ascending X values",
         note="the points (0,0) (1,1) (2,4) lie on y = x*x: their interpolating polynomial is "
              "x*x (3 points, degree 2); the function writes its XY input, a VAR_INPUT: the "
              "caller's array keeps its values (pi_xy[3, 1], read after both calls)",
         vars=("pi_xy : ARRAY[1..5, 0..1] OF REAL := [0.0, 0.0, 1.0, 1.0, 2.0, 4.0, 4(0.0)];",)),
    Case("EVEN", "EVEN", [("EVEN(4)", "BOOL", True), ("EVEN(7)", "BOOL", False)],
         "checks an input for even value the output is true if the input is even"),
    Case("SGN", "SGN", [("SGN(-2.5)", "INT", -1), ("SGN(0.0)", "INT", 0), ("SGN(3.0)", "INT", 1)],
         "sgn returns 0 when X = 0 , -1 when X < 1 and +1 when X > 1",
         note="'< 1' and '> 1' read as < 0 and > 0 (inputs chosen away from 0..1)"),
    Case("SIGN_I/SIGN_R", "SIGN_I", [("SIGN_I(-5)", "BOOL", True), ("SIGN_R(2.0)", "BOOL", False)],
         "this function return true if the integer input is negative / if the real input is "
         "negative", needs=("SIGN_R",)),
    Case("FLOOR/CEIL", "FLOOR", [("FLOOR(3.14)", "INT", 3), ("FLOOR(-3.14)", "INT", -4),
                                 ("CEIL(3.14)", "INT", 4), ("CEIL(-3.14)", "INT", -3)],
         "floor(3.14) = 3 floor(-3.14) = -4; ceil(3.14) = 4 ceil(-3.14) = -3", needs=("CEIL",)),
    Case("FLOOR2/CEIL2", "FLOOR2", [("FLOOR2(-3.14)", "DINT", -4), ("CEIL2(-3.14)", "DINT", -3)],
         "floor2(3.14) = 3 floor2(-3.14) = -4; CEIL2 returns the smallest possible integer "
         "which is greater or equal to X", needs=("CEIL2",)),
    Case("FRACT", "FRACT", [("FRACT(3.14)", "REAL", 0.14)],
         "this function returns the fraction of a real number fract(3.14) = 0.14"),
    Case("MODR", "MODR", [("MODR(5.5, 2.5)", "REAL", 0.5)],
         "modulo funtion for real numbers modr(5.5,2.5) = 0.5"),
    Case("ROUND", "ROUND", [("ROUND(3.1415, 1)", "REAL", 3.1), ("ROUND(2.71828, 3)", "REAL", 2.718)],
         "this function rounds a real down to n digits behind the comma. round(3.1415,1) = 3.1",
         note="the second value: 2.71828 to 3 digits, down or to nearest give 2.718 alike"),
    Case("RND", "RND", [("RND(3.1415, 2)", "REAL", 3.1)],
         "this function rounds a real down to n digits total. round(3.1415,2) = 3.1"),
    Case("CMP", "CMP", [("CMP(3.141516, 3.141517, 6)", "BOOL", True),
                        ("CMP(3.14, 3.15, 3)", "BOOL", False)],
         "checks two inputs x and y if they are identical with the first N digits example : "
         "cmp(3.141516,3.141517,6 is true",
         known="the code tests ABS(X - Y) < 10^(FLOOR(LOG(ABS(X))) - N + 1), a tolerance, not "
               "digits: 3.15 - 3.14 is 0.00999.. in REAL, under 0.01, so 3.14 and 3.15 count "
               "as equal to 3 digits; the documentation is ambiguous at the boundary"),
    Case("HYPOT", "HYPOT", [("HYPOT(3.0, 4.0)", "REAL", 5.0)],
         "calculates the pythagorean function"),
    Case("MAX3/MIN3/MID3", "MAX3", [("MAX3(1.0, 5.0, 3.0)", "REAL", 5.0),
                                    ("MIN3(1.0, 5.0, 3.0)", "REAL", 1.0),
                                    ("MID3(1.0, 5.0, 3.0)", "REAL", 3.0)],
         "returns the highest / the lowest / the mid value of 3 real inputs",
         needs=("MIN3", "MID3")),
    Case("INC", "INC", [("INC(X := 10, _D := 1, M := 10)", "INT", 0),
                        ("INC(X := 3, _D := 2, M := 10)", "INT", 5)],
         "increments the input X by the value D and compares the result with M. if the output "
         "exceeds M it will continue to count from 0 again."),
    Case("INC1", "INC1", [("INC1(X := 4, N := 5)", "INT", 0), ("INC1(X := 2, N := 5)", "INT", 3)],
         "increments the variable X by 1 and if N is reached, it begins with 0 instead of N "
         "again."),
    Case("DEC1", "DEC1", [("DEC1(x := 0, n := 3)", "INT", 3), ("DEC1(x := 2, n := 3)", "INT", 1)],
         "decrements the variable X by 1 and if 0 is reached, it begins with M again. "
         "_dec1(3,X) will generate 3,2,1,0,3,2,...",
         note="the example's sequence 3,2,1,0,3: after 0 comes N",
         known="the code gives N - 1 after 0 (DEC1 counts N values, N-1 .. 0, like INC1's "
               "0 .. N-1): the example '_dec1(3,X) ... 3,2,1,0,3' names neither argument "
               "order nor N; the documentation is ambiguous"),
    Case("EXPN", "EXPN", [("EXPN(2.0, 10)", "REAL", 1024.0), ("EXPN(2.0, -1)", "REAL", 0.5)],
         "this function calculates X to the power of N (Y = X^N) whilke N is an integer"),
    Case("EXP10", "EXP10", [("EXP10(2.0)", "REAL", 100.0)],
         "calculates the exponent to the basis 10", tol=1e-4),
    Case("DEG/RAD", "DEG", [("DEG(3.14159265)", "REAL", 180.0), ("RAD(180.0)", "REAL", PI)],
         "DEG: 'this function converts degrees into Radiant'; RAD: 'this function converts "
         "Radiant to degrees'", needs=("RAD",), tol=1e-4,
         note="the two sentences are swapped in plc.xml; the input names (DEG(RAD_IN), "
              "RAD(_DEG)) and OSCAT's manual give DEG: radians -> degrees"),
    Case("INV/NEGX/MUL_ADD", "INV", [("INV(4.0)", "REAL", 0.25), ("NEGX(2.5)", "REAL", -2.5),
                                     ("MUL_ADD(2.0, 3.0, 1.0)", "REAL", 7.0)],
         "1 / X; returns -X; multiplies an input X with K and adds Offset O to the result",
         needs=("NEGX", "MUL_ADD")),
    Case("DIFFER", "DIFFER", [("DIFFER(1.0, 1.5, 0.4)", "BOOL", True),
                              ("DIFFER(1.0, 1.3, 0.4)", "BOOL", False)],
         "this function checks if in1 differs more then x from in2 the output is true if "
         "abs(in1-in2) > X"),
    Case("D_TRUNC", "D_TRUNC", [("D_TRUNC(1.5)", "DINT", 1), ("D_TRUNC(-1.5)", "DINT", -1)],
         "d_trunc truncates a real to a dint 1.5 will be 1 and -1.5 will be -1"),
    Case("GAMMA", "GAMMA", [("GAMMA(5.0)", "REAL", 24.0)],
         "calculates the stirling function which is an approximation for the gamma function",
         tol=2e-2, note="Stirling's formula is within 2 % of Gamma(5) = 24"),
    Case("ERF", "ERF", [("ERF(0.5)", "REAL", 0.52049988)],
         "calculates the erf (error) function", tol=1e-3),
    Case("SIGMOID", "SIGMOID", [("SIGMOID(0.0)", "REAL", 0.5)],
         "this function calculates the sigmoid function"),
    Case("hyperbolic", "COSH", [("COSH(1.0)", "REAL", 1.54308063), ("TANH(0.5)", "REAL", 0.46211716),
                                ("ASINH(1.0)", "REAL", 0.88137359), ("ACOSH(2.0)", "REAL", 1.31695790)],
         "calculates the cos hyperbolicus; the tangens hyperbolicus; the arcus sin hyperbolicus; "
         "the arcus cos hyperbolicus", needs=("TANH", "ASINH", "ACOSH"), tol=1e-4),
    Case("LANGEVIN", "LANGEVIN", [("LANGEVIN(1.0)", "REAL", 0.31303529)],
         "this function calculates the langevin function", tol=1e-4,
         note="L(x) = coth(x) - 1/x"),
    Case("ATAN2", "ATAN2", [("ATAN2(X := 1.0, Y := 1.0)", "REAL", PI / 4),
                            ("ATAN2(X := 0.0, Y := 2.0)", "REAL", PI / 2)],
         "this function calculates the angle in a coordinate system in rad.", tol=1e-4),
    Case("BINOM", "BINOM", [("BINOM(N := 5, K := 2, i := 0)", "INT", 10)],
         "the binomial coefficient N over K (no documentation text in plc.xml)",
         note="the translation made BINOM's loop counter i a VAR_INPUT; 0 is passed"),
    # ---------------------------------------------------------- 16 Logic
    Case("BIT_COUNT", "BIT_COUNT", [("BIT_COUNT(DWORD#16#F0F0_0001)", "INT", 9)],
         "BIT_COUNT counts the amount True of bits in a dword."),
    Case("PARITY/CHECK_PARITY", "PARITY",
         [("PARITY(DWORD#2#0111)", "BOOL", True), ("CHECK_PARITY(DWORD#2#0111, TRUE)", "BOOL", True),
          ("CHECK_PARITY(DWORD#2#0111, FALSE)", "BOOL", False)],
         "this function calculates the even parity of an input Dword; this function checks for "
         "an even partity for a dword and partity bit", needs=("CHECK_PARITY",),
         note="even parity: the parity bit makes the count of ones even (3 ones -> TRUE)"),
    Case("REVERSE", "REVERSE", [("REVERSE(BYTE#2#0000_0001)", "BYTE", 128),
                                ("REVERSE(BYTE#2#1100_0001)", "BYTE", 0b10000011)],
         "This function reverses the bits of a byte so that after execution bit 7 is at bit 0 "
         "location and so forth"),
    Case("SWAP_BYTE/SWAP_BYTE2", "SWAP_BYTE", [("SWAP_BYTE(WORD#16#1234)", "WORD", 0x3412),
                                               ("SWAP_BYTE2(DWORD#16#12345678)", "DWORD", 0x78563412)],
         "This function swaps the high and low byte of the word in; This function reverses the "
         "byte order in the dword.", needs=("SWAP_BYTE2",)),
    Case("GRAY", "BYTE_TO_GRAY", [("BYTE_TO_GRAY(BYTE#5)", "BYTE", 7), ("GRAY_TO_BYTE(BYTE#7)", "BYTE", 5),
                                  ("BYTE_TO_GRAY(BYTE#255)", "BYTE", 128)],
         "this function converts a binary to gray code; this function converts a gray code into "
         "binary", needs=("GRAY_TO_BYTE",)),
    Case("BCDC", "INT_TO_BCDC", [("INT_TO_BCDC(42)", "BYTE", 0x42), ("BCDC_TO_INT(BYTE#16#42)", "INT", 42)],
         "this function converts an integer into a two digit bcd number",
         needs=("BCDC_TO_INT",)),
    Case("SHL1/SHR1", "SHL1", [("SHL1(DWORD#1, 4)", "DWORD", 0x1F),
                               ("SHR1(DWORD#16#8000_0000, 4)", "DWORD", 0xF8000000)],
         "SHL1 shifts N bits to the left filling the new bits with 1; SHR1 shifts N bits to the "
         "right filling the new bits with 1", needs=("SHR1",)),
    Case("BIT_LOAD/TOGGLE", "BIT_LOAD_B", [("BIT_LOAD_B(IN := BYTE#0, VAL := TRUE, POS := 3)", "BYTE", 8),
                                           ("BIT_TOGGLE_B(IN := BYTE#255, POS := 0)", "BYTE", 254)],
         "this function loads a bit into a byte at position pos.; this function toggles a bit of "
         "a BYTE at position pos.", needs=("BIT_TOGGLE_B",)),
    Case("BIT_OF_DWORD", "BIT_OF_DWORD", [("BIT_OF_DWORD(DWORD#4, 2)", "BOOL", True),
                                          ("BIT_OF_DWORD(DWORD#4, 0)", "BOOL", False)],
         "this function extracts a single bit from the nth position from right (right is lowest "
         "bit the lowest Bit (Bit0 from in) is selected with N=0"),
    Case("BYTE_OF_DWORD", "BYTE_OF_DWORD", [("BYTE_OF_DWORD(DWORD#16#11223344, BYTE#1)", "BYTE", 0x33)],
         "this function extracts a single byte from the nth position from right",
         note="N=0 is the lowest byte, as for BIT_OF_DWORD"),
    Case("REFLECT", "REFLECT", [("REFLECT(DWORD#2#0001, 4)", "DWORD", 8)],
         "This function reverses the specified amount of bits from bit 0 to bit n within a dword "
         "while L specifies the amount of Bits to be reflected"),
    Case("MUX_4", "MUX_4", [("MUX_4(D0 := FALSE, D1 := FALSE, D2 := TRUE, D3 := FALSE, "
                             "A0 := FALSE, A1 := TRUE)", "BOOL", True)],
         "quad input multiplexer", note="A1 A0 = 2#10 selects D2"),
    # ---------------------------------------------------------- 12 Time and Date
    Case("LEAP_YEAR", "LEAP_YEAR", [("LEAP_YEAR(2024)", "BOOL", True), ("LEAP_YEAR(2023)", "BOOL", False),
                                    ("LEAP_YEAR(2000)", "BOOL", True)],
         "leap_year is true if the tested year is a leap year"),
    Case("SET_DATE", "SET_DATE", [("SET_DATE(2024, 3, 1)", "UDINT", 1709251200)],
         "creates a date output from year, month and day of month"),
    Case("YEAR_BEGIN", "YEAR_BEGIN", [("YEAR_BEGIN(2024)", "UDINT", 1704067200)],
         "returs the date of january 1st for the given year the function works for dates from "
         "1970 - 2099"),
    Case("DAY_OF_WEEK", "DAY_OF_WEEK", [("DAY_OF_WEEK(UDINT#1704067200)", "INT", 1),
                                        ("DAY_OF_WEEK(UDINT#1709251200)", "INT", 5)],
         "calculates the weekday of a week according to ISO8601 monday = 1 ..... sunday = 7",
         note="2024-01-01 was a Monday, 2024-03-01 a Friday"),
    Case("DAY_OF_YEAR", "DAY_OF_YEAR", [("DAY_OF_YEAR(UDINT#1709251200)", "INT", 61)],
         "calculates the day of the year", note="2024-03-01: 31 + 29 + 1"),
    Case("DAYS_IN_MONTH", "DAYS_IN_MONTH", [("DAYS_IN_MONTH(UDINT#1707523200)", "INT", 29)],
         "returs the total days of the current month", note="2024-02-10"),
    Case("date parts", "YEAR_OF_DATE", [("YEAR_OF_DATE(UDINT#1709251200)", "INT", 2024),
                                       ("MONTH_OF_DATE(UDINT#1709251200)", "INT", 3),
                                       ("DAY_OF_MONTH(UDINT#1709251200)", "INT", 1)],
         "returs the year of a date; returns the current month of the year; returns the day OF "
         "month for any DATE", needs=("MONTH_OF_DATE", "DAY_OF_MONTH")),
    Case("EASTER", "EASTER", [("EASTER(2024)", "UDINT", 1711843200), ("EASTER(2025)", "UDINT", 1745107200)],
         "easter calculates the day of easter sunday for a given year",
         note="Easter Sunday 2024-03-31 and 2025-04-20"),
    Case("DATE_ADD", "DATE_ADD", [("DATE_ADD(IDATE := UDINT#1706659200, _D := 1, W := 0, M := 0, "
                                   "Y := 0)", "UDINT", 1706745600)],
         "date_add adds days, weeks, month or years to a date.", note="2024-01-31 + 1 day"),
    Case("HOUR/SET_TOD", "HOUR", [("HOUR(UDINT#49500000)", "INT", 13),
                                  ("SET_TOD(12, 30, 15.5)", "UDINT", 45015500)],
         "extracts the hour of a Time_of_day; creates tod from hour minute and second",
         needs=("SET_TOD",), note="TOD as milliseconds: 13:45:00 and 12:30:15.5"),
    Case("HOUR_TO_TIME", "HOUR_TO_TIME", [("HOUR_TO_TIME(1.5)", "TIME", 5400 * 10**9),
                                          ("MINUTE_TO_TIME(2.5)", "TIME", 150 * 10**9)],
         "converts an amount of hours in real to time; converts an amount of minutes in real to "
         "time", needs=("MINUTE_TO_TIME",)),
    # ---------------------------------------------------------- 10/11 Geometry, vectors
    Case("CIRCLE", "CIRCLE_A", [("CIRCLE_A(AX := 360.0, RX := 1.0)", "REAL", PI),
                                ("CIRCLE_C(AX := 360.0, RX := 1.0)", "REAL", 2 * PI)],
         "circle_A calculates the Area of a circle segement if ax = 360 the whole circle is "
         "calculated; circle_C calculates the Circumference ...", needs=("CIRCLE_C",), tol=1e-4),
    Case("SPHERE_V/CONE_V", "SPHERE_V", [("SPHERE_V(3.0)", "REAL", 113.097336),
                                         ("CONE_V(RX := 3.0, HX := 4.0)", "REAL", 37.6991118)],
         "calculates the Volume of a Sphere; cone_V calculates the Volume of a cone",
         needs=("CONE_V",), tol=1e-4),
    Case("ELLIPSE_A", "ELLIPSE_A", [("ELLIPSE_A(2.0, 3.0)", "REAL", 18.8495559)],
         "ellipse_A calculates the Area of an ellipe based on the two radians R1 and R2", tol=1e-4),
    Case("TRIANGLE_A", "TRIANGLE_A", [("TRIANGLE_A(A := 0.0, S1 := 3.0, S2 := 4.0, S3 := 5.0)",
                                       "REAL", 6.0)],
         "triangle_A calculates the Area of a triangle. if any input is 0 it will be neglected "
         "and the are will be calculated from eiter: two sides and an angle ... or 3 sides.",
         tol=1e-4),
    # ---------------------------------------------------------- 19 Signal processing
    Case("SCALE", "SCALE", [("SCALE(X := 2.0, K := 3.0, O := 1.0, MX := 100.0, MN := 0.0)", "REAL", 7.0)],
         "Scale is used to translate an input x to output by the formula Y = X*K + O"),
    Case("MUX_R4", "MUX_R4", [("MUX_R4(IN0 := 1.0, IN1 := 2.0, IN2 := 3.0, IN3 := 4.0, A0 := TRUE, "
                               "A1 := TRUE)", "REAL", 4.0)],
         "MUX_R4 is an analog Multiplexer", note="A1 A0 = 2#11 selects IN3"),
    Case("BYTE_TO_RANGE/RANGE_TO_BYTE", "BYTE_TO_RANGE",
         [("BYTE_TO_RANGE(X := BYTE#51, LOW := 0.0, HIGH := 100.0)", "REAL", 20.0),
          ("RANGE_TO_BYTE(X := 20.0, LOW := 0.0, HIGH := 100.0)", "BYTE", 51)],
         "Byte_to_Range converts a Byte into a real between low and high; Range_to_byte converts "
         "a real value between low and high into a byte", needs=("RANGE_TO_BYTE",), tol=1e-4),
    Case("SCALE_B", "SCALE_B", [("SCALE_B(X := BYTE#51, I_LO := BYTE#0, I_HI := BYTE#255, "
                                 "O_LO := 0.0, O_HI := 100.0)", "REAL", 20.0)],
         "scales a byte input from I_LO..I_HI to O_LO..O_HI (no documentation text in plc.xml)",
         tol=1e-4),
    # ---------------------------------------------------------- function blocks
    Case("TOGGLE", "TOGGLE", [("Q", "BOOL", True)],
         "toggle flip flop the output changes state with every rising edge of clk",
         calls=["CLK := TRUE", "CLK := FALSE", "CLK := TRUE", "CLK := FALSE", "CLK := TRUE"],
         note="three rising edges"),
    Case("LTCH", "LTCH", [("Q", "BOOL", True)],
         "Transparent Latch with asynchronous reset",
         calls=["DI := TRUE, L := TRUE, RST := FALSE", "DI := FALSE, L := FALSE, RST := FALSE"],
         note="with L low the latch holds the value it had"),
    Case("FF_JKE", "FF_JKE", [("Q", "BOOL", False)],
         "JK-type flip flop with set, reset and rising clock trigger",
         calls=["J := TRUE, K := FALSE, CLK := TRUE", "J := TRUE, K := FALSE, CLK := FALSE",
                "J := TRUE, K := TRUE, CLK := TRUE"],
         note="J sets Q on the first edge; J and K together toggle it on the second"),
    Case("SHR_4E", "SHR_4E", [("Q0", "BOOL", False), ("Q1", "BOOL", True), ("Q2", "BOOL", False)],
         "4 bit shift register with reset",
         calls=["D0 := TRUE, CLK := TRUE", "D0 := TRUE, CLK := FALSE", "D0 := FALSE, CLK := TRUE"],
         note="D0 enters Q0 on a rising CLK and moves up one place an edge",
         known="the translation's SHR_4E never calls its R_TRIG instance (no trig(CLK := CLK)"
               " line), so trig.Q stays FALSE and the register never shifts: a defect of the "
               "translation (or OSCAT), the engines run what the code says"),
    Case("COUNT_BR", "COUNT_BR", [("CNT", "BYTE", 3)],
         "Count_R is a byte counter with independen up and dn inputs",
         calls=["UP := TRUE", "UP := FALSE", "UP := TRUE", "UP := FALSE", "UP := TRUE"],
         note="_STEP defaults to 1; edges and levels of UP give 3 alike with this pattern"),
    Case("STACK_16", "STACK_16", [("DOUT", "DWORD", 2), ("EMPTY", "BOOL", False)],
         "STACK_16: a last-in-first-out memory of 16 DWORDs (no documentation text in plc.xml)",
         calls=["DIN := DWORD#1, WD := TRUE", "WD := FALSE", "DIN := DWORD#2, WD := TRUE",
                "WD := FALSE", "RD := TRUE"]),
    Case("FIFO_16", "FIFO_16", [("DOUT", "DWORD", 1), ("EMPTY", "BOOL", False)],
         "FIFO_16: a first-in-first-out memory of 16 DWORDs (no documentation text in plc.xml)",
         calls=["DIN := DWORD#1, WD := TRUE", "WD := FALSE", "DIN := DWORD#2, WD := TRUE",
                "WD := FALSE", "RD := TRUE"]),
    Case("DELAY_4", "DELAY_4", [("OUT1", "REAL", 4.0), ("OUT2", "REAL", 3.0), ("OUT3", "REAL", 2.0),
                                ("OUT4", "REAL", 1.0)],
         "this function block delays input values by each programm cycle",
         calls=["IN := 1.0", "IN := 2.0", "IN := 3.0", "IN := 4.0", "IN := 5.0"],
         note="OUTn is the input of n cycles before"),
    Case("TREND_DW", "TREND_DW", [("TU", "BOOL", True), ("TD", "BOOL", False)],
         "trend_DW analyses the trend of a input signal.",
         calls=["X := DWORD#10", "X := DWORD#20"], note="a rising input: trend up"),
    # ---------------------------------------------------------- the manual's examples
    # (CEIL, FLOOR, FLOOR2, CEIL2, DEG and RAD examples are the plc.xml cases above)
    Case("SWAP_BYTE (manual)", "SWAP_BYTE", [("SWAP_BYTE(16#33DF)", 'WORD', 0xDF33)],
         manual("Logic/swap_byte")),
    Case("SWAP_BYTE2 (manual)", "SWAP_BYTE2", [("SWAP_BYTE2(16#33DF1122)", 'DWORD', 0x2211DF33)],
         manual("Logic/swap_byte2")),
    Case("REVERSE (manual)", "REVERSE", [("REVERSE(2#10011110)", 'BYTE', 0b01111001)],
         manual("Logic/reverse")),
    Case("BIT_TOGGLE_W (manual)", "BIT_TOGGLE_W", [("BIT_TOGGLE_W(2#0000_1111, 2)", 'WORD', 0b1011)],
         manual("Logic/bit_toggle_w")),
    Case("BIT_TOGGLE_DW (manual)", "BIT_TOGGLE_DW", [("BIT_TOGGLE_DW(2#0000_1111, 7)", 'DWORD', 0b10001111)],
         manual("Logic/bit_toggle_dw")),
    Case("BIT_LOAD_B2 (manual)", "BIT_LOAD_B2", [("BIT_LOAD_B2(2#1111_0000, TRUE, 1, 2)", 'BYTE', 0b11110110),
                                                 ("BIT_LOAD_B2(2#1111_1111, FALSE, 7, 2)", 'BYTE', 0b01111110)],
         manual("Logic/bit_load_b2")),
    Case("MAX3 (manual)", "MAX3", [("MAX3(1.0, 3.0, 2.0)", 'REAL', 3.0)],
         manual("Mathematical/max3")),
    Case("MIN3 (manual)", "MIN3", [("MIN3(1.0, 3.0, 2.0)", 'REAL', 1.0)],
         manual("Mathematical/min3")),
    Case("MID3 (manual)", "MID3", [("MID3(1.0, 5.0, 2.0)", 'REAL', 2.0)],
         manual("Mathematical/mid3")),
    Case("RND (manual)", "RND", [("RND(355.55, 2)", 'REAL', 360.0), ("RND(3.555, 2)", 'REAL', 3.6)],
         manual("Mathematical/rnd")),
    Case("ROUND (manual)", "ROUND", [("ROUND(3.555, 2)", 'REAL', 3.56)],
         manual("Mathematical/round")),
    Case("CMP (manual)", "CMP", [("CMP(3.140, 3.149, 3)", 'BOOL', True),
                                 ("CMP(3.140, 3.149, 4)", 'BOOL', False)],
         manual("Mathematical/cmp")),
    Case("FIB (manual)", "FIB", [("FIB(5)", 'DINT', 5), ("FIB(4)", 'DINT', 3)],
         manual("Mathematical/fib")),
    Case("EXPN (manual)", "EXPN", [("EXPN(1.5, 2)", 'REAL', 2.25),
                                   ("EXPN(10.0, -2)", 'REAL', 0.01)],
         manual("Mathematical/expn")),
    Case("EXP10 (manual)", "EXP10", [("EXP10(0.0)", 'REAL', 1.0)],
         manual("Mathematical/exp10")),
    Case("D_TRUNC (manual)", "D_TRUNC", [("D_TRUNC(-1.6)", 'DINT', -1)],
         manual("Mathematical/d_trunc")),
    Case("SINC (manual)", "SINC", [("SINC(0.0)", 'REAL', 1.0)],
         manual("Mathematical/sinc")),
    Case("TANC (manual)", "TANC", [("TANC(0.0)", 'REAL', 1.0)],
         manual("Mathematical/tanc")),
    Case("OVERRIDE (manual)", "OVERRIDE", [("OVERRIDE(10.0, -12.0, 11.0, TRUE, TRUE, TRUE)", 'REAL', -12.0),
                                           ("OVERRIDE(10.0, -12.0, 11.0, TRUE, FALSE, TRUE)", 'REAL', 11.0)],
         manual("Mathematical/override")),
    Case("DAY_OF_WEEK (manual)", "DAY_OF_WEEK", [(f"DAY_OF_WEEK({d(2007, 1, 8)})", 'INT', 1)],
         manual("Time&Date/day_of_week")),
    Case("DAY_OF_YEAR (manual)", "DAY_OF_YEAR", [(f"DAY_OF_YEAR({d(2007, 12, 31)})", 'INT', 365),
                                                 (f"DAY_OF_YEAR({d(2008, 12, 31)})", 'INT', 366)],
         manual("Time&Date/day_of_year")),
    Case("DAYS_DELTA (manual)", "DAYS_DELTA", [(f"DAYS_DELTA({d(2007, 1, 10)}, {d(2007, 1, 1)})", 'DINT', -9)],
         manual("Time&Date/days_delta")),
    Case("LEAP_DAY (manual)", "LEAP_DAY", [(f"LEAP_DAY({d(2004, 2, 29)})", 'BOOL', True)],
         manual("Time&Date/leap_day")),
    Case("MONTH_BEGIN (manual)", "MONTH_BEGIN", [(f"MONTH_BEGIN({d(2008, 2, 13)})", 'UDINT', d(2008, 2, 1))],
         manual("Time&Date/month_begin")),
    Case("MONTH_END (manual)", "MONTH_END", [(f"MONTH_END({d(2008, 2, 13)})", 'UDINT', d(2008, 2, 29))],
         manual("Time&Date/month_end")),
    Case("MONTH_OF_DATE (manual)", "MONTH_OF_DATE", [(f"MONTH_OF_DATE({d(2007, 12, 31)})", 'INT', 12)],
         manual("Time&Date/month_of_date")),
    Case("YEAR_OF_DATE (manual)", "YEAR_OF_DATE", [(f"YEAR_OF_DATE({d(2007, 12, 31)})", 'INT', 2007)],
         manual("Time&Date/year_of_date")),
    Case("HOUR (manual)", "HOUR", [(f"HOUR({tod(22, 55, 13)})", 'INT', 22)],
         manual("Time&Date/hour")),
    Case("SET_DATE (manual)", "SET_DATE", [("SET_DATE(2007, 1, 22)", 'UDINT', d(2007, 1, 22)),
                                           ("SET_DATE(2007, 1, 365)", 'UDINT', d(2007, 12, 31))],
         manual("Time&Date/set_date")),
    Case("SET_DT (manual)", "SET_DT", [("SET_DT(2007, 1, 22, 13, 10, 22)", 'UDINT', d(2007, 1, 22, 13, 10, 22))],
         manual("Time&Date/set_dt")),
    Case("SET_TOD (manual)", "SET_TOD", [("SET_TOD(13, 10, 22.33)", 'UDINT', tod(13, 10, 22.33))],
         manual("Time&Date/set_tod")),
    Case("SECOND_TO_TIME (manual)", "SECOND_TO_TIME", [("SECOND_TO_TIME(63.123)", 'TIME', t('T#1m3s123ms'))],
         manual("Time&Date/second_to_time")),
    Case("MINUTE_TO_TIME (manual)", "MINUTE_TO_TIME", [("MINUTE_TO_TIME(122.5)", 'TIME', t('T#2h2m30s'))],
         manual("Time&Date/minute_to_time")),
    Case("HOUR_TO_TIME (manual)", "HOUR_TO_TIME", [("HOUR_TO_TIME(1.1)", 'TIME', t('T#1h6m'))],
         manual("Time&Date/hour_to_time")),
    Case("DAY_TO_TIME (manual)", "DAY_TO_TIME", [("DAY_TO_TIME(1.1)", 'TIME', t('T#1d2h24m'))],
         manual("Time&Date/day_to_time")),
    Case("HOUR_TO_TOD (manual)", "HOUR_TO_TOD", [("HOUR_TO_TOD(12.1)", 'UDINT', tod(12, 6))],
         manual("Time&Date/hour_to_tod")),
    Case("HOUR_OF_DT (manual)", "HOUR_OF_DT", [(f"HOUR_OF_DT({d(2008, 6, 6, 10, 22, 20)})", 'INT', 10)],
         manual("Time&Date/hour_of_dt")),
    Case("SECOND_OF_DT (manual)", "SECOND_OF_DT", [(f"SECOND_OF_DT({d(2008, 6, 6, 10, 22, 20)})", 'INT', 20)],
         manual("Time&Date/second_of_dt")),
]

# POUs of the translation that need a construct outside ed.2 (or are
# translation defects), with the reason: benchmarks/oscat.py does not count
# them as failures when the library leaves them out
KNOWN_REFUSALS = {
    "BYTE_TO_STRH": "the translation's body passes a printf format to the conversion, "
                    "BYTE_TO_STRING(IN, '%c') (plc.xml: '%02X'): a type conversion has one "
                    "input in ed.2 (Table 22) and in MatIEC's library; ed.2 code builds the two "
                    "hex digits itself",
    "_ARRAY_MEDIAN": "the translation passes its array to the inner _ARRAY_SORT instance by "
                     "writing the instance's VAR_IN_OUT as a member (inst.PT := pt) and then "
                     "calling it without PT: an in-out must be connected in the call (ed.2 "
                     "2.5.2.1) and is not accessible from outside; ed.2 code: "
                     "inst(PT := pt, SIZE := size)",
    "ARRAY_SDV": "as _ARRAY_MEDIAN: FB_array_var.pt := pt; FB_array_var() leaves the "
                 "VAR_IN_OUT PT of ARRAY_VAR unconnected; ed.2 code: FB_array_var(PT := pt, "
                 "SIZE := size)",
}
