# SPDX-License-Identifier: MIT
"""pytest fixtures for the QEMU tier.

Use them from a conftest.py::

    from iec2kmod.testing.vm.pytest_fixtures import (   # noqa: F401
        guest, guest_session, guest_workdir, guest_tmp_path, guest_factory, kdir)

* ``guest`` (per test): the session's running guest.  One guest boots for the
  whole pytest session, shared by every conftest that imports these fixtures.
  Its kernel log is read with a cursor (:meth:`Guest.read_kernel_log`), so
  every line is checked exactly once, and failures are attributed so:

  - at the end of a test (teardown): what was logged during the test; a
    ``WARNING:``, ``BUG:``, ``Oops``, ``Call Trace``, panic, stall, hung-task
    line (:data:`KERNEL_LOG_PATTERNS`) fails the test, and so does a guest
    that died during the test (QEMU exited: with ``oops=panic`` every Oops
    does), whether or not a command noticed: then the console output up to
    the death is scanned and listed;
  - at the start of a test (setup): what was logged *between* the previous
    test's final check and now (delayed work after ``rmmod``, a hung task
    report, an RCU stall) and a death in that gap, or, for a freshly booted
    guest, its boot log.  They fail this test's setup (an ERROR naming the
    previous test, which most likely caused it) rather than the previous
    test, whose result is already reported; this test does not run on a
    kernel that has just misbehaved.  After a death the next test boots a
    new guest;
  - at the end of the session: after a settling second, the tail after the
    last test's check (or a death since); a problem fails the run (an ERROR
    at the teardown of the last test).

  A test that provokes such lines on purpose consumes them itself, with
  ``pytest.raises(KernelLogError): guest.check_kernel_log()`` or
  ``guest.check_kernel_log(allow=[...])``.  ``guest.baseline`` is the log
  timestamp at the start of the test (``guest.dmesg(guest.baseline)``).
  The session guest has a parallel port (``Guest(parallel=...)``: LPT1 at
  0x378, IRQ 7) on a host file, ``guest.parallel``, for the tests of bound
  I/O (tests/qemu/test_io_parport.py); no driver claims it at boot, and a
  test that writes to it reads the file from the size it had before.
* ``guest_session``: the same guest without the per-test log check.
* ``guest_workdir``: the read-write directory shared with the guest (same
  absolute path inside the guest); ``guest_tmp_path``: a fresh subdirectory of
  it per test.  Build ``.ko`` files there, then ``guest.insmod(path)``.
* ``guest_factory(**Guest kwargs)``: boot an extra, private guest (e.g.
  ``icount=True``) that is closed at the end of the test.  At the end its
  unread kernel log is checked like the session guest's, and the test fails
  if the guest died without the test having seen it (no command raised
  :class:`GuestDied`/:class:`GuestTimeout`).
* ``kdir``: the PREEMPT_RT kbuild directory.

A missing prerequisite (qemu, busybox-static, headers, the extracted kernel
image) FAILS the test with what to install or run; nothing is skipped.

Environment: ``IEC2KMOD_VM_ICOUNT=1`` boots the session guest in icount mode;
``IEC2KMOD_VM_MEMORY`` (MiB), ``IEC2KMOD_VM_SMP``; ``IEC2KMOD_VM_HOST_CACHE``
(``loose``/``none``); ``IEC2KMOD_VM_PRELOAD`` (comma-separated modules the
guest's Python fork server imports once, default ``pyroute2``).
"""

from __future__ import annotations

import os
import re
import time
from pathlib import Path
from typing import Any, Dict, List, Optional

import pytest

from ... import kbuild
from .guest import Guest, GuestError, KernelLogError
from .kernel import check_prerequisites

__all__ = ["guest", "guest_session", "guest_workdir", "guest_tmp_path", "guest_factory",
           "kdir", "log_report", "factory_report"]

_STATE: Dict[str, Any] = {"guest": None, "workdir": None, "logdir": None, "boots": 0,
                          "users": 0, "last_test": None}

SETTLE_SECONDS = 1.0          # the session guest's wait before its last log read


def log_report(g: Guest, window: str) -> Optional[str]:
    """Read *g*'s kernel log up to now (each line once, see
    :meth:`Guest.read_kernel_log`) and return why the window named *window*
    fails, or None if it is clean: problem lines, lost records, or a dead
    guest (then the console output since the last read is scanned)."""
    if g.alive:
        try:
            g.check_kernel_log()
            return None
        except KernelLogError as e:
            return f"kernel log {window}: {e}"
        except GuestError as e:
            if g.alive:
                return f"the kernel log {window} could not be read: {e}"
    return f"the guest died {window}: {g.death_report()}"


def factory_report(g: Guest, window: str) -> Optional[str]:
    """:func:`log_report` for a private guest: a death the test has seen
    (a command raised :class:`GuestDied`/:class:`GuestTimeout`, so
    ``dead_reason`` is set) is the test's business, not a failure."""
    if not g.alive and g.dead_reason is not None:
        return None
    return log_report(g, window)


def _retire_dead_guest() -> None:
    g = _STATE["guest"]
    if g is not None and not g.alive:
        g.kill()
        _STATE["guest"] = None


