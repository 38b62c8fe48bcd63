# SPDX-License-Identifier: MIT
"""plc-manager when the kernel gives up waiting for a task (ETIMEDOUT from
a stop or a slot clear: a task does not come back from its cycle within
the kernel's bound): one line naming the task and how long it has been
inside its cycle, exit 1, nothing else attempted.  The kernel side is
tests/qemu/test_bounded_waits.py."""

import errno

import pytest

from plc_manager import cli, ops
from plc_manager.errors import PLCError
from plc_manager.netlink import KernelError, Resource, Status, Task

pytestmark = pytest.mark.unit


def _task(name, resource, in_cycle_ns=None, state="running"):
    return Task(name=name, resource=resource, state=state, interval_ns=10_000_000,
                priority=5, last_cpu=1, cycles=7, overruns=0, faults=0, exec_min_ns=1,
                exec_avg_ns=1, exec_max_ns=1, latency_avg_ns=1, latency_max_ns=1,
                histogram=[], in_cycle_ns=in_cycle_ns)


def _status():
    return Status(abi=1, configuration="stuck", module="iec_stuck_config", source_hash="s",
                  interface_hash="i", now_ns=0, forced=0, slots=[],
                  resources=[Resource("rheavy", "iec_stuck_r_rheavy", 1,
                                      [_task("heavy", "rheavy", 3_456_000_000, "stopped")]),
                             Resource("rbeat", "iec_stuck_r_rbeat", 0,
                                      [_task("beat", "rbeat", 20_000)])])


class FakeClient:
    """The netlink client of a configuration whose task rheavy.heavy stays
    inside one cycle: stop and clear time out in the kernel."""

    def __init__(self):
        self.calls = []

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        pass

    def status(self):
        self.calls.append("status")
        return _status()

    def stop(self, resource=None):
        self.calls.append(f"stop {resource}")
        raise KernelError(errno.ETIMEDOUT, "a task does not come back from its cycle "
                                           "(kernel log, status: in_cycle)")

    def clear(self, slot=None):
        self.calls.append(f"clear {slot}")
        raise KernelError(errno.ETIMEDOUT, "")


@pytest.mark.parametrize("kw", [{"keep_loaded": True}, {"resource": "rheavy"}])
def test_stop_names_the_task_that_does_not_come_back(monkeypatch, kw):
    fake = FakeClient()
    monkeypatch.setattr(ops, "connect", lambda what="": fake)
    with pytest.raises(PLCError) as e:
        ops.stop(**kw)
    msg = str(e.value)
    assert "\n" not in msg
    assert msg.startswith("stop: task rheavy.heavy (inside one cycle for 3456 ms) does not "
                          "come back"), msg
    assert "rbeat.beat" not in msg          # its cycles are short: not named
    assert fake.calls[-1] == "status" and not any(c.startswith("clear") for c in fake.calls)


def test_cli_prints_one_line_and_exits_1(monkeypatch, capsys):
    fake = FakeClient()
    monkeypatch.setattr(ops, "connect", lambda what="": fake)
    assert cli.main(["stop", "--keep-loaded"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("plc-manager: stop: task rheavy.heavy "), err


def test_unload_stops_at_the_timeout_and_removes_nothing(monkeypatch):
    fake = FakeClient()
    removed = []
    monkeypatch.setattr(ops, "Client", lambda: fake)
    monkeypatch.setattr(ops.kmod, "remove", removed.append)
    with pytest.raises(PLCError, match=r"^stop: task rheavy\.heavy \(inside one cycle"):
        ops.unload("iec_stuck_config")
    assert removed == []


def test_other_kernel_errors_pass_through(monkeypatch):
    fake = FakeClient()

    def refuse(resource=None):
        raise KernelError(errno.ENOENT, "no such resource")
    fake.stop = refuse
    with pytest.raises(KernelError, match="no such resource"):
        ops._kernel_call(fake, "stop", fake.stop)


def test_status_shows_a_long_cycle():
    text = cli.status_text(_status())
    assert "tasks inside a long cycle" in text
    assert "rheavy.heavy: inside one cycle for 3456 ms" in text
    assert "rbeat.beat: inside" not in text


def test_status_shows_the_last_fault_and_the_restart():
    st = _status()
    t = st.resources[0].tasks[0]
    t.state, t.fault, t.fault_pou, t.fault_line = "fault", "division by zero", "Faulty", 15
    t.fault_ns, t.starts, t.started_ns = 1_700_000_000_123_000_000, 1, 1_699_999_990_000_000_000
    text = cli.status_text(st)
    assert f"{t.path}: stopped on a fault: division by zero in Faulty line 15 at " \
           f"{cli.fmt_time(t.fault_ns)}" in text, text
    t.state, t.starts, t.started_ns = "running", 2, 1_700_000_005_000_000_000
    text = cli.status_text(st)
    assert f"{t.path}: last fault: division by zero in Faulty line 15 at " \
           f"{cli.fmt_time(t.fault_ns)}; restarted at {cli.fmt_time(t.started_ns)}" in text, text
    assert "RESTARTS" in text and "LAST RESTART" in text
