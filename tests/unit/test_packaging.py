"""The packages fit their users (pyproject.toml):

- every third-party module imported anywhere in the repository is declared,
  in the core dependencies or in the extra of the code that imports it;
- the product (iec2kmod/ outside iec2kmod/testing, manager/, containers/)
  needs nothing from the test extra, and plc-manager nothing but its own
  extra;
- `iec2kmod check` and `iec2kmod gen` run with only the core dependencies
  importable (z3, docker, pyroute2 and the test tools blocked);
- plc-manager runs without the compiler's and the verifier's dependencies;
- the data folders install inside the package, not as top-level packages.
"""

from __future__ import annotations

import ast
import re
import subprocess
import sys
import tomllib
from importlib import metadata
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
TREES = ["iec2kmod", "manager", "containers", "kmod_templates", "benchmarks", "tests", "scripts"]
PRODUCT = {"core": ["iec2kmod"], "manager": ["manager"], "container": ["containers"]}


def _norm(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def _req_name(req: str) -> str:
    return _norm(re.split(r"[\s\[<>=!~;]", req.strip(), maxsplit=1)[0])


def declared() -> dict[str, set[str]]:
    """{'core' | extra: {distribution}} from pyproject.toml (self-references
    such as iec2kmod[verify,...] expanded)."""
    proj = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    raw = {"core": list(proj["dependencies"]), **proj["optional-dependencies"]}
    out: dict[str, set[str]] = {}

    def expand(group, seen=()):
        names = set()
        for req in raw[group]:
            name = _req_name(req)
            if name == "iec2kmod":
                for extra in re.search(r"\[(.*)\]", req).group(1).split(","):
                    assert extra.strip() not in seen, f"extra cycle through {extra}"
                    names |= expand(extra.strip(), seen + (group,))
            else:
                names.add(name)
        return names

    for group in raw:
        out[group] = expand(group)
    return out


def _local_names() -> set[str]:
    """Module names the repository itself provides (packages, the test and
    benchmark helpers put on sys.path by conftest files and scripts)."""
    names = {"plc_manager"}
    for p in ROOT.rglob("*"):
        if ".git" in p.parts or "__pycache__" in p.parts:
            continue
        if p.suffix == ".py":
            names.add(p.stem)
        elif p.is_dir():
            names.add(p.name)
    return names


def third_party_imports(trees) -> dict[str, set[str]]:
    """{top-level module: {file}} of the absolute imports in *trees* that
    are neither the standard library nor the repository's own."""
    local = _local_names()
    found: dict[str, set[str]] = {}
    for tree in trees:
        for path in sorted((ROOT / tree).rglob("*.py")):
            mod = ast.parse(path.read_text(), str(path))
            for node in ast.walk(mod):
                if isinstance(node, ast.Import):
                    tops = [a.name.split(".")[0] for a in node.names]
                elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                    tops = [node.module.split(".")[0]]
                else:
                    continue
                for top in tops:
                    if top not in sys.stdlib_module_names and top not in local:
                        found.setdefault(top, set()).add(str(path.relative_to(ROOT)))
    return found


def distributions_of(imports) -> dict[str, set[str]]:
    """{distribution: {file}}; a module no installed distribution provides
    is reported as '?<module>'."""
    provides = metadata.packages_distributions()
    out: dict[str, set[str]] = {}
    for top, files in imports.items():
        dists = provides.get(top) or [f"?{top}"]
        for d in dists:
            out.setdefault(_norm(d) if not d.startswith("?") else d, set()).update(files)
    return out


def _report(dists: dict[str, set[str]], allowed: set[str]) -> list[str]:
    return [f"{d} (imported by {', '.join(sorted(files)[:4])})"
            for d, files in sorted(dists.items()) if d not in allowed]


def test_every_third_party_import_is_declared():
    groups = declared()
    everything = set().union(*groups.values())
    bad = _report(distributions_of(third_party_imports(TREES)), everything)
    assert not bad, ("imported but not declared in pyproject.toml (dependencies or an "
                     "extra): " + "; ".join(bad))


@pytest.mark.parametrize("user", sorted(PRODUCT))
def test_product_needs_nothing_from_the_test_extra(user):
    """The compiler may use core and the feature extras (it imports them
    lazily, where the feature is used); plc-manager only core, manager and serve;
    the container recipe only core and container.  iec2kmod/testing is the
    test harness and is left out."""
    groups = declared()
    allowed = groups["core"] | (groups["all"] if user == "core" else groups[user])
    if user == "manager":                    # plc-manager serve (manager/serve/)
        allowed |= groups["serve"]
    imports = third_party_imports(PRODUCT[user])
    imports = {m: {f for f in fs if not f.startswith("iec2kmod/testing/")}
               for m, fs in imports.items()}
    bad = _report(distributions_of({m: fs for m, fs in imports.items() if fs}), allowed)
    assert not bad, f"the {user} code imports what its install does not bring: " + "; ".join(bad)


def test_declaration_checks_can_fail():
    """The walk finds an undeclared import (the check above is not vacuous)."""
    groups = declared()
    dists = distributions_of({"pytest": {"x.py"}, "surely_not_a_module_xyz": {"y.py"}})
    assert _report(dists, groups["core"]) == ["?surely_not_a_module_xyz (imported by y.py)",
                                              "pytest (imported by x.py)"]
    assert _report(dists, set().union(*groups.values())) == [
        "?surely_not_a_module_xyz (imported by y.py)"]


def test_extras():
    groups = declared()
    assert {"textx", "jinja2", "arpeggio"} <= groups["core"]
    assert groups["core"] & {"z3-solver", "docker", "pyroute2", "pyuppaal", "pytest"} == set()
    assert groups["verify"] == {"z3-solver"}
    assert "docker" in groups["container"] and groups["manager"] == {"pyroute2"}
    assert groups["plcopen"] == {"lxml"}
    assert groups["all"] == (groups["verify"] | groups["container"] | groups["manager"] |
                             groups["serve"] | groups["plcopen"])
    assert {"asyncua", "pymodbus"} <= groups["serve"]
    assert {"pytest", "hypothesis", "ruff", "pyuppaal"} <= groups["test"]
    reqs = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    z3 = [r for r in reqs["optional-dependencies"]["verify"] if _req_name(r) == "z3-solver"]
    assert z3 and "==" in z3[0], "z3-solver is pinned to the tested version"
    # scripts/setup.sh (the README's set-up command) installs every extra
    assert "[all,test]" in (ROOT / "scripts" / "setup.sh").read_text()


# A meta path finder that refuses the given top-level modules and records
# the attempts, then runs a command of a CLI.
BLOCKED_RUN = r"""
import importlib.abc, sys
BLOCK = set(sys.argv[1].split(","))
tried = []
class Blocker(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in BLOCK:
            tried.append(name)
            raise ModuleNotFoundError(f"No module named {name!r} (blocked by the test)", name=name)
        return None
sys.meta_path.insert(0, Blocker())
import importlib
main = getattr(importlib.import_module(sys.argv[2]), "main")
try:
    rc = main(sys.argv[3:])
except SystemExit as exc:
    rc = exc.code
print("BLOCKED-IMPORTS:", ",".join(sorted(set(tried))))
sys.exit(rc)
"""

NOT_CORE = ["z3", "docker", "requests", "pyroute2", "pyuppaal", "pytest", "hypothesis", "mpmath"]


def run_blocked(block, module, *args):
    p = subprocess.run([sys.executable, "-c", BLOCKED_RUN, ",".join(block), module, *args],
                       cwd=ROOT, capture_output=True, text=True, timeout=300)
    tried = [ln for ln in p.stdout.splitlines() if ln.startswith("BLOCKED-IMPORTS:")]
    assert tried, p.stdout + p.stderr
    return p, tried[-1].split(":", 1)[1].strip()


@pytest.mark.parametrize("example", ["traffic_light", "two_resources", "pid_loop"])
def test_check_and_gen_need_only_the_core(example, tmp_path):
    p, tried = run_blocked(NOT_CORE, "iec2kmod.cli", "check", f"examples/{example}")
    assert p.returncode == 0, p.stderr
    assert tried == "", f"check tried to import {tried}"
    p, tried = run_blocked(NOT_CORE, "iec2kmod.cli", "gen", f"examples/{example}",
                           "-o", str(tmp_path / "out"))
    assert p.returncode == 0, p.stderr
    assert tried == "", f"gen tried to import {tried}"
    assert "wrote" in p.stdout and list((tmp_path / "out").rglob("*.c"))


def test_a_missing_extra_is_named():
    """verify needs z3: with z3 blocked it stops with a usage error naming
    the extra to install (not an internal error), so the blocker works."""
    p, tried = run_blocked(["z3"], "iec2kmod.cli", "verify", "examples/traffic_light",
                           "--depth", "1")
    assert "z3" in tried
    assert p.returncode == 2, p.stderr
    assert "pip install 'iec2kmod[verify]'" in p.stderr and "internal error" not in p.stderr


def test_manager_needs_only_its_extra():
    p, tried = run_blocked(NOT_CORE[:2] + ["textx", "arpeggio", "jinja2", "pyuppaal", "pytest"],
                           "plc_manager.cli", "--help")
    assert p.returncode == 0, p.stderr
    assert tried == "" and "usage" in p.stdout.lower()


def test_data_folders_install_inside_the_package():
    tool = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    assert "kmod_templates" not in tool["packages"]
    assert tool["package-dir"]["iec2kmod.kmod_templates"] == "kmod_templates"
    top = {p.split(".")[0] for p in tool["packages"]}
    assert top == {"iec2kmod", "plc_manager"}, f"top-level packages installed: {top}"
    from iec2kmod.resources import containers_root, templates_root
    assert (templates_root() / "runtime" / "iec_fault.h").is_file()
    assert (containers_root() / "build-rootfs.sh").is_file()


def test_no_stray_files_at_the_root():
    tracked = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True,
                             check=True).stdout.split()
    root_files = sorted({f for f in tracked if "/" not in f})
    assert root_files == [".gitignore", "README.md", "pyproject.toml"], root_files
    top_dirs = sorted({f.split("/")[0] for f in tracked
                       if "/" in f and not f.startswith(".")})   # .ci/: the CI entry
    assert top_dirs == ["benchmarks", "containers", "examples", "iec2kmod", "kmod_templates",
                        "manager", "scripts", "tests"], top_dirs


