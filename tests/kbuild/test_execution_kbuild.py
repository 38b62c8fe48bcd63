"""kbuild tier: every execution-test source builds into kernel modules with
W=1 and zero warnings on the host (with sparse, C=1: zero sparse warnings
too), and a representative set of them in the container.  The sources of an
area are wrapped into one configuration exactly as the execution runner
does (one task and one program instance per case), so one kbuild run
covers an area; a case with its own CONFIGURATION builds alone.

The container builds the same generated C with the same compiler and
kernel headers (the image installs exactly the host's headers version, its
tag hashes it; the test checks that the compilers agree): what the host
build proves of every source's code holds there too, and what is the
container's own (the image, the bind mount, its make, the no-network run,
its toolchain's warnings on each runtime piece) is proved by a set of cases
chosen from the host's generated trees so that together they use every
module kind (configuration, resource, program), every runtime and kernel
template file a module compiles or includes, a program on the FPU, and
every runtime function, macro and type family the generated code of all
cases names (iec_add_int and iec_add_dint are one family, iec_string_80 and
iec_string_16 one).  ``IEC2KMOD_CONTAINER_ALL=1`` builds every source in
the container, as it does by itself when the compilers differ.

Host builds are kept under ``$IEC2KMOD_CACHE/kbuild_exec/<group>-<key>``,
the key hashing the group's sources and everything that generates or
compiles them (iec2kmod/, kmod_templates/, the kernel headers used): the
QEMU tier (tests/qemu/test_exec_kernel.py) loads these same modules
instead of building them a second time."""

from __future__ import annotations

import fcntl
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "execution"))

import runner  # noqa: E402


def _groups():
    cases = runner.discover()
    groups = {}
    for c in cases:
        if c.standalone:
            groups[f"{c.area}_{c.path.stem}"] = [c]
        else:
            groups.setdefault(c.area, []).append(c)
    return groups


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "iec2kmod.cli", *args], cwd=ROOT,
                          capture_output=True, text=True, timeout=3600)


def group_sources(name, cases, tmp: Path) -> list[str]:
    """The sources of a group: the cases, and the runner's wrapper
    configuration unless the case has its own."""
    if len(cases) == 1 and cases[0].standalone:
        return [str(cases[0].path)]
    cfg = tmp / f"{name}_config.st"
    cfg.write_text(runner.wrapper_config(name, cases))
    return [str(c.path) for c in cases] + [str(cfg)]


def _generator_key() -> str:
    h = hashlib.sha256()
    for top in ("iec2kmod", "kmod_templates"):
        for f in sorted((ROOT / top).rglob("*")):
            if f.is_file() and "__pycache__" not in f.parts:
                h.update(str(f.relative_to(ROOT)).encode())
                h.update(f.read_bytes())
    h.update(os.uname().release.encode())
    h.update(" ".join(sorted(p.name for p in Path("/usr/src").glob("linux-headers-*"))).encode())
    return h.hexdigest()


_GEN_KEY: list = []


def cache_dir(name, sources) -> Path:
    if not _GEN_KEY:
        _GEN_KEY.append(_generator_key())
    h = hashlib.sha256(_GEN_KEY[0].encode())
    for src in sources:
        h.update(Path(src).name.encode())
        h.update(Path(src).read_bytes())
    return runner.build_root() / "kbuild_exec" / f"{name}-{h.hexdigest()[:16]}"


_FPU_REG = re.compile(r"%(?:[xyz]mm\d+|mm\d|st(?:\(\d\))?)\b")


def fpu_outside_sections(tree: Path) -> list:
    """Instructions on FPU/SIMD registers in code that does not run between
    kernel_fpu_begin() and kernel_fpu_end(): every module but a program
    type that uses REAL (manifest "uses_fpu").  Such an instruction clobbers
    the registers of the user process the task preempted (a heap corrupted
    in plc-manager, found in the QEMU tier)."""
    manifest = json.loads((tree / "manifest.json").read_text())
    found = []
    for m in manifest["modules"]:
        # a resource module with REAL-scaled I/O: only iec_io_real.c's
        # functions, called between kernel_fpu_begin/end by iec_io.c
        fp_funcs = ("iec_io_real_",) if m.get("kind") == "resource" else ()
        if m.get("uses_fpu") and not fp_funcs:
            continue
        ko = tree / m.get("dir", m["name"]) / f"{m['name']}.ko"
        p = subprocess.run(["objdump", "-d", "--no-show-raw-insn", str(ko)],
                           capture_output=True, text=True, timeout=120)
        assert p.returncode == 0, p.stderr
        func = "?"
        for line in p.stdout.splitlines():
            if line.endswith(">:"):
                func = line.split("<", 1)[1][:-2]
            elif _FPU_REG.search(line) and not func.startswith(fp_funcs or ("\0",)):
                found.append(f"{ko.name}: {func}: {line.strip()}")
    return found


