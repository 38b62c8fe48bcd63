# SPDX-License-Identifier: MIT
"""plc-manager when the kernel gives up waiting for a task (ETIMEDOUT from
a stop or a slot clear: a task does not come back from its cycle within
the kernel's bound): one line naming the task and how long it has been
inside its cycle, exit 1; a full stop still removes every module that task
cannot be running.  The kernel side is
tests/qemu/test_bounded_waits.py."""

import errno

import pytest

from plc_manager import cli, ops
from plc_manager.errors import PLCError
from plc_manager.netlink import KernelError, Resource, Slot, Status, Task

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

    def status(self, slots_only=False):
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


class StuckKernel:
    """The modules of that configuration: rheavy.heavy is inside a cycle
    that runs the HEAVY body, so its resource module and the HEAVY program
    type are in use; the clear of every slot and of HEAVY's time out, the
    clear of BEAT's slot (a slot rheavy.heavy does not run) releases it."""

    def __init__(self):
        self.loaded = {"iec_stuck_config": [], "iec_stuck_r_rheavy": ["iec_stuck_config"],
                       "iec_stuck_r_rbeat": ["iec_stuck_config"],
                       "iec_stuck_p_heavy_1": ["iec_stuck_config"],
                       "iec_stuck_p_beat_1": ["iec_stuck_config"]}
        self.busy = {"iec_stuck_r_rheavy", "iec_stuck_p_heavy_1", "iec_stuck_p_beat_1"}
        self.removed = []

    def remove(self, name):
        if name not in self.loaded:
            raise ops.kmod.ModuleError(f"remove {name}: not loaded", errno.ENOENT)
        if name in self.busy or self.holders(name):
            raise ops.kmod.ModuleError(f"remove {name}: in use", errno.EWOULDBLOCK)
        del self.loaded[name]
        self.removed.append(name)

    def holders(self, name):
        return sorted(m for m, uses in self.loaded.items() if name in uses)


def test_unload_removes_what_the_stuck_task_cannot_run(monkeypatch):
    fake, k = FakeClient(), StuckKernel()
    fake.status = lambda: Status(**{**_status().__dict__, "slots": [
        Slot(0, "HEAVY", "0" * 16, "iec_stuck_p_heavy_1", "b1", 0, 1),
        Slot(1, "BEAT", "1" * 16, "iec_stuck_p_beat_1", "b1", 0, 1)]})

    def clear(slot=None):
        fake.calls.append(f"clear {slot}")
        if slot == 1:
            k.busy.discard("iec_stuck_p_beat_1")      # its old body's reference dropped
            return
        raise KernelError(errno.ETIMEDOUT, "")
    fake.clear = clear
    monkeypatch.setattr(ops, "Client", lambda: fake)
    monkeypatch.setattr(ops.kmod, "remove", k.remove)
    monkeypatch.setattr(ops.kmod, "holders", k.holders)
    monkeypatch.setattr(ops.kmod, "loaded", lambda: list(k.loaded))
    with pytest.raises(PLCError) as e:
        ops.unload("iec_stuck_config")
    msg = str(e.value)
    assert "\n" not in msg
    assert msg.startswith("stop: task rheavy.heavy (inside one cycle for 3456 ms) does not "
                          "come back"), msg
    assert k.removed == ["iec_stuck_r_rbeat", "iec_stuck_p_beat_1"]
    assert msg.endswith("; removed iec_stuck_r_rbeat, iec_stuck_p_beat_1; still loaded: "
                        "iec_stuck_p_heavy_1, iec_stuck_r_rheavy, iec_stuck_config "
                        "(stop again once that cycle has ended)"), msg
    assert fake.calls.count("clear None") == 1 and "clear 0" in fake.calls

    # once the cycle has ended, the same unload removes the rest
    k.busy.clear()
    fake.stop = lambda resource=None: None
    fake.clear = lambda slot=None: None
    assert ops.unload("iec_stuck_config") == ["iec_stuck_r_rheavy", "iec_stuck_p_heavy_1",
                                              "iec_stuck_config"]
    assert k.loaded == {}


def test_full_stop_goes_on_to_unload_past_a_stuck_task(monkeypatch):
    """`plc-manager stop` (not --keep-loaded): the timeout of its stop is
    not the end; unload() removes what it can and names what is left."""
    fake = FakeClient()
    calls = []
    monkeypatch.setattr(ops, "connect", lambda what="": fake)
    monkeypatch.setattr(ops.kmod, "require", lambda *a: None)

    def unload(module, progress):
        calls.append(module)
        raise PLCError("stop: task rheavy.heavy ... still loaded: x")
    monkeypatch.setattr(ops, "unload", unload)
    with pytest.raises(PLCError, match="still loaded"):
        ops.stop()
    assert calls == ["iec_stuck_config"]


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
