# SPDX-License-Identifier: MIT
"""Built projects (a directory with manifest.json, as `iec2kmod gen` and
`iec2kmod build` write it), program-type modules given for a swap, the
interface comparison that decides whether a swap is allowed, and the state
plc-manager keeps about the running configuration."""

from __future__ import annotations

import hashlib
import json
import os
import re
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, List, Optional

from . import kmod
from .errors import PLCError, UsageError

MANIFEST = "manifest.json"


class Project:
    """A project directory and its manifest."""

    def __init__(self, path: Path, manifest: dict, text: Optional[str] = None) -> None:
        self.path = path
        self.m = manifest
        self.text = text        # the manifest file as read (State copies it as it is)

    @classmethod
    def open(cls, path) -> "Project":
        p = Path(path).resolve()
        if not p.exists():
            raise UsageError(f"{path}: no such directory")
        if not p.is_dir():
            raise UsageError(f"{path}: not a directory")
        f = p / MANIFEST
        if not f.is_file():
            raise UsageError(f"{path}: no {MANIFEST} (not a project written by `iec2kmod gen`)")
        try:
            text = f.read_text()
            m = json.loads(text)
        except (OSError, ValueError) as e:
            raise UsageError(f"{f}: unreadable manifest: {e}") from None
        if not isinstance(m, dict):
            raise UsageError(f"{f}: not an iec2kmod manifest")
        for key in ("configuration", "load_order", "modules", "program_types", "variables"):
            if key not in m:
                raise UsageError(f"{f}: not an iec2kmod manifest (no {key!r})")
        if "digest" not in m:
            raise UsageError(f"{f}: no digest (written by an older iec2kmod, or by hand): "
                             f"run `iec2kmod gen` and `iec2kmod build` again")
        if m["digest"] != manifest_digest(m):
            raise UsageError(f"{f}: the manifest was changed after `iec2kmod gen` wrote it "
                             f"(its digest does not match): run `iec2kmod gen` and "
                             f"`iec2kmod build` again")
        return cls(p, m, text)

    # ------------------------------------------------------------------
    @property
    def configuration(self) -> str:
        return self.m["configuration"]

    def ko(self, module: str) -> Path:
        return self.path / module / f"{module}.ko"

    def module_kind(self, module: str) -> str:
        for m in self.m["modules"]:
            if m["name"] == module:
                return m["kind"]
        return "?"

    def program_type(self, name: str) -> Optional[dict]:
        for p in self.m["program_types"]:
            if p["name"].upper() == name.upper():
                return p
        return None

    def check_built(self, modules: Optional[List[str]] = None) -> None:
        for name in modules if modules is not None else self.m["load_order"]:
            if not self.ko(name).is_file():
                raise UsageError(f"{self.path}: {name}.ko is missing: the project is not built "
                                 f"(run `iec2kmod build {self.path}`)")

    def check_kernel(self, modules: Optional[List[str]] = None,
                     release: Optional[str] = None) -> None:
        """Every module was built for the running kernel."""
        release = release or os.uname().release
        built = self.m.get("kernel_release")
        if built and built != release:
            raise UsageError(f"{self.path}: built for kernel {built}, this is {release} "
                             f"(rebuild with `iec2kmod build {self.path}` on this kernel)")
        for name in modules if modules is not None else self.m["load_order"]:
            check_module_kernel(self.ko(name), release)


    def check_modules(self) -> None:
        """Every module file is the one the manifest names: the module of
        this configuration and of these sources (a file copied from another
        project or another build is refused before anything is inserted)."""
        for name in self.m["load_order"]:
            check_module_identity(self.ko(name), name, self.configuration,
                                  self.m.get("source_hash"))


_OF_CONFIG = re.compile(r"(?:configuration| of) (\S+?)(?:,|:| \(|$)")


