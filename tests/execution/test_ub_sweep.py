"""No undefined behaviour reaches the generated code: every integer
operation on the extreme values of every integer type, shifts and rotations
by any count, every *_TO_* conversion of extreme values (REAL ones
included: NaN, Inf, out of range), time arithmetic at its limits and the
numeric functions outside their domains run under ASan+UBSan without a
report.  The values sit in arrays read by loop variables, so the C compiler
cannot fold them away."""

from __future__ import annotations

from pathlib import Path

import pytest

import runner
from iec2kmod import sim
from iec2kmod.checks.stdlib import CONVERTIBLE, conversion

pytestmark = pytest.mark.execution

SIGNED = {"SINT": 8, "INT": 16, "DINT": 32, "LINT": 64}
UNSIGNED = {"USINT": 8, "UINT": 16, "UDINT": 32, "ULINT": 64}
BITS = {"BYTE": 8, "WORD": 16, "DWORD": 32, "LWORD": 64}


def _extremes(name):
    if name in SIGNED:
        b = SIGNED[name]
        lo, hi = -(1 << (b - 1)), (1 << (b - 1)) - 1
        return [lo, lo + 1, -2, -1, 0, 1, 2, hi - 1, hi]
    b = (UNSIGNED | BITS)[name]
    hi = (1 << b) - 1
    return [0, 1, 2, hi // 2, hi // 2 + 1, hi - 1, hi]


def _lit(name, v):
    if v < 0:
        return f"{name}#-{-v}" if name != "LINT" or v != -(1 << 63) else \
            "LINT#-9223372036854775808"
    return f"{name}#{v}"


REALS = ["-1.0E300", "-3.4E38", "-2147483648.5", "-1.5", "-0.5", "0.0", "0.5", "2.5",
         "4294967295.5", "1.0E19", "1.0E300"]
STRINGS = ["''", "'abc'", "'  -9223372036854775809 '", "'99999999999999999999999'",
           "'16#FFFFFFFFFFFFFFFFFF'", "'-1'", "'T#-106751d'", "'T#106752d'", "'1.0E400'",
           "'TRUE'", "'D#9999-12-31'", "'DT#1-01-01-00:00:00'", "'TOD#23:59:59.999999999'"]


def sweep_source() -> str:
    decl, body = [], []
    ints = list(SIGNED) + list(UNSIGNED)
    for t in ints + list(BITS):
        vals = _extremes(t)
        decl.append(f"    v_{t} : ARRAY[0..{len(vals) - 1}] OF {t} := "
                    f"[{', '.join(_lit(t, v) for v in vals)}];")
        decl.append(f"    r_{t} : {t};")
    decl.append(f"    v_REAL : ARRAY[0..{len(REALS) + 1}] OF LREAL := [{', '.join(REALS)}];")
    decl.append(f"    v_STRING : ARRAY[0..{len(STRINGS) - 1}] OF STRING := "
                f"[{', '.join(STRINGS)}];")
    decl += ["    i, j : INT;", "    n : INT;", "    x : LREAL;", "    zero : LREAL;",
             "    t1 : TIME;", "    tv : ARRAY[0..4] OF TIME := [T#-106751d, T#-1ms, T#0s, T#1ms,"
             " T#106751d];", "    rr : REAL;", "    sw : WSTRING;", "    ok : BOOL;"]
    for t in CONVERTIBLE:
        if t not in ("STRING", "WSTRING") and f"r_{t}" not in " ".join(decl):
            decl.append(f"    r_{t} : {t};")
    decl.append("    r_STRING : STRING;")
    decl.append("    r_WSTRING : WSTRING;")
    # NaN and Inf at the end of the REAL table
    body += [f"    v_REAL[{len(REALS)}] := zero / zero;",
             f"    v_REAL[{len(REALS) + 1}] := 1.0 / zero;"]
    for t in ints:
        n = len(_extremes(t)) - 1
        body += [f"    FOR i := 0 TO {n} DO", f"        FOR j := 0 TO {n} DO",
                 f"            r_{t} := v_{t}[i] + v_{t}[j];",
                 f"            r_{t} := v_{t}[i] - v_{t}[j];",
                 f"            r_{t} := v_{t}[i] * v_{t}[j];",
                 f"            IF v_{t}[j] <> 0 THEN",
                 f"                r_{t} := v_{t}[i] / v_{t}[j];",
                 f"                r_{t} := v_{t}[i] MOD v_{t}[j];",
                 "            END_IF;",
                 "        END_FOR;",
                 f"        r_{t} := ABS(v_{t}[i]);"]
        if t in SIGNED:
            body.append(f"        r_{t} := -v_{t}[i];")
        body += ["    END_FOR;"]
    for t in BITS:
        n = len(_extremes(t)) - 1
        body += [f"    FOR i := 0 TO {n} DO", "        FOR n := -70 TO 70 DO",
                 f"            r_{t} := SHL(v_{t}[i], n);", f"            r_{t} := SHR(v_{t}[i], n);",
                 f"            r_{t} := ROL(v_{t}[i], n);", f"            r_{t} := ROR(v_{t}[i], n);",
                 "        END_FOR;", f"        r_{t} := NOT v_{t}[i];", "    END_FOR;"]
    # conversions from every integer and bit type, REAL, LREAL, STRING
    for src in ints + list(BITS):
        n = len(_extremes(src)) - 1
        body.append(f"    FOR i := 0 TO {n} DO")
        for dst in CONVERTIBLE:
            if dst != src and conversion(f"{src}_TO_{dst}") is not None:
                body.append(f"        r_{dst} := {src}_TO_{dst}(v_{src}[i]);")
        body.append("    END_FOR;")
    body.append(f"    FOR i := 0 TO {len(REALS) + 1} DO")
    body.append("        rr := LREAL_TO_REAL(v_REAL[i]);")
    for dst in CONVERTIBLE:
        for src in ("REAL", "LREAL"):
            if dst != src and conversion(f"{src}_TO_{dst}") is not None:
                arg = "rr" if src == "REAL" else "v_REAL[i]"
                body.append(f"        r_{dst} := {src}_TO_{dst}({arg});")
    for dst in ints:
        body.append(f"        r_{dst} := LREAL_TRUNC_{dst}(v_REAL[i]);")
        body.append(f"        r_{dst} := REAL_TRUNC_{dst}(rr);")
    for fn in ("SQRT", "LN", "LOG", "EXP", "SIN", "COS", "TAN", "ASIN", "ACOS", "ATAN"):
        body.append(f"        x := {fn}(v_REAL[i]);")
    body += ["        x := ATAN2(v_REAL[i], 1.0);", "        x := EXPT(v_REAL[i], v_REAL[i]);",
             "        x := EXPT(v_REAL[i], 3);", "        t1 := MUL_TIME(T#1d, v_REAL[i]);",
             "        IF v_REAL[i] <> 0.0 THEN t1 := DIV_TIME(T#1d, v_REAL[i]); END_IF;",
             "    END_FOR;"]
    body.append(f"    FOR i := 0 TO {len(STRINGS) - 1} DO")
    for dst in CONVERTIBLE:
        if dst != "STRING" and conversion(f"STRING_TO_{dst}") is not None:
            body.append(f"        r_{dst} := STRING_TO_{dst}(v_STRING[i]);")
    body += ["        sw := STRING_TO_WSTRING(v_STRING[i]);",
             "        r_LINT := WSTRING_TO_LINT(sw);", "    END_FOR;"]
    body += ["    FOR i := 0 TO 4 DO", "        FOR j := 0 TO 4 DO",
             "            t1 := tv[i] + tv[j];", "            t1 := tv[i] - tv[j];",
             "            t1 := tv[i] * 1000000;",
             "            r_TOD := TOD#12:00:00 + tv[i];", "            r_DT := DT#2000-01-01-00:00:00 + tv[j];",
             "        END_FOR;", "        t1 := tv[i] / -1;", "        t1 := -tv[i];",
             "        r_STRING := TIME_TO_STRING(tv[i]);",
             "        r_STRING := DT_TO_STRING(TIME_TO_DT(tv[i]));", "    END_FOR;"]
    return ("PROGRAM ub_sweep\nVAR\n" + "\n".join(decl) + "\nEND_VAR\n" + "\n".join(body) +
            "\nEND_PROGRAM\n")


def test_no_undefined_behaviour(tmp_path):
    src = tmp_path / "ub_sweep.st"
    src.write_text(sweep_source())
    case = runner.Case(src, "ub", "ub_sweep")
    cfg = tmp_path / "config.st"
    cfg.write_text(runner.wrapper_config("ub", [case]))
    project = runner.check_project([src, cfg])
    res = sim.run(project, 0, watch=["ub_sweep.r_DINT"], sanitize=True,
                  build_dir=runner.build_root() / "sim")
    assert not runner.SANITIZER_REPORT.search(res.stderr or ""), res.stderr[:4000]
    assert not res.faults, res.faults
    assert res.cycles == {"t_ub_sweep": 1}


def test_sanitized_simulator_has_the_sanitizers(tmp_path):
    """The sanitize build really links ASan and UBSan (a report would show)."""
    project = runner.check_project([Path(__file__).resolve().parents[2] / "examples" /
                                    "traffic_light"])
    exe, _ = sim.build(project, runner.build_root() / "sim", sanitize=True)
    data = exe.read_bytes()
    assert b"__asan_init" in data and b"__ubsan_handle" in data
    assert runner.SANITIZER_REPORT.search(
        "x.c:3:5: runtime error: signed integer overflow: 2147483647 + 1")
    assert runner.SANITIZER_REPORT.search("==123==ERROR: AddressSanitizer: heap-buffer-overflow")


FLOAT_CAST_UB = r"""
#include <stdio.h>
#include <stdlib.h>
int main(int argc, char **argv)
{
	volatile double big = strtod(argc > 1 ? argv[1] : "1e300", NULL);
	int i = (int)big;               /* undefined: out of int's range */

	printf("%d\n", i);
	return 0;
}
"""


def _is_gcc(cc):
    import subprocess
    p = subprocess.run([cc, "--version"], capture_output=True, text=True)
    return "Free Software Foundation" in p.stdout and "clang" not in p.stdout


def test_sanitizer_flags_report_a_float_cast_overflow(tmp_path):
    """A C cast of 1e300 to int, compiled with the simulator's sanitizer
    flags, is reported and ends the run; gcc's plain -fsanitize=undefined
    (the flags before) let it through."""
    import subprocess
    cc = sim._compiler()
    src = tmp_path / "cast.c"
    src.write_text(FLOAT_CAST_UB)
    exe = tmp_path / "cast"
    p = subprocess.run([cc, *sim.CFLAGS, *sim.SANITIZE_FLAGS, str(src), "-o", str(exe)],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    r = subprocess.run([str(exe)], capture_output=True, text=True, timeout=60)
    assert r.returncode != 0 and r.stdout == "", (r.returncode, r.stdout)
    assert "runtime error" in r.stderr and "outside the range of representable values" \
        in r.stderr, r.stderr
    assert runner.SANITIZER_REPORT.search(r.stderr)
    r = subprocess.run([str(exe), "12.0"], capture_output=True, text=True, timeout=60)
    assert (r.returncode, r.stdout, r.stderr) == (0, "12\n", "")
    if _is_gcc(cc):                # the blind spot this flag closes
        old = tmp_path / "cast_old"
        p = subprocess.run([cc, *sim.CFLAGS, "-fsanitize=undefined,address",
                            "-fno-sanitize-recover=all", str(src), "-o", str(old)],
                           capture_output=True, text=True)
        assert p.returncode == 0, p.stderr
        r = subprocess.run([str(old)], capture_output=True, text=True, timeout=60)
        assert r.returncode == 0 and "runtime error" not in r.stderr, r.stderr


def test_real_to_int_out_of_range_is_defined_under_the_sanitizers(tmp_path):
    """REAL/LREAL -> integer of huge values, Inf and NaN, and REAL division by
    zero, are defined in IEC code (saturation, 0 for NaN, IEEE Inf; see
    kmod_templates/runtime/iec_real.h): the sanitized simulator reports
    nothing and gives the documented values."""
    src = tmp_path / "bigconv.st"
    src.write_text("""PROGRAM bigconv
VAR
    big : ARRAY[0..3] OF LREAL := [1.0E300, -1.0E300, 3.0E38, -3.0E38];
    zero : LREAL;
    rzero : REAL;
    i : INT;
    d : DINT;
    l : LINT;
    u : UDINT;
    t : DINT;
    n : INT := 5;
    inf : REAL;
    ok : BOOL;
END_VAR
    i := LREAL_TO_INT(big[0]);
    d := LREAL_TO_DINT(big[1]);
    l := REAL_TO_LINT(LREAL_TO_REAL(big[2]));
    u := LREAL_TO_UDINT(big[3]);
    t := LREAL_TRUNC_DINT(big[0]);
    n := LREAL_TO_INT(zero / zero);
    inf := 1.0 / rzero;
    ok := inf > 3.0E38 AND REAL_TO_DINT(inf) = 2147483647;
END_PROGRAM
""")
    case = runner.Case(src, "bigconv", "bigconv")
    cfg = tmp_path / "config.st"
    cfg.write_text(runner.wrapper_config("bigconv", [case]))
    project = runner.check_project([src, cfg])
    names = ["i", "d", "l", "u", "t", "n", "ok"]
    res = sim.run(project, 0, watch=[f"bigconv.{v}" for v in names], sanitize=True,
                  build_dir=runner.build_root() / "sim")
    assert not runner.SANITIZER_REPORT.search(res.stderr or ""), res.stderr[:4000]
    assert not res.faults, res.faults
    got = res.values_at()
    assert [got[f"bigconv.{v}"] for v in names] == \
        [32767, -2147483648, 9223372036854775807, 0, 2147483647, 0, True], got
