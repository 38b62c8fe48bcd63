"""The C emitter: deterministic output that names its sources, and the
checker fix it relies on (alias types carry their initial value)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from helpers import parse_ok  # noqa: F401 - keeps the helpers importable

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = sorted(p for p in (ROOT / "examples").iterdir() if p.is_dir())
# an empty or shrunken list would pass as "skipped": fail at collection instead
assert len(EXAMPLES) >= 12, f"only {len(EXAMPLES)} example projects under {ROOT / 'examples'}"

_GEN = r"""
import hashlib, json, sys
from iec2kmod.parse import frontend
from iec2kmod.codegen import generate, source_names
from iec2kmod.sim import render_sim
out = {}
for d in sys.argv[1:]:
    res = frontend.run([d], use_cache=False)
    assert res.ok, d
    gen = generate(res.project)
    files = {gen.header_name: gen.header}
    files.update({name: text for name, text in gen.bodies.values()})
    sim_files, _ = render_sim(res.project)
    files["sim_project.c"] = sim_files["sim_project.c"]
    # named relative to the directory holding the sources (no machine path)
    names = {id(u.src): n for u, n in source_names(res.project)}
    assert all("/" not in n for n in names.values()), names
    out[d] = {"files": files, "sources": sorted(names.values()),
              "pou_src": {name: names[id(p.src)] for name, p in
                          ((f"pou_{p.name.lower()}.c", p) for p in res.project.pous.values())}}
print(json.dumps(out))
"""


def _generate(seed: str):
    env = dict(os.environ, PYTHONHASHSEED=seed)
    p = subprocess.run([sys.executable, "-c", _GEN, *map(str, EXAMPLES)], cwd=ROOT, env=env,
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr[-3000:]
    return json.loads(p.stdout)


@pytest.fixture(scope="module")
def two_runs():
    return _generate("1"), _generate("4242")


def test_generated_c_is_deterministic(two_runs):
    a, b = two_runs
    assert a.keys() == b.keys()
    for d in a:
        fa, fb = a[d]["files"], b[d]["files"]
        assert fa.keys() == fb.keys(), d
        for name in fa:
            assert fa[name] == fb[name], f"{d}/{name} differs between two runs"


def _leading_comment(text: str) -> str:
    """The comments a file starts with (everything before the first line of code)."""
    out = []
    in_comment = False
    for line in text.splitlines():
        s = line.strip()
        if in_comment or s.startswith(("/*", "//")) or not s:
            out.append(line)
            if s.startswith("/*"):
                in_comment = "*/" not in s
            elif in_comment and "*/" in s:
                in_comment = False
            continue
        break
    return "\n".join(out)


def test_generated_c_names_its_sources(two_runs):
    a, _ = two_runs
    for d, info in a.items():
        files = info["files"]
        header = next(n for n in files if n.endswith("_types.h"))
        lead = _leading_comment(files[header])
        for src in info["sources"]:
            assert src in lead, f"{d}/{header} does not name {src} in its first comment"
        for name, src in info["pou_src"].items():
            assert name in files, name
            assert src in _leading_comment(files[name]), f"{d}/{name} does not name {src}"
        lead = _leading_comment(files["sim_project.c"])
        for src in info["sources"]:
            assert src in lead, f"{d}/sim_project.c does not name {src} in its first comment"


def test_alias_types_carry_their_initial_value():
    from iec2kmod.checks import check_project
    from iec2kmod.diagnostics import Diagnostics, SourceFile
    from iec2kmod.parse.parser import parse_source
    text = """
TYPE
    Count : DINT := 42;
    Count2 : Count;
    Name : STRING[8] := 'anon';
    S : STRUCT a : Count; b : Count := 1; END_STRUCT;
END_TYPE
PROGRAM p
VAR
    n : Count;
    m : Count := 7;
    k : Count2;
    who : Name;
    s : S;
END_VAR
    n := n + m + k;
END_PROGRAM
"""
    diags = Diagnostics()
    unit = parse_source(SourceFile("t.st", text), diags)
    project = check_project([unit], diags)
    assert not diags.errors, [d.format() for d in diags.items]
    v = project.pous["P"].vars
    assert v["N"].init.value == 42
    assert v["M"].init.value == 7
    assert v["K"].init.value == 42
    assert v["WHO"].init.value == "anon"
    fields = project.types["S"].fields
    assert fields["A"][2].value == 42 and fields["B"][2].value == 1


def test_frame_need_of_many_callees_stays_small_after_preprocessing(tmp_path):
    """A POU's frame need is the MAX over its callees' (IEC_FRAME_MAX names
    each argument twice): as one chained macro, 20 callees expanded to 2^20
    copies (a program calling OSCAT's 60 functions took gcc minutes and
    18 GB); as enumeration constants, one per partial maximum, it is
    linear."""
    from iec2kmod.checks import check_project
    from iec2kmod.codegen import generate
    from iec2kmod.diagnostics import Diagnostics, SourceFile
    from iec2kmod.parse.parser import parse_source
    k = 20
    funcs = "".join(f"FUNCTION F{i} : INT\n  VAR_INPUT a : INT; END_VAR\n"
                    f"  VAR t : ARRAY[1..4] OF INT; END_VAR\n  t[1] := a; F{i} := t[1] + {i};\n"
                    "END_FUNCTION\n" for i in range(k))
    calls = " + ".join(f"F{i}(n)" for i in range(k))
    text = funcs + f"PROGRAM p\n  VAR n : INT; END_VAR\n  n := {calls};\nEND_PROGRAM\n"
    diags = Diagnostics()
    unit = parse_source(SourceFile("t.st", text), diags)
    project = check_project([unit], diags)
    assert not diags.errors, [d.format() for d in diags.items]
    gen = generate(project)
    defines = [line for body in gen.bodies.values() for line in body[1].splitlines()
               if line.startswith(("#define IEC_FRAME_NEED_", "enum { IEC_FRAME_NEED_"))]
    assert len(defines) >= k + 1
    c = tmp_path / "need.c"
    c.write_text("#define IEC_FRAME_MAX(a, b)\t((a) > (b) ? (a) : (b))\n"
                 "#define IEC_FRAME_ALIGN(n) (n)\n" + "\n".join(
                     d for d in defines) + "\nunsigned long need = IEC_FRAME_NEED_PROG_P;\n")
    p = subprocess.run(["gcc", "-E", "-P", str(c)], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    assert len(p.stdout) < 200_000, len(p.stdout)
