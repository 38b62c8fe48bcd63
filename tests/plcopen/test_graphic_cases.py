# SPDX-License-Identifier: MIT
"""Hand-written FBD and LD cases (issue 28, slice 2): each cases/*.xml is a
PLCopen project whose expected values are written in XML comments with the
annotations of tests/execution/runner.py (``<!-- EXPECT after N cycles:
res.inst.x = v -->``, ``<!-- INPUT at cycle N: ... -->``), derived from the
standard's rules (each file says which), not from our output.  Every case
runs in the C simulator and in the reference interpreter; when a TC6 2.01
XSD is configured (IEC2KMOD_TC6_XSD) the cases are validated against it."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "execution"))
import runner  # noqa: E402

pytestmark = pytest.mark.execution
# the project the QEMU tier also runs in the kernel (tests/qemu/test_plcopen_kernel.py)
KERNEL_PROJECT = HERE.parent / "qemu" / "projects" / "plcopen_ld" / "plc.xml"
CASES = sorted((HERE / "cases").glob("*.xml")) + [KERNEL_PROJECT]
assert len(CASES) >= 1, f"only {len(CASES)} cases under {HERE / 'cases'}"


def load(path: Path) -> runner.Case:
    """The case's annotations, read from the XML comments (the runner's
    grammar and strictness: a comment that looks like an annotation but is
    not one fails the case)."""
    text = path.read_text(encoding="utf-8")
    case = runner.Case(path, "plcopen", None)
    for m in re.finditer(r"<!--(.*?)-->", text, re.S):
        body = m.group(1)
        where = f"{path}:{text.count(chr(10), 0, m.start()) + 1}"
        if mm := runner._EXPECT.match(body):
            case.checkpoints.append((int(mm.group(1)), runner._assignments(mm.group(2), where)))
        elif mm := runner._INPUT.match(body):
            for c in runner._assignments(mm.group(2), where):
                case.inputs.append((int(mm.group(1)), c.path, c.text))
        elif any(runner.looks_like_directive(ln) for ln in body.split("\n")):
            raise runner.CaseError(f"{where}: malformed annotation: {body.strip()[:70]}")
    if not case.checkpoints:
        raise runner.CaseError(f"{path}: no EXPECT")
    return case


@pytest.mark.parametrize("engine", ["c", "vm"])
@pytest.mark.parametrize("path", CASES, ids=[p.parent.name if p.stem == "plc" else p.stem
                                             for p in CASES])
def test_graphic_case(path, engine):
    case = load(path)
    run = runner.run_group(f"plcopen_{path.parent.name}_{path.stem}_{engine}", [case],
                           engine=engine)
    problems = runner.verify(case, run)
    assert not problems, f"{path}:\n  " + "\n  ".join(problems)
