# SPDX-License-Identifier: MIT
"""Pieces of the guest harness that need no guest: the cpio writer, module
dependency order, kernel-log matching, the kbuild helper's errors."""

import os
import stat
import subprocess

import pytest

from iec2kmod import kbuild
from iec2kmod.testing.vm import kernel_log_problems
from iec2kmod.testing.vm.initramfs import CpioWriter, ModuleIndex
from iec2kmod.testing.vm.kernel import find_kernel, VMSetupError


def test_cpio_newc_archive_is_read_by_gnu_cpio(tmp_path):
    w = CpioWriter()
    w.add_dirs("a/b")
    w.add_file("a/b/f.txt", b"hello\n", 0o640)
    w.add_file("a/odd", b"x" * 5, 0o755)          # lengths that need padding
    w.add_symlink("a/link", "b/f.txt")
    w.add_chardev("a/null", 1, 3, 0o666)
    data = w.finish()
    assert len(data) % 512 == 0
    with pytest.raises(ValueError):
        w.add_file("late", b"")
    out = tmp_path / "x"
    out.mkdir()
    p = subprocess.run(["cpio", "-i", "-d", "--no-absolute-filenames", "--quiet"],
                       input=data, cwd=out, capture_output=True)
    assert p.returncode == 0, p.stderr
    assert (out / "a/b/f.txt").read_bytes() == b"hello\n"
    assert stat.S_IMODE(os.stat(out / "a/b/f.txt").st_mode) == 0o640
    assert (out / "a/odd").read_bytes() == b"xxxxx"
    assert os.readlink(out / "a/link") == "b/f.txt"
    st = os.lstat(out / "a/null")
    assert stat.S_ISCHR(st.st_mode) and os.major(st.st_rdev) == 1 and os.minor(st.st_rdev) == 3


def test_cpio_rejects_duplicates():
    w = CpioWriter()
    w.add_dir("d")
    with pytest.raises(ValueError):
        w.add_dir("d")


def test_module_load_order_puts_dependencies_first():
    try:
        k = find_kernel()
    except VMSetupError as e:
        pytest.fail(str(e), pytrace=False)
    idx = ModuleIndex(k.moddir)
    order = idx.load_order(["9p", "9pnet_virtio", "virtio_pci"])
    for mod in order:
        for dep in idx.depends(mod):
            assert order.index(dep) < order.index(mod)
    assert {"9p", "9pnet", "netfs", "virtio", "virtio_ring", "virtio_pci"} <= set(order)
    with pytest.raises(KeyError, match="no_such_module"):
        idx.load_order(["no_such_module"])


def test_kernel_log_patterns():
    log = ("[ 1.0] ok line\n"
           "[ 2.0] WARNING: CPU: 1 PID: 7 at foo.c:3 bar+0x1\n"
           "[ 2.1] Call Trace:\n"
           "[ 3.0] BUG: scheduling while atomic: x/1/0x00000002\n"
           "[ 4.0] BUG: sleeping function called from invalid context at y.c:1\n"
           "[ 5.0] Oops: 0000 [#1] PREEMPT_RT SMP\n"
           "[ 6.0] iec2kmod: harmless\n")
    bad = kernel_log_problems(log)
    assert len(bad) == 5 and "ok line" not in " ".join(bad)
    assert kernel_log_problems(log, allow=[r"foo\.c", r"Call Trace"]) == bad[2:]


def test_kbuild_errors_name_what_to_do(tmp_path, monkeypatch):
    monkeypatch.setenv("IEC2KMOD_KDIR", str(tmp_path))
    with pytest.raises(kbuild.KbuildError, match="not a kbuild directory"):
        kbuild.find_kdir()
    monkeypatch.delenv("IEC2KMOD_KDIR")
    with pytest.raises(kbuild.KbuildError, match="apt-get install linux-headers-rt-amd64"):
        kbuild.find_kdir(release="0.0.0-no-such-rt-amd64")
    with pytest.raises(kbuild.KbuildError, match="does not exist"):
        kbuild.build_modules(str(tmp_path / "missing"))
    (tmp_path / "notko").write_bytes(b"not an elf")
    with pytest.raises(kbuild.KbuildError, match="not a kernel module"):
        kbuild.modinfo(str(tmp_path / "notko"))