def _build(name, cases, tmp: Path, container: bool):
    sources = group_sources(name, cases, tmp)
    cached = None if container else cache_dir(name, sources)
    if cached is not None:
        # the QEMU lane (tests/qemu/test_exec_kernel.py) builds the same trees
        # at the same time: the second one waits for the first, then finds it
        cached.parent.mkdir(parents=True, exist_ok=True)
        with open(cached.parent / f".{name}.lock", "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            return _build_locked(name, sources, tmp, cached, container)
    return _build_locked(name, sources, tmp, cached, container)


def _build_locked(name, sources, tmp: Path, cached, container: bool):
    if cached is not None and (cached / "built.ok").exists():
        return None
    out = tmp / f"tree_{name}"
    p = _cli("gen", *sources, "-o", str(out))
    if p.returncode != 0:
        return f"{name}: gen failed: {p.stderr[-2000:]}"
    # the host build runs sparse too (C=1): zero warnings from it as well
    p = _cli("build", str(out), *(["--container"] if container else ["--sparse"]))
    if p.returncode != 0:
        return f"{name}: build failed ({p.returncode}): {p.stderr[-3000:]}"
    fpu = fpu_outside_sections(out)
    if fpu:
        return (f"{name}: FPU registers used outside kernel_fpu_begin/end:\n  "
                + "\n  ".join(fpu[:20]))
    if cached is not None:
        (out / "built.ok").write_text("")
        for old in cached.parent.glob(f"{name}-*"):
            shutil.rmtree(old, ignore_errors=True)
        cached.parent.mkdir(parents=True, exist_ok=True)
        shutil.copytree(out, cached.with_suffix(".tmp"), dirs_exist_ok=True)
        os.replace(cached.with_suffix(".tmp"), cached)
    return None


def built_tree(name, cases, tmp: Path) -> Path:
    """The host-built module tree of a group, from the cache (built now if
    missing); raises AssertionError with the build's message on failure."""
    err = _build(name, cases, tmp, container=False)
    assert err is None, err
    return cache_dir(name, group_sources(name, cases, tmp))


def _all(tmp_path, container, groups=None):
    groups = _groups() if groups is None else groups
    with ThreadPoolExecutor(max_workers=2) as pool:
        errors = [e for e in pool.map(lambda kv: _build(kv[0], kv[1], tmp_path, container),
                                      groups.items()) if e]
    assert not errors, "\n\n".join(errors)


# ---- the container's representative set (the module docstring says why) ----

_IDENT = re.compile(r"\b(?:iec|IEC)_\w+")
_INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)
_TYPE_WORDS = frozenset(
    "sint int dint lint usint uint udint ulint real lreal bool byte word dword lword time "
    "ltime date ldate tod ltod dt ldt string wstring char wchar s8 s16 s32 s64 u8 u16 u32 "
    "u64 f32 f64".split())


def _template_names() -> frozenset:
    return frozenset(p.name for p in (ROOT / "kmod_templates").rglob("*") if p.is_file())


def family(ident: str) -> str:
    """A runtime name without its operand types and sizes: iec_add_dint ->
    iec_add, iec_int_to_real -> iec_to, iec_string_80 -> iec_string."""
    words = [re.sub(r"\d+$", "", w) or w for w in ident.split("_")
             if w.lower() not in _TYPE_WORDS and not w.isdigit()]
    return "_".join(words)


def module_features(tree: Path) -> dict:
    """{module name: the features its build exercises} of a generated tree:
    its kind, "fpu", every template file it compiles or includes, and the
    family of every runtime name (iec_*, IEC_*) in the generated code it
    compiles (its own files and the include/ files they include), leaving
    out the names the generator makes from the project's own."""
    tpl = _template_names()
    manifest = json.loads((tree / "manifest.json").read_text())
    own = ["iec_" + manifest["configuration"].lower(), "iec_frame_need_"]
    own += [m["name"].lower() for m in manifest["modules"]]
    out = {}
    for m in manifest["modules"]:
        mdir = tree / m.get("dir", m["name"])
        feats = {f"kind:{m['kind']}"} | ({"fpu"} if m.get("uses_fpu") else set())
        todo = [f for f in mdir.glob("*.[ch]") if not f.name.endswith(".mod.c")]
        seen = set()
        while todo:
            f = todo.pop()
            if f in seen:
                continue
            seen.add(f)
            if f.name in tpl:
                feats.add(f"template:{f.name}")
                continue
            text = f.read_text(errors="replace")
            for inc in _INCLUDE.findall(text):
                name = Path(inc).name
                if name in tpl:
                    feats.add(f"template:{name}")
                for d in (mdir, tree / "include", tree / "runtime"):
                    if (d / inc).is_file():
                        todo.append((d / inc).resolve())
                        break
            feats |= {family(i) for i in _IDENT.findall(text)
                      if not i.lower().startswith(tuple(own))}
        kbuild_objs = (mdir / "Kbuild").read_text() if (mdir / "Kbuild").is_file() else ""
        feats |= {f"template:{Path(o).stem}.c" for o in re.findall(r"[\w./-]+\.o\b", kbuild_objs)
                  if f"{Path(o).stem}.c" in tpl}
        out[m["name"]] = feats
    return out


