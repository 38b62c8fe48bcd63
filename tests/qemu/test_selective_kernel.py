# SPDX-License-Identifier: MIT
"""QEMU tier: selective execution (``iec2kmod gen --selective``) in the
PREEMPT_RT guest, with plc-manager.

tests/qemu/projects/selective is built twice with --selective: A as
written, B with another algorithm in the Station function block (same
interface; only its program-type module is built, and swapped in as a
module).  In the guest:

* the task statistics count evaluated and skipped blocks (``plc-manager
  status``, text and --json); while the inputs do not change, the skipped
  count grows with the cycles and the evaluated count does not;
* the program follows its inputs (written by the manager: globals copied
  into the task's image) and latches a trip in its function blocks' state;
* a hot swap while the blocks are being skipped: the new body runs at once
  although no input changed (the module's token differs, every block is
  evaluated once by the new code), and the latched state stays (it lives
  in the instances, in the resource module);
* stop leaves nothing loaded; the kernel log stays clean (fixture)."""

from __future__ import annotations

import compileall
import json
import shutil
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import pytest

from iec2kmod import kbuild
from kmod_helpers import loaded_modules

pytestmark = pytest.mark.qemu
HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
PROJECT = HERE / "projects" / "selective"
ALGO_A = "setpoint := demand * 2;    (* ALGO *)"
ALGO_B = "setpoint := demand * 3;    (* ALGO *)"


def _gen_build(src: Path, out: Path):
    if out.exists():
        shutil.rmtree(out)
    for cmd in (["gen", str(src), "-o", str(out), "--selective"], ["build", str(out)]):
        p = subprocess.run([sys.executable, "-m", "iec2kmod.cli", *cmd], cwd=ROOT,
                           capture_output=True, text=True, timeout=900)
        assert p.returncode == 0, f"iec2kmod {' '.join(cmd)} failed:\n{p.stdout}{p.stderr}"
    return json.loads((out / "manifest.json").read_text())


@pytest.fixture(scope="module")
def lines(guest_workdir, kdir):
    base = Path(guest_workdir) / "selective"
    if base.exists():
        shutil.rmtree(base)
    base.mkdir()
    a = base / "a"
    ma = _gen_build(PROJECT, a)
    src_b = base / "src_b"
    src_b.mkdir()
    text = (PROJECT / "line.st").read_text()
    assert ALGO_A in text
    (src_b / "line.st").write_text(text.replace(ALGO_A, ALGO_B))
    # B: only its program-type module is built (the swap inserts nothing else)
    b = base / "b"
    p = subprocess.run([sys.executable, "-m", "iec2kmod.cli", "gen", str(src_b), "-o", str(b),
                        "--selective"], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stdout + p.stderr
    mb = json.loads((b / "manifest.json").read_text())
    ta = {m["name"]: m for m in ma["program_types"]}
    tb = {m["name"]: m for m in mb["program_types"]}
    assert ta["Line"]["interface_hash"] == tb["Line"]["interface_hash"]
    assert ta["Line"]["build_id"] != tb["Line"]["build_id"]
    mod = tb["Line"]["module"]
    kbuild.build_modules(str(b / mod), kdir=kdir, extra_args=[
        f"KBUILD_EXTRA_SYMBOLS={a / 'Module.symvers'}"]).check()
    compileall.compile_dir(str(ROOT / "manager"), quiet=1)
    return SimpleNamespace(a=a, b_ko=b / mod / f"{mod}.ko")


def pm(guest, *args):
    r = guest.pyrun(script="plc-manager", argv=[str(a) for a in args], timeout=300)
    assert r.exit_code == 0, f"plc-manager {' '.join(map(str, args))}: exit {r.exit_code}\n" \
                             f"{r.output}"
    return r.output


def task(guest):
    st = json.loads(pm(guest, "status", "--json"))
    (t,) = [t for r in st["resources"] for t in r["tasks"]]
    return t


def value(guest, name):
    return json.loads(pm(guest, "read", "--json", name))[0]["value"]


def wait_for(guest, name, want, timeout=20.0):
    deadline = time.monotonic() + timeout
    while True:
        v = value(guest, name)
        if v == want:
            return
        assert time.monotonic() < deadline, f"{name} = {v!r}, expected {want!r}"
        time.sleep(0.1)


def skipping(guest):
    """While nothing changes, cycles are skipped and nothing is evaluated."""
    t0 = task(guest)
    time.sleep(0.5)
    t1 = task(guest)
    cycles = t1["cycles"] - t0["cycles"]
    assert cycles > 10, (t0, t1)
    assert t1["sel_evaluated"] == t0["sel_evaluated"], (t0, t1)
    # one skip per cycle (the program instance); status reads the counters
    # at two moments between which a cycle may be half counted
    assert abs((t1["sel_skipped"] - t0["sel_skipped"]) - cycles) <= 2, (t0, t1)
    return t1


def test_selective_modules_in_the_guest(guest, lines):
    out = pm(guest, "load", lines.a)
    assert "loaded SelLine" in out, out
    try:
        wait_for(guest, "sp_total", 92)                  # 2 * (10 + 11 + 12 + 13)
        t = skipping(guest)
        assert t["state"] == "running" and t["sel_evaluated"] >= 5, t
        human = pm(guest, "status")
        assert "BLOCKS EVALUATED" in human and "main.fast" in human, human

        # inputs through the task image; a trip latched in the stations' state
        pm(guest, "write", "en", "TRUE")
        wait_for(guest, "n_running", 4)
        pm(guest, "write", "guard", "FALSE")
        wait_for(guest, "n_running", 0)
        pm(guest, "write", "guard", "TRUE")
        time.sleep(0.2)
        assert value(guest, "n_running") == 0             # s1, s2 stay tripped
        assert value(guest, "main.line1.s1.tripped") is True
        before = skipping(guest)

        # hot swap while every block is skipped: the new algorithm runs at
        # once, the latched trips stay
        out = pm(guest, "swap", lines.b_ko)
        assert "swapped LINE" in out, out
        wait_for(guest, "sp_total", 138)                 # 3 * (10 + 11 + 12 + 13)
        after = skipping(guest)
        assert after["sel_evaluated"] > before["sel_evaluated"]
        assert value(guest, "n_running") == 0
        assert value(guest, "main.line1.s1.tripped") is True

        # reset and run again under the new body
        pm(guest, "write", "en", "FALSE")
        wait_for(guest, "main.line1.s1.tripped", False)
        pm(guest, "write", "en", "TRUE")
        wait_for(guest, "n_running", 4)
        pm(guest, "write", "dem", "20")
        wait_for(guest, "sp_total", 3 * (20 + 21 + 22 + 23))
        skipping(guest)
    finally:
        pm(guest, "stop")
    assert loaded_modules(guest) == []
