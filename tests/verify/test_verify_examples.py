"""The examples' safety properties ({verify} pragmas in their sources) are
proved; deliberately broken variants (tests/verify/broken/) are caught, and
each counterexample replays in `iec2kmod sim --inputs` (the compiled C
engine): the property is FALSE, or the runtime error happens, in the cycle
the verifier names."""

from __future__ import annotations

import csv
import re
from pathlib import Path

import pytest

try:
    import z3  # noqa: F401
except ImportError:
    z3 = None

from iec2kmod import cli

ROOT = Path(__file__).resolve().parents[2]
BROKEN = Path(__file__).resolve().parent / "broken"


@pytest.fixture(autouse=True)
def _need_z3():
    if z3 is None:
        pytest.fail("z3-solver is not installed: pip install z3-solver (scripts/setup.sh)")


def _pragmas(d):
    n = 0
    for f in Path(d).iterdir():
        if f.suffix in (".st", ".il"):
            n += len(re.findall(r"\{verify\b", f.read_text(), re.I))
    return n


@pytest.mark.parametrize("example", ["traffic_light", "motor_il", "conveyor_counter",
                                     "packaging_il_st", "tank_level", "elevator", "hvac",
                                     "two_resources", "pid_loop", "watchdog_event",
                                     "alarm_handler", "batch_mixer"])
def test_example_properties_proved(example, capsys, tmp_path):
    d = ROOT / "examples" / example
    n = _pragmas(d)
    assert n >= 3, f"{example} has {n} {{verify}} pragmas"
    rc = cli.main(["verify", str(d), "--cex-dir", str(tmp_path)])
    out = capsys.readouterr()
    assert rc == 0, out.out + out.err
    assert out.out.count("proved (induction") == n + 1, out.out     # + no runtime error


@pytest.mark.parametrize("example, props, construct", [
    # the trip depends on the alarm texts (FIND): a property reading it,
    # not proved with FIND free
    ("alarm_handler", ["plc.annunciator.compressor_permit OR NOT alarms[1].latched"],
     "the string function FIND"),
])
def test_examples_outside_the_encoding_are_refused(example, props, construct, capsys):
    args = ["verify", str(ROOT / "examples" / example)]
    for p in props:
        args += ["--property", p]
    rc = cli.main(args)
    err = capsys.readouterr().err
    assert rc == 1
    assert f"error: verify: {construct}" in err and "cannot be encoded" in err, err
    assert "Traceback" not in err


def _values_at(rows, head, t_ns):
    """The watched values after the cycle at t_ns (the CSV lists changes)."""
    cur = {}
    for row in rows:
        if int(row[0]) > t_ns:
            break
        for name, v in zip(head[1:], row[1:]):
            if v != "":
                cur[name] = v
    return cur


BROKEN_CASES = {
    # name: (property, cycle, watched paths, check of the values after that cycle)
    "star_delta_no_interlock": ("plc.pump1.star_delta_interlock", 6, ["%QX0.1", "%QX0.2"],
                                lambda v: v["%QX0.1"] == "TRUE" and v["%QX0.2"] == "TRUE"),
    "crossing_latched_green": ("plc.crossing.no_conflicting_greens", 8, ["%QX0.2", "%QX0.5"],
                               lambda v: v["%QX0.2"] == "TRUE" and v["%QX0.5"] == "TRUE"),
    "conveyor_slot_index": ("no runtime error", 1, ["plc.line1.boxes_on_belt"], None),
}


@pytest.mark.parametrize("name", sorted(BROKEN_CASES))
def test_broken_variant_caught_and_replayed(name, capsys, tmp_path):
    prop, cycle, watch, check = BROKEN_CASES[name]
    proj = BROKEN / name
    rc = cli.main(["verify", str(proj), "--cex-dir", str(tmp_path)])
    out = capsys.readouterr().out
    assert rc == 3, out
    line = next(ln for ln in out.splitlines() if ln.strip().startswith(prop))
    assert f"violated at cycle {cycle}" in line, out
    stem = "cex_" + re.sub(r"[^A-Za-z0-9_]+", "_", prop).strip("_")
    trace = tmp_path / f"{stem}.csv"
    assert (tmp_path / f"{stem}.vcd").stat().st_size > 0
    sim_csv = tmp_path / "sim.csv"
    rc = cli.main(["sim", str(proj), "--inputs", str(trace), "--cycles", str(cycle),
                   "--watch", ",".join(watch), "--csv", str(sim_csv)])
    err = capsys.readouterr().err
    period = {"star_delta_no_interlock": 10, "crossing_latched_green": 50,
              "conveyor_slot_index": 5}[name] * 1_000_000
    if check is None:           # a runtime error in that very cycle
        assert rc == 1 and "runtime error: array index out of range" in err, err
        assert f"t={(cycle - 1) * period / 1e9:.6f} s" in err, err
        return
    assert rc == 0, err
    with open(sim_csv) as fh:
        rows = list(csv.reader(fh))
    head, rows = rows[0], rows[1:]
    before = _values_at(rows, head, (cycle - 2) * period)
    after = _values_at(rows, head, (cycle - 1) * period)
    assert check(after), (after, rows)
    assert cycle == 1 or not check(before), before      # not already violated a cycle earlier
