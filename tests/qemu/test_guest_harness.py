# SPDX-License-Identifier: MIT
"""The QEMU guest harness itself: module insertion, host Python in the guest,
the command channel's semantics, kernel-log checking, failure reporting."""

import os
import shutil
import signal
import sys
import time
from pathlib import Path

import pytest

from iec2kmod import kbuild
from iec2kmod.testing.vm import pytest_fixtures as fx
from iec2kmod.testing.vm import (GuestCommandTimeout, GuestDied, GuestTimeout, KernelLogError,
                         CommandFailed)

HELLO_SRC = Path(__file__).parent / "hello_module"

pytestmark = pytest.mark.qemu


def build_hello(dest: Path, kdir: str) -> Path:
    for f in HELLO_SRC.iterdir():
        shutil.copy(f, dest / f.name)
    res = kbuild.build_modules(str(dest), kdir=kdir)
    assert res.ok, res.output
    assert res.warnings() == [], res.output
    ko = dest / "iec2kmod_hello.ko"
    assert ko.is_file()
    return ko


def test_hello_module_built_after_boot_inserts_and_removes(guest, guest_tmp_path, kdir):
    # the guest is already up: the module is built on the host afterwards
    ko = build_hello(guest_tmp_path, kdir)
    vermagic = kbuild.modinfo(str(ko))["vermagic"][0]
    assert "preempt_rt" in vermagic.lower()
    assert vermagic.split()[0] == guest.check_call("uname -r").strip()

    out = guest.insmod(str(ko), "greeting=servus")
    assert "iec2kmod_hello" in guest.loaded_modules()
    assert guest.check_call("cat /sys/module/iec2kmod_hello/parameters/greeting").strip() \
        == "servus"
    assert "iec2kmod_hello: servus from the PREEMPT_RT guest" in guest.dmesg(guest.baseline)
    rc, out = guest.run(f"insmod {ko}")          # a second insert is refused
    assert rc != 0 and "File exists" in out
    guest.rmmod("iec2kmod_hello")
    assert "iec2kmod_hello" not in guest.loaded_modules()
    assert "iec2kmod_hello: goodbye" in guest.dmesg(guest.baseline)
    guest.check_kernel_log()                      # the teardown checks what follows


def test_host_kmod_tools_work_in_chroot(guest, guest_tmp_path, kdir):
    # plc-manager runs in the chroot and uses the host's kmod tools there
    rc, out = guest.run("command -v insmod rmmod modinfo", chroot=True)
    assert rc == 0, "kmod missing on the host: apt-get install kmod (scripts/setup.sh)"
    ko = build_hello(guest_tmp_path, kdir)
    guest.check_call(f"insmod {ko} greeting=kmod", chroot=True)
    assert "iec2kmod_hello" in guest.check_call("lsmod", chroot=True)
    guest.check_call("rmmod iec2kmod_hello", chroot=True)
    assert "iec2kmod_hello: kmod from the PREEMPT_RT guest" in guest.dmesg(guest.baseline)


def test_kernel_is_preempt_rt(guest):
    assert guest.check_call("cat /sys/kernel/realtime").strip() == "1"
    assert "PREEMPT_RT" in guest.check_call("uname -v")
    assert guest.check_call("uname -r").strip() == kbuild.kernel_release()
    assert guest.check_call("nproc").strip() == str(guest.smp)


def test_host_python_with_pyroute2_in_chroot(guest):
    # a fresh interpreter (sys.executable of the host) inside the guest, with
    # pyroute2 and this project (editable install, seen through 9p) importable
    rc, out = guest.python("import pyroute2, sys; print(sys.version)\n"
                           "import iec2kmod, os; print(os.path.dirname(iec2kmod.__file__))")
    assert rc == 0, out
    assert out.splitlines() == [sys.version,
                                os.path.dirname(__import__("iec2kmod").__file__)]


