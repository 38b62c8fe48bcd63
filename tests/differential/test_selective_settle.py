"""Differential tier, aimed at rule 8 of selective execution
(iec2kmod/codegen/selective.py: a type proved idempotent settles after one
evaluation; otherwise its confirm comparison is narrowed to what z3 proves
enough).  The general campaign (test_fuzz_diff.py) rarely reaches the rule:
most of its bodies have loops, which the rule refuses.  Here every project
holds loop-free function blocks built at random from what the rule must
judge -- combinational logic, seal-ins, SR/RS, R_TRIG/F_TRIG, CTU, state
read before it is written, a counter, a division that may fault, read-only
externals and in-outs -- each instantiated twice, driven by globals that
change now and then.  Plain and selective runs must give identical traces
(every variable of the table, faults included); the projects together must
contain types of both kinds (idempotent, narrowed), and blocks must have
been skipped.

Widen: IEC2KMOD_SETTLE_COUNT=40 python3 -m pytest tests/differential/test_selective_settle.py"""

from __future__ import annotations

import os
import random

import pytest

from iec2kmod import sim
from iec2kmod.parse import frontend
from iec2kmod.compilation import Compilation
from iec2kmod.compilation import selective_plan

pytestmark = pytest.mark.execution

COUNT = int(os.environ.get("IEC2KMOD_SETTLE_COUNT", "8"))
SEED = 20261126
TYPES = 8
CYCLES = 200
MS = 1_000_000

BOOLS = ["a", "b", "x", "y", "h"]
STD = {"t": "R_TRIG", "f": "F_TRIG", "l": "SR", "r": "RS", "c": "CTU"}


def _bexpr(rnd, d, env):
    if d <= 0 or rnd.random() < 0.35:
        pool = BOOLS + ["t.Q", "f.Q", "l.Q1", "r.Q1", "c.Q", "n > 2", "k > m"]
        if env["ext"]:
            pool.append("gx")
        if env["io"]:
            pool.append("io")
        return rnd.choice(pool)
    k = rnd.random()
    if k < 0.2:
        return f"NOT ({_bexpr(rnd, d - 1, env)})"
    op = "AND" if k < 0.6 else "OR"
    return f"({_bexpr(rnd, d - 1, env)} {op} {_bexpr(rnd, d - 1, env)})"


def _iexpr(rnd, env):
    pool = ["n", "k", "m", "n + 1", "k + n", "MAX(k, n)", "c.CV", "LIMIT(0, k + 1, 5)"]
    if env["ext"]:
        pool.append("gk")
    return rnd.choice(pool)


def _stmt(rnd, d, env):
    k = rnd.random()
    if k < 0.3:
        return f"{rnd.choice(['x', 'y', 'h'])} := {_bexpr(rnd, 2, env)};"
    if k < 0.42:
        return f"{rnd.choice(['k', 'm'])} := {_iexpr(rnd, env)};"
    if k < 0.62 and d > 0:
        els = f" ELSE {_stmt(rnd, d - 1, env)}" if rnd.random() < 0.6 else ""
        return f"IF {_bexpr(rnd, 2, env)} THEN {_stmt(rnd, d - 1, env)}{els} END_IF;"
    if k < 0.85:
        inst = rnd.choice(list(STD))
        if inst in ("t", "f"):
            return f"{inst}(CLK := {_bexpr(rnd, 1, env)});"
        if inst == "l":
            return f"l(S1 := {_bexpr(rnd, 1, env)}, R := {_bexpr(rnd, 1, env)});"
        if inst == "r":
            return f"r(S := {_bexpr(rnd, 1, env)}, R1 := {_bexpr(rnd, 1, env)});"
        return f"c(CU := {_bexpr(rnd, 1, env)}, R := {_bexpr(rnd, 1, env)}, PV := 3);"
    if k < 0.93:
        return f"IF {_bexpr(rnd, 1, env)} THEN k := k + 1; END_IF;"
    if k < 0.96:
        # may fault (n is 0 now and then): faults must come at the same cycle
        return f"IF {_bexpr(rnd, 1, env)} AND h THEN m := 100 / n; END_IF;"
    return f"x := x XOR {_bexpr(rnd, 1, env)};"


