"""QEMU tier: pointer members in the kernel (issue 8).

The program of issue 8 (an FB reaching a global through VAR_EXTERNAL inside
a program) oopsed the kernel with a NULL dereference in the task thread.
Here it runs and counts, as does a configuration with externals at depth 3,
in arrays of FB instances, of ARRAY/STRING/CONSTANT globals, a program's
VAR_GLOBAL and VAR_IN_OUT, over two resources; and a resource module whose
binding table was tampered with refuses to load, naming the pointer."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import pytest

from kmod_helpers import ROOT, control, gen_and_build, loaded_modules, status

pytestmark = pytest.mark.qemu
CASES = ROOT / "tests" / "execution" / "cases" / "config"


def manager(guest, *argv, timeout=300):
    r = guest.pyrun(script="plc-manager", argv=[str(a) for a in argv], timeout=timeout)
    return r.exit_code, r.output


def _run_until(guest, tree, manifest, cycles, paths):
    rc, out = manager(guest, "load", tree)
    assert rc == 0, out
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            tasks = status(guest, manifest)["tasks"]
            if all(int(t["cycles"]) >= cycles for t in tasks.values()):
                break
            time.sleep(0.5)
        else:
            pytest.fail(status(guest, manifest)["text"])
        rc, out = manager(guest, "stop", "--keep-loaded")   # one consistent state to read
        assert rc == 0, out
        rc, out = manager(guest, "read", "--json", *paths)
        assert rc == 0, out
        return {v["path"]: v["value"] for v in json.loads(out)}, status(guest, manifest)
    finally:
        rc, out = manager(guest, "stop")
        assert rc == 0, out
        assert loaded_modules(guest) == []


def test_fb_external_in_a_program_runs_and_counts(guest, guest_workdir):
    tree = Path(guest_workdir) / "fb_external_minimal"
    manifest = gen_and_build(CASES / "fb_external_minimal.st", tree)
    values, st = _run_until(guest, tree, manifest, 20, ["G"])
    task = st["tasks"]["R.T"] if "R.T" in st["tasks"] else next(iter(st["tasks"].values()))
    assert task["fault"] == "none", st["text"]
    assert int(values["G"]) >= 20, values


def test_externals_at_every_depth_run_in_the_kernel(guest, guest_workdir):
    tree = Path(guest_workdir) / "fb_external_depth"
    manifest = gen_and_build(CASES / "fb_external_depth.st", tree)
    values, st = _run_until(guest, tree, manifest, 10, ["g", "a[2]", "h", "r1.local",
                                                        "r1.d.seen_k", "s"])
    assert all(t["fault"] == "none" for t in st["tasks"].values()), st["text"]
    def wrap(x):   # INT arithmetic wraps around
        return (x + 0x8000) % 0x10000 - 0x8000

    n = int(values["h"])   # io (connected to h) counts the cycles of r1.t
    assert n >= 10
    # every pointer of every depth reached its global in the same cycle
    assert int(values["r1.local"]) == wrap(2 * n)
    assert int(values["a[2]"]) == 2 * n
    assert int(values["r1.d.seen_k"]) == wrap(20 * n)
    assert int(values["g"]) == wrap(104 * n)
    assert values["s"] == "xxxxx"


def test_a_module_with_an_unbound_pointer_refuses_to_load(guest, guest_workdir):
    """The generator's own check is switched off and the table truncated as
    the bug did; the resource module's init check must refuse the insert."""
    tree = Path(guest_workdir) / "fb_unbound"
    script = f"""
import sys
from iec2kmod import kmod
from iec2kmod.parse import frontend
from iec2kmod.checks import config as C
from iec2kmod.codegen import plan as P
real = C.ConfigChecker._bind
def only_top(self, pou, scope, r, inst, stack, src, steps):
    real(self, pou, scope, r, inst, stack, src, steps)
    inst.bindings[:] = [b for b in inst.bindings if len(b.steps) == 1]
C.ConfigChecker._bind = only_top
P.check_bindings = lambda ip: None
res = frontend.run([{str(CASES / 'fb_external_minimal.st')!r}], use_cache=False)
kmod.generate_tree(res.project, __import__('pathlib').Path({str(tree)!r}))
"""
    p = subprocess.run([sys.executable, "-c", script], cwd=ROOT, capture_output=True,
                       text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    p = subprocess.run([sys.executable, "-m", "iec2kmod.cli", "build", str(tree)], cwd=ROOT,
                       capture_output=True, text=True, timeout=900)
    assert p.returncode == 0, p.stdout + p.stderr
    manifest = json.loads((tree / "manifest.json").read_text())
    res = [m["name"] for m in manifest["modules"] if m["kind"] == "resource"]
    inserted = []
    try:
        for name in manifest["load_order"]:
            r = guest.run(f"insmod {tree / name / (name + '.ko')}")
            if name in res:
                assert r.exit_code != 0, f"insmod {name} succeeded with an unbound pointer"
                assert "Invalid argument" in r.output, r.output
            else:
                assert r.exit_code == 0, r.output
                inserted.append(name)
        log = guest.run("dmesg | tail -n 20").output
        assert "pointer member R.I.X.G is not bound; not loading" in log, log
    finally:
        if inserted:
            control(guest, manifest, "clear all")   # the program type's GFT slot
        for name in reversed(inserted):
            r = guest.run(f"rmmod {name}")
            assert r.exit_code == 0, r.output
    assert loaded_modules(guest) == []