def _env_options() -> Dict[str, Any]:
    opts: Dict[str, Any] = {}
    if os.environ.get("IEC2KMOD_VM_ICOUNT", "") not in ("", "0"):
        opts["icount"] = True
    if os.environ.get("IEC2KMOD_VM_MEMORY"):
        opts["memory"] = int(os.environ["IEC2KMOD_VM_MEMORY"])
    if os.environ.get("IEC2KMOD_VM_SMP"):
        opts["smp"] = int(os.environ["IEC2KMOD_VM_SMP"])
    if os.environ.get("IEC2KMOD_VM_PRELOAD"):
        opts["preload"] = tuple(m for m in os.environ["IEC2KMOD_VM_PRELOAD"].split(",") if m)
    if os.environ.get("IEC2KMOD_VM_HOST_CACHE"):
        opts["host_cache"] = os.environ["IEC2KMOD_VM_HOST_CACHE"]
    if os.environ.get("IEC2KMOD_VM_APPEND"):     # e.g. "slub_debug=FZPU page_poison=1"
        opts["append"] = os.environ["IEC2KMOD_VM_APPEND"]
    return opts


def _fail_if_missing() -> None:
    problems = check_prerequisites()
    if problems:
        pytest.fail("QEMU tier cannot run, prerequisites missing:\n  - "
                    + "\n  - ".join(problems), pytrace=False)


def _boot(workdir: str, logdir: str, **kw) -> Guest:
    _STATE["boots"] += 1
    log = os.path.join(logdir, f"guest-console-{_STATE['boots']}.log")
    g = Guest(workdir, console_log=log, **kw)
    try:
        g.start()
    except GuestError as e:
        pytest.fail(f"the QEMU guest did not boot: {e}", pytrace=False)
    return g


def _live_guest() -> Guest:
    g = _STATE["guest"]
    if g is None or not g.alive:
        if g is not None:
            g.kill()
        opts = {"parallel": os.path.join(_STATE["logdir"], f"lpt1-{_STATE['boots'] + 1}.bin"),
                **_env_options()}
        g = _boot(_STATE["workdir"], _STATE["logdir"], **opts)
        _STATE["guest"] = g
    return g


@pytest.fixture(scope="session")
def guest_workdir(tmp_path_factory) -> Path:
    if _STATE["workdir"] is None:
        _STATE["workdir"] = str(tmp_path_factory.mktemp("guestwork"))
        _STATE["logdir"] = str(tmp_path_factory.mktemp("guestlogs"))
    return Path(_STATE["workdir"])


@pytest.fixture(scope="session")
def guest_session(guest_workdir):
    _fail_if_missing()
    _STATE["users"] += 1
    try:
        yield _live_guest()
    finally:
        _STATE["users"] -= 1
        if _STATE["users"] == 0 and _STATE["guest"] is not None:
            _end_of_session()


def _end_of_session() -> None:
    """The session guest's tail: what was logged after the last test's check
    (after a settling second for delayed work), or its death since.  Fails
    the run if anything is wrong."""
    g = _STATE["guest"]
    if g.alive:
        time.sleep(SETTLE_SECONDS)
    msg = log_report(g, f"after {_STATE['last_test'] or 'boot'} ended (end of the session)")
    g.close()
    _STATE["guest"] = None
    if msg is not None:
        pytest.fail(msg, pytrace=False)


@pytest.fixture
def guest(guest_session, request):
    prev = _STATE["last_test"]
    _STATE["last_test"] = request.node.nodeid
    g = _STATE["guest"]
    if g is not None and not g.alive:
        msg = log_report(g, f"after {prev or 'its boot'} ended and before this test started")
        _retire_dead_guest()
        pytest.fail(msg, pytrace=False)
    g = _live_guest()
    if g.klog_reads == 0:
        window = "while the guest booted"
    else:
        window = (f"after {prev} ended and before this test started (most likely caused "
                  "by that test)")
    msg = log_report(g, window)
    if msg is not None:
        _retire_dead_guest()
        pytest.fail(msg, pytrace=False)
    g.baseline = g.klog_last_ts
    yield g
    msg = log_report(g, "during this test")
    g.baseline = None
    if msg is not None:
        _retire_dead_guest()
        pytest.fail(msg, pytrace=False)


@pytest.fixture
def guest_tmp_path(guest_workdir, request) -> Path:
    name = re.sub(r"[^A-Za-z0-9_.-]", "_", request.node.name)[:60]
    p = guest_workdir / name
    n = 0
    while p.exists():
        n += 1
        p = guest_workdir / f"{name}-{n}"
    p.mkdir(parents=True)
    return p


@pytest.fixture
def guest_factory(guest_workdir):
    _fail_if_missing()
    made: List[Guest] = []

    def make(**kw) -> Guest:
        kw.setdefault("workdir", _STATE["workdir"])
        for k, v in _env_options().items():
            kw.setdefault(k, v)
        workdir = kw.pop("workdir")
        g = _boot(str(workdir), _STATE["logdir"], **kw)
        made.append(g)
        return g

    yield make
    problems = []
    for i, g in enumerate(made, 1):
        msg = factory_report(g, f"in the test's guest #{i}")
        g.close()
        if msg is not None:
            problems.append(msg)
    if problems:
        pytest.fail("\n\n".join(problems), pytrace=False)


@pytest.fixture(scope="session")
def kdir() -> str:
    try:
        return kbuild.find_kdir()
    except kbuild.KbuildError as e:
        pytest.fail(str(e), pytrace=False)
