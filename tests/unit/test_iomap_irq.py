"""The I/O map's INTERRUPT statement (iec2kmod/iomap.py, issue 26): an event
task's SINGLE variable, a located BOOL input, bound to an interrupt source
of a device (comedi_parport's ACK); every wrong statement is an error at
file:line:col.  Project: tests/unit/iomap/irq.st."""

import pytest

from test_iomap import assert_one_error_at, diags_of

pytestmark = pytest.mark.unit
PROJECT = __import__("pathlib").Path(__file__).resolve().parent / "iomap" / "irq.st"
HEAD = "DEVICE lpt : comedi comedi_parport MINOR 0\nDEVICE daq : comedi comedi_test MINOR 1\n"


def run(tmp_path, text):
    return diags_of(tmp_path, text, PROJECT)


def test_an_interrupt_wakes_the_tasks_of_its_single_variable(tmp_path):
    res, errors = run(tmp_path, HEAD + "INTERRUPT %IX9.0 : lpt.ack IRQ 7\n"
                                       "interrupt %ix3.0 : lpt.ACK irq 5\n")
    # one source wakes one variable's tasks: the second statement is refused
    assert [(d.line, d.col) for d in errors] == [(4, 20)], [d.format() for d in errors]
    assert "lpt.ACK already wakes the tasks of %IX9.0" in errors[0].message
    res, errors = run(tmp_path, HEAD + "INTERRUPT %IX9.0 : lpt.ack IRQ 7   # ACK\n")
    assert res.ok, [d.format() for d in errors]
    io = res.project.configurations[0].io["FAST"]
    (q,) = io.interrupts
    assert (q.address, q.device, q.source, q.irq, q.tasks) == ("%IX9.0", "lpt", "ACK", 7,
                                                                ["onack"])
    assert io.manifest()["interrupts"] == [
        {"address": "%IX9.0", "device": "lpt", "source": "ACK", "irq": 7, "tasks": ["onack"]}]
    # a configuration global's SINGLE works too
    res, errors = run(tmp_path, HEAD + "INTERRUPT %IX3.0 : lpt.ACK IRQ 7\n")
    assert res.ok and res.project.configurations[0].io["FAST"].interrupts[0].tasks == ["oncfg"]


ERRORS = [
    ("INTERRUPT %IX9.1 : lpt.ACK IRQ 7\n", "no TASK of resource Fast has SINGLE := the "
                                           "variable at %IX9.1", 3, 11),
    ("INTERRUPT %IW20 : lpt.ACK IRQ 7\n", "bind a bit input address (%IX)", 3, 11),
    ("INTERRUPT %QX1.0 : lpt.ACK IRQ 7\n", "bind a bit input address (%IX)", 3, 11),
    ("INTERRUPT %IX8.0 : lpt.ACK IRQ 7\n", "no located variable at %IX8.0", 3, 11),
    ("INTERRUPT %IX9.0 : daq.ACK IRQ 7\n", "device 'daq' (comedi_test) has no interrupt "
                                           "source 'ACK': it has no interrupt source", 3, 24),
    ("INTERRUPT %IX9.0 : lpt.BUSY IRQ 7\n", "has no interrupt source 'BUSY': its interrupt "
                                            "sources are ACK", 3, 24),
    ("INTERRUPT %IX9.0 : pp.ACK IRQ 7\n", "unknown device 'pp'", 3, 20),
    ("INTERRUPT %IX9.0 : lpt.ACK\n", "expected IRQ and the interrupt line's number, found "
                                     "the end of the line", 3, 27),
    ("INTERRUPT %IX9.0 : lpt.ACK IRQ 0\n", "IRQ 0 is out of range: 1..255", 3, 32),
    ("INTERRUPT %IX9.0 : lpt.ACK IRQ seven\n", "expected an IRQ number", 3, 32),
    ("INTERRUPT %IX9.0 : lpt.ACK IRQ 7 SHARED\n", "unexpected 'SHARED'", 3, 34),
    ("INTERRUPT ack : lpt.ACK IRQ 7\n", "expected the address of an event task's SINGLE", 3, 11),
    ("INTERRUPT %IX9.0 lpt.ACK IRQ 7\n", "expected ':' and device.SOURCE", 3, 18),
    ("%IX9.0 : lpt.1.3\nINTERRUPT %IX9.0 : lpt.ACK IRQ 7\n", "%IX9.0 is already bound (", 4, 11),
    ("INTERRUPT %IX9.0 : lpt.ACK IRQ 7\n%IX9.0 : lpt.1.3\n", "%IX9.0 is already bound (", 4, 1),
]


@pytest.mark.parametrize("text,message,line,col", ERRORS, ids=[e[1][:40] for e in ERRORS])
def test_each_error_is_located(tmp_path, text, message, line, col):
    res, errors = run(tmp_path, HEAD + text)
    assert_one_error_at(tmp_path, res, errors, message, line, col)