def test_pyrun_forks_a_warm_interpreter(guest, guest_tmp_path):
    info = guest.start_pyserver()
    assert "pyroute2" in info["preloaded"], info
    t0 = time.monotonic()
    rc, out = guest.pyrun(
        "import sys, os\n"
        "from pyroute2 import IPRoute\n"
        "with IPRoute() as ip: names = [l.get_attr('IFLA_IFNAME') for l in ip.get_links()]\n"
        "print(sys.argv[1:], os.getcwd(), os.environ['X'], names)",
        argv=["a", "b"], env={"X": "y"}, cwd=str(guest_tmp_path))
    assert rc == 0, out
    assert out == f"['a', 'b'] {guest_tmp_path} y ['lo']\n"
    assert time.monotonic() - t0 < 10            # a fork, not a 5-15 s interpreter start
    assert guest.pyrun("raise SystemExit(4)") == (4, "")
    rc, out = guest.pyrun("print('partial'); 1/0")
    assert rc == 1 and out.startswith("partial\n") and "ZeroDivisionError" in out
    assert "pyserver" not in out                 # the server's own frame is hidden
    rc, out = guest.pyrun(module="json.tool", argv=["--help"])
    assert rc == 0 and "usage:" in out
    rc, out = guest.pyrun(script="pyroute2-decoder", argv=["--help"])
    assert rc == 0 and "usage: pyroute2-decoder" in out
    assert guest.pyrun(script="no-such-script")[0] == 127
    with pytest.raises(GuestCommandTimeout) as ei:
        guest.pyrun("import time; print('x', flush=True); time.sleep(60)", timeout=2)
    assert ei.value.output == "x\n"
    assert guest.pyrun("print('next')") == (0, "next\n")


def test_workdir_is_shared_both_ways_at_the_same_path(guest, guest_tmp_path):
    f = guest_tmp_path / "from_host.txt"
    f.write_text("written on the host after boot\n")
    for chroot in (False, True):
        rc, out = guest.run(f"cat {f}", chroot=chroot)
        assert (rc, out) == (0, "written on the host after boot\n")
    g = guest_tmp_path / "from_guest.txt"
    guest.check_call(f"echo guest > {g}")
    assert g.read_text() == "guest\n"
    guest.check_call(f"echo chroot >> {g}", chroot=True)
    assert g.read_text() == "guest\nchroot\n"
    # the host root is read-only in the guest; /tmp there is the guest's own
    rc, out = guest.run("touch /usr/iec2kmod-should-not-exist", chroot=True)
    assert rc != 0 and "Read-only file system" in out
    assert guest.run("touch /tmp/x && ls /tmp/x", chroot=True) == (0, "/tmp/x\n")


def test_run_returns_exit_code_and_exact_output(guest):
    assert guest.run("exit 7") == (7, "")
    assert guest.run("printf 'no newline'") == (0, "no newline")
    assert guest.run("echo out; echo err >&2; false") == (1, "out\nerr\n")
    assert guest.run("echo \"$FOO\" $(pwd)", env={"FOO": "a b'c"}, cwd="/proc") \
        == (0, "a b'c /proc\n")
    # commands do not read the control channel
    assert guest.run("cat") == (0, "")
    # a long command goes through a file in the work directory
    long = "echo " + "x" * 5000
    assert guest.run(long) == (0, "x" * 5000 + "\n")
    # bulk output arrives complete
    rc, out = guest.run("i=0; while [ $i -lt 20000 ]; do echo line$i; i=$((i+1)); done")
    lines = out.splitlines()
    assert rc == 0 and len(lines) == 20000 and lines[-1] == "line19999"
    with pytest.raises(CommandFailed) as ei:
        guest.check_call("echo failing; exit 3")
    assert "exit 3" in str(ei.value) and "failing" in str(ei.value)


def test_command_timeout_kills_command_not_guest(guest):
    t0 = time.monotonic()
    with pytest.raises(GuestCommandTimeout):
        guest.run("echo started; sleep 60", timeout=2)
    assert time.monotonic() - t0 < 20
    assert guest.alive
    assert guest.run("echo still here") == (0, "still here\n")