def test_kbuild_clean(tmp_path):
    (tmp_path / "Kbuild").write_text("obj-m := nothing.o\n")
    (tmp_path / "stale.o").write_text("")
    (tmp_path / ".stale.o.cmd").write_text("")
    res = kbuild.clean_modules(str(tmp_path))
    assert res.ok, res.output
    assert not (tmp_path / "stale.o").exists()


# ---------------------------------------------------------------------------
# The kernel log cursor and the pytest fixtures' checks, against a simulated
# guest (the real Guest code with QEMU replaced by a record file and a
# console file), so the blind spots they close are shown without a boot.

FAKE_GUEST = r'''
import re
from iec2kmod.testing.vm.guest import CommandResult, Guest


class FakeProc:
    pid = -1
    stdout = None

    def __init__(self):
        self.rc = None

    def poll(self):
        return self.rc

    def wait(self, timeout=None):
        return self.rc


class FakeGuest(Guest):
    """Guest with QEMU simulated: the guest's copy of /dev/kmsg (what its
    reader writes), the console (levels <= 4) and death.  Everything else,
    read_kernel_log, check_kernel_log, death_report, is the real code."""

    def start(self):
        self._proc = FakeProc()
        self._sock = object()
        self.kmsg, self.seq, self.clock, self.after_read = "", 0, 1.0, []
        open(self.console_log, "wb").close()
        self.emit("Linux version 6.1.0-fake")
        return self

    def emit(self, msg, level=4):
        self.clock += 0.001
        usec = int(round(self.clock * 1e6))
        self.kmsg += f"{level},{self.seq},{usec},-;{msg}\n"
        self.seq += 1
        if level <= 4:
            self.console(f"[{usec // 10**6:5d}.{usec % 10**6:06d}] {msg}")

    def console(self, line):
        data = (line + "\r\n").encode()
        with open(self.console_log, "ab") as f:
            f.write(data)
        self._console_bytes += len(data)
        self._console_tail.append(line)

    def die(self, *lines):
        for line in lines:
            self.console(line)
        self._proc.rc = 0              # panic=-1 with -no-reboot: QEMU exits 0

    def run(self, cmd, timeout=60.0, **kw):
        self._ensure_alive()
        m = re.search(r"echo '<7>(\S+)' >/dev/kmsg", cmd)
        if m is None:
            return CommandResult(0, "")
        self.emit(m.group(1), 7)
        off = int(re.search(r"tail -c \+(\d+)", cmd).group(1))
        out = self.kmsg[off - 1:]
        todo, self.after_read = self.after_read, []
        for what in todo:               # after the read: "later"
            what()
        return CommandResult(0, out)

    def close(self, timeout=15.0):
        if self._proc.rc is None:
            self._proc.rc = 0

    def kill(self):
        self.close()
'''

FAKE_CONFTEST = r'''
import os
import iec2kmod.testing.vm.pytest_fixtures as fx
from fakeguest import FakeGuest


def _boot(workdir, logdir, **kw):
    fx._STATE["boots"] += 1
    g = FakeGuest(workdir, console_log=os.path.join(
        logdir, f"console-{fx._STATE['boots']}.log")).start()
    if fx._STATE["boots"] == 2:         # the second session guest warns while booting
        g.emit("WARNING: CPU: 0 PID: 1 at init/fake.c:7 boot_warning")
    return g


fx._boot = _boot
fx._fail_if_missing = lambda: None
fx.SETTLE_SECONDS = 0
from iec2kmod.testing.vm.pytest_fixtures import guest, guest_factory, guest_session, guest_workdir  # noqa
'''

