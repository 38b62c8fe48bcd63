"""benchmarks/mutate.py --smoke (issue 29): the mutation benchmark runs end
to end -- finds its sites, applies two mutants in a copy of the tree, runs
their tests, reports a verdict each and the score table -- and leaves the
working tree as it was, so the script cannot rot."""

from __future__ import annotations

import hashlib
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _digest(rel):
    return hashlib.sha256((ROOT / rel).read_bytes()).hexdigest()


def test_mutation_benchmark_smoke():
    before = _digest("iec2kmod/checks/types.py")
    p = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "mutate.py"), "--smoke"],
                       cwd=ROOT, capture_output=True, text=True, timeout=600)
    out = p.stdout + p.stderr
    assert p.returncode == 0, out
    assert re.search(r"^\d+ sites in checks; 2 mutants", out, re.M), out
    verdicts = re.findall(r"^\[(\d)/2\] (killed|survived) ", out, re.M)
    assert [n for n, _ in verdicts] == ["1", "2"], out
    row = re.search(r"^total\s+(\d+)\s+(\d+)\s+(\d+)", out, re.M)
    assert row and int(row[1]) + int(row[2]) == 2, out
    assert _digest("iec2kmod/checks/types.py") == before


def test_mutation_sites_cover_every_area():
    sys.path.insert(0, str(ROOT / "benchmarks"))
    import mutate
    found = mutate.sites(ROOT, list(mutate.AREAS))
    per = {a: sum(1 for m in found if m.area == a) for a in mutate.AREAS}
    assert all(n >= 20 for n in per.values()), per
    kinds = {m.kind for m in found}
    assert {"compare", "and/or", "drop not", "off by one", "drop mask", "operator"} <= kinds
    # every site's text is where the mutant says
    for m in found[::37]:
        line = (ROOT / m.path).read_text().splitlines()[m.line - 1]
        assert line[m.col:m.col + len(m.old)] == m.old, m.label()
