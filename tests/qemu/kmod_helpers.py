"""Helpers of the QEMU tier: build a project's modules on the host into the
guest's work directory, load them in the guest, read the sysfs status."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def gen_and_build(project: Path, out: Path) -> dict:
    """`iec2kmod gen` + `iec2kmod build`, as a user would; returns the manifest."""
    if out.exists():
        shutil.rmtree(out)
    for cmd in (["gen", str(project), "-o", str(out)], ["build", str(out)]):
        p = subprocess.run([sys.executable, "-m", "iec2kmod.cli", *cmd], cwd=ROOT,
                           capture_output=True, text=True, timeout=900)
        assert p.returncode == 0, f"iec2kmod {' '.join(cmd)} failed:\n{p.stdout}{p.stderr}"
    return json.loads((out / "manifest.json").read_text())


def load(guest, tree: Path, manifest: dict):
    for name in manifest["load_order"]:
        r = guest.run(f"insmod {tree / name / (name + '.ko')}")
        assert r.exit_code == 0, f"insmod {name}: {r.output}"


def sysfs(manifest) -> str:
    return f"/sys/kernel/iec2kmod/{manifest['configuration'].lower()}"


def control(guest, manifest, command: str):
    r = guest.run(f"echo {command} > {sysfs(manifest)}/control")
    assert r.exit_code == 0, r.output


def status(guest, manifest) -> dict:
    """Tasks and slots from the sysfs status file."""
    text = guest.run(f"cat {sysfs(manifest)}/status").output
    tasks, slots = {}, {}
    for line in text.splitlines():
        words = line.split()
        if not words:
            continue
        if words[0] == "task":
            fields = dict(zip(words[2::2], words[3::2]))
            m = re.search(r" faults \d+ fault (.*?) pou (\S+) line (\d+)(?: |$)", line)
            fields["fault"], fields["pou"], fields["line"] = m.groups()
            tasks[words[1]] = fields
        elif words[0] == "slot":
            slots[words[2]] = dict(zip(words[3::2], words[4::2]))
    return {"tasks": tasks, "slots": slots, "text": text}


def unload(guest, manifest):
    """The manager's stop sequence: stop, remove resources, clear the GFT,
    remove program types, remove the configuration."""
    control(guest, manifest, "stop all")
    order = manifest["load_order"]
    res = [m["name"] for m in manifest["modules"] if m["kind"] == "resource"]
    for name in reversed(order):
        if name in res:
            r = guest.run(f"rmmod {name}")
            assert r.exit_code == 0, f"rmmod {name}: {r.output}"
    control(guest, manifest, "clear all")
    for name in reversed(order):
        if name not in res:
            r = guest.run(f"rmmod {name}")
            assert r.exit_code == 0, f"rmmod {name}: {r.output}"


def loaded_modules(guest) -> list[str]:
    return [ln.split()[0] for ln in guest.run("cat /proc/modules").output.splitlines()
            if ln.startswith("iec_")]


def pm(guest, *args, check=0, timeout=300):
    """plc-manager ARGS in the guest: (exit code, output); the exit code must
    be *check* (None: any)."""
    r = guest.pyrun(script="plc-manager", argv=[str(a) for a in args], timeout=timeout)
    assert check is None or r.exit_code == check, \
        f"plc-manager {' '.join(map(str, args))}: exit {r.exit_code}\n{r.output}"
    return r.exit_code, r.output


def kernel_modules(guest) -> set:
    """Every module loaded in the guest (/proc/modules)."""
    return {ln.split()[0] for ln in guest.run("cat /proc/modules").output.splitlines()
            if ln.strip()}
