"""The user-space provider in the I/O map (iec2kmod/iomap.py, issue 26):
``DEVICE fb : user INPUTS n OUTPUTS m STALE ms|OFF`` and ``%IW4 : fb.1``
bindings, each error at file:line:col; the generator's rule that one task
exchanges a user device.  Project: tests/unit/iomap/plant.st."""

import subprocess
import sys
from pathlib import Path

import pytest

from test_iomap import assert_one_error_at, diags_of

pytestmark = pytest.mark.unit
ROOT = Path(__file__).resolve().parents[2]
HEAD = "RESOURCE Station\nDEVICE fb : user INPUTS 4 OUTPUTS 3 STALE 250\n"




def test_a_user_device_binds_32_bit_slots(tmp_path):
    res, errors = diags_of(tmp_path, HEAD + "%IX0.0 : fb.0\n%IW4 : fb.1\n%ID8 : fb.2\n"
                           "%ID12 : fb.3\n%QX0.0 : fb.0 SAFE TRUE\n%QW2 : fb.1 SAFE HOLD\n"
                           "%QD4 : fb.2 SAFE -2.5\n")
    assert res.ok, [d.format() for d in errors]
    io = res.project.configurations[0].io["STATION"]
    got = {b.address: (b.device, b.subdevice, b.channel, b.kind, b.type, b.safe)
           for b in io.bindings}
    assert got == {
        "%IX0.0": ("fb", None, 0, "USER", "BOOL", None),
        "%IW4": ("fb", None, 1, "USER", "INT", None),
        "%ID8": ("fb", None, 2, "USER", "REAL", None),
        "%ID12": ("fb", None, 3, "USER", "DINT", None),
        "%QX0.0": ("fb", None, 0, "USER", "BOOL", 1),
        "%QW2": ("fb", None, 1, "USER", "WORD", "HOLD"),
        "%QD4": ("fb", None, 2, "USER", "REAL", -2.5)}
    assert io.manifest()["devices"] == [
        {"name": "fb", "provider": "user", "board": None, "minor": 0,
         "node": "/dev/iec_io_plant_station_fb", "inputs": 4, "outputs": 3, "stale_ms": 250}]


def test_stale_defaults_and_off(tmp_path):
    for decl, stale in (("INPUTS 1", 1000), ("OUTPUTS 2 STALE OFF", 0),
                        ("stale 5 inputs 1", 5)):
        res, errors = diags_of(tmp_path, f"RESOURCE Station\nDEVICE fb : user {decl}\n")
        assert res.ok, [d.format() for d in errors]
        assert res.project.configurations[0].io["STATION"].devices["FB"].stale_ms == stale


# (lines after HEAD, message fragment, line, column)
ERRORS = [
    ("DEVICE g : user\n", "a user device needs slots: INPUTS n and/or OUTPUTS n", 3, 16),
    ("DEVICE g : user INPUTS 2000\n", "2000 inputs: a user device has at most 1024", 3, 24),
    ("DEVICE g : user INPUTS 1 INPUTS 2\n", "INPUTS is given twice", 3, 26),
    ("DEVICE g : user INPUTS 1 STALE 0\n", "STALE 0: 1 to 3600000 ms, or OFF", 3, 32),
    ("DEVICE g : user INPUTS 1 STALE SOON\n", "a staleness timeout in ms, or OFF", 3, 32),
    ("DEVICE g : user INPUTS 1 MINOR 2\n", "a user device has no minor", 3, 26),
    ("DEVICE g : user INPUTS 1 FAST\n", "unexpected 'FAST'", 3, 26),
    ("DEVICE fb : user INPUTS 1\n", "device 'fb' is already declared", 3, 8),
    ("SUBDEVICE fb.0 : DI 8\n", "device 'fb' is a user device", 3, 11),
    ("%IW4 : fb.4\n", "input slot 4 is out of range: user device 'fb' has 4 input slots (0..3)",
     3, 11),
    ("%QW2 : fb.3\n", "output slot 3 is out of range", 3, 11),
    ("%IW4 : fb.0.1\n", "expected device.slot (a number) for user device 'fb'", 3, 8),
    ("%QW2 : fb.0 RANGE 1\n", "RANGE applies to analog comedi channels only", 3, 19),
    ("%QW2 : fb.0 SAFE 70000\n", "safe value 70000 does not fit WORD (0..65535)", 3, 18),
    ("%QW2 : fb.0 SAFE TRUE\n", "safe value TRUE of a WORD output: a number or HOLD", 3, 18),
    ("%QX0.0 : fb.0 SAFE 3\n", "TRUE, FALSE or HOLD", 3, 20),
    ("%IW4 : fb.1 SAFE 1\n", "an input has no safe state", 3, 18),
    ("%QW2 : fb.0\n%QB9 : fb.0\n", "output slot fb.0 is already driven", 4, 11),
    ("%IW4 : fb.1\n%IW4 : fb.2\n", "%IW4 is already bound", 4, 1),
]


