"""Error tests: each .st file here holds a program and, in a final
``(* EXPECT ... *)`` comment, every diagnostic it must produce
(``line:col: severity: message``).  The list must match exactly."""

import re
from pathlib import Path

import pytest

from iec2kmod.checks import check_project
from iec2kmod.diagnostics import Diagnostics, SourceFile
from iec2kmod.parse.parser import parse_source

HERE = Path(__file__).resolve().parent
CASES = sorted(HERE.glob("*.st"))
# an empty or shrunken list would pass as "skipped": fail at collection instead
assert len(CASES) >= 10, f"only {len(CASES)} error test files in {HERE}"
EXPECT = re.compile(r"\(\*\s*EXPECT\s*\n(.*?)\*\)", re.S)


def expected_of(text):
    m = EXPECT.search(text)
    assert m, "an error test needs an (* EXPECT ... *) block"
    return [line.strip() for line in m.group(1).splitlines() if line.strip()]


def actual_of(path, text):
    diags = Diagnostics()
    unit = parse_source(SourceFile(str(path), text), diags)
    if unit is not None and not diags.errors:
        check_project([unit], diags)
    return [f"{d.line}:{d.col}: {d.severity}: {d.message}" for d in diags.sorted()]


@pytest.mark.unit
@pytest.mark.parametrize("path", CASES, ids=[p.stem for p in CASES])
def test_error_file(path):
    text = path.read_text()
    assert actual_of(path, text) == expected_of(text)


def test_there_are_error_tests():
    assert len(CASES) >= 10