FAKE_TESTS = r'''
import pytest
import iec2kmod.testing.vm.pytest_fixtures as fx
from iec2kmod.testing.vm import GuestDied

W = "WARNING: CPU: 0 PID: 9 at fake.c:1 "


def test_a_clean(guest):
    guest.emit("iec2kmod: a harmless line", 6)


def test_b_warns_during(guest):
    guest.emit(W + "during_b")


def test_c_warns_after_its_check(guest):
    # after this test's final check: delayed work after rmmod
    guest.after_read.append(lambda: guest.emit(W + "late_c"))


def test_d_innocent(guest):
    pass


def test_e_dies_after_its_last_command(guest):
    guest.emit("iec2kmod: last command", 6)
    guest.die("[    9.100000] BUG: kernel NULL pointer dereference, address: 0",
              "[    9.200000] Kernel panic - not syncing: Fatal exception")


def test_f_runs_on_a_fresh_guest_that_warned_at_boot(guest):
    pass


def test_f2_same_fresh_guest(guest):
    assert fx._STATE["boots"] == 2 and guest.alive


def test_g_guest_dies_after_its_check(guest):
    guest.after_read.append(lambda: guest.die(
        "[   12.000000] INFO: task kworker/0:1:33 blocked for more than 120 seconds.",
        "[   12.500000] Kernel panic - not syncing: hung_task: blocked tasks"))


def test_h_innocent(guest):
    pass


def test_i_factory_guest_dies_unseen(guest_factory):
    g = guest_factory()
    g.die("[    3.000000] Kernel panic - not syncing: unseen")


def test_j_factory_guest_death_seen(guest_factory):
    g = guest_factory()
    g.die("[    3.000000] Kernel panic - not syncing: seen")
    with pytest.raises(GuestDied):
        g.run("true")


def test_k_factory_guest_warns(guest_factory):
    g = guest_factory()
    g.emit("BUG: sleeping function called from invalid context at factory.c:3")


def test_l_provoked_and_consumed(guest):
    from iec2kmod.testing.vm import KernelLogError
    guest.emit(W + "provoked")
    with pytest.raises(KernelLogError):
        guest.check_kernel_log()


def test_z_last_test_leaves_a_tail(guest):
    guest.after_read.append(lambda: guest.emit(
        "rcu: INFO: rcu_preempt detected stalls on CPUs/tasks:", 3))
'''


def _junit_results(path):
    import xml.etree.ElementTree as ET
    out = {}
    for tc in ET.parse(path).getroot().iter("testcase"):
        kinds = [(c.tag, c.get("message", "") + (c.text or "")) for c in tc
                 if c.tag in ("failure", "error", "skipped")]
        out[tc.get("name")] = kinds
    return out


