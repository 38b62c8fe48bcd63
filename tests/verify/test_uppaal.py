"""`iec2kmod export --uppaal`: the model parses with pyuppaal, its queries
are the properties, and random input traces replayed through the exported
automata (uppaal_net.py) give, after every scan, the values the simulator
gives (the reference interpreter, `sim --engine interp`)."""

from __future__ import annotations

import random
from pathlib import Path

import pytest

try:
    import pyuppaal  # noqa: F401
except ImportError:
    pyuppaal = None
try:
    import z3  # noqa: F401
except ImportError:
    z3 = None

from iec2kmod import cli

ROOT = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent


@pytest.fixture(autouse=True)
def _need_tools():
    if pyuppaal is None:
        pytest.fail("pyuppaal is not installed: pip install pyuppaal (scripts/setup.sh)")
    if z3 is None:
        pytest.fail("z3-solver is not installed: pip install z3-solver (scripts/setup.sh)")


def export(capsys, proj, out):
    rc = cli.main(["export", "--uppaal", str(proj), "-o", str(out)])
    cap = capsys.readouterr()
    return rc, cap.out, cap.err


CASES = {
    "traffic_light": (ROOT / "examples" / "traffic_light", 4, {"TON", "Task"}),
    "crossing_short_phases": (HERE / "broken" / "crossing_latched_green", 4, {"TON", "Task"}),
    "press_il": (HERE / "diff" / "press.il", 2, {"TON", "TP", "Task"}),
    "eno_read": (HERE / "diff" / "eno_uppaal.st", 1, {"TON", "Task"}),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_export_parses_and_replays(case, capsys, tmp_path):
    from pyuppaal import UModel
    import shutil
    import uppaal_net
    from iec2kmod.parse.frontend import run
    from iec2kmod.interp import run as vm_run
    from iec2kmod.interp.machine import Machine
    from iec2kmod.verify.uppaal import Exporter, ident

    proj, queries, templates = CASES[case]
    out = tmp_path / "model.xml"
    rc, text, err = export(capsys, proj, out)
    assert rc == 0, err
    copy = tmp_path / "parsed.xml"
    shutil.copy(out, copy)
    m = UModel(str(copy))
    assert {t.name for t in m.templates} == templates
    assert len(m.queries) == queries
    assert all(q.startswith("A[] (Task.wait imply (") for q in m.queries)

    # random inputs, the same trace for the interpreter and the network
    project = run([str(proj)], use_cache=False).project
    ex = Exporter(project)
    period = ex.sym.period
    leaves = [ex.sym.by_name[n] for n in ex.input_names]
    rnd = random.Random(case)
    scans = 120
    rows = ["time,variable,value"]
    per_scan = []
    held = {}
    for k in range(scans):
        vals = {}
        for leaf in leaves:
            t = leaf.type
            # inputs hold their value for a while (so that timers expire)
            if leaf.name in held and rnd.random() < 0.85:
                v = held[leaf.name]
            elif getattr(t, "name", "") == "BOOL":
                v = rnd.random() < 0.6
            else:
                v = rnd.randint(-20, 250)
            held[leaf.name] = v
            text = ("TRUE" if v else "FALSE") if isinstance(v, bool) else str(v)
            rows.append(f"{k * period}ns,{leaf.name},{text}")
            vals[ident(leaf.name)] = v
        per_scan.append(vals)
    trace = tmp_path / "trace.csv"
    trace.write_text("\n".join(rows) + "\n")

    net = uppaal_net.Network(out)
    machine = Machine(project)
    table = machine.table()
    watch = [e.path for e in table if ident(e.path) in net.env]
    assert len(watch) >= 10
    res = vm_run(project, (scans - 1) * period, watch=watch, inputs=str(trace),
                 machine=machine)
    assert not res.faults
    by_time = {}
    for t, i, v in res.changes:
        by_time.setdefault(t, []).append((i, v))
    current = {}
    compared = 0
    for k in range(scans):
        net.scan(per_scan[k])
        for i, v in by_time.get(k * period, []):
            current[res.names[i]] = v
        for path in watch:
            want = current[path]
            entry = next(e for e in table if e.path == path)
            got = net.env[ident(path)]
            if entry.kind == "e":
                got = next(name for name, val in entry.type.values.values() if val == got)
            elif entry.kind == "t":
                got = got * 1_000_000
            elif entry.kind == "b":
                got = bool(got)
            assert got == want, f"scan {k + 1}: {path} is {got} in the network, {want} in sim"
            compared += 1
    assert compared >= 10 * scans
    # the timers' automata were exercised: some Q was TRUE at some scan
    assert any(v is True for path, v in _all_changes(res) if path.endswith(".Q")), case


def _all_changes(res):
    return [(res.names[i], v) for _, i, v in res.changes]


def test_export_refuses_what_it_cannot_model(capsys, tmp_path):
    rc, out, err = export(capsys, ROOT / "examples" / "motor_il", tmp_path / "m.xml")
    assert rc == 1
    assert "error: export:" in err and "DINT cannot be exported to UPPAAL exactly" in err, err
    assert not (tmp_path / "m.xml").exists()
    rc, out, err = export(capsys, ROOT / "examples" / "pid_loop", tmp_path / "p.xml")
    assert rc == 1 and "a second task" in err, err


def test_export_refuses_rtc_by_name(capsys, tmp_path):
    # RTC reads the kernel's wall clock: no automaton models it
    src = tmp_path / "r.st"
    src.write_text("PROGRAM P\nVAR c : RTC; x : BOOL; END_VAR\n"
                   "c(IN := x, PDT := DT#2024-01-01-00:00:00);\nEND_PROGRAM\n"
                   "CONFIGURATION C RESOURCE R ON CPU0 TASK t(INTERVAL := T#10ms, PRIORITY := 1);"
                   " PROGRAM p WITH t : P; END_RESOURCE END_CONFIGURATION\n")
    rc, out, err = export(capsys, src, tmp_path / "r.xml")
    assert rc == 1, err
    assert "r.st:2:5: error: export: 'c' holds an RTC instance (it reads the real-time clock" \
        in err, err
    assert "Traceback" not in err and not (tmp_path / "r.xml").exists()


def test_export_refuses_a_negated_integer_store(capsys, tmp_path):
    # STN of a bit string is a bitwise NOT; UPPAAL's ! is logical (it wrote
    # b = !cr0, so b was 0 or 1): refused as LDN and NOT of an integer are
    src = tmp_path / "s.il"
    src.write_text("PROGRAM P\nVAR a : BYTE; b : BYTE; END_VAR\nLD a\nSTN b\nEND_PROGRAM\n"
                   "CONFIGURATION C RESOURCE R ON CPU0 TASK t(INTERVAL := T#10ms, PRIORITY := 1);"
                   " PROGRAM p WITH t : P; END_RESOURCE END_CONFIGURATION\n")
    rc, out, err = export(capsys, src, tmp_path / "s.xml")
    assert rc == 1, out + err
    assert "s.il:4:1: error: export: STN of an integer cannot be exported to UPPAAL exactly" \
        in err, err
    assert not (tmp_path / "s.xml").exists()
