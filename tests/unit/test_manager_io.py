"""plc-manager and bound I/O (issue 26, manager/io.py): the device check
`load` makes before inserting anything (/dev/comedi<minor>, /proc/comedi),
and the I/O section of `status` (the manifest's bindings, kept in the small
state file at load, with the last samples of the kernel's iec_io file).
The kernel side is tests/qemu/test_io_manager.py."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from plc_manager import io, netlink
from plc_manager.cli import status_json, status_text
from plc_manager.errors import PLCError
from plc_manager.project import Project, State

pytestmark = pytest.mark.unit
ROOT = Path(__file__).resolve().parents[2]
TANK_IO = ROOT / "examples" / "tank_io"

PROC = """comedi version 0.7.76
format string: "%2d: %-20s %-20s %4d", i, driver_name, board_name, n_subdevices
 0: comedi_test          comedi_test             2
 3: comedi_parport       comedi_parport          4
comedi_test:
 comedi_test
"""


@pytest.fixture(scope="module")
def tank(tmp_path_factory):
    out = tmp_path_factory.mktemp("tank") / "t"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    p = subprocess.run([sys.executable, "-m", "iec2kmod", "gen", str(TANK_IO), "-o", str(out)],
                       env=env, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    return Project.open(out)


def _devs(tmp_path, minors=(0,), proc=PROC):
    d = tmp_path / "dev"
    d.mkdir()
    for n in minors:           # a character device: /dev/null under the name
        (d / f"comedi{n}").symlink_to("/dev/null")
    (tmp_path / "proc_comedi").write_text(proc)
    return str(d), str(tmp_path / "proc_comedi")


def _check(m, tmp_path, **kw):
    dev, proc = _devs(tmp_path, **kw)
    return io.check_devices(m, dev_dir=dev, proc_comedi=proc)


def test_load_checks_the_devices_of_the_io_map(tank, tmp_path):
    assert _check(tank.m, tmp_path) == 1


def test_a_missing_device_is_refused_naming_it(tank, tmp_path):
    with pytest.raises(PLCError) as e:
        _check(tank.m, tmp_path, minors=())
    assert str(e.value) == (f"resource Tank: device daq ({tmp_path}/dev/comedi0, comedi_test) "
                            "is missing: load its comedi driver first (modprobe comedi_test); "
                            "nothing inserted")


def test_an_unattached_minor_is_refused(tank, tmp_path):
    with pytest.raises(PLCError, match=r"device daq \(.*/comedi0, comedi_test\) has no board "
                                       r"attached"):
        _check(tank.m, tmp_path, proc=PROC.replace(" 0: comedi_test", " 5: comedi_test"))


def test_another_board_is_refused(tank, tmp_path):
    with pytest.raises(PLCError, match=r"device daq .* is a comedi_parport \(driver "
                                       r"comedi_parport\), not a comedi_test"):
        _check(tank.m, tmp_path,
               proc=PROC.replace(" 0: comedi_test          comedi_test             2",
                                 " 0: comedi_parport       comedi_parport          4"))


def test_too_few_subdevices_are_refused(tank, tmp_path):
    with pytest.raises(PLCError, match=r"has 1 subdevices, the I/O map uses subdevice 1"):
        _check(tank.m, tmp_path, proc=PROC.replace("comedi_test             2",
                                                   "comedi_test             1"))


def test_comedi_not_loaded_is_refused(tank, tmp_path):
    dev, _ = _devs(tmp_path)
    with pytest.raises(PLCError, match=r"cannot be read \(is comedi loaded\?\)"):
        io.check_devices(tank.m, dev_dir=dev, proc_comedi=str(tmp_path / "none"))


def test_a_project_without_io_checks_nothing(tmp_path):
    assert io.check_devices({"io": {}}) == 0 and io.check_devices({}) == 0


def _status():
    t = netlink.Task(name="cycle", resource="tank", state="stopped", interval_ns=100_000_000,
                     priority=1, last_cpu=0, cycles=10, overruns=0, faults=0,
                     exec_min_ns=1000, exec_avg_ns=2000, exec_max_ns=3000,
                     latency_avg_ns=100, latency_max_ns=200, histogram=[])
    return netlink.Status(abi=1, configuration="Plant", module="iec_plant_config",
                          source_hash="s", interface_hash="i", now_ns=0, forced=0,
                          resources=[netlink.Resource("tank", "iec_plant_r_tank", 0, [t])],
                          slots=[])


def test_status_shows_the_bindings_and_their_last_values(tank, tmp_path, monkeypatch):
    monkeypatch.setenv("PLC_MANAGER_STATE_DIR", str(tmp_path / "state"))
    s = State.create(tank)
    s.data.update(source_hash="s", interface_hash="i")
    s.save()
    sysfs = tmp_path / "sys"
    (sysfs / "module" / "iec_plant_r_tank").mkdir(parents=True)
    (sysfs / "module" / "iec_plant_r_tank" / "iec_io").write_text(
        "%ID0 daq.0.0 45875\n%ID4 daq.0.1 -\n%QD0 daq.1.0 45875\n%QD4 daq.1.1 32768\n")
    monkeypatch.setattr(io, "SYSFS", str(sysfs))
    text = status_text(_status())
    lines = {ln.split()[1]: ln.split() for ln in text.splitlines()
             if ln.startswith("Tank ")}
    # raw 45875 of -10..10 V: -10 + 45875 * 20 / 65535 = 4.00015 V (6 digits)
    assert lines["%ID0"] == ["Tank", "%ID0", "Tank.level", "daq.0.0", "in", "-", "45875",
                             "4.00015", "V"], text
    assert lines["%ID4"] == ["Tank", "%ID4", "Tank.valve_fb", "daq.0.1", "in", "-", "-", "-"]
    assert lines["%QD0"][4:] == ["out", "hold", "45875", "4.00015", "V"]
    assert lines["%QD4"][2:] == ["Tank.valve", "daq.1.1", "out", "0", "V", "32768",
                                 "0.00015259", "V"], text
    js = status_json(_status())["io"]
    assert [(b["address"], b["last"], b["where"]) for b in js] == [
        ("%ID0", 45875, "daq.0.0"), ("%ID4", None, "daq.0.1"), ("%QD0", 45875, "daq.1.0"),
        ("%QD4", 32768, "daq.1.1")]


def test_status_without_saved_state_shows_no_io(tmp_path, monkeypatch):
    monkeypatch.setenv("PLC_MANAGER_STATE_DIR", str(tmp_path / "none"))
    assert "I/O" not in status_text(_status())
    assert status_json(_status())["io"] == []


def test_user_slots_in_status_and_the_device_check():
    """A user device's bindings have no subdevice (iomap: device.slot): the
    load's device check skips them (no comedi device to look for) and status
    shows slot and value by the variable's type (the 32 bits of iec_io_user.c).
    Both raised TypeError (int(None)) before."""
    m = {"addresses": {"%ID0": "rig.x", "%QD0": "rig.y"},
         "resources": [{"name": "BENCH", "module": "iec_rig_r_bench"}],
         "io": {"BENCH": {"devices": [{"name": "fb", "provider": "user"}],
                          "bindings": [
                              {"address": "%ID0", "device": "fb", "subdevice": None,
                               "channel": 0, "kind": "USER", "type": "DINT", "scale": "word",
                               "safe": None},
                              {"address": "%QD0", "device": "fb", "subdevice": None,
                               "channel": 1, "kind": "USER", "type": "REAL", "scale": "word",
                               "safe": 1.5}]}}}
    assert io.check_devices(m) == 0
    dint, real = io.bindings(io.summary(m), sysroot="/nonexistent")
    assert (dint.where, dint.safe_text, real.where, real.safe_text) == \
        ("fb.0", "-", "fb.1", "1.5")
    dint.last, real.last = 0xFFFFFFFE, 0x3FC00000
    assert (dint.value, real.value) == ("-2", "1.5")


PARPORT = ROOT / "tests" / "qemu" / "projects" / "io_parport"


def test_status_shows_the_interrupts_and_their_counts(tmp_path, monkeypatch):
    """projects/io_parport: resource Events binds no channel, only the
    INTERRUPT that wakes task onack.  status lists it (address, variable,
    device.source, IRQ, the task it wakes, the count from the kernel's
    iec_io file) in text and JSON; without the kernel's line the count is
    unknown.  Before, status showed no interrupt at all."""
    out = tmp_path / "t"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    p = subprocess.run([sys.executable, "-m", "iec2kmod", "gen", str(PARPORT), "-o", str(out)],
                       env=env, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    monkeypatch.setenv("PLC_MANAGER_STATE_DIR", str(tmp_path / "state"))
    s = State.create(Project.open(out))
    s.data.update(source_hash="s", interface_hash="i")
    s.save()
    sysfs = tmp_path / "sys"
    for mod in ("iec_crossing_r_events", "iec_crossing_r_lights"):
        (sysfs / "module" / mod).mkdir(parents=True)
    (sysfs / "module" / "iec_crossing_r_events" / "iec_io").write_text(
        "irq %IX9.0 lpt.ACK 7 205\n")
    (sysfs / "module" / "iec_crossing_r_lights" / "iec_io").write_text(
        "%QX0.0 lpt.0.0 1\n")
    monkeypatch.setattr(io, "SYSFS", str(sysfs))
    st = _status()
    st.configuration, st.module = "Crossing", "iec_crossing_config"
    text = status_text(st)
    head = "interrupts (COUNT: taken since the load; /sys/module/<module>/iec_io):"
    assert head in text, text
    rows = text.split(head, 1)[1].splitlines()[1:4]
    assert rows[0].split() == ["RESOURCE", "ADDRESS", "VARIABLE", "SOURCE", "IRQ", "WAKES",
                               "COUNT"], text
    assert rows[1].split() == ["Events", "%IX9.0", "Events.ack", "lpt.ACK", "7", "onack",
                               "205"], text
    assert rows[2].strip() == "", text       # one source; the binding table is apart
    # the interrupt line is not a binding: Lights' table is unchanged
    assert [ln.split()[:2] for ln in text.splitlines() if ln.startswith("Lights ")][0] == \
        ["Lights", "%QX0.0"], text
    assert status_json(st)["interrupts"] == [
        {"resource": "Events", "module": "iec_crossing_r_events", "address": "%IX9.0",
         "variable": "Events.ack", "device": "lpt", "source": "ACK", "irq": 7,
         "tasks": ["onack"], "count": 205, "where": "lpt.ACK"}]
    # a module that shows no count (older, or gone): the source, count "-"
    (sysfs / "module" / "iec_crossing_r_events" / "iec_io").write_text("")
    rows = [ln for ln in status_text(st).splitlines() if ln.startswith("Events ")]
    assert len(rows) == 1 and rows[0].split()[-2:] == ["onack", "-"], rows
    assert status_json(st)["interrupts"][0]["count"] is None