def _project(seed):
    rnd = random.Random(seed)
    pous, decls, calls = [], [], []
    for i in range(TYPES):
        env = {"ext": rnd.random() < 0.4, "io": rnd.random() < 0.3}
        body = "\n".join("    " + _stmt(rnd, 2, env) for _ in range(rnd.randint(2, 7)))
        ext = "VAR_EXTERNAL gx : BOOL; gk : INT; END_VAR\n" if env["ext"] else ""
        io = "VAR_IN_OUT io : BOOL; END_VAR\n" if env["io"] else ""
        pous.append(f"FUNCTION_BLOCK F{i}\nVAR_INPUT a, b : BOOL; n : INT; END_VAR\n"
                    f"VAR_OUTPUT x, y : BOOL; k : INT; END_VAR\n{ext}{io}"
                    f"VAR m : INT; h : BOOL; t : R_TRIG; f : F_TRIG; l : SR; r : RS; "
                    f"c : CTU; END_VAR\n{body}\nEND_FUNCTION_BLOCK\n")
        for j in range(2):
            a, b = rnd.sample(["ga", "gb", "gc", "gx"], 2)
            n = rnd.choice(["gn", "gk"])
            decls.append(f"u{i}_{j} : F{i};")
            arg = ", io := gio" if env["io"] else ""
            calls.append(f"    u{i}_{j}(a := {a}, b := {b}, n := {n}{arg});")
            calls.append(f"    o{len(calls)} := u{i}_{j}.x OR u{i}_{j}.y;")
    outs = [c.split(" := ")[0].strip() for c in calls if c.strip().startswith("o")]
    text = "\n".join(pous) + f"""
PROGRAM Main
VAR_EXTERNAL ga, gb, gc, gx, gio : BOOL; gn, gk : INT; {', '.join(outs)} : BOOL; END_VAR
VAR {' '.join(decls)} END_VAR
{chr(10).join(calls)}
END_PROGRAM

CONFIGURATION c
VAR_GLOBAL ga, gb, gc, gx, gio : BOOL; gn, gk : INT := 1; {', '.join(outs)} : BOOL; END_VAR
RESOURCE r ON CPU0
  TASK t (INTERVAL := T#10ms, PRIORITY := 1);
  PROGRAM p WITH t : Main;
END_RESOURCE
END_CONFIGURATION
"""
    rows, t = [], 0
    while t < CYCLES * 10:
        t += 10 * rnd.randint(1, 9)
        g = rnd.choice(["ga", "gb", "gc", "gx", "gio", "gn", "gk"])
        v = rnd.randint(0, 4) if g in ("gn", "gk") else rnd.choice(["TRUE", "FALSE"])
        rows.append(f"{t}ms,{g},{v}\n")
    return text, "".join(rows)


def test_settle_rule_on_random_loop_free_blocks(tmp_path):
    kinds = {"idempotent": 0, "narrowed": 0, "full": 0}
    skipped = 0
    for i in range(COUNT):
        text, rows = _project(SEED + i)
        f = tmp_path / f"s{i}.st"
        f.write_text(text)
        res = frontend.run([str(f)], use_cache=False)
        assert res.ok, [d.format() for d in res.diags.sorted()]
        project = res.project
        plan = selective_plan(project, "all")
        for b in plan.blocks.values():
            if b.pou.kind != "FUNCTION_BLOCK":
                continue
            if b.idempotent:
                kinds["idempotent"] += 1
            elif len(b.written) < len(plan._written(b.pou)) or \
                    any("." in m for m, _ in b.written):
                kinds["narrowed"] += 1
            else:
                kinds["full"] += 1
        trace = tmp_path / f"s{i}.csv"
        trace.write_text(rows)
        watch = [e.path for e in Compilation(project).plan.table]
        end = CYCLES * 10 * MS
        a = sim.run(project, end, watch=watch, inputs=str(trace))
        b = sim.run(project, end, watch=watch, inputs=str(trace), selective="all")
        assert a.faults == b.faults, (SEED + i, a.faults, b.faults)
        if a.changes != b.changes:
            k = next((n for n, (x, y) in enumerate(zip(a.changes, b.changes)) if x != y),
                     min(len(a.changes), len(b.changes)))
            x = a.changes[k] if k < len(a.changes) else None
            y = b.changes[k] if k < len(b.changes) else None
            pytest.fail(f"seed {SEED + i}: traces differ at change {k}: plain "
                        f"{x and (x[0], a.names[x[1]], x[2])}, selective "
                        f"{y and (y[0], b.names[y[1]], y[2])}\n{text}")
        skipped += sum(sk for _, sk in b.selective.values())
    assert kinds["idempotent"] >= 3 and kinds["narrowed"] >= 3, kinds
    assert skipped > 100 * COUNT, skipped