def check_module_identity(ko: Path, name: str, configuration: str,
                          source_hash: Optional[str]) -> None:
    """*ko* is module *name* of *configuration*, built from the sources
    with *source_hash* (None: any build)."""
    try:
        info = kmod.modinfo(str(ko))
    except PLCError as e:
        raise UsageError(str(e)) from None
    desc = (info.get("description") or [""])[0]
    m = _OF_CONFIG.search(desc)
    if "(iec2kmod)" not in desc or not m:
        raise UsageError(f"{ko}: not a module written by iec2kmod")
    if m.group(1).lower() != configuration.lower():
        raise UsageError(f"{ko}: a module of configuration {m.group(1)}, not of "
                         f"{configuration}")
    got = (info.get("name") or ["?"])[0]
    if got != name:
        raise UsageError(f"{ko}: is module {got}, not {name} (a file of another build: run "
                         f"`iec2kmod build` again)")
    built = (info.get("iec_source_hash") or ["?"])[0]
    if source_hash is not None and built != source_hash:
        raise UsageError(f"{ko}: built from other sources ({built}) than the manifest's "
                         f"({source_hash}): run `iec2kmod gen` and `iec2kmod build` again")


def manifest_digest(manifest: dict) -> str:
    """The checksum `iec2kmod gen` writes into the manifest ("digest"):
    sha256 of its canonical JSON without "digest" and "kernel_release"
    (added by `iec2kmod build`).  The same as iec2kmod.kmod.manifest_digest."""
    body = {k: v for k, v in manifest.items() if k not in ("digest", "kernel_release")}
    return hashlib.sha256(json.dumps(body, sort_keys=True,
                                     separators=(",", ":")).encode()).hexdigest()[:32]


def check_module_kernel(ko: Path, release: Optional[str] = None) -> None:
    release = release or os.uname().release
    try:
        got = kmod.vermagic_release(str(ko))
    except PLCError as e:
        raise UsageError(str(e)) from None
    except OSError as e:
        raise UsageError(f"{ko}: {e.strerror}") from None
    if got != release:
        raise UsageError(f"{ko.name} was built for kernel {got or '?'}, this is {release} "
                         f"(rebuild it on this kernel)")


# ---------------------------------------------------------------------------
# interfaces

def interface_changes(old: List[dict], new: List[dict]) -> List[str]:
    """What changed between two program-type interfaces (manifest
    ``interface`` lists): variables added, removed, retyped, moved to
    another section, reordered."""
    o = {v["name"].upper(): v for v in old}
    n = {v["name"].upper(): v for v in new}
    out = []
    for k, v in o.items():
        if k not in n:
            out.append(f"variable removed: {v['name']} : {v['type']} ({v['section']})")
    for k, v in n.items():
        if k not in o:
            out.append(f"variable added: {v['name']} : {v['type']} ({v['section']})")
    for k, v in n.items():
        if k in o:
            if o[k]["type"].upper() != v["type"].upper():
                out.append(f"variable retyped: {v['name']} : {o[k]['type']} -> {v['type']}")
            if o[k]["section"] != v["section"]:
                out.append(f"variable {v['name']} moved from {o[k]['section']} to "
                           f"{v['section']}")
    if not out:
        common_o = [k for k in o if k in n]
        common_n = [k for k in n if k in o]
        if common_o != common_n:
            out.append("variables reordered: " + ", ".join(n[k]["name"] for k in common_n))
    return out


# ---------------------------------------------------------------------------
# swap candidates

@dataclass
class Candidate:
    """A rebuilt program-type module to swap in."""
    ko: Path
    module: str
    type_name: str
    build_id: str
    interface_hash: str
    entry: Optional[dict]          # its manifest entry (program_types), if known
    manifest: Optional[dict]       # the manifest it came with, if known
    configuration: Optional[str] = None   # the configuration it was built for


_DESC = re.compile(r"program type (\S+) of (\S+), build (\w+)")


