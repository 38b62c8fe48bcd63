"""The I/O map (iec2kmod/iomap.py, issue 26): a .iomap file binds located
addresses of a resource to device channels; `check` reports every wrong
binding as file:line:col with the line and a caret.  Project:
tests/unit/iomap/plant.st (resource Station, located globals of each kind)
and its valid map plant.iomap."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from iec2kmod.parse import frontend

pytestmark = pytest.mark.unit
ROOT = Path(__file__).resolve().parents[2]
HERE = ROOT / "tests" / "unit" / "iomap"
PLANT = HERE / "plant.st"
HEAD = "RESOURCE Station\nDEVICE daq : comedi comedi_test MINOR 0\n" \
       "DEVICE pp : comedi comedi_parport MINOR 1\n"


def diags_of(tmp_path, text, source=PLANT):
    """Check *source* with *text* as its t.iomap: (result, the errors)."""
    m = tmp_path / "t.iomap"
    m.write_text(text)
    res = frontend.run([str(source), str(m)], use_cache=False)
    return res, [d for d in res.diags.items if d.severity == "error"]


def assert_one_error_at(tmp_path, res, errors, message, line, col):
    """The map was refused with one error, holding *message*, at t.iomap
    line:col (test_iomap_user and test_iomap_irq use it too)."""
    assert not res.ok
    assert len(errors) == 1, [d.format() for d in errors]
    d = errors[0]
    assert message in d.message, d.format()
    assert (d.path, d.line, d.col) == (str(tmp_path / "t.iomap"), line, col), d.format()
    return d


def test_the_valid_map_binds_every_kind():
    res = frontend.run([str(PLANT), str(HERE / "plant.iomap")], use_cache=False)
    assert res.ok, [d.format() for d in res.diags.items]
    io = res.project.configurations[0].io["STATION"]
    got = {b.address: (b.device, b.subdevice, b.channel, b.kind, b.scale, b.safe)
           for b in io.bindings}
    assert got == {
        "%IX0.0": ("pp", 1, 0, "DI", "bit", None),
        "%IW2": ("daq", 0, 0, "AI", "raw", None),
        "%ID8": ("daq", 0, 1, "AI", "phys", None),
        "%QX0.0": ("pp", 0, 3, "DIO", "bit", "HOLD"),
        "%QW2": ("daq", 1, 0, "AO", "raw", 32768),
        "%QD4": ("daq", 1, 1, "AO", "phys", -2.5)}
    phys = next(b for b in io.bindings if b.address == "%ID8")
    assert (phys.lo, phys.hi, phys.range) == (-5.0, 5.0, 1)
    assert [d.name for d in io.devices.values()] == ["daq", "pp"]


def test_a_directory_brings_its_map(tmp_path):
    (tmp_path / "plant.st").write_text(PLANT.read_text())
    (tmp_path / "plant.iomap").write_text(HEAD + "%IW2 : daq.0.9\n")
    res = frontend.run([str(tmp_path)], use_cache=False)
    assert [(d.line, d.col) for d in res.diags.errors] == [(4, 14)]


# (binding lines after HEAD, message fragment, line, column)
ERRORS = [
    # unknown device / provider / board
    ("%IW2 : card.0.0\n", "unknown device 'card'", 4, 8),
    ("DEVICE x : modbus MINOR 3\n", "unknown provider 'modbus'", 4, 12),
    ("DEVICE x : comedi ni_pcimio MINOR 3\n", "unknown board 'ni_pcimio'", 4, 19),
    ("DEVICE daq : comedi comedi_test MINOR 4\n", "device 'daq' is already declared", 4, 8),
    ("DEVICE y : comedi comedi_test MINOR 0\n", "already declared as 'daq'", 4, 8),
    ("DEVICE y : comedi MINOR 16\n", "minor 16 is out of range", 4, 25),
    ("SUBDEVICE daq.3 : DI 8\n", "whose subdevices are known", 4, 11),
    # channel / subdevice out of range
    ("%IW2 : daq.0.8\n", "channel 8 is out of range: subdevice daq.0 (AI) has channels 0..7",
     4, 14),
    ("%IX0.0 : pp.1.5\n", "channel 5 is out of range", 4, 15),
    ("%IW2 : daq.7.0\n", "device 'daq' has no subdevice 7", 4, 12),
    ("%ID8 : daq.0.1 RANGE 2\n", "range 2 is out of range", 4, 22),
    # width or type that does not fit the address
    ("%IW4 : daq.0.0\n", "%IW4 is INT, up to 32767", 4, 1),
    ("%QB9 : daq.1.0\n", "%QB9 is BYTE (8 bits); channel daq.1.0 gives 16-bit samples", 4, 1),
    ("%IX0.0 : daq.0.0\n", "%IX0.0 is a bit (BOOL); channel daq.0.0 is analog", 4, 1),
    ("%IW2 : pp.1.0\n", "one digital line: bind a bit address", 4, 1),
    ("%IW2 : daq.1.0\n", "%IW2 is an input; subdevice daq.1 is AO", 4, 12),
    ("%QW2 : daq.0.0\n", "%QW2 is an output; subdevice daq.0 is AI", 4, 12),
    ("%IX0.0 : pp.1.0 RANGE 0\n", "RANGE applies to analog channels only", 4, 23),
    ("%QW2 : daq.1.0 SAFE 70000\n", "safe value 70000 does not fit", 4, 21),
    ("%QD4 : daq.1.1 SAFE 11.5\n", "outside the channel's range -10..10", 4, 21),
    ("%QX0.0 : pp.0.0 SAFE 2\n", "TRUE, FALSE or HOLD", 4, 22),
    ("%IW2 : daq.0.0 SAFE 0\n", "an input has no safe state", 4, 21),
    # one address bound twice
    ("%IW2 : daq.0.0\n%IW2 : daq.0.1\n", "%IW2 is already bound (", 5, 1),
    ("%IW2 : daq.0.0\n%iw2 : daq.0.1\n", "%IW2 is already bound (", 5, 1),
    # addresses the map cannot bind
    ("%IW6 : daq.0.0\n", "no located variable at %IW6", 4, 1),
    ("%MW0 : daq.0.0\n", "%MW0 is memory", 4, 1),
    ("%IX7.0 : pp.1.0\n", "%IX7.0 is used by resource Other, not by Station", 4, 1),
    # syntax
    ("%IW2 daq.0.0\n", "expected ':' and device.subdevice.channel, found 'daq.0.0'", 4, 6),
    ("%IW2 : daq.0\n", "expected device.subdevice.channel (numbers)", 4, 8),
    ("%IW2 : daq.0.0 FAST\n", "unexpected 'FAST'", 4, 16),
    ("WIRE %IW2\n", "expected RESOURCE, DEVICE, SUBDEVICE, INTERRUPT or an address", 4, 1),
    ("RESOURCE Nowhere\n", "unknown resource 'Nowhere'", 4, 10),
]


@pytest.mark.parametrize("text,message,line,col", ERRORS,
                         ids=[e[1][:40] for e in ERRORS])
def test_each_error_is_located(tmp_path, text, message, line, col):
    res, errors = diags_of(tmp_path, HEAD + text)
    d = assert_one_error_at(tmp_path, res, errors, message, line, col)
    assert d.source_line == (HEAD + text).split("\n")[line - 1]


def test_two_resources_need_a_resource_line(tmp_path):
    res, errors = diags_of(tmp_path, "DEVICE daq : comedi comedi_test\n")
    assert [(d.line, d.col) for d in errors] == [(1, 1)]
    assert "which resource: the configuration has 2" in errors[0].message


def test_a_declared_board_checks_like_a_known_one(tmp_path):
    text = ("RESOURCE Station\nDEVICE card : comedi MINOR 2\n"
            "SUBDEVICE card.0 : AI 16 BITS 12 RANGE -10..10, 0..5\n"
            "SUBDEVICE card.2 : DIO 24\n"
            "%IW2 : card.0.15\n%ID8 : card.0.0 RANGE 1\n%QX0.0 : card.2.23 SAFE TRUE\n")
    res, errors = diags_of(tmp_path, text)
    assert res.ok, [d.format() for d in errors]
    b = {x.address: x for x in res.project.configurations[0].io["STATION"].bindings}
    assert (b["%IW2"].bits, b["%ID8"].lo, b["%ID8"].hi, b["%QX0.0"].safe) == (12, 0.0, 5.0, 1)
    res, errors = diags_of(tmp_path, text.replace("card.0.15", "card.0.16"))
    assert [(d.line, d.col) for d in errors] == [(5, 15)]
    res, errors = diags_of(tmp_path, text + "SUBDEVICE card.0 : DI 8\n")
    assert "subdevice card.0 is already declared" in errors[0].message
    res, errors = diags_of(tmp_path, text.replace("RANGE -10..10", "RANGE 10..-10"))
    assert "lo must be below hi" in errors[0].message


def test_check_prints_the_line_and_a_caret(tmp_path):
    m = tmp_path / "plant.iomap"
    m.write_text(HEAD + "%IW2   : daq.0.12\n")
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    p = subprocess.run([sys.executable, "-m", "iec2kmod", "check", "--no-cache", str(PLANT),
                        str(m)], env=env, capture_output=True, text=True, timeout=120)
    assert p.returncode == 1
    assert p.stderr.splitlines()[:3] == [
        f"{m}:4:16: error: channel 12 is out of range: subdevice daq.0 (AI) has channels 0..7",
        "%IW2   : daq.0.12",
        "               ^"], p.stderr
    assert "Traceback" not in p.stderr


def test_a_map_alone_is_not_a_project(tmp_path):
    m = tmp_path / "plant.iomap"
    m.write_text(HEAD)
    with pytest.raises(frontend.InputError, match="no source files"):
        frontend.collect_files([str(m)])
