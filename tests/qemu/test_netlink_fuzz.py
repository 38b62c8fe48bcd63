# SPDX-License-Identifier: MIT
"""QEMU tier: the netlink fuzzer (issue 23, item 5; tests/qemu/netlink_fuzz.py).

20,000 structure-aware random messages to the ``iec2kmod`` family, against
tests/qemu/projects/nl_fuzz loaded by plc-manager with its tasks running
(1 ms, 10 ms and an event task).  Sent from inside the guest in batches.
Then:

* no message that the generator made invalid was acknowledged (each has
  the reason the kernel must refuse it: wrong value size, a subrange or
  enumeration value out of range, a string over its capacity or without
  its NUL, bytes after a NUL, a force of a read-only variable, unknown
  attributes and commands, cut or misaligned messages ...), and every
  message got its answer;
* after ``unforce --all``: every task still runs, none faulted, the
  periodic ones' cycle counts advance; every variable holds a value of its
  type, the CONSTANTs are unchanged;
* the kernel log is clean; ``plc-manager stop`` leaves no module loaded.

The seed is printed; IEC2KMOD_NLFUZZ_SEED and IEC2KMOD_NLFUZZ_COUNT change
it and the number of messages.  Any number of messages, in a guest of its
own: ``python3 benchmarks/netlink_fuzz.py --messages N --seed S``.
"""

from __future__ import annotations

import compileall
import os
import shutil
import time
from pathlib import Path

import pytest

import netlink_fuzz as nf
from kmod_helpers import ROOT, gen_and_build, loaded_modules

pytestmark = pytest.mark.qemu
PROJECT = Path(__file__).resolve().parent / "projects" / "nl_fuzz"
SEED = int(os.environ.get("IEC2KMOD_NLFUZZ_SEED", "2323"))
COUNT = int(os.environ.get("IEC2KMOD_NLFUZZ_COUNT", "20000"))


def pm(guest, *args, timeout=300):
    r = guest.pyrun(script="plc-manager", argv=[str(a) for a in args], timeout=timeout)
    return r.exit_code, r.output


def test_netlink_fuzz_leaves_the_plc_running_and_every_value_typed(guest, guest_workdir):
    t0 = time.monotonic()
    tree = Path(guest_workdir) / "nl_fuzz"
    if tree.exists():
        shutil.rmtree(tree)
    manifest = gen_and_build(PROJECT, tree)
    compileall.compile_dir(str(ROOT / "manager"), quiet=1)
    t_build = time.monotonic() - t0
    rc, out = pm(guest, "load", tree)
    assert rc == 0, out
    t_load = time.monotonic() - t0 - t_build
    try:
        t1 = time.monotonic()
        res, before = nf.run(guest, Path(guest_workdir), manifest, SEED, COUNT)
        t_fuzz = time.monotonic() - t1
        print("\n" + res.summary())
        assert all(t["state"] == "running" for t in before["tasks"].values()), before["tasks"]
        problems = [f"message {i} (seed {SEED}) was acknowledged; the kernel must refuse it: "
                    f"{why}" for i, why in res.violations[:40]]
        if len(res.violations) > 40:
            problems.append(f"... {len(res.violations) - 40} more")
        if res.unanswered:
            problems.append(f"{res.unanswered} messages got no answer")
        t2 = time.monotonic()
        problems += nf.check_after(guest, manifest, before)
        guest.check_kernel_log()
        t_check = time.monotonic() - t2
    finally:
        t3 = time.monotonic()
        rc, out = pm(guest, "stop")
    assert rc == 0, f"plc-manager stop: {out}"
    left = loaded_modules(guest)
    print(f"build {t_build:.0f} s, load {t_load:.0f} s, fuzz (probe, generate, send) "
          f"{t_fuzz:.0f} s, checks {t_check:.0f} s, stop {time.monotonic() - t3:.0f} s, "
          f"total {time.monotonic() - t0:.0f} s")
    assert not problems, f"seed {SEED}, {COUNT} messages:\n" + "\n".join(problems)
    assert left == [], f"modules left after plc-manager stop: {left}"