def _candidate_from_ko(ko: Path, manifest: Optional[dict]) -> Candidate:
    info = kmod.modinfo(str(ko))
    module = (info.get("name") or [ko.stem])[0]
    m = _DESC.search((info.get("description") or [""])[0])
    if not m:
        raise UsageError(f"{ko}: not an iec2kmod program-type module")
    if manifest and manifest.get("configuration", "").lower() != m.group(2).lower():
        manifest = None            # not the manifest of this module's project
    entry = None
    if manifest:
        entry = next((p for p in manifest["program_types"] if p["module"] == module), None)
    if entry:
        return Candidate(ko, module, entry["name"], entry["build_id"],
                         entry["interface_hash"], entry, manifest, m.group(2))
    return Candidate(ko, module, m.group(1), m.group(3),
                     (info.get("iec_interface_hash") or ["?"])[0], None, manifest, m.group(2))


def swap_candidates(new: str, running_builds: Dict[str, str]) -> List[Candidate]:
    """The program-type modules NEW names: a .ko file, a module directory,
    or a project directory (every program type whose build differs from the
    one running; *running_builds* maps type name (upper) -> build id)."""
    p = Path(new).resolve()
    if not p.exists():
        raise UsageError(f"{new}: no such file or directory")
    if p.is_file():
        if p.suffix != ".ko":
            raise UsageError(f"{new}: not a kernel module (.ko), a module directory or a "
                             f"project directory")
        manifest = _manifest_near(p.parent.parent)
        return [_candidate_from_ko(p, manifest)]
    if (p / MANIFEST).is_file():
        proj = Project.open(p)
        out = []
        for t in proj.m["program_types"]:
            if running_builds.get(t["name"].upper()) == t["build_id"]:
                continue
            out.append(Candidate(proj.ko(t["module"]), t["module"], t["name"], t["build_id"],
                                 t["interface_hash"], t, proj.m, proj.configuration))
        return out
    ko = p / f"{p.name}.ko"
    if ko.is_file():
        return [_candidate_from_ko(ko, _manifest_near(p.parent))]
    if (p / "Kbuild").is_file():
        raise UsageError(f"{new}: module directory without {p.name}.ko (not built)")
    raise UsageError(f"{new}: not a kernel module (.ko), a module directory or a project "
                     f"directory with {MANIFEST}")


def _manifest_near(d: Path) -> Optional[dict]:
    """The manifest of the project a module directory sits in, if there is
    one (checked like any other: an edited one is refused)."""
    if not (d / MANIFEST).is_file():
        return None
    return Project.open(d).m


# ---------------------------------------------------------------------------
# state

def state_dir() -> Path:
    return Path(os.environ.get("PLC_MANAGER_STATE_DIR", "/run/plc-manager"))


def _io_summary(m: dict) -> dict:
    """The state's "io" (bindings) and "irqs" (interrupt sources), when
    the project has them."""
    from .io import interrupt_summary, summary
    irqs = interrupt_summary(m)
    return {"io": summary(m), **({"irqs": irqs} if irqs else {})} if m.get("io") else {}


