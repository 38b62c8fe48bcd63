# SPDX-License-Identifier: MIT
"""`plc-manager shell`: commands read from standard input, run in one
process (the resident mode that keeps the manager's start-up out of a
swap's path), each followed by `= <exit status>`."""

import os
import subprocess
import sys

import pytest

pytestmark = pytest.mark.unit


def test_shell_runs_each_line_and_reports_its_status(tmp_path):
    lines = ["status", "", "# a comment", "bogus-cmd", "swap --publish", '"unterminated',
             "shell", "quit", "status"]
    p = subprocess.run([sys.executable, "-m", "plc_manager.cli", "shell"],
                       input="\n".join(lines) + "\n", capture_output=True, text=True,
                       timeout=120, env=dict(os.environ, PLC_MANAGER_STATE_DIR=str(tmp_path)))
    assert p.returncode == 0, p.stderr
    # status with nothing loaded: 1; an unknown command: 2 (usage); swap
    # --publish with nothing loaded: 1; bad quoting: 2; a nested shell: 2;
    # quit ends it (the last status is not run)
    assert p.stdout.splitlines() == ["= 1", "= 2", "= 1", "= 2", "= 2"], p.stdout
    err = p.stderr
    assert err.count("no iec2kmod configuration is loaded") == 1, err
    assert "invalid choice: 'bogus-cmd'" in err and "No closing quotation" in err
    assert "already in the shell" in err and "Traceback" not in err
