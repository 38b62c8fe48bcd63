# SPDX-License-Identifier: MIT
"""pytest fixtures for the QEMU tier.

Use them from a conftest.py::

    from iec2kmod.vm.pytest_fixtures import (   # noqa: F401
        guest, guest_session, guest_workdir, guest_tmp_path, guest_factory, kdir)

* ``guest`` (per test): the session's running guest.  One guest boots for the
  whole pytest session, shared by every conftest that imports these fixtures.
  If an earlier test killed it (panic, hang), a fresh one boots.  At the start
  of the test it records a kernel-log mark (``guest.baseline``); at the end it
  fails the test (teardown error) if the kernel logged ``WARNING:``, ``BUG:``,
  ``Oops``, ``Call Trace`` etc. meanwhile.  A test that provokes such lines on
  purpose moves ``guest.baseline = guest.log_mark()`` past them.
* ``guest_session``: the same guest without the per-test log check.
* ``guest_workdir``: the read-write directory shared with the guest (same
  absolute path inside the guest); ``guest_tmp_path``: a fresh subdirectory of
  it per test.  Build ``.ko`` files there, then ``guest.insmod(path)``.
* ``guest_factory(**Guest kwargs)``: boot an extra, private guest (e.g.
  ``icount=True``) that is closed at the end of the test.
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
from pathlib import Path
from typing import Any, Dict, List

import pytest

from .. import kbuild
from .guest import Guest, GuestError
from .kernel import check_prerequisites

__all__ = ["guest", "guest_session", "guest_workdir", "guest_tmp_path", "guest_factory",
           "kdir"]

_STATE: Dict[str, Any] = {"guest": None, "workdir": None, "logdir": None, "boots": 0,
                          "users": 0}


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
        g = _boot(_STATE["workdir"], _STATE["logdir"], **_env_options())
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
            _STATE["guest"].close()
            _STATE["guest"] = None


@pytest.fixture
def guest(guest_session):
    g = _live_guest()
    try:
        g.baseline = g.log_mark()
    except GuestError as e:
        pytest.fail(f"the QEMU guest does not answer: {e}", pytrace=False)
    yield g
    if g.alive:
        try:
            g.check_kernel_log(since=g.baseline)
        except GuestError as e:
            pytest.fail(str(e), pytrace=False)
    g.baseline = None


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
        workdir = kw.pop("workdir")
        g = _boot(str(workdir), _STATE["logdir"], **kw)
        made.append(g)
        return g

    yield make
    for g in made:
        g.close()


@pytest.fixture(scope="session")
def kdir() -> str:
    try:
        return kbuild.find_kdir()
    except kbuild.KbuildError as e:
        pytest.fail(str(e), pytrace=False)
