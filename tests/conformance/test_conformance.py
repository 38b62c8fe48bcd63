"""The conformance corpus (issue 10, item 3): for each construct the grammar
knows, a valid file that must check clean and, where it runs, execute with
known results in the C simulator and in the reference interpreter; invalid
files with their expected diagnostics; the standard's Annex F examples; a
program in the shape OpenPLC Editor generates, which must also build as
kernel modules (kbuild tier).  The layout and the annotations are in
README.md here."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
VALID = HERE / "valid"
INVALID = HERE / "invalid"
ANNEXF = HERE / "annexf"
sys.path.insert(0, str(ROOT / "tests" / "execution"))

import runner  # noqa: E402

from iec2kmod.parse import frontend  # noqa: E402
from iec2kmod.checks import check_project  # noqa: E402
from iec2kmod.diagnostics import Diagnostics, SourceFile  # noqa: E402
from iec2kmod.parse.parser import metamodel, parse_source  # noqa: E402


def _sources(d: Path) -> list[Path]:
    return sorted(p for p in d.rglob("*") if p.suffix in (".st", ".il"))


VALID_FILES = _sources(VALID)
INVALID_FILES = _sources(INVALID)
ANNEXF_FILES = _sources(ANNEXF)
# the standard's own typo: refused, with this message (README.md)
ANNEXF_REFUSED = {"f6_10_diffeq.st": "expected unary operator, identifier, literal, '(' or "
                                     "direct address, found ']'"}
ANNEXF_LIBRARY = [p for p in ANNEXF_FILES if p.name not in ANNEXF_REFUSED]
# an empty or shrunken corpus would pass as "skipped": fail at collection
assert len(VALID_FILES) >= 11 and len(INVALID_FILES) >= 10 and len(ANNEXF_FILES) >= 19, \
    (len(VALID_FILES), len(INVALID_FILES), len(ANNEXF_FILES))

_WARNS = re.compile(r"\(\*\s*CHECK WARNS at line (\d+): (.*?)\s*\*\)")


def _project_files(path: Path) -> list[Path]:
    """A valid file and what it needs: the Annex F programs use the library."""
    return [path] + (ANNEXF_LIBRARY if path.parent.name == "annexf" else [])


# ---------------------------------------------------------------- valid files

@pytest.mark.unit
@pytest.mark.parametrize("path", VALID_FILES, ids=[p.stem for p in VALID_FILES])
def test_valid_file_checks_clean(path):
    """No error; no warning but those the file announces with
    (* CHECK WARNS at line N: message *)."""
    res = frontend.run([str(p) for p in _project_files(path)], use_cache=False)
    got = sorted((d.line, d.message) for d in res.diags.items if Path(d.path) == path)
    others = [d.format() for d in res.diags.items if Path(d.path) != path]
    want = sorted((int(n), m) for n, m in _WARNS.findall(path.read_text()))
    assert res.ok and not others, "\n".join(d.format() for d in res.diags.sorted())
    assert got == want, "\n".join(d.format() for d in res.diags.sorted())


def _rule_names(node, out: set):
    stack = [node]
    while stack:
        n = stack.pop()
        out.add(n.rule_name)
        if not hasattr(n, "value") or isinstance(n, list):
            stack.extend(n)


# grammar rules no valid file needs to reach, and why
NOT_REACHED = {
    "SIMPLE_OPERAND": "a fast path of the parser: matches only what Operand's other rules would",
    "ANY_NAME": "declared for member and parameter names; no rule uses it at present",
    "SFC_END_TRANSITION": "a negative look-ahead only (where an IL condition ends): never a "
                          "node of the parse tree",
    "Comment": "skipped before the parse tree is built: the three kinds are checked in the "
               "text (test_every_comment_kind_is_used)",
}


@pytest.mark.unit
def test_every_comment_kind_is_used():
    text = "".join(p.read_text() for p in VALID_FILES)
    assert "(*" in text and "//" in text and re.search(r"\{[^}*]*\}", text)


@pytest.mark.unit
def test_every_grammar_rule_is_used_by_a_valid_file():
    """The corpus covers the grammar: every rule of iec61131.tx appears in
    the parse tree of some valid file (or of the Annex F library)."""
    mm = metamodel()
    seen: set = set()
    for path in VALID_FILES + ANNEXF_LIBRARY:
        parser = mm._parser_blueprint.clone()
        _rule_names(parser.parse(path.read_text(), file_name=str(path)), seen)
    grammar = (ROOT / "iec2kmod" / "parse" / "grammar" / "iec61131.tx").read_text()
    grammar = re.sub(r"/\*.*?\*/", "", grammar, flags=re.S)
    rules = set(re.findall(r"^([A-Za-z_][A-Za-z0-9_]*)(?:\[[^\]]*\])?:", grammar, re.M))
    assert len(rules) > 100
    missing = sorted(rules - seen - set(NOT_REACHED))
    assert not missing, f"no valid file in {VALID} uses the grammar rules {missing}"


def _cases():
    out = []
    for area in sorted(p for p in VALID.iterdir() if p.is_dir() and p.name != "check"):
        for f in _sources(area):
            out.append(runner.load_case(f, area.name))
    return out


CASES = _cases()
assert len(CASES) >= 9, len(CASES)
_RUNS: dict = {}


def _run(case, engine):
    if case.standalone:
        key, group = (case.name, engine), [case]
    else:
        key = (case.area, engine)
        group = [c for c in CASES if c.area == case.area and not c.standalone]
    if key not in _RUNS:
        extra = ANNEXF_LIBRARY if case.area == "annexf" else ()
        _RUNS[key] = runner.run_group(f"conf_{key[0].replace('/', '_').replace('.', '_')}",
                                      group, engine=engine, extra_sources=extra)
    return _RUNS[key]


@pytest.mark.execution
@pytest.mark.parametrize("engine", ["c", "vm"])
@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_valid_file_runs(case, engine):
    """The values written in the file's EXPECT blocks, in the compiled C
    simulator and in the reference interpreter."""
    problems = runner.verify(case, _run(case, engine))
    assert not problems, f"{case.path} ({engine}):\n  " + "\n  ".join(problems)


# -------------------------------------------------------------- invalid files

_EXPECT = re.compile(r"\(\*\s*EXPECT\s*\n(.*?)\*\)", re.S)


def _diagnostics(path: Path) -> list[str]:
    diags = Diagnostics()
    unit = parse_source(SourceFile(str(path), path.read_text()), diags)
    if unit is not None and not diags.errors:
        check_project([unit], diags)
    return [f"{d.line}:{d.col}: {d.severity}: {d.message}" for d in diags.sorted()]


@pytest.mark.unit
@pytest.mark.parametrize("path", INVALID_FILES, ids=[p.stem for p in INVALID_FILES])
def test_invalid_file_diagnostics(path):
    m = _EXPECT.search(path.read_text())
    assert m, f"{path}: an invalid file needs an (* EXPECT ... *) block"
    want = [ln.strip() for ln in m.group(1).splitlines() if ln.strip()]
    assert any(": error: " in w for w in want)
    assert _diagnostics(path) == want


@pytest.mark.unit
def test_invalid_files_get_file_line_col_and_a_caret():
    """Through the CLI, as a user sees it: exit status 1, every error as
    file:line:col: error: message, then the source line and a caret under
    the column; never a traceback."""
    for path in INVALID_FILES:
        p = subprocess.run([sys.executable, "-m", "iec2kmod.cli", "check", str(path)],
                           cwd=ROOT, capture_output=True, text=True, timeout=300)
        out = p.stdout + p.stderr
        assert p.returncode == 1 and "Traceback" not in out, (path, p.returncode, out)
        lines = out.splitlines()
        src = path.read_text().splitlines()
        errors = 0
        for i, ln in enumerate(lines):
            m = re.match(rf"^{re.escape(str(path))}:(\d+):(\d+): error: \S", ln)
            if not m:
                continue
            errors += 1
            line, col = int(m.group(1)), int(m.group(2))
            assert lines[i + 1] == src[line - 1], (path, ln)
            assert lines[i + 2] == " " * (col - 1) + "^", (path, ln, lines[i + 2])
        assert errors >= 1, (path, out)


# -------------------------------------------------------------------- Annex F

@pytest.mark.unit
@pytest.mark.parametrize("path", ANNEXF_FILES, ids=[p.stem for p in ANNEXF_FILES])
def test_annexf_example(path):
    """Each Annex F example with the examples it instantiates: accepted, but
    for the standard's own typo (refused with its message)."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        from annexf_tally import DEPENDS
    finally:
        sys.path.remove(str(ROOT / "benchmarks"))
    files = [path] + [ANNEXF / d for d in DEPENDS.get(path.name, [])]
    res = frontend.run([str(p) for p in files], use_cache=False)
    errors = [d.message for d in res.diags.items if d.severity == "error"]
    if path.name in ANNEXF_REFUSED:
        assert errors == [ANNEXF_REFUSED[path.name]]
    else:
        assert res.ok, "\n".join(d.format() for d in res.diags.sorted())


# ------------------------------------------------------------------ OpenPLC

@pytest.mark.kbuild
def test_openplc_program_builds_as_kernel_modules(tmp_path):
    """generated_plc.st (its run is test_valid_file_runs) builds with W=1,
    sparse and zero warnings, through the kbuild tier's cached builder."""
    sys.path.insert(0, str(ROOT / "tests" / "kbuild"))
    try:
        from test_execution_kbuild import built_tree
    finally:
        sys.path.remove(str(ROOT / "tests" / "kbuild"))
    case = next(c for c in CASES if c.area == "openplc")
    tree = built_tree("conformance_openplc", [case], tmp_path)
    import json
    manifest = json.loads((tree / "manifest.json").read_text())
    assert manifest["configuration"] == "Config0"
    missing = [m for m in manifest["load_order"] if not (tree / m / f"{m}.ko").exists()]
    assert not missing and len(manifest["load_order"]) == 3, manifest["load_order"]
