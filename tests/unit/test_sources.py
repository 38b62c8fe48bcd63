"""Which files are sources: .st, .il and .iec only (issue 22: a .txt in a
project directory was parsed as a source)."""

from __future__ import annotations

from iec2kmod import cli

PROG = """
PROGRAM P
VAR x : INT; END_VAR
x := x + 1;
END_PROGRAM
CONFIGURATION C RESOURCE R ON CPU0
  TASK t (INTERVAL := T#10ms, PRIORITY := 1);
  PROGRAM p WITH t : P;
END_RESOURCE END_CONFIGURATION
"""


def test_a_txt_in_a_project_directory_is_ignored_with_a_note(tmp_path, capsys):
    (tmp_path / "p.st").write_text(PROG)
    (tmp_path / "notes.txt").write_text("remember: x counts cycles\n")
    for _ in range(2):      # the second run from the front end's cache: the note again
        rc = cli.main(["check", "--no-cache" if _ == 0 else "--jobs=1", str(tmp_path)])
        err = capsys.readouterr().err
        assert rc == 0, err
        assert f"{tmp_path / 'notes.txt'}:1:1: note: ignored: not a source file (sources " \
               "are .st, .il or .iec files)" in err
        assert "error" not in err


def test_a_txt_named_on_the_command_line_is_refused(tmp_path, capsys):
    (tmp_path / "p.txt").write_text(PROG)
    rc = cli.main(["check", str(tmp_path / "p.txt")])
    err = capsys.readouterr().err
    assert rc == 2
    assert f"{tmp_path / 'p.txt'}: not a source file (sources are .st, .il or .iec files, " \
           f"or a PLCopen .xml project)" in err
