"""iec2kmod check: output format, exit codes, no tracebacks on any input."""

import os
import random
import subprocess
import sys
from pathlib import Path

import pytest

from iec2kmod import cli

pytestmark = pytest.mark.unit
ROOT = Path(__file__).resolve().parents[2]


def run(*args, cwd=None, env_extra=None):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    env.update(env_extra or {})
    p = subprocess.run([sys.executable, "-m", "iec2kmod.cli", *args], cwd=cwd, env=env,
                       capture_output=True, text=True, timeout=120)
    return p.returncode, p.stdout, p.stderr


GOOD = """PROGRAM Main
  VAR_EXTERNAL run : BOOL; END_VAR
  VAR n : INT; END_VAR
  IF run THEN n := n + 1; END_IF;
END_PROGRAM
CONFIGURATION C
  VAR_GLOBAL run : BOOL; END_VAR
  TASK t (INTERVAL := T#10ms, PRIORITY := 1);
  PROGRAM m WITH t : Main;
END_CONFIGURATION
"""


def test_clean_project_exits_0(tmp_path):
    f = tmp_path / "good.st"
    f.write_text(GOOD)
    rc, out, err = run("check", "--no-cache", str(f))
    assert (rc, out, err) == (0, "", "")


def test_error_format_is_gcc_like(tmp_path):
    f = tmp_path / "bad.st"
    f.write_text(GOOD.replace("n := n + 1;", "n := n + TRUE;"))
    rc, out, err = run("check", "--no-cache", str(f))
    assert rc == 1
    lines = err.splitlines()
    assert lines[0] == f"{f}:4:15: error: operator +: arguments of ADD have incompatible types " \
                       "INT and BOOL" or lines[0].startswith(f"{f}:4:")
    assert lines[1] == "  IF run THEN n := n + TRUE; END_IF;"
    col = int(lines[0].split(":")[2])
    assert lines[2] == " " * (col - 1) + "^"
    assert lines[-1] == "1 error(s), 0 warning(s)"


def test_warnings_keep_exit_0(tmp_path):
    f = tmp_path / "warn.st"
    f.write_text(GOOD.replace("VAR n : INT; END_VAR", "VAR n, spare : INT; END_VAR"))
    rc, _, err = run("check", "--no-cache", str(f))
    assert rc == 0 and "warning: unused variable 'spare'" in err


def test_directories_and_multiple_files(tmp_path):
    (tmp_path / "a.st").write_text(GOOD.split("CONFIGURATION")[0])
    (tmp_path / "b.st").write_text("CONFIGURATION" + GOOD.split("CONFIGURATION", 1)[1])
    rc, _, err = run("check", "--no-cache", str(tmp_path))
    assert (rc, err) == (0, "")


@pytest.mark.parametrize("args, message", [
    (["check", "/no/such/file.st"], "no such file or directory"),
    (["check"], "the following arguments are required"),
    (["frobnicate"], "invalid choice"),
    ([], "the following arguments are required"),
])
def test_usage_and_io_errors_exit_2(args, message):
    rc, out, err = run(*args)
    assert rc == 2 and message in err and "Traceback" not in err


def test_empty_directory_is_a_usage_error(tmp_path):
    rc, _, err = run("check", str(tmp_path))
    assert rc == 2 and "no .st, .il or .iec files" in err


def test_no_traceback_on_any_input(tmp_path, capsys):
    rng = random.Random(1234)
    alphabet = "PROGRAM END_PROGRAM VAR END_VAR := ; ( ) [ ] 'x' T#5s 16#F IF THEN x y 1 2 . , : \n"
    words = alphabet.split(" ")
    inputs = [bytes(rng.randrange(256) for _ in range(500)),
              b"", b"\xff\xfe\x00", ("PROGRAM p\n" + "(" * 5000).encode()]
    for _ in range(30):
        inputs.append(" ".join(rng.choice(words) for _ in range(60)).encode())
    for i, data in enumerate(inputs):
        f = tmp_path / f"fuzz{i}.st"
        f.write_bytes(data)
    # in-process (the same main() the console script runs), then two of them
    # in a fresh interpreter as the user would
    for i in range(len(inputs)):
        rc = cli.main(["check", "--no-cache", str(tmp_path / f"fuzz{i}.st")])
        err = capsys.readouterr().err
        assert rc in (0, 1), (i, err)
        assert "Traceback" not in err and "internal error" not in err, (i, err)
    for i in (0, len(inputs) - 1):
        rc, out, err = run("check", "--no-cache", str(tmp_path / f"fuzz{i}.st"))
        assert rc in (0, 1) and "Traceback" not in err, (i, err)


def test_internal_errors_are_one_line_and_exit_70(monkeypatch, capsys):
    def boom(args):
        raise KeyError("oops")
    monkeypatch.setitem(cli.COMMANDS, "check", boom)
    assert cli.main(["check", "x.st"]) == 70
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("iec2kmod: internal error: KeyError")


def test_repeat_run_uses_the_cache(tmp_path):
    f = tmp_path / "bad.st"
    f.write_text(GOOD.replace("n := n + 1;", "n := n + TRUE;"))
    env = {"IEC2KMOD_CACHE": str(tmp_path / "cache")}
    first = run("check", "--timings", str(f), env_extra=env)
    second = run("check", "--timings", str(f), env_extra=env)
    assert first[0] == second[0] == 1
    strip = lambda err: [l for l in err.splitlines() if " ms" not in l]
    assert strip(first[2]) == strip(second[2])
    assert "cache:" in second[2] and "parse:" in first[2]
    f.write_text(GOOD)
    assert run("check", str(f), env_extra=env)[0] == 0


# Beremiz's LOGGER block as in every plc.st of OSCAT's OpenPLC translation:
# MatIEC's inline C {{ ... }} runs to the first }}, whatever braces,
# semicolons or keywords its C code holds
LOGGER = """FUNCTION_BLOCK LOGGER
  VAR_INPUT TRIG : BOOL; MSG : STRING; LEVEL : BYTE := 2; END_VAR
  VAR TRIG0 : BOOL; END_VAR
  IF TRIG AND NOT TRIG0 THEN
  {{
   if (1) { LogMessage(GetFbVar(LEVEL),(char*)GetFbVar(MSG, .body),GetFbVar(MSG, .len)); }
   /* END_IF; END_FUNCTION_BLOCK */
  }}
  END_IF;
  TRIG0:=TRIG;
END_FUNCTION_BLOCK
"""


@pytest.mark.parametrize("jobs", ["1", "2"])
def test_matiec_inline_c_pragma_is_warned_and_ignored(tmp_path, jobs):
    # with -j 2 the file (over 40000 characters) is cut between POUs for the
    # parallel parser: the cut must not fall inside the pragma either
    fillers = "".join(f"FUNCTION F{i} : INT\n  VAR_INPUT a : INT; END_VAR\n  F{i} := a + {i};\n"
                      f"END_FUNCTION\n" for i in range(700))
    prog = GOOD.replace("VAR n : INT; END_VAR", "VAR n : INT; log : LOGGER; END_VAR").replace(
        "END_IF;\nEND_PROGRAM", "END_IF;\n  log(TRIG := run, MSG := 'on');\n  n := F7(n);\nEND_PROGRAM")
    f = tmp_path / "plc.st"
    f.write_text(LOGGER + fillers + prog)
    assert len(f.read_text()) > 40000
    rc, out, err = run("check", "--no-cache", "-j", jobs, str(f))
    assert rc == 0, err
    assert err.splitlines()[0] == f"{f}:5:3: warning: pragma ignored"
    assert err.splitlines()[-1] == "0 error(s), 1 warning(s)"