def representative_set(groups: dict, trees: dict) -> tuple:
    """({group: the cases chosen from it}, every feature of all cases).  Greedy set cover over
    the cases, cost one module each (plus a group's configuration and
    resource modules when the group is first opened); a case with its own
    configuration is one item of all its modules."""
    items = []        # (group, case or None, features, cost)
    base = {}         # group -> (features, cost) of the modules every build of it has
    for name, cases in groups.items():
        feats = module_features(trees[name])
        if len(cases) == 1 and cases[0].standalone:
            items.append((name, None, set().union(*feats.values()), len(feats)))
            continue
        manifest = json.loads((trees[name] / "manifest.json").read_text())
        by_type = {m.get("program_type", "").lower(): m["name"] for m in manifest["modules"]
                   if m["kind"] == "program"}
        shared = [m["name"] for m in manifest["modules"] if m["kind"] != "program"]
        base[name] = (set().union(*(feats[m] for m in shared)), len(shared))
        for c in cases:
            items.append((name, c, feats[by_type[c.program.lower()]], 1))
    all_items = list(items)
    every = set().union(*(i[2] for i in items), *(b[0] for b in base.values()))
    left, chosen = set(every), {}
    while left:
        def gain(it):
            g, _, f, cost = it
            new = f | (base[g][0] if g in base and g not in chosen else set())
            extra = base[g][1] if g in base and g not in chosen else 0
            return len(new & left) / (cost + extra), -(cost + extra)
        g, case, f, _ = max(items, key=gain)
        if not (f | base.get(g, (set(), 0))[0]) & left:
            break
        chosen.setdefault(g, [])
        if case is not None:
            chosen[g].append(case)
        else:
            chosen[g] = groups[g]
        left -= f | base.get(g, (set(), 0))[0]
        items = [it for it in items if not (it[0] == g and (case is None or it[1] is case))]
    covered = set()
    for g, cs in chosen.items():
        covered |= base.get(g, (set(), 0))[0]
        covered |= set().union(*(f for gg, c, f, _ in all_items
                                 if gg == g and (c is None or c in cs)))
    assert covered == every, f"the chosen set misses {sorted(every - covered)[:20]}"
    return chosen, every


def _gcc_version(container_image=None, tmp=None) -> str:
    if container_image is None:
        p = subprocess.run(["gcc", "--version"], capture_output=True, text=True, timeout=60)
        return p.stdout.splitlines()[0]
    from iec2kmod import container
    r = container.run_in_container(str(tmp), "gcc --version", image=container_image)
    assert r.ok, r.output
    return r.output.splitlines()[0]


@pytest.mark.kbuild
def test_every_execution_source_builds_on_the_host(tmp_path):
    n = sum(len(v) for v in _groups().values())
    assert n >= 150, f"only {n} execution cases"
    _all(tmp_path, container=False)


@pytest.mark.container
def test_execution_sources_build_in_the_container(tmp_path):
    """The representative set (module docstring) in the container, or every
    source with IEC2KMOD_CONTAINER_ALL=1 or when the compilers differ."""
    from iec2kmod import container
    groups = _groups()
    try:
        image = container.image_tag()
    except container.ContainerError as e:
        pytest.fail(str(e), pytrace=False)
    host, inside = _gcc_version(), _gcc_version(image, tmp_path)
    if os.environ.get("IEC2KMOD_CONTAINER_ALL", "") not in ("", "0") or host != inside:
        print(f"\nevery execution source in the container (host {host!r}, "
              f"container {inside!r})")
        _all(tmp_path, container=True, groups=groups)
        return
    host_dir = tmp_path / "host"
    host_dir.mkdir()
    with ThreadPoolExecutor(max_workers=2) as pool:
        trees = dict(zip(groups, pool.map(lambda kv: built_tree(kv[0], kv[1], host_dir),
                                          groups.items())))
    chosen, every = representative_set(groups, trees)
    print(f"\ncontainer: {sum(len(v) for v in chosen.values())} of "
          f"{sum(len(v) for v in groups.values())} execution cases, covering {len(every)} "
          f"features: " + ", ".join(f"{g}({len(cs)})" for g, cs in sorted(chosen.items())))
    _all(tmp_path, container=True, groups=chosen)
