"""Generates a large, realistic IEC 61131-3 project for the benchmarks:
function blocks mixing ST statements, standard functions and timers, one IL
function block in four, programs that use them, and a configuration.

    python3 benchmarks/gen_project.py [LINES] > project.st   (default 10000)
    python3 benchmarks/gen_project.py --smoke    (CI: small ones, checked)"""

from __future__ import annotations

import sys


def fb_st(k: int) -> str:
    return f"""FUNCTION_BLOCK FB{k}
VAR_INPUT a, b : INT; enable : BOOL; END_VAR
VAR_OUTPUT y : INT; q : BOOL; END_VAR
VAR i, acc : INT; t : TON; arr : ARRAY[0..9] OF INT; r : REAL; END_VAR
  t(IN := enable, PT := T#100ms);
  acc := 0;
  FOR i := 0 TO 9 DO
    arr[i] := a * i + b - (i MOD 3);
    acc := acc + arr[i];
  END_FOR;
  IF acc > 100 AND enable OR NOT t.Q THEN
    y := acc / 2;
  ELSIF acc < -100 THEN
    y := -acc;
  ELSE
    y := LIMIT(0, acc, 50);
  END_IF;
  CASE y OF
    0: q := FALSE;
    1..10: q := TRUE;
  ELSE
    q := enable XOR q;
  END_CASE;
  WHILE i > 0 DO
    i := i - 1;
  END_WHILE;
  REPEAT
    i := i + 1;
  UNTIL i >= 3 END_REPEAT;
  r := INT_TO_REAL(y) * 1.5 + SQRT(ABS(INT_TO_REAL(a)));
  y := y + ABS(a - b) * 2 + REAL_TO_INT(r);
  q := (a > b) = (b < a);
  acc := acc + 1;
  acc := acc + 2;
  acc := acc + 3;
  y := MAX(acc, y);
END_FUNCTION_BLOCK

"""


def fb_il(k: int) -> str:
    return f"""FUNCTION_BLOCK FB{k}
VAR_INPUT a, b : INT; enable : BOOL; END_VAR
VAR_OUTPUT y : INT; q : BOOL; END_VAR
VAR acc : INT; t : TON; END_VAR
    CAL t(IN := enable, PT := T#50ms)
    LD a
    ADD b
    MUL 3
    ST acc
    LD acc
    GT 100
    JMPC big
    LD acc
    SUB( b
    MUL 2
    )
    ST y
    JMP done
big:
    LD 100
    ST y
done:
    LD enable
    AND t.Q
    OR( a
    GT b
    )
    ST q
    LD y
    LIMIT 0, 1000
    ST y
    LD acc
    ADD 1
    ST acc
    LD q
    XOR enable
    ST q
    LD acc
    SUB 1
    ST acc
    LD a
    ST y
    LD b
    ADD y
    ST y
END_FUNCTION_BLOCK

"""


def program(k: int, nfb: int) -> str:
    calls = "\n".join(
        f"  f{j}(a := in{j % 4}, b := {j}, enable := run);\n  out := out + f{j}.y;"
        for j in range(8))
    decls = " ".join(f"f{j} : FB{(k * 8 + j) % nfb};" for j in range(8))
    return f"""PROGRAM P{k}
VAR_EXTERNAL run : BOOL; in0, in1, in2, in3 : INT; END_VAR
VAR out : INT; {decls} END_VAR
  out := 0;
{calls}
END_PROGRAM

"""


def project(lines: int) -> str:
    parts = []
    n = 0
    k = 0
    while n < lines * 0.85:
        part = fb_il(k) if k % 4 == 3 else fb_st(k)
        parts.append(part)
        n += part.count("\n")
        k += 1
    nfb = k
    progs = []
    p = 0
    while n < lines - 40:
        part = program(p, nfb)
        progs.append(part)
        n += part.count("\n")
        p += 1
    insts = "\n".join(f"    PROGRAM i{j} WITH t{j % 2} : P{j};" for j in range(p))
    config = f"""CONFIGURATION Bench
  VAR_GLOBAL
    run : BOOL := TRUE;
    in0, in1, in2, in3 : INT;
  END_VAR
  RESOURCE r0 ON CPU0
    TASK t0 (INTERVAL := T#1ms, PRIORITY := 0);
    TASK t1 (INTERVAL := T#10ms, PRIORITY := 1);
{insts}
  END_RESOURCE
END_CONFIGURATION
"""
    return "".join(parts + progs) + config


def dense_pou(lines: int = 10000) -> str:
    """One PROGRAM of about ``lines`` lines, expression-dense (issue 14):
    every line an assignment with three or four operators, every third one
    an IF around one."""
    out = ["PROGRAM Dense",
           "VAR a, b, c, d, e : DINT; x, y : DINT; k : INT; f : BOOL; END_VAR"]
    i = 0
    while len(out) < lines - 1:
        if i % 3 == 2:
            out.append(f"    IF a > {i} AND b < c + {i % 7} THEN x := x + (a - {i}) * 2; "
                       f"END_IF;")
        else:
            out.append(f"    {'abcde'[i % 5]} := (a + b * {i % 13 + 1}) - (c - d) / {i % 5 + 1}"
                       f" + e MOD {i % 9 + 2};")
        i += 1
    out.append("END_PROGRAM")
    return "\n".join(out) + "\n"


def smoke(text: str, what: str) -> int:
    """--smoke: the generated project (small) passes `iec2kmod check`."""
    import subprocess
    import tempfile
    import time
    from pathlib import Path
    root = Path(__file__).resolve().parents[1]
    with tempfile.TemporaryDirectory() as tmp:
        src = Path(tmp) / "project.st"
        src.write_text(text)
        t0 = time.monotonic()
        p = subprocess.run([sys.executable, "-m", "iec2kmod", "check", "--no-cache", str(src)],
                           cwd=root, capture_output=True, text=True)
        dt = time.monotonic() - t0
    print(f"{what}: {text.count(chr(10))} lines; iec2kmod check: exit {p.returncode} in "
          f"{dt:.2f} s")
    if p.returncode != 0:
        print(p.stdout + p.stderr, file=sys.stderr)
    return p.returncode


if __name__ == "__main__":
    if sys.argv[1:] == ["--smoke"]:       # CI: an 800-line project and a dense POU, checked
        sys.exit(smoke(project(800), "project") or smoke(dense_pou(200), "dense POU"))
    sys.stdout.write(project(int(sys.argv[1]) if len(sys.argv) > 1 else 10000))
