"""The FPU flags of a program-type module follow exactly its .uses_fpu, the
flag that makes iec2kmod_run_program() call its body between
kernel_fpu_begin() and kernel_fpu_end().  Every body.o used to get them:
gcc then copied and zeroed structures through %xmm registers in programs
without REAL, run outside such a section, and so overwrote the registers
of whatever user process the task preempted (plc-manager aborted with
'malloc(): unsorted double linked list corrupted' in the QEMU tier).  The
kbuild tier checks the built objects themselves
(tests/kbuild/test_execution_kbuild.py, fpu_outside_sections)."""

import json

import pytest

from iec2kmod import kmod
from iec2kmod.parse import frontend

pytestmark = pytest.mark.unit

SOURCE = """
TYPE Pair : STRUCT a : DINT; b : DINT; c : LINT; d : LINT; END_STRUCT; END_TYPE
PROGRAM Ints
VAR p, q : Pair; s : STRING[40]; END_VAR
  q := p; s := CONCAT(s, 'x');
END_PROGRAM
PROGRAM Reals
VAR r : REAL; END_VAR
  r := r + 0.5;
END_PROGRAM
CONFIGURATION C
  RESOURCE R ON PLC
    TASK t (INTERVAL := T#10ms, PRIORITY := 1);
    PROGRAM i WITH t : Ints;
    PROGRAM j WITH t : Reals;
  END_RESOURCE
END_CONFIGURATION
"""


def test_fpu_flags_only_where_the_body_runs_in_a_kernel_fpu_section(tmp_path):
    src = tmp_path / "fpu.st"
    src.write_text(SOURCE)
    result = frontend.run([str(src)], use_cache=False)
    assert result.ok, result
    out = tmp_path / "tree"
    kmod.generate_tree(result.project, out)
    manifest = json.loads((out / "manifest.json").read_text())
    seen = {}
    for m in manifest["modules"]:
        kbuild = (out / m["dir"] / "Kbuild").read_text()
        flagged = [l for l in kbuild.splitlines() if kmod.FP_FLAGS in l]
        if m["kind"] == "program":
            seen[m["program_type"].upper()] = m["uses_fpu"]
            main = (out / m["dir"] / "main.c").read_text()
            assert f".uses_fpu = {'true' if m['uses_fpu'] else 'false'}," in main
        if m.get("uses_fpu"):
            assert "CFLAGS_body.o += " + kmod.FP_FLAGS in flagged, kbuild
        else:
            assert flagged == [], f"{m['name']}: {flagged}"
    assert seen == {"INTS": False, "REALS": True}