class State:
    """What plc-manager remembers about the running configuration, in two
    files of state_dir():

    <configuration>.json           small, rewritten by every swap: the
                                   configuration, its source and interface
                                   hashes, the project directory, and the
                                   build each swapped slot runs now;
    <configuration>.manifest.json  the manifest it was loaded from (a copy:
                                   the project directory may be regenerated
                                   for a swap), written once by load, read
                                   only by a command that needs it
                                   (variables, instances).

    A swap thus reads and writes a few hundred bytes, not a plant's
    manifest (megabytes, tens of ms to parse in the guest)."""

    def __init__(self, data: dict, manifest: Optional[dict] = None,
                 manifest_dirty: bool = False, manifest_text: Optional[str] = None) -> None:
        self.data = data
        self.data.setdefault("slots", {})
        self._manifest = manifest
        self._manifest_dirty = manifest_dirty
        # the file the manifest was read from, written as it is (no slot of
        # it is swapped yet): a plant's manifest takes a third of a second to
        # serialise again in the guest
        self._manifest_text = manifest_text
        if manifest is not None:
            self._apply(manifest)

    @property
    def configuration(self) -> str:
        return self.data["configuration"]

    @property
    def interface_hash(self) -> Optional[str]:
        return self.data.get("interface_hash")

    @property
    def source_hash(self) -> Optional[str]:
        return self.data.get("source_hash")

    @property
    def manifest(self) -> dict:
        """The manifest, with the swapped slots' builds (read on first use)."""
        if self._manifest is None:
            p = self.manifest_path(self.configuration)
            try:
                m = json.loads(p.read_text())
            except (OSError, ValueError) as e:
                raise PLCError(f"the manager's copy of the manifest, {p}, cannot be read "
                               f"({getattr(e, 'strerror', None) or e}): `plc-manager stop` "
                               f"and load again") from None
            self._apply(m)
            self._manifest = m
        return self._manifest

    def _apply(self, m: dict) -> None:
        for t in m.get("program_types", []):
            rec = self.data["slots"].get(t["name"].upper())
            if rec:
                t.update(rec)

    def record(self, type_name: str, module: str, build_id: str, ko: Optional[str]) -> None:
        """Records that *module* (build *build_id*, file *ko*) runs in the
        slot of *type_name* now (a swap: same interface)."""
        rec = {"module": module, "build_id": build_id}
        if ko:
            rec["ko"] = ko
        self.data["slots"].setdefault(type_name.upper(), {}).update(rec)
        if self._manifest is not None:
            self._apply(self._manifest)

    @classmethod
    def path(cls, configuration: str) -> Path:
        return state_dir() / f"{configuration.lower()}.json"

    @classmethod
    def manifest_path(cls, configuration: str) -> Path:
        return state_dir() / f"{configuration.lower()}.manifest.json"

    @classmethod
    def load(cls, configuration: str) -> Optional["State"]:
        try:
            data = json.loads(cls.path(configuration).read_text())
        except (OSError, ValueError):
            return None
        if not isinstance(data, dict) or "configuration" not in data:
            return None
        if "manifest" in data:          # the one-file state of earlier versions
            m = data.pop("manifest")
            data.update(interface_hash=m.get("interface_hash"),
                        source_hash=m.get("source_hash"))
            return cls(data, m, manifest_dirty=True)
        return cls(data)

    @classmethod
    def create(cls, project: Project) -> "State":
        m = project.m
        return cls({"configuration": project.configuration, "project": str(project.path),
                    "interface_hash": m.get("interface_hash"),
                    "source_hash": m.get("source_hash"), "slots": {},
                    # the I/O bindings (plc-manager status): a few lines,
                    # where the manifest may be megabytes
                    **_io_summary(m)},
                   m, manifest_dirty=True, manifest_text=getattr(project, "text", None))

    @staticmethod
    def _write(p: Path, text: str) -> None:
        try:
            p.parent.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(dir=p.parent, prefix=".state-")
            with os.fdopen(fd, "w") as f:
                f.write(text)
            os.replace(tmp, p)
        except OSError as e:
            raise PLCError(f"cannot save the manager's state in {p.parent}: {e.strerror}") \
                from None

    def save(self) -> None:
        # dumps, not dump: json.dump streams through the pure-Python
        # encoder, four times slower on a plant-sized manifest (about two
        # seconds of `load` in the icount guest)
        if self._manifest_dirty:
            # the swaps are in the small file (applied on reading)
            text = self._manifest_text
            if text is None:
                text = json.dumps(self._manifest)
            self._write(self.manifest_path(self.configuration), text)
            self._manifest_dirty = False
            self._manifest_text = None
        self._write(self.path(self.configuration), json.dumps(self.data))

    @classmethod
    def remove(cls, configuration: str) -> None:
        for p in (cls.path(configuration), cls.manifest_path(configuration)):
            try:
                p.unlink()
            except OSError:
                pass