# ------------------------------------------- targets changing under a pointer
# Issue 29: a selective-execution bug (an FB's VAR_IN_OUT target changing
# while the pointer stays) passed the campaign.  Here reader blocks take
# in-outs bound to elements of global arrays (the index -- the pointer --
# changes now and then) and read externals, and writer blocks called
# between them write through the same in-outs and into the externals in
# the same cycle: the pointer is unchanged, what it points to is not.

SHARED_COUNT = int(os.environ.get("IEC2KMOD_SHARED_COUNT", "4"))
READERS = 5


def _rexpr(rnd, d):
    if d <= 0 or rnd.random() < 0.35:
        return rnd.choice(["a", "io", "gx", "t.Q", "c.Q", "iv > 2", "gk > 3", "iv = gk", "x"])
    op = rnd.choice(["AND", "OR", "XOR"])
    return f"({_rexpr(rnd, d - 1)} {op} {_rexpr(rnd, d - 1)})"


def _reader_stmt(rnd):
    k = rnd.random()
    if k < 0.3:
        return f"x := {_rexpr(rnd, 2)};"
    if k < 0.5:
        return f"k := {rnd.choice(['iv', 'gk', 'iv + gk', 'MAX(iv, k)', 'c.CV', 'm'])};"
    if k < 0.65:
        return f"t(CLK := {_rexpr(rnd, 1)});"
    if k < 0.8:
        return f"c(CU := {_rexpr(rnd, 1)}, R := {_rexpr(rnd, 1)}, PV := 3);"
    return f"IF {_rexpr(rnd, 1)} THEN m := m + 1; END_IF;"


