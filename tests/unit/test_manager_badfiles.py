"""Every kind of bad file given to `plc-manager load` or `swap` (issue 9,
item 4): truncated, zero bytes, not ELF, an ELF that is no module, a module
for another architecture, a module of another configuration or of another
build, a manifest edited by hand, the directory of another project.  Each
gets one line and exit 1 before anything is inserted (kmod.insert is
replaced by a recorder that must stay empty).

The project is the QEMU tier's tests/qemu/projects/faults written by
`iec2kmod gen`; its .ko files are made here: minimal ELF relocatable objects
whose .modinfo carries what kbuild would write (name, vermagic of the
running kernel, the description and hashes of the templates), so no kernel
build is needed.  What a real insert does with nothing refused is the QEMU
tier's (tests/qemu/test_faults.py checks that a refused load and swap
change nothing in the guest).
"""

from __future__ import annotations

import json
import os
import shutil
import struct
import subprocess
import sys
from pathlib import Path

import pytest

from plc_manager import cli, kmod, ops, project
from plc_manager.errors import PLCError
from plc_manager.netlink import Resource, Slot, Status, Task

ROOT = Path(__file__).resolve().parents[2]
FAULTS = ROOT / "tests" / "qemu" / "projects" / "faults"
EM_X86_64, EM_AARCH64 = 62, 183


def elf_module(modinfo: dict, machine: int = EM_X86_64, etype: int = 1) -> bytes:
    """An ELF64 little-endian object with a .modinfo section."""
    info = b"".join(f"{k}={v}".encode() + b"\0" for k, v in modinfo.items())
    shstr = b"\0.modinfo\0.shstrtab\0"
    off_info = 64
    off_str = off_info + len(info)
    shoff = (off_str + len(shstr) + 7) & ~7
    head = b"\x7fELF" + bytes([2, 1, 1]) + bytes(9)
    head += struct.pack("<HHIQQQIHHHHHH", etype, machine, 1, 0, 0, shoff, 0, 64, 0, 0, 64, 3, 2)
    body = head + info + shstr
    body += bytes(shoff - len(body))

    def sh(name, typ, off, size):
        return struct.pack("<IIQQQQIIQQ", name, typ, 0, 0, off, size, 0, 0, 1, 0)
    body += sh(0, 0, 0, 0) + sh(1, 1, off_info, len(info)) + sh(10, 3, off_str, len(shstr))
    return body


def modinfo_of(m: dict, mod: dict, config: str) -> dict:
    kind = mod["kind"]
    if kind == "configuration":
        desc = f"IEC 61131-3 configuration {config}: globals and GFT (iec2kmod)"
    elif kind == "program":
        desc = (f"IEC 61131-3 program type {mod['program_type']} of {config}, build "
                f"{mod['build_id']} (iec2kmod)")
    else:
        desc = (f"IEC 61131-3 resource {mod['resource']} of {config}: tasks and program "
                f"instances (iec2kmod)")
    return {"license": "Dual MIT/GPL", "description": desc,
            "iec_source_hash": m["source_hash"],
            "iec_interface_hash": mod.get("interface_hash", m["interface_hash"]),
            "name": mod["name"],
            "vermagic": f"{os.uname().release} SMP preempt mod_unload modversions "}


