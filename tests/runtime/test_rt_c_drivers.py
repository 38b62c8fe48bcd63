# SPDX-License-Identifier: MIT
"""Run the C test drivers in tests/runtime/c, each built twice: with the
strict warning flags and with UBSan+ASan (no recovery)."""
import re

import pytest

from rt_helpers import MODES, cfile, rt, run_driver

# driver -> runtime sources it links
DRIVERS = {
    "test_int.c": [],
    "test_string.c": ["iec_string.c"],
    "test_fb.c": ["iec_std_fb.c"],
    "test_real.c": ["iec_math.c", "iec_real.c", "iec_string.c"],
}

pytestmark = pytest.mark.execution


@pytest.mark.parametrize("mode", sorted(MODES))
@pytest.mark.parametrize("driver", sorted(DRIVERS))
def test_driver(builder, driver, mode):
    exe = builder.build([cfile(driver), *rt(*DRIVERS[driver])], mode=mode,
                        libs=["-lm"])
    r = run_driver(exe)
    out = r.stdout + r.stderr
    assert r.returncode == 0, out
    m = re.search(r"^(\d+) passed, (\d+) failed$", r.stdout, re.M)
    assert m, out
    assert int(m.group(1)) > 0 and int(m.group(2)) == 0, out


def test_every_driver_file_is_run():
    """A test_*.c added to tests/runtime/c but not to DRIVERS would never run."""
    on_disk = sorted(p.name for p in cfile("test_int.c").parent.glob("test_*.c"))
    assert len(on_disk) >= 4, on_disk
    assert on_disk == sorted(DRIVERS), f"drivers on disk {on_disk}, run {sorted(DRIVERS)}"
