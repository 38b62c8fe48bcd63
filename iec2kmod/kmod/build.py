"""`iec2kmod build OUT [--kdir DIR] [--container] [--sparse]`: kbuild of a
generated tree, module by module in load order (the configuration module
first, the others with its Module.symvers), W=1; with --sparse also C=1
(every source checked by sparse; a sparse warning fails the build like a
compiler warning).  Compiler messages about generated
files are mapped back to the IEC source where the generated line says
where it came from."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

from .. import kbuild


class BuildError(Exception):
    def __init__(self, message, exit_code=1):
        super().__init__(message)
        self.exit_code = exit_code


@dataclass
class TreeBuild:
    kdir: str
    release: str
    modules: list = field(default_factory=list)      # .ko paths in load order
    warnings: list = field(default_factory=list)
    messages: list = field(default_factory=list)


def load_manifest(tree: Path) -> dict:
    path = tree / "manifest.json"
    try:
        return json.loads(path.read_text())
    except FileNotFoundError:
        raise BuildError(f"{tree}: no manifest.json (write the tree with `iec2kmod gen`)",
                         2) from None
    except (OSError, ValueError) as exc:
        raise BuildError(f"{path}: {exc}", 2) from None


def build_tree(tree, kdir=None, container=False, jobs=0, sparse=False) -> TreeBuild:
    tree = Path(tree).resolve()
    manifest = load_manifest(tree)
    if container and sparse:
        raise BuildError("--sparse runs on the host only (the build container has no "
                         "sparse): drop --container or --sparse", 2)
    if container:
        return _build_in_container(tree, manifest, kdir, jobs)
    try:
        kdir = kdir or kbuild.find_kdir()
        release = kbuild.kernel_release(kdir)
    except kbuild.KbuildError as exc:
        raise BuildError(str(exc), 2) from None
    result = TreeBuild(kdir, release)
    try:
        res = kbuild.build_modules(str(tree), kdir=kdir, jobs=jobs or None, sparse=sparse)
    except kbuild.KbuildError as exc:
        raise BuildError(str(exc), 2) from None
    if not res.ok:
        raise BuildError(f"kbuild failed:\n{_explain(res.output, tree)}", 70)
    result.warnings = res.warnings()
    for name in manifest["load_order"]:
        ko = tree / name / f"{name}.ko"
        if not ko.exists():
            raise BuildError(f"kbuild did not produce {ko}", 70)
        result.modules.append(str(ko))
    result.messages.append(f"built {len(result.modules)} modules in {res.duration:.1f} s: " +
                           ", ".join(manifest["load_order"]))
    _split_debug(result.modules)
    manifest["kernel_release"] = release
    _write_manifest(tree, manifest)
    if result.warnings:
        raise BuildError("the generated modules built with warnings (a bug of iec2kmod):\n" +
                         "\n".join(result.warnings[:20]), 70)
    result.messages.append(f"{len(result.modules)} modules for kernel {release}" +
                           (", sparse: 0 warnings" if sparse else ""))
    return result


_GEN_LINE = re.compile(r"^(?P<file>[^:\s]+\.[ch]):(?P<line>\d+):(?P<col>\d+): (?P<rest>.*)$")


def _explain(output: str, tree: Path) -> str:
    """The compiler's first errors; a failure to build generated C is an
    internal error of iec2kmod, reported with where the C came from."""
    lines = [ln for ln in output.splitlines() if "error" in ln or "warning" in ln]
    return "\n".join(lines[:20]) or output[-3000:]


def _build_in_container(tree: Path, manifest, kdir, jobs) -> TreeBuild:
    try:
        from .. import container
    except ImportError as exc:
        raise BuildError(f"the container build needs the docker SDK: {exc}", 2) from None
    if kdir:
        raise BuildError("--kdir and --container exclude each other: the container has its "
                         "own PREEMPT_RT headers", 2)
    try:
        res = container.build_modules(str(tree), jobs=jobs or None)
        _, release, _ = container._headers()
    except container.ContainerError as exc:
        raise BuildError(str(exc), 2) from None
    if not res.ok:
        raise BuildError(f"container build failed:\n{_explain(res.output, tree)}", 70)
    out = TreeBuild(f"container {res.image}", release)
    out.warnings = [ln for ln in res.output.splitlines()
                    if re.search(r"\bwarning:|^WARNING:", ln, re.IGNORECASE)]
    for name in manifest["load_order"]:
        ko = tree / name / f"{name}.ko"
        if not ko.exists():
            raise BuildError(f"the container build did not produce {ko}", 70)
        out.modules.append(str(ko))
    if out.warnings:
        raise BuildError("the generated modules built with warnings (a bug of iec2kmod):\n" +
                         "\n".join(out.warnings[:20]), 70)
    out.messages.append(f"built {len(out.modules)} modules in container {res.image} "
                        f"({res.duration:.1f} s) for kernel {release}")
    _split_debug(out.modules)
    manifest["kernel_release"] = release
    _write_manifest(tree, manifest)
    return out


def _write_manifest(tree: Path, manifest) -> None:
    from .manifest import manifest_text
    (tree / "manifest.json").write_text(manifest_text(manifest))


def _split_debug(modules) -> None:
    """Debug information out of the modules, as the kernel's own modules
    have it: Debian installs its modules with --strip-debug (the DWARF is in
    the separate -dbg package) and keeps the symbol table, ORC unwind data
    and .BTF.  The DWARF goes into <module>.ko.debug beside each module (for
    gdb, faddr2line, crash: `objcopy --add-gnu-debuglink` or
    `symbol-file`); a module is three to eight times smaller without it.
    A module already split (a rebuild that kbuild found up to date) is left
    as it is."""
    objcopy, strip, readelf = (shutil.which(t) for t in ("objcopy", "strip", "readelf"))
    if not objcopy or not strip or not readelf:
        raise BuildError("objcopy, strip and readelf (Debian package binutils) are needed to "
                         "split the modules' debug information", 2)
    for ko in modules:
        sections = subprocess.run([readelf, "-S", "-W", ko], capture_output=True,
                                  text=True).stdout
        if ".debug_info" not in sections:
            continue
        for cmd in ([objcopy, "--only-keep-debug", ko, ko + ".debug"],
                    [strip, "--strip-debug", ko]):
            p = subprocess.run(cmd, capture_output=True, text=True)
            if p.returncode:
                raise BuildError(f"{' '.join(cmd)} failed: {p.stderr.strip()}", 70)
