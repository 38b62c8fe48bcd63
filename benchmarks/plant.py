# SPDX-License-Identifier: MIT
"""A plant-sized configuration (issue 14): program types with a TON, a FOR
loop and DINT arithmetic, many instances over two resources and 16
periodic tasks (1-8 ms), a block of plain INT globals and three connected
globals per instance (two inputs, one output).

    python benchmarks/plant.py [INSTANCES] > plant.st     (default 1000)
    python benchmarks/plant.py --smoke       (CI: 20 instances, checked)
"""

from __future__ import annotations

import sys

TYPES = 10
RESOURCES = 2
TASKS_PER_RESOURCE = 8          # INTERVAL 1..8 ms
PLAIN_GLOBALS = 10_000


def program(k: int, algo: int = 0) -> str:
    return f"""PROGRAM P{k}
VAR_INPUT a, b : INT; END_VAR
VAR_OUTPUT y : INT; END_VAR
VAR n, acc : DINT; i : INT; t : TON; END_VAR
    n := n + 1;
    acc := INT_TO_DINT(a) * {k + 2} - INT_TO_DINT(b);
    FOR i := 1 TO 4 DO
        acc := acc + (n MOD INT_TO_DINT(i + {k + 1})) * 3;
    END_FOR;
    t(IN := NOT t.Q, PT := T#{10 + k}ms);
    IF t.Q THEN acc := acc + 1; END_IF;
    y := DINT_TO_INT(acc MOD 30000 + {algo});
END_PROGRAM

"""


def project(instances: int = 1000, types: int = TYPES, plain: int = PLAIN_GLOBALS,
            algo: dict | None = None) -> str:
    """The configuration's text; algo maps a type number to a constant that
    changes its algorithm (not its interface) for a swap."""
    algo = algo or {}
    out = [program(k, algo.get(k, 0)) for k in range(types)]
    out.append("CONFIGURATION Plant\n    VAR_GLOBAL\n")
    for n in range(0, plain, 10):
        out.append("        " + ", ".join(f"g{m}" for m in range(n, min(n + 10, plain)))
                   + " : INT;\n")
    for n in range(instances):
        out.append(f"        c{n}a, c{n}b, c{n}y : INT;\n")
    out.append("    END_VAR\n")
    per = -(-instances // RESOURCES)
    for r in range(RESOURCES):
        out.append(f"    RESOURCE r{r} ON board\n")
        for t in range(TASKS_PER_RESOURCE):
            out.append(f"        TASK t{t + 1} (INTERVAL := T#{t + 1}ms, PRIORITY := {t + 1});\n")
        for n in range(r * per, min((r + 1) * per, instances)):
            out.append(f"        PROGRAM i{n} WITH t{n % TASKS_PER_RESOURCE + 1} : "
                       f"P{n % types} (a := c{n}a, b := c{n}b, y => c{n}y);\n")
        out.append("    END_RESOURCE\n")
    out.append("END_CONFIGURATION\n")
    return "".join(out)


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
    if sys.argv[1:] == ["--smoke"]:       # CI: 20 instances, checked
        sys.exit(smoke(project(20), "plant of 20 instances"))
    sys.stdout.write(project(int(sys.argv[1]) if len(sys.argv) > 1 else 1000))
