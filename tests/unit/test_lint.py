# SPDX-License-Identifier: MIT
"""The tree is clean under ruff's pyflakes rules (F: unused imports and
variables, undefined names, f-strings without placeholders, ...): a name
imported or computed and never used is dead code or a slip, and an
undefined one a crash waiting on its path.  E402: imports stay at the top of
the module.  Configured in pyproject.toml
([tool.ruff]); ruff comes with the test extra (scripts/setup.sh)."""

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.unit
ROOT = Path(__file__).resolve().parents[2]
TREES = ["iec2kmod", "manager", "kmod_templates", "containers", "benchmarks", "tests", "scripts"]


def _ruff():
    exe = shutil.which("ruff") or str(Path(sys.executable).with_name("ruff"))
    if not Path(exe).exists():
        pytest.fail("ruff not found: pip install ruff (or run scripts/setup.sh)")
    return exe


def test_the_tree_is_clean_under_pyflakes_rules():
    p = subprocess.run([_ruff(), "check", "--output-format", "concise", *TREES], cwd=ROOT,
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stdout + p.stderr


def test_the_lint_can_fail(tmp_path):
    bad = tmp_path / "bad.py"
    bad.write_text("import os\n\n\ndef f():\n    x = 1\n    return undefined_name\n\n\n"
                   "import sys\n")
    p = subprocess.run([_ruff(), "check", "--config", str(ROOT / "pyproject.toml"),
                        "--output-format", "concise", str(bad)],
                       capture_output=True, text=True)
    assert p.returncode == 1
    for code in ("F401", "F841", "F821", "E402"):
        assert code in p.stdout, p.stdout


def test_late_imports_in_the_product_name_their_cycle():
    """An import below code in iec2kmod/ or manager/ (``noqa: E402``) is only
    there to break an import cycle, and its comment says which."""
    bad = []
    for tree in ("iec2kmod", "manager"):
        for path in sorted((ROOT / tree).rglob("*.py")):
            for n, line in enumerate(path.read_text().splitlines(), 1):
                if "noqa: E402" in line and "cycle" not in line:
                    bad.append(f"{path.relative_to(ROOT)}:{n}: {line.strip()}")
    assert not bad, "late imports without a cycle to break:\n" + "\n".join(bad)
