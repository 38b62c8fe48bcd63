"""Sweeps: every conversion of every convertible type on edge values, and
every integer/bit/REAL/string operation on the extreme values of its type,
each result in its own variable, run in the C simulator and in the
reference interpreter: the values must be identical (floats within
test_vm_vs_c.ULP_TOLERANCE for the transcendental functions)."""

from __future__ import annotations

import pytest

import runner
from iec2kmod import interp, sim
from iec2kmod.checks import stdlib
from test_ub_sweep import BITS, REALS, SIGNED, STRINGS, UNSIGNED, _extremes, _lit
from test_vm_vs_c import first_difference

pytestmark = pytest.mark.execution

CONFIG = ("CONFIGURATION C\n  RESOURCE R ON PLC\n    TASK T (INTERVAL := T#10ms, PRIORITY := 1);\n"
          "    PROGRAM p WITH T : Sweep;\n  END_RESOURCE\nEND_CONFIGURATION\n")


def conversions_source() -> str:
    T = stdlib.CONVERTIBLE
    VALUES = {
     "BOOL": ["TRUE", "FALSE"],
     "SINT": ["SINT#-128", "SINT#127", "SINT#-1"], "INT": ["INT#-32768", "INT#300", "INT#-1"],
     "DINT": ["DINT#-2147483648", "DINT#100000", "DINT#-1"], "LINT": ["LINT#-9223372036854775808", "LINT#9223372036854775807", "LINT#-86400001"],
     "USINT": ["USINT#255", "USINT#99"], "UINT": ["UINT#65535", "UINT#1234"], "UDINT": ["UDINT#4294967295", "UDINT#16777217"],
     "ULINT": ["ULINT#18446744073709551615", "ULINT#9007199254740993"],
     "REAL": ["REAL#2.5", "REAL#-2.5", "REAL#1.0E10", "REAL#-0.0", "REAL#3.4E38", "REAL#0.1", "REAL#1.5E-7", "REAL#16777217.0"],
     "LREAL": ["LREAL#-3.5", "LREAL#1.0E300", "LREAL#0.1", "LREAL#123456789012345678.0", "LREAL#-1.0E-20", "LREAL#4294967295.5"],
     "BYTE": ["BYTE#16#FF", "BYTE#16#99", "BYTE#16#9A"], "WORD": ["WORD#16#FFFF", "WORD#16#1234"], "DWORD": ["DWORD#16#80000000"], "LWORD": ["LWORD#16#FFFFFFFFFFFFFFFF", "LWORD#16#0000000099999999"],
     "TIME": ["T#-1.5ms", "T#1d2h3m4s5ms6us7ns", "T#0s", "T#-106751d"], "LTIME": ["LTIME#1ms5ns", "LTIME#-3s"],
     "DATE": ["D#2024-02-29", "D#1969-12-31"], "TOD": ["TOD#23:59:59.999", "TOD#00:00:00.5"], "DT": ["DT#2024-02-29-13:45:01.5", "DT#1969-12-31-23:59:59"],
     "STRING": ["' 16#FF '", "'-3'", "'abc'", "'1.5E3'", "'T#1s'", "'TRUE'", "'  -2_000 '", "'99999999999999999999'", "'D#2024-01-31'", "'TOD#12:00:00'", "'DT#2024-01-31-01:02:03'", "'2.5'", "'8#17'", "'1_000.5'", "'NaN'", "'-Inf'", "''"],
     "WSTRING": ["\"42\"", "\"x$20ACy\"", "\"TRUE\""],
    }
    decls, body = [], []
    n = 0
    for s in T:
        for d in T:
            if s == d: continue
            name = f"{s}_TO_{d}"
            if stdlib.conversion(name) is None: continue
            dt = "STRING" if d == "STRING" else d
            for v in VALUES[s]:
                decls.append(f"  r{n} : {dt};")
                body.append(f"  r{n} := {name}({v});")
                n += 1
    for s in ("REAL", "LREAL"):
        for d in ("SINT", "INT", "DINT", "LINT", "USINT", "UINT", "UDINT", "ULINT"):
            for v in VALUES[s]:
                decls.append(f"  r{n} : {d};"); body.append(f"  r{n} := {s}_TRUNC_{d}({v});"); n += 1
    for name, src, dst in (("BYTE_BCD_TO_USINT","BYTE","USINT"),("WORD_BCD_TO_UINT","WORD","UINT"),("LWORD_BCD_TO_ULINT","LWORD","ULINT"),("USINT_TO_BCD_BYTE","USINT","BYTE"),("UDINT_TO_BCD_DWORD","UDINT","DWORD"),("ULINT_TO_BCD_LWORD","ULINT","LWORD")):
        for v in VALUES[src]:
            decls.append(f"  r{n} : {dst};"); body.append(f"  r{n} := {name}({v});"); n += 1
    return ("PROGRAM Sweep\nVAR\n" + "\n".join(decls) + "\nEND_VAR\n" + "\n".join(body) +
            "\nEND_PROGRAM\n" + CONFIG)


