"""Located variables in programs (issue 25): the address is a second name of
its variable in the simulator and the interpreter (inputs trace, --watch),
in the generated manifest (plc-manager), and each address has one variable.
The kernel side is tests/qemu/test_located_programs.py; the behaviour with
names, tests/conformance/valid/realcode/openplc_located.st."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from iec2kmod.parse import frontend
from iec2kmod.located import name_index

pytestmark = pytest.mark.unit
ROOT = Path(__file__).resolve().parents[2]
PROJECT = ROOT / "tests" / "conformance" / "valid" / "realcode" / "openplc_located.st"


def run(*args):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    p = subprocess.run([sys.executable, "-m", "iec2kmod.cli", *args], env=env,
                       capture_output=True, text=True, timeout=600)
    return p.returncode, p.stdout, p.stderr


def test_every_address_names_its_variable():
    res = frontend.run([str(PROJECT)], use_cache=False)
    assert res.ok, [d.format() for d in res.diags.items]
    assert res.project.configurations[0].addresses == {
        "%QX3.0": "alarm", "%IX0.0": "Res0.instance0.Start", "%IX0.1": "Res0.instance0.Stop",
        "%IW2": "Res0.instance0.Level", "%QX0.0": "Res0.instance0.Valve",
        "%QW2": "Res0.instance0.Setpoint", "%MW2": "Res0.instance0.Count",
        "%QX1.0": "Res0.instance0.p1.motor", "%QX1.1": "Res0.instance0.p2.motor"}


@pytest.mark.parametrize("engine", ["c", "vm"])
def test_sim_takes_addresses_in_the_trace_and_the_watch_list(tmp_path, engine):
    trace = tmp_path / "in.csv"
    trace.write_text("time,variable,value\n0,%IX0.0,TRUE\n0,%IW2,40\n"
                     "40ms,%IW2,120\n60ms,%IX0.1,TRUE\n")
    out = tmp_path / "out.csv"
    code, stdout, err = run("sim", "--engine", engine, "--cycles", "4", str(PROJECT),
                            "--inputs", str(trace), "--csv", str(out),
                            "--watch", "%QX0.0,%QW2,Res0.instance0.Valve,%QX3.0,%QX1.0,%MW2")
    assert code == 0, err
    rows = out.read_text().splitlines()
    # an address and the name of its variable are one column, under the name
    assert rows[0] == ("time_ns,Res0.instance0.Valve,Res0.instance0.Setpoint,alarm,"
                       "Res0.instance0.p1.motor,Res0.instance0.Count")
    assert rows[1:] == ["0,TRUE,80,FALSE,TRUE,6", "20000000,TRUE,80,FALSE,TRUE,7",
                        "40000000,FALSE,240,TRUE,TRUE,8", "60000000,FALSE,240,TRUE,FALSE,9"]


def test_the_manifest_lists_the_addresses(tmp_path):
    code, _, err = run("gen", str(PROJECT), "-o", str(tmp_path / "t"))
    assert code == 0, err
    m = json.loads((tmp_path / "t" / "manifest.json").read_text())
    paths = {v["path"] for v in m["variables"]}
    assert m["addresses"]["%IW2"] == "Res0.instance0.Level"
    assert set(m["addresses"].values()) <= paths
    assert not any(p.startswith("%") for p in paths)        # no second table entry


def test_an_unknown_address_is_refused_like_an_unknown_name(tmp_path):
    trace = tmp_path / "in.csv"
    trace.write_text("0,%IW40,1\n")
    code, _, err = run("sim", "--cycles", "1", str(PROJECT), "--inputs", str(trace))
    assert code == 2 and "unknown variable '%IW40'" in err, err


def test_name_index_keeps_a_connection_address_its_own_entry():
    class E:
        def __init__(self, path):
            self.path = path
    table = [E("a"), E("%QW2"), E("r.p.x")]
    got = name_index(table, {"%QW2": "r.p.x", "%IX0.0": "r.p.x", "%MW0": "missing"})
    assert got == {"A": 0, "%QW2": 1, "R.P.X": 2, "%IX0.0": 2}


GUARD = """PROGRAM Guard
VAR
    Stop AT %IX0.1 : BOOL;
    Valve AT %QX0.0 : BOOL;
    Seen AT %MX1.0 : BOOL;
END_VAR
    Valve := NOT Stop;
    Seen := Seen OR Stop;
END_PROGRAM
CONFIGURATION C
    RESOURCE R ON PLC
        TASK t (INTERVAL := T#20ms, PRIORITY := 0);
        PROGRAM g WITH t : Guard;
    END_RESOURCE
END_CONFIGURATION
"""


@pytest.mark.parametrize("engine", ["z3", "explicit"])
def test_verify_takes_a_programs_located_input_as_free(tmp_path, engine):
    """A program's %I variable is an input of every cycle (as a located %I
    global is), not a constant at its initial value: 'R.g.Valve' is violated
    by Stop = TRUE; %Q and %M ones are state."""
    f = tmp_path / "guard.st"
    f.write_text(GUARD)
    code, out, err = run("verify", "--engine", engine, "--depth", "3", "--cex-dir",
                         str(tmp_path), str(f), "-p", "R.g.Valve", "-p",
                         "R.g.Valve = NOT R.g.Stop")
    assert code == 3, out + err                  # EXIT_VIOLATED
    lines = [ln.split() for ln in out.splitlines() if ln.strip().startswith("property")]
    assert [ln[:3] for ln in lines] == [["property", "1", "violated"],
                                        ["property", "2", "proved"]], out