def test_manager_without_pyroute2_says_so():
    p, tried = run_blocked(["pyroute2"], "plc_manager.cli", "status")
    assert "pyroute2" in tried
    assert p.returncode == 1, p.stdout + p.stderr
    assert "pip install 'iec2kmod[manager]'" in p.stderr and "internal error" not in p.stderr


def test_the_harness_is_a_testing_package(tmp_path):
    """The QEMU harness is iec2kmod.testing.vm; `python3 -m iec2kmod.vm`
    (named by older documents) runs it; the compiler never imports it."""
    a = subprocess.run([sys.executable, "-m", "iec2kmod.testing.vm", "--help"], cwd=ROOT,
                       capture_output=True, text=True, timeout=120)
    b = subprocess.run([sys.executable, "-m", "iec2kmod.vm", "--help"], cwd=ROOT,
                       capture_output=True, text=True, timeout=120)
    assert a.returncode == b.returncode == 0, a.stderr + b.stderr
    assert "prepare" in a.stdout and b.stdout == a.stdout
    code = ("import sys; from iec2kmod.cli import main; rc = main(['gen', "
            "'examples/traffic_light', '-o', sys.argv[1]]); "
            "print(sorted(m for m in sys.modules if m.startswith('iec2kmod.testing') "
            "or m == 'iec2kmod.vm')); sys.exit(rc)")
    p = subprocess.run([sys.executable, "-c", code, str(tmp_path / "out")],
                       cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    assert p.stdout.strip().splitlines()[-1] == "[]"