@pytest.mark.parametrize("text,message,line,col", ERRORS, ids=[e[1][:40] for e in ERRORS])
def test_each_error_is_located(tmp_path, text, message, line, col):
    res, errors = diags_of(tmp_path, HEAD + text)
    assert_one_error_at(tmp_path, res, errors, message, line, col)


def test_a_64_bit_variable_does_not_fit_a_slot(tmp_path):
    st = tmp_path / "big.st"
    st.write_text("PROGRAM P\n  VAR_EXTERNAL big : LINT; END_VAR\n  big := big + 1;\n"
                  "END_PROGRAM\nCONFIGURATION C\n  RESOURCE R ON CPU0\n"
                  "    VAR_GLOBAL big AT %QL0 : LINT; END_VAR\n"
                  "    TASK t (INTERVAL := T#10ms, PRIORITY := 1);\n"
                  "    PROGRAM p WITH t : P;\n  END_RESOURCE\nEND_CONFIGURATION\n")
    res, errors = diags_of(tmp_path, "DEVICE fb : user OUTPUTS 1\n%QL0 : fb.0\n", st)
    assert [(d.line, d.col) for d in errors] == [(2, 1)], [d.format() for d in errors]
    assert "%QL0 is LINT: a user slot carries 32 bits" in errors[0].message


TWO_TASKS = """PROGRAM A
  VAR_EXTERNAL x : INT; END_VAR
  x := x + 1;
END_PROGRAM
PROGRAM B
  VAR_EXTERNAL y : INT; END_VAR
  y := y + 1;
END_PROGRAM
CONFIGURATION C
  RESOURCE R ON CPU0
    VAR_GLOBAL x AT %QW0 : INT; y AT %QW2 : INT; END_VAR
    TASK t1 (INTERVAL := T#10ms, PRIORITY := 1);
    TASK t2 (INTERVAL := T#20ms, PRIORITY := 2);
    PROGRAM a WITH t1 : A;
    PROGRAM b WITH t2 : B;
  END_RESOURCE
END_CONFIGURATION
"""


def test_one_task_exchanges_a_user_device(tmp_path):
    (tmp_path / "two.st").write_text(TWO_TASKS)
    m = tmp_path / "two.iomap"
    m.write_text("DEVICE fb : user OUTPUTS 2\n%QW0 : fb.0\n%QW2 : fb.1\n")
    p = subprocess.run([sys.executable, "-m", "iec2kmod", "gen", str(tmp_path), "-o",
                        str(tmp_path / "out")], cwd=ROOT, capture_output=True, text=True,
                       timeout=300)
    assert p.returncode != 0
    assert f"{m}:3:1: user device 'fb' is exchanged by task t1 (%QW0, {m}:2:1) and task t2 " \
           "(%QW2): a user device serves one task" in p.stderr, p.stderr
    assert "Traceback" not in p.stderr
    # one device per task: accepted
    m.write_text("DEVICE f1 : user OUTPUTS 1\nDEVICE f2 : user OUTPUTS 1\n"
                 "%QW0 : f1.0\n%QW2 : f2.0\n")
    p = subprocess.run([sys.executable, "-m", "iec2kmod", "gen", str(tmp_path), "-o",
                        str(tmp_path / "out")], cwd=ROOT, capture_output=True, text=True,
                       timeout=300)
    assert p.returncode == 0, p.stderr
    main = next((tmp_path / "out").glob("iec_c_r_r/main.c")).read_text()
    assert '.node = "iec_io_c_r_f1"' in main and '.node = "iec_io_c_r_f2"' in main
    assert ".interval_ns = 10000000LL" in main and ".interval_ns = 20000000LL" in main