def test_check_kernel_log_reports_warnings(guest):
    guest.check_kernel_log()
    guest.check_call("echo 'WARNING: CPU: 0 PID: 1 at fake/test.c:1 provoked by the test' "
                     "> /dev/kmsg")
    with pytest.raises(KernelLogError) as ei:
        guest.check_kernel_log()
    assert "provoked by the test" in str(ei.value)
    guest.check_kernel_log()                     # reported once: consumed by the check
    guest.check_call("echo 'BUG: allowed by the test' > /dev/kmsg")
    guest.check_kernel_log(allow=[r"allowed by the test"])
    guest.check_kernel_log()                     # the teardown check is clean too


def test_kernel_warnings_between_two_tests_are_reported(guest, guest_tmp_path, kdir):
    """What the kernel logs after a test's final check (here: a real WARN in
    a module's exit path, and a line written to /dev/kmsg) fails the next
    test's setup; the old per-test mark skipped it.  The fixture's own check
    function is called for the two windows."""
    ko = build_hello(guest_tmp_path, kdir)
    guest.insmod(str(ko), "warn_on_exit=1")
    assert fx.log_report(guest, "during test A") is None       # A's teardown: clean
    guest.rmmod("iec2kmod_hello")                                # between A and B
    guest.check_call("echo 'BUG: injected between two tests' > /dev/kmsg")
    msg = fx.log_report(guest, "before test B")                  # B's setup
    assert msg is not None and msg.startswith("kernel log before test B:"), msg
    assert "WARNING:" in msg and "iec2kmod_hello_exit" in msg, msg
    assert "BUG: injected between two tests" in msg, msg
    assert fx.log_report(guest, "again") is None                # each line once
    assert "iec2kmod_hello: goodbye" in guest.dmesg(guest.baseline)


def test_guest_death_and_hang_are_reported(guest_factory):
    g = guest_factory(smp=1)
    assert g.run("echo up") == (0, "up\n")
    # the guest panics after the test's last command returned: nobody sees
    # it, yet the fixture's check reports the death and the console's lines
    g.run("(sleep 1; echo c > /proc/sysrq-trigger) >/dev/null 2>&1 &")
    deadline = time.monotonic() + 120
    while g.alive and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not g.alive and g.dead_reason is None
    msg = fx.factory_report(g, "in guest #1")
    assert msg is not None and msg.startswith("the guest died in guest #1: QEMU exited"), msg
    assert "Kernel panic - not syncing" in msg.split("last console lines")[0], msg
    with pytest.raises(GuestDied) as ei:
        g.run("true", timeout=60)
    msg = str(ei.value)
    assert "last console lines" in msg and "sysrq" in msg.lower()
    assert not g.alive
    with pytest.raises(GuestDied):
        g.run("true")
    assert fx.factory_report(g, "in guest #1") is None         # the test has seen it

    g2 = guest_factory(smp=1)
    os.kill(g2._proc.pid, signal.SIGSTOP)         # freeze the whole VM
    try:
        t0 = time.monotonic()
        with pytest.raises(GuestTimeout):
            g2.run("true", timeout=1, grace=3)
        assert time.monotonic() - t0 < 30
    finally:
        try:
            os.kill(g2._proc.pid, signal.SIGCONT)
        except OSError:
            pass
    assert not g2.alive and g2._proc.poll() is not None


def test_icount_mode_boots_single_cpu(guest_factory):
    g = guest_factory(icount=True)
    assert g.check_call("nproc").strip() == "1"
    assert g.check_call("cat /sys/kernel/realtime").strip() == "1"
    # virtual time advances while the guest sleeps (sleep=off skips idle time)
    out = g.check_call("cut -d' ' -f1 /proc/uptime; sleep 2; cut -d' ' -f1 /proc/uptime")
    t0, t1 = map(float, out.split())
    assert 1.9 < t1 - t0 < 5
    g.check_kernel_log()
