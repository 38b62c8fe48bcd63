# SPDX-License-Identifier: MIT
# QEMU-tier fixtures; the session guest is shared with any other conftest that
# imports the same fixtures (one boot per pytest session).
from __future__ import annotations

import pytest

from iec2kmod.testing.vm.pytest_fixtures import (  # noqa: F401
    guest, guest_factory, guest_session, guest_tmp_path, guest_workdir, kdir)
from kmod_helpers import kernel_modules, loaded_modules, pm

# comedi's modules, in their load order (comedi_test needs only comedi; the
# resource modules of an I/O map need kcomedilib; comedi_parport both)
COMEDI_KO = {"comedi": "comedi.ko", "kcomedilib": "kcomedilib/kcomedilib.ko",
             "comedi_test": "drivers/comedi_test.ko",
             "comedi_parport": "drivers/comedi_parport.ko"}


@pytest.fixture
def comedi(guest):  # noqa: F811 (the fixture guest, imported above)
    """Loads comedi's modules into the session guest for one test:
    ``comedi("comedi_test")`` (comedi, kcomedilib, comedi_test: /dev/comedi0
    auto-configured) or ``comedi("comedi_parport", legacy_minors=1)``.  At
    the end of the test a configuration it left loaded is stopped, the
    modules it loaded are removed, and the test fails unless the guest's
    modules are those it found (the kernel log of the removal is checked by
    the guest fixture, which ends after this one)."""
    before = kernel_modules(guest)
    assert not any(m in before for m in COMEDI_KO), \
        f"comedi's modules already loaded before the test: {sorted(before)}"
    md = "/host" + guest.kernel.moddir + "/drivers/comedi"
    ours: list = []

    def load(*drivers: str, legacy_minors: int = 0):
        for name in ("comedi", "kcomedilib", *drivers):
            if name in ours:
                continue
            arg = f" comedi_num_legacy_minors={legacy_minors}" \
                if name == "comedi" and legacy_minors else ""
            guest.check_call(f"insmod {md}/{COMEDI_KO[name]}{arg}")
            ours.append(name)
        return md

    yield load
    problems = []
    if loaded_modules(guest):
        rc, out = pm(guest, "stop", check=None)
        if rc:
            problems.append(f"plc-manager stop: exit {rc}: {out}")
    left = kernel_modules(guest)
    if left - before - set(ours):
        problems.append(f"the test left modules loaded: {sorted(left - before - set(ours))}")
    # ours in reverse order, then what the test added itself, a few passes
    # (one may hold another): the next test finds the guest as this one did
    for _ in range(3):
        todo = [m for m in reversed(ours) if m in left] + sorted(left - before - set(ours))
        if not todo:
            break
        for name in todo:
            guest.run(f"rmmod {name}")
        left = kernel_modules(guest)
    if left != before:
        problems.append(f"the guest's modules differ after the test: added "
                        f"{sorted(left - before)}, removed {sorted(before - left)}")
    if problems:
        pytest.fail("\n".join(problems), pytrace=False)