def make_project(src: Path, out: Path) -> dict:
    p = subprocess.run([sys.executable, "-m", "iec2kmod.cli", "gen", str(src), "-o", str(out)],
                       cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stdout + p.stderr
    m = json.loads((out / "manifest.json").read_text())
    for mod in m["modules"]:
        ko = out / mod["name"] / f"{mod['name']}.ko"
        ko.write_bytes(elf_module(modinfo_of(m, mod, m["configuration"])))
    return m


@pytest.fixture(scope="module")
def projects(tmp_path_factory):
    base = tmp_path_factory.mktemp("badfiles")
    good = base / "good"
    m = make_project(FAULTS, good)
    # the same program with a fixed Faulty (same interface): a swap candidate
    src_b = base / "src_b"
    src_b.mkdir()
    text = (FAULTS / "faults.st").read_text()
    (src_b / "faults.st").write_text(text.replace("1000 / divisor;", "1000 / MAX(divisor, 1);"))
    fixed = base / "fixed"
    mb = make_project(src_b, fixed)
    # another configuration (same program types, another name)
    src_o = base / "src_o"
    src_o.mkdir()
    (src_o / "faults.st").write_text(text.replace("CONFIGURATION Faults", "CONFIGURATION Other"))
    other = base / "other"
    mo = make_project(src_o, other)
    return base, good, m, fixed, mb, other, mo


@pytest.fixture
def no_insert(monkeypatch):
    inserted = []

    def insert(path, params=""):
        inserted.append(path)
        raise PLCError("reached insert")
    monkeypatch.setattr(kmod, "insert", insert)
    monkeypatch.setattr(kmod, "require", lambda cap, what: None)
    monkeypatch.setattr(kmod, "loaded", lambda: {})
    monkeypatch.setattr(ops, "_loaded_configurations", lambda: [])
    return inserted


def copy(src: Path, dst: Path) -> Path:
    if dst.exists():
        shutil.rmtree(dst)
    shutil.copytree(src, dst)
    return dst


def refused_load(path, want, capsys):
    assert cli.main(["load", str(path)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("plc-manager: "), err
    assert want in err[0], (want, err[0])


def test_a_good_project_reaches_insert(projects, no_insert, capsys):
    _, good, m, *_ = projects
    refused_load(good, "reached insert", capsys)
    assert [Path(p).stem for p in no_insert] == [m["load_order"][0]]


def _bad_files(m, good: Path, base: Path):
    """(what, how the file of module *victim* is replaced, expected text)."""
    prog = next(x for x in m["modules"] if x["kind"] == "program")
    data = (good / prog["name"] / f"{prog['name']}.ko").read_bytes()
    other_mod = dict(prog, name=prog["name"])
    return prog, [
        ("truncated", data[:len(data) // 2], "not a valid kernel module (truncated or corrupt"),
        ("headers only", data[:64], "not a valid kernel module (truncated or corrupt"),
        ("zero bytes", b"", "not a 64-bit ELF kernel module"),
        ("not ELF", b"obj-m += x.o\n" * 20, "not a 64-bit ELF kernel module"),
        ("an ELF program", Path(shutil.which("true") or "/bin/true").read_bytes(),
         "not a kernel module (an ELF "),
        ("another architecture",
         elf_module(modinfo_of(m, other_mod, m["configuration"]), machine=EM_AARCH64),
         "a module for another architecture (aarch64), this machine is"),
        ("another configuration", elf_module(modinfo_of(m, other_mod, "Other")),
         "a module of configuration Other, not of Faults"),
        ("another module", elf_module(dict(modinfo_of(m, other_mod, m["configuration"]),
                                           name="iec_faults_p_faulty_00000000")),
         "is module iec_faults_p_faulty_00000000, not " + prog["name"]),
        ("another build", elf_module(dict(modinfo_of(m, other_mod, m["configuration"]),
                                          iec_source_hash="0123456789abcdef")),
         "built from other sources (0123456789abcdef)"),
        ("no module of ours", elf_module({"name": prog["name"], "description": "a driver",
                                          "vermagic": f"{os.uname().release} SMP "}),
         "not a module written by iec2kmod"),
    ]


@pytest.mark.skipif(os.uname().machine != "x86_64", reason="the fake modules are x86-64")
def test_load_refuses_every_kind_of_bad_module_file(projects, no_insert, capsys):
    base, good, m, *_ = projects
    prog, cases = _bad_files(m, good, base)
    for what, data, want in cases:
        d = copy(good, base / "bad_load")
        (d / prog["name"] / f"{prog['name']}.ko").write_bytes(data)
        refused_load(d, want, capsys)
    assert no_insert == []


def test_load_refuses_an_edited_manifest_or_another_project(projects, no_insert, capsys):
    base, good, m, *_ = projects
    edits = [
        ("a variable retyped", lambda x: x["variables"][0].update(type="LINT")),
        ("the load order changed", lambda x: x["load_order"].reverse()),
        ("a build id changed", lambda x: x["program_types"][0].update(build_id="deadbeef")),
        ("the configuration renamed", lambda x: x.update(configuration="Other")),
    ]
    for what, edit in edits:
        d = copy(good, base / "edited")
        mm = json.loads((d / "manifest.json").read_text())
        edit(mm)
        (d / "manifest.json").write_text(json.dumps(mm, indent=2))
        refused_load(d, "the manifest was changed after `iec2kmod gen` wrote it", capsys)
    d = copy(good, base / "edited")
    mm = json.loads((d / "manifest.json").read_text())
    del mm["digest"]
    (d / "manifest.json").write_text(json.dumps(mm))
    refused_load(d, "no digest (written by an older iec2kmod, or by hand)", capsys)
    # `iec2kmod build` adds the kernel release: not an edit
    mm = json.loads((good / "manifest.json").read_text())
    mm["kernel_release"] = os.uname().release
    d = copy(good, base / "built")
    (d / "manifest.json").write_text(json.dumps(mm))
    refused_load(d, "reached insert", capsys)
    no_insert.clear()
    # the directory of another project
    for name, content in (("npm", {"name": "x", "version": "1.0.0"}), ("list", [1, 2]),
                          ("string", "manifest")):
        d = base / f"proj_{name}"
        d.mkdir(exist_ok=True)
        (d / "manifest.json").write_text(json.dumps(content))
        refused_load(d, "not an iec2kmod manifest", capsys)
    assert no_insert == []


def _running(m) -> Status:
    tasks = {r["name"]: [Task(name=t["name"], resource=r["name"].lower(), state="fault",
                              interval_ns=10_000_000, priority=2, last_cpu=0, cycles=5,
                              overruns=0, faults=1, exec_min_ns=1, exec_avg_ns=1,
                              exec_max_ns=1, latency_avg_ns=1, latency_max_ns=1, histogram=[])
                         for t in r.get("tasks", [])] for r in m["resources"]}
    return Status(abi=1, configuration=m["configuration"], module=m["load_order"][0],
                  source_hash=m["source_hash"], interface_hash=m["interface_hash"], now_ns=0,
                  forced=0,
                  resources=[Resource(name=r["name"].lower(), module=r["module"], cpu=-1,
                                      tasks=tasks[r["name"]]) for r in m["resources"]],
                  slots=[Slot(index=p["slot"], type_name=p["name"].upper(),
                              interface=p["interface_hash"], module=p["module"],
                              build_id=p["build_id"], since_ns=0, publications=1)
                         for p in m["program_types"]])


class FakeClient:
    def __init__(self, st):
        self.st = st

    def status(self, slots_only=False):
        return self.st

    def __enter__(self):
        return self

    def __exit__(self, *a):
        pass


@pytest.mark.skipif(os.uname().machine != "x86_64", reason="the fake modules are x86-64")
def test_swap_refuses_every_kind_of_bad_file(projects, no_insert, capsys, monkeypatch,
                                             tmp_path):
    base, good, m, fixed, mb, other, mo = projects
    monkeypatch.setattr(ops, "connect", lambda what="": FakeClient(_running(m)))
    monkeypatch.setattr(project, "state_dir", lambda: tmp_path)

    def refused(arg, want):
        assert cli.main(["swap", str(arg)]) == 1
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("plc-manager: "), err
        assert want in err[0], (arg, want, err[0])

    # the fixed build is accepted up to the insert
    refused(fixed, "reached insert")
    no_insert.clear()
    faulty = next(p for p in mb["program_types"] if p["name"] == "Faulty")["module"]
    prog, cases = _bad_files(mb, fixed, base)
    # the module alone: what it says of itself is all there is to check
    alone = {"another configuration": "belongs to configuration Other, the running one is",
             "another module": None,       # a module of that name: nothing wrong with it
             "no module of ours": "not an iec2kmod program-type module"}
    for what, data, want in cases:
        d = copy(fixed, base / "bad_swap")
        ko = d / prog["name"] / f"{prog['name']}.ko"
        ko.write_bytes(data)
        refused(d, want)                    # the project form
        want = alone.get(what, want)
        if want:
            refused(ko, want)               # the module form
    # the project and a module of another configuration
    refused(other, "belongs to configuration Other, the running one is Faults")
    oko = next(p for p in mo["program_types"] if p["name"] == "Faulty")["module"]
    refused(other / oko / f"{oko}.ko", "belongs to configuration Other, the running one is")
    # an edited manifest beside a module, or of a project
    d = copy(fixed, base / "edited_swap")
    mm = json.loads((d / "manifest.json").read_text())
    mm["program_types"][0]["interface_hash"] = "0" * 16
    (d / "manifest.json").write_text(json.dumps(mm))
    refused(d, "the manifest was changed after")
    refused(d / faulty / f"{faulty}.ko", "the manifest was changed after")
    assert no_insert == []


def test_the_manager_computes_the_generators_digest(projects):
    from iec2kmod.kmod import manifest_digest
    _, good, m, *_ = projects
    assert m["digest"] == manifest_digest(m) == project.manifest_digest(m)
    assert project.manifest_digest(dict(m, kernel_release="x")) == m["digest"]