def _shared_project(seed):
    rnd = random.Random(seed)
    pous = []
    for i in range(READERS):
        body = "\n".join("    " + _reader_stmt(rnd) for _ in range(rnd.randint(2, 6)))
        pous.append(f"FUNCTION_BLOCK R{i}\nVAR_INPUT a : BOOL; END_VAR\n"
                    "VAR_IN_OUT io : BOOL; iv : INT; END_VAR\n"
                    "VAR_EXTERNAL gx : BOOL; gk : INT; END_VAR\n"
                    "VAR_OUTPUT x : BOOL; k : INT; END_VAR\n"
                    f"VAR m : INT; t : R_TRIG; c : CTU; END_VAR\n{body}\nEND_FUNCTION_BLOCK\n")
    pous.append("""FUNCTION_BLOCK W
VAR_INPUT s : INT; END_VAR
VAR_IN_OUT io : BOOL; iv : INT; END_VAR
VAR_EXTERNAL gx : BOOL; gk : INT; END_VAR
    IF s = 1 THEN io := NOT io;
    ELSIF s = 2 THEN iv := (iv + 1) MOD 7;
    ELSIF s = 3 THEN gx := NOT gx;
    ELSIF s = 4 THEN gk := (gk + 1) MOD 7;
    END_IF;
END_FUNCTION_BLOCK
""")
    decls, calls, outs = [], [], []
    for j in range(2 * READERS):
        i = j % READERS
        decls.append(f"r{j} : R{i};")
        b, v = rnd.choice(["gi", "gj", "1"]), rnd.choice(["gi", "gj", "0"])
        calls.append(f"    r{j}(a := {rnd.choice(['ga', 'gb'])}, io := gbs[{b}], "
                     f"iv := gvs[{v}]);")
        outs.append(f"o{j}")
        calls.append(f"    o{j} := r{j}.x; n{j} := r{j}.k;")
        if rnd.random() < 0.5:
            w = len([d for d in decls if d.startswith("w")])
            decls.append(f"w{w} : W;")
            calls.append(f"    w{w}(s := {rnd.choice(['gs', 'gt'])}, "
                         f"io := gbs[{rnd.choice(['gi', 'gj', '1'])}], "
                         f"iv := gvs[{rnd.choice(['gi', 'gj', '0'])}]);")
    ns = [f"n{j}" for j in range(2 * READERS)]
    text = "\n".join(pous) + f"""
PROGRAM Main
VAR_EXTERNAL ga, gb, gx : BOOL; gi, gj, gs, gt, gk : INT;
    gbs : ARRAY[0..2] OF BOOL; gvs : ARRAY[0..2] OF INT; END_VAR
VAR {' '.join(decls)} {', '.join(outs)} : BOOL; {', '.join(ns)} : INT; END_VAR
{chr(10).join(calls)}
END_PROGRAM

CONFIGURATION c
VAR_GLOBAL ga, gb, gx : BOOL; gi, gj, gs, gt, gk : INT;
    gbs : ARRAY[0..2] OF BOOL; gvs : ARRAY[0..2] OF INT; END_VAR
RESOURCE r ON CPU0
  TASK t (INTERVAL := T#10ms, PRIORITY := 1);
  PROGRAM p WITH t : Main;
END_RESOURCE
END_CONFIGURATION
"""
    rows, t = [], 0
    while t < CYCLES * 10:
        t += 10 * rnd.randint(1, 9)
        g = rnd.choice(["ga", "gb", "gx", "gi", "gj", "gs", "gt", "gk"])
        if g in ("gi", "gj"):
            v = rnd.randint(0, 2)
        elif g in ("gs", "gt"):
            v = rnd.choice([0, 0, 1, 2, 3, 4])
        elif g == "gk":
            v = rnd.randint(0, 6)
        else:
            v = rnd.choice(["TRUE", "FALSE"])
        rows.append(f"{t}ms,{g},{v}\n")
    return text, "".join(rows)


def test_selective_when_targets_change_under_unchanged_pointers(tmp_path):
    skipped = evaluated = 0
    for i in range(SHARED_COUNT):
        text, rows = _shared_project(SEED + 1000 + i)
        f = tmp_path / f"w{i}.st"
        f.write_text(text)
        res = frontend.run([str(f)], use_cache=False)
        assert res.ok, [d.format() for d in res.diags.sorted()]
        project = res.project
        trace = tmp_path / f"w{i}.csv"
        trace.write_text(rows)
        watch = [e.path for e in Compilation(project).plan.table]
        end = CYCLES * 10 * MS
        a = sim.run(project, end, watch=watch, inputs=str(trace))
        b = sim.run(project, end, watch=watch, inputs=str(trace), selective="all")
        assert a.faults == b.faults, (SEED + 1000 + i, a.faults, b.faults)
        if a.changes != b.changes:
            k = next((n for n, (x, y) in enumerate(zip(a.changes, b.changes)) if x != y),
                     min(len(a.changes), len(b.changes)))
            x = a.changes[k] if k < len(a.changes) else None
            y = b.changes[k] if k < len(b.changes) else None
            pytest.fail(f"seed {SEED + 1000 + i}: traces differ at change {k}: plain "
                        f"{x and (x[0], a.names[x[1]], x[2])}, selective "
                        f"{y and (y[0], b.names[y[1]], y[2])}\n{text}")
        skipped += sum(sk for _, sk in b.selective.values())
        evaluated += sum(ev for ev, _ in b.selective.values())
    # the readers must have been skipped, or nothing was tested
    assert skipped > 50 * SHARED_COUNT, (skipped, evaluated)
