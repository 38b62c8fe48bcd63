"""Test of the harness: a parametrization built from a directory listing
fails at collection when the listing comes back empty, instead of being
reported as "skipped" with exit status 0.

Each guarded test module is copied into an empty tree (no examples, no
cases, no pairs, no error files) and collected there: every one of them
must be an error, naming its guard."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.unit
ROOT = Path(__file__).resolve().parents[2]

# test module -> the helper files it imports from its own directory
GUARDED = {
    "tests/execution/test_examples_cli.py": ["tests/execution/conftest.py",
                                             "tests/execution/runner.py"],
    "tests/execution/test_cases.py": ["tests/execution/conftest.py",
                                      "tests/execution/runner.py"],
    "tests/execution/test_pairs.py": ["tests/execution/conftest.py",
                                      "tests/execution/runner.py"],
    "tests/execution/test_cases_vm.py": ["tests/execution/conftest.py",
                                         "tests/execution/runner.py"],
    "tests/execution/test_vm_vs_c.py": ["tests/execution/conftest.py",
                                        "tests/execution/runner.py"],
    "tests/execution/test_examples_behaviour.py": [],
    "tests/unit/test_codegen.py": ["tests/unit/conftest.py", "tests/unit/helpers.py"],
    "tests/unit/test_fast_builder.py": ["tests/unit/conftest.py"],
    "tests/errors/test_error_files.py": [],
    "tests/kbuild/test_examples_kbuild.py": [],
}
EMPTY_DIRS = ["examples", "tests/errors", "tests/execution/cases", "tests/execution/pairs"]


def test_empty_listings_fail_collection(tmp_path):
    for module, helpers in GUARDED.items():
        for f in [module, *helpers]:
            (tmp_path / f).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy(ROOT / f, tmp_path / f)
    for d in EMPTY_DIRS:
        (tmp_path / d).mkdir(parents=True, exist_ok=True)
    assert not any((tmp_path / "examples").iterdir())
    (tmp_path / "pytest.ini").write_text("[pytest]\nmarkers =\n    unit\n    execution\n"
                                         "    kbuild\n    container\n    qemu\n")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(ROOT)] + ([os.environ["PYTHONPATH"]] if os.environ.get("PYTHONPATH") else [])))
    p = subprocess.run([sys.executable, "-m", "pytest", "--collect-only", "-q",
                        "-p", "no:cacheprovider", *GUARDED],
                       cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    out = p.stdout + p.stderr
    assert p.returncode != 0, out
    for module in GUARDED:
        assert f"ERROR collecting {module}" in out, f"{module} collected an empty list:\n{out}"
    # each fails on its own guard (not on some unrelated import error)
    assert out.count("AssertionError: only 0 ") >= len(GUARDED), out
    assert "skipped" not in out.lower(), out
