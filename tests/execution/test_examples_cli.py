"""Every example project compiles (-Wall -Wextra -Werror
-Wdeclaration-after-statement) and runs in the simulator, plain and with
ASan+UBSan; `iec2kmod sim` reports a runtime fault as file:line."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

import runner
from iec2kmod import sim

pytestmark = pytest.mark.execution

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = sorted(p for p in (ROOT / "examples").iterdir() if p.is_dir())
# an empty or shrunken list would pass as "skipped": fail at collection instead
assert len(EXAMPLES) >= 12, f"only {len(EXAMPLES)} example projects under {ROOT / 'examples'}"


@pytest.mark.parametrize("sanitize", [False, True], ids=["plain", "sanitize"])
@pytest.mark.parametrize("example", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_example_runs(example, sanitize):
    project = runner.check_project([example])
    res = sim.run(project, 2_000_000_000, sanitize=sanitize,
                  build_dir=runner.build_root() / "sim")
    assert not runner.SANITIZER_REPORT.search(res.stderr or ""), res.stderr[:3000]
    assert res.cycles and any(n > 0 for n in res.cycles.values()), res.cycles
    assert not res.faults, res.faults


def test_cli_reports_runtime_error_with_file_and_line(tmp_path):
    case = runner.load_case(runner.CASES / "faults" / "div_zero_int.st", "faults")
    cfg = tmp_path / "config.st"
    cfg.write_text(runner.wrapper_config("cli", [case]))
    p = subprocess.run([sys.executable, "-m", "iec2kmod.cli", "sim", str(case.path), str(cfg),
                        "--cycles", "5", "--watch", "div_zero_int.after"],
                       cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert p.returncode == 1, p.stderr
    (cycle, line, _), = case.faults
    assert f"{case.path}:{line}: runtime error: division by zero in div_zero_int" in p.stderr
    assert "t=0.020000 s" in p.stderr and "the task is stopped" in p.stderr
    assert "div_zero_int.after  2" in p.stdout