def operations_source() -> str:
    decl, body = [], []
    ints = list(SIGNED) + list(UNSIGNED)
    decl += ["    i, j, n, k : INT;", "    zero : LREAL;"]
    for t in ints + list(BITS):
        vals = _extremes(t)
        m = len(vals)
        decl.append(f"    v_{t} : ARRAY[0..{m-1}] OF {t} := [{', '.join(_lit(t, v) for v in vals)}];")
        ops = ["+", "-", "*", "/", "MOD"] if t in ints else ["AND", "OR", "XOR"]
        for o, name in zip(ops, ["add", "sub", "mul", "div", "mod"] if t in ints else ["and", "or", "xor"]):
            decl.append(f"    {name}_{t} : ARRAY[0..{m*m-1}] OF {t};")
        decl.append(f"    cmp_{t} : ARRAY[0..{m*m-1}] OF BOOL;")
        decl.append(f"    un_{t} : ARRAY[0..{2*m-1}] OF {t};")
        body += [f"  FOR i := 0 TO {m-1} DO", f"    FOR j := 0 TO {m-1} DO", f"      k := i * {m} + j;"]
        for o, name in zip(ops, ["add", "sub", "mul", "div", "mod"] if t in ints else ["and", "or", "xor"]):
            if o in ("/", "MOD"):
                body.append(f"      IF v_{t}[j] <> 0 THEN {name}_{t}[k] := v_{t}[i] {o} v_{t}[j]; END_IF;")
            else:
                body.append(f"      {name}_{t}[k] := v_{t}[i] {o} v_{t}[j];")
        body.append(f"      cmp_{t}[k] := v_{t}[i] < v_{t}[j] XOR v_{t}[i] >= v_{t}[j] AND v_{t}[i] <> v_{t}[j];")
        body += ["    END_FOR;"]
        if t in SIGNED:
            body.append(f"    un_{t}[i] := -v_{t}[i];")
        if t in ints:
            body.append(f"    un_{t}[i + {m}] := ABS(v_{t}[i]);")
        else:
            body.append(f"    un_{t}[i] := NOT v_{t}[i];")
            decl.append(f"    sh_{t} : ARRAY[0..{m*4*15-1}] OF {t};")
            body += ["    FOR n := 0 TO 14 DO", "      k := (i * 15 + n) * 4;",
                     f"      sh_{t}[k] := SHL(v_{t}[i], n * 5 - 3);", f"      sh_{t}[k + 1] := SHR(v_{t}[i], n * 5 - 3);",
                     f"      sh_{t}[k + 2] := ROL(v_{t}[i], n * 5 - 3);", f"      sh_{t}[k + 3] := ROR(v_{t}[i], n * 5 - 3);",
                     "    END_FOR;"]
        body.append("  END_FOR;")
    nr = len(REALS) + 2
    decl.append(f"    v_R : ARRAY[0..{nr-1}] OF LREAL := [{', '.join(REALS)}];")
    decl.append(f"    v_f : ARRAY[0..{nr-1}] OF REAL;")
    fns = ("SQRT", "LN", "LOG", "EXP", "SIN", "COS", "TAN", "ASIN", "ACOS", "ATAN")
    for fn in fns:
        decl.append(f"    f_{fn} : ARRAY[0..{nr-1}] OF LREAL;")
        decl.append(f"    g_{fn} : ARRAY[0..{nr-1}] OF REAL;")
    decl += [f"    rar : ARRAY[0..{nr*nr-1}] OF REAL;", f"    lar : ARRAY[0..{nr*nr-1}] OF LREAL;",
             f"    ex : ARRAY[0..{nr*nr-1}] OF LREAL;", f"    mx : ARRAY[0..{nr*nr-1}] OF LREAL;",
             f"    tm : ARRAY[0..{nr-1}] OF TIME;", f"    ex3 : ARRAY[0..{nr-1}] OF LREAL;", f"    at2 : ARRAY[0..{nr-1}] OF LREAL;"]
    body += [f"  v_R[{nr-2}] := zero / zero;", f"  v_R[{nr-1}] := 1.0 / zero;",
             f"  FOR i := 0 TO {nr-1} DO", "    v_f[i] := LREAL_TO_REAL(v_R[i]);"]
    for fn in fns:
        body += [f"    f_{fn}[i] := {fn}(v_R[i]);", f"    g_{fn}[i] := {fn}(v_f[i]);"]
    body += ["    ex3[i] := EXPT(v_R[i], 3);", "    at2[i] := ATAN2(v_R[i], -1.0);",
             "    tm[i] := MUL_TIME(T#1d, v_R[i] / 1.0E10);",
             f"    FOR j := 0 TO {nr-1} DO", f"      k := i * {nr} + j;",
             "      rar[k] := v_f[i] * v_f[j] + v_f[i] / v_f[j];",
             "      lar[k] := v_R[i] - v_R[j] * 3.0;",
             "      ex[k] := EXPT(v_R[i], v_R[j]);",
             "      mx[k] := LIMIT(v_R[j], MAX(v_R[i], 0.5), MIN(v_R[i], 10.0));",
             "    END_FOR;", "  END_FOR;"]
    ns = len(STRINGS)
    decl.append(f"    v_S : ARRAY[0..{ns-1}] OF STRING[40] := [{', '.join(STRINGS)}];")
    decl += [f"    s_out : ARRAY[0..{ns*ns*2-1}] OF STRING[30];", f"    s_num : ARRAY[0..{ns*ns-1}] OF INT;",
             f"    s_cmp : ARRAY[0..{ns*ns-1}] OF BOOL;"]
    body += [f"  FOR i := 0 TO {ns-1} DO", f"    FOR j := 0 TO {ns-1} DO", f"      k := i * {ns} + j;",
             "      s_out[2 * k] := CONCAT(v_S[i], v_S[j], 'x');",
             "      s_out[2 * k + 1] := REPLACE(INSERT(v_S[i], v_S[j], j - 2), 'ab', i - 3, j - 5);",
             "      s_num[k] := FIND(v_S[i], MID(v_S[j], 3, i - 2)) + LEN(DELETE(v_S[i], j, i - 4));",
             "      s_cmp[k] := v_S[i] < v_S[j] OR LEFT(v_S[i], j) = RIGHT(v_S[j], i);",
             "    END_FOR;", "  END_FOR;"]
    return ("PROGRAM Sweep\nVAR\n" + "\n".join(decl) + "\nEND_VAR\n" + "\n".join(body) +
            "\nEND_PROGRAM\n" + CONFIG)


@pytest.mark.parametrize("name,source", [("conversions", conversions_source),
                                         ("operations", operations_source)])
def test_sweep_same_in_c_and_vm(name, source, tmp_path):
    f = tmp_path / f"{name}.st"
    f.write_text(source())
    project = runner.check_project([f])
    table = interp.Machine(project).table()
    watch = [e.path for e in table]
    assert len(watch) > 1000
    c_res = sim.run(project, 0, watch=watch, build_dir=runner.build_root() / "sim")
    vm_res = interp.run(project, 0, watch=watch)
    assert not c_res.faults and not vm_res.faults
    diff = first_difference(c_res, vm_res)
    assert diff is None, diff