def test_fixtures_fail_every_blind_spot_of_the_kernel_log(tmp_path):
    """A pytest session over a simulated guest: a WARN during a test fails
    it; one logged after its final check fails the next test's setup, naming
    the test before; a guest that dies after a test's last command fails that
    test with the console's panic lines, and the next test gets a fresh
    guest, whose boot log is checked; a death between tests fails the next
    setup; a private guest's
    unseen death and its warnings fail its test; the tail after the last test
    fails the run."""
    import subprocess
    import sys
    (tmp_path / "fakeguest.py").write_text(FAKE_GUEST)
    (tmp_path / "conftest.py").write_text(FAKE_CONFTEST)
    (tmp_path / "test_inner.py").write_text(FAKE_TESTS)
    repo = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(tmp_path), repo]))
    p = subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-q",
                        "--junitxml", str(tmp_path / "r.xml"), "test_inner.py"],
                       cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    assert p.returncode == 1, p.stdout + p.stderr
    r = _junit_results(tmp_path / "r.xml")
    text = {k: "\n".join(m for _, m in v) for k, v in r.items()}
    kinds = {k: [t for t, _ in v] for k, v in r.items()}
    assert kinds["test_a_clean"] == [], text["test_a_clean"]
    assert kinds["test_b_warns_during"] == ["error"]
    assert "kernel log during this test" in text["test_b_warns_during"]
    assert "during_b" in text["test_b_warns_during"]
    assert kinds["test_c_warns_after_its_check"] == [], text["test_c_warns_after_its_check"]
    assert kinds["test_d_innocent"] == ["error"]
    assert "failed on setup" in text["test_d_innocent"]
    assert "late_c" in text["test_d_innocent"]
    assert "after test_inner.py::test_c_warns_after_its_check ended" in text["test_d_innocent"]
    t = text["test_e_dies_after_its_last_command"]
    assert kinds["test_e_dies_after_its_last_command"] == ["error"], t
    assert "the guest died during this test: QEMU exited" in t
    scanned = t.split("last console lines")[0]
    assert "BUG: kernel NULL pointer dereference" in scanned and "Kernel panic" in scanned, t
    t = text["test_f_runs_on_a_fresh_guest_that_warned_at_boot"]
    assert kinds["test_f_runs_on_a_fresh_guest_that_warned_at_boot"] == ["error"], t
    assert "failed on setup" in t and "kernel log while the guest booted" in t, t
    assert "boot_warning" in t, t
    assert kinds["test_f2_same_fresh_guest"] == [], text["test_f2_same_fresh_guest"]
    assert kinds["test_g_guest_dies_after_its_check"] == []
    t = text["test_h_innocent"]
    assert kinds["test_h_innocent"] == ["error"] and "failed on setup" in t, t
    assert "the guest died after test_inner.py::test_g_guest_dies_after_its_check ended" in t
    assert "blocked for more than 120 seconds" in t.split("last console lines")[0], t
    t = text["test_i_factory_guest_dies_unseen"]
    assert kinds["test_i_factory_guest_dies_unseen"] == ["error"], t
    assert "the guest died in the test's guest #1" in t and "unseen" in t, t
    assert kinds["test_j_factory_guest_death_seen"] == [], text["test_j_factory_guest_death_seen"]
    t = text["test_k_factory_guest_warns"]
    assert kinds["test_k_factory_guest_warns"] == ["error"] and "factory.c:3" in t, t
    assert kinds["test_l_provoked_and_consumed"] == [], text["test_l_provoked_and_consumed"]
    t = text["test_z_last_test_leaves_a_tail"]
    assert kinds["test_z_last_test_leaves_a_tail"] == ["error"], t
    assert "end of the session" in t and "detected stalls" in t, t
    assert "11 passed, 8 errors" in p.stdout, p.stdout


def _reader_guest(tmp_path):
    from iec2kmod.testing.vm import Guest
    g = Guest(str(tmp_path), console_log=str(tmp_path / "console.log"))
    return g


def test_kernel_log_cursor_reads_every_record_exactly_once(tmp_path):
    from iec2kmod.testing.vm.guest import _KLOG_SYNC
    g = _reader_guest(tmp_path)
    f = ("6,0,1000,-;Linux version x\n"
         " SUBSYSTEM=virtio\n"
         f"15,1,2000,-;{_KLOG_SYNC}abc-1@\n"
         "4,2,2500000,-;WARNING: CPU: 1 at a.c:3\\x0asecond line \\x5cx41\n"
         "4,3,2600")                        # a record still being written
    r = g._consume_kmsg(f)
    assert r.lines == ["[    0.001000] Linux version x",
                       "[    2.500000] WARNING: CPU: 1 at a.c:3",
                       "[    2.500000] second line \\x41"]
    assert r.lost == [] and r.last_ts == 2.5
    # the next read starts at the partial record; the reader restarted after
    # an overrun and copied records 2.. again (dropped), 5..6 were lost
    rest = f[f.rindex("\n") + 1:] + "000,-;BUG: x\n" + \
        "4,2,2500000,-;WARNING: CPU: 1 at a.c:3\n4,7,9000000,-;after the gap\n"
    r = g._consume_kmsg(rest)
    assert r.lines == ["[    2.600000] BUG: x", "[    9.000000] after the gap"]
    assert r.lost == ["kernel log records 4..6 were lost (the ring buffer overran before "
                      "they were read)"]
    assert g._consume_kmsg("") == ([], [], 9.0)
