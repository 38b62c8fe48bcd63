#!/usr/bin/env python3
"""PLCopen XML projects of the tools users have (issue 28): Beremiz's
examples and test projects (and OpenPLC Editor projects) through iec2kmod.

    python3 benchmarks/plcopen_corpus.py PATH [PATH...] [--cycles N]
                                         [--engines c,interp] [--list]
    python3 benchmarks/plcopen_corpus.py --smoke   (tests/plcopen/projects, 3 cycles)

PATH is a checkout the user fetched: a Beremiz repository (its
``exemples/*/plc.xml`` and ``tests/projects/*/plc.xml`` are taken, and its
``plcopen/tc6_xml_v201.xsd`` validates them), or any directory whose
``plc.xml`` files are projects (an OpenPLC Editor workspace, or a
collection of OpenPLC projects: the editor's own ``editor/examples`` and
``editor/tests`` are in the history of github.com/thiagoralves/OpenPLC_Editor
before commit 7398ab9 moved them to a submodule; gracesrm/OpenPLC_Sample_Programs,
kato-works/openplc_school_01, virajdesai0309/OpenPLC_Tutorials and
wonka929/OSCAT_OpenPLC hold more), or a single file.  Nothing is fetched and
no project is copied into this repository (Beremiz is GPL).

Each project is checked (``iec2kmod check``); one that checks clean and has
a configuration is simulated N cycles of its fastest task in every engine
asked, every variable recorded after every cycle, and the engines' traces
compared.  A project is "IEC only" when its directory holds no Beremiz
extension (a ``NAME@KIND`` directory: py_ext, c_ext, svghmi, modbus, ...):
those are the ones issue 28 asks to run; the others are reported apart
since their refusals come from the extension's types and blocks.

--generator (a full Beremiz checkout; benchmarks/plcopen_vs_beremiz.py
does the same on any projects): Beremiz's own XML-to-ST generator
(PLCGenerator, run headless in a subprocess with Beremiz's fake_wx and stub
modules for the GUI's imports) writes its ST of every project that runs
here; that ST is checked and simulated too (interpreter), and every
variable the two have in common (hidden temporaries left out) is compared
after every cycle: "same" or the first difference.

Printed: one line per project (result or first error), then the counts by
result and refusal cause, for the IEC-only projects and for the others.
The exit status is 1 when an IEC-only project fails or two engines differ.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def projects(path: Path) -> list[Path]:
    if (path / "exemples").is_dir() or (path / "tests" / "projects").is_dir():
        found = sorted(path.glob("exemples/*/plc.xml")) + \
            sorted(path.glob("tests/projects/*/plc.xml"))
    elif path.is_file():
        found = [path]
    else:
        found = sorted(path.rglob("plc.xml"))
    return found


def shown(root: Path, proj: Path) -> Path:
    """How a project found under root is named in a report: its path below
    root, or its file name when root is the project file itself."""
    if proj == root or not proj.is_relative_to(root):
        return Path(proj.name) if proj == root else proj
    return proj.relative_to(root)


def extensions(project: Path) -> list[str]:
    return sorted({d.name.split("@", 1)[1] for d in project.parent.iterdir()
                   if d.is_dir() and "@" in d.name})


def cause(message: str) -> str:
    """An error message without its names: the refusal's kind."""
    m = re.sub(r"\s*\((?:block localId|pou|variable|step|transition|action|dataType|"
               r"task|resource|configuration|pouInstance|member)[^()]*\)$", "", message)
    if not m.startswith("unknown type"):   # which type is the cause: kept
        m = re.sub(r"'[^']*'", "'…'", m)
    m = re.sub(r"localId \d+", "localId N", m)
    m = re.sub(r"%[IQM][XBWDL]?[\d.]+", "%…", m)
    return m


def simulate(project, cycles, engine):
    from iec2kmod import interp, sim
    from iec2kmod.compilation import Compilation
    periods = [t.interval_ns for c in project.configurations for r in c.resources
               for t in r.tasks.values() if t.interval_ns]
    if not periods:
        raise sim.SimError("no periodic task")
    step = min(periods)
    end = step * (cycles - 1)
    comp = Compilation(project)
    watch = [e.path for e in comp.plan.table]
    if engine == "interp":
        res = interp.run(project, end, watch=watch)
    else:
        res = sim.run(comp, end, watch=watch)
    trace = [res.values_at(k * step) for k in range(cycles)]
    return trace, [f[2] for f in res.faults]


def same(a, b) -> bool:
    """Equal values, a NaN equal to a NaN (a REAL both sides computed as
    NaN is the same result)."""
    if isinstance(a, float) and isinstance(b, float) and a != a and b != b:
        return True
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    return a == b


def run_one(path: Path, cycles: int, engines: list[str]):
    from iec2kmod.parse import frontend
    t0 = time.perf_counter()
    res = frontend.run([str(path)], use_cache=False)
    errors = res.diags.errors
    if errors:
        return "refused", cause(errors[0].message), errors[0].format().split("\n")[0], \
            time.perf_counter() - t0
    if not res.project.configurations:
        return "no configuration", "", "", time.perf_counter() - t0
    traces = {}
    for e in engines:
        try:
            traces[e] = simulate(res.project, cycles, e)
        except Exception as exc:  # noqa: BLE001 - reported as the project's result
            return "sim failed", f"{e}: {type(exc).__name__}", f"{e}: {exc}"[:300], \
                time.perf_counter() - t0
    first = next(iter(traces.values()))
    for e, tr in traces.items():
        if not same(tr, first):
            bad = next(k for k in range(cycles) if not same(tr[0][k], first[0][k])) \
                if not same(tr[0], first[0]) else None
            return "engines differ", e, f"first difference after cycle {bad}", \
                time.perf_counter() - t0
    faults = first[1]
    if faults:
        return "runs (faults)", faults[0], "", time.perf_counter() - t0
    return "runs", "", "", time.perf_counter() - t0


PLCGEN = r"""
import importlib, sys, types
bz, src, out = sys.argv[1:4]
sys.path.insert(0, bz)
import fake_wx


class _Stub(types.ModuleType):
    def __getattr__(self, name):
        if name.startswith("__"):
            raise AttributeError(name)
        return type(name, (), {"__init__": lambda self, *a, **k: None})


for _ in range(40):
    try:
        importlib.import_module("ProjectController")
        break
    except ModuleNotFoundError as exc:
        for k in [k for k in sys.modules if k.split(".")[0] in
                  ("ProjectController", "dialogs", "controls", "editors", "graphics")]:
            del sys.modules[k]
        parts = exc.name.split(".")
        for i in range(1, len(parts) + 1):
            sys.modules.setdefault(".".join(parts[:i]), _Stub(".".join(parts[:i])))
from PLCControler import PLCControler
c = PLCControler()
err = c.OpenXMLFile(src)
if err:
    print("open:", err)
# the runtime library's block types (LOGGER), as ProjectController's
# LoadLibraries gives them to the project's controller
lib = PLCControler()
lib.OpenXMLFile(bz + "/NativeLib.xml")
c.AddConfNodeTypesList([{"name": "Native", "types": lib.Project}])
text, errors, warnings = c.GenerateProgram(out)
for e in errors:
    print("error:", e)
sys.exit(1 if errors or not text else 0)
"""


def beremiz_st(beremiz: Path, proj: Path, out: Path):
    """Beremiz's PLCGenerator's ST of proj, or (None, why)."""
    import subprocess
    p = subprocess.run([sys.executable, "-c", PLCGEN, str(beremiz), str(proj), str(out)],
                       capture_output=True, text=True, timeout=300, cwd=str(beremiz))
    if p.returncode != 0 or not out.is_file():
        tail = (p.stdout + p.stderr).strip().splitlines()
        return None, (tail[-1] if tail else f"exit {p.returncode}")[:200]
    return out, None


def exported_st(proj: Path, out: Path):
    """Our own `export --st` of proj, or (None, why): what stands in for
    Beremiz's generator in plcopen_vs_beremiz's smoke run, where no Beremiz
    checkout exists (the comparison is then the round trip XML -> ST)."""
    from iec2kmod.plcopen.reader import to_text
    text, items = to_text(str(proj))
    errors = [d for d in items if d.severity == "error"]
    if errors:
        return None, errors[0].message
    out.write_text(text, encoding="utf-8")
    return out, ""


def compare_generator(beremiz, proj: Path, cycles: int, workdir: Path) -> str:
    """'same', or what differs between our translation and Beremiz's
    (beremiz: a checkout, or a function (proj, out) -> (ST path | None, why)
    that writes the other ST)."""
    from iec2kmod import interp
    from iec2kmod.parse import frontend
    from iec2kmod.compilation import Compilation
    out = workdir / (proj.parent.name + ".st")
    st, why = beremiz(proj, out) if callable(beremiz) else beremiz_st(beremiz, proj, out)
    if st is None:
        return f"Beremiz's generator failed: {why}"
    text = st.read_text(encoding="utf-8")
    if re.search(r"\bLOGGER\b", text, re.I) and \
            not re.search(r"FUNCTION_BLOCK\s+LOGGER\b", text, re.I):
        # the runtime library's LOGGER is not in the generated program (the
        # IDE compiles the library apart): the same definition as ours
        from iec2kmod.plcopen.reader import BEREMIZ_LIBRARY
        text = BEREMIZ_LIBRARY["LOGLEVEL"][1] + "\n" + BEREMIZ_LIBRARY["LOGGER"][1] + \
            "\n" + text
        st.write_text(text, encoding="utf-8")
    theirs = frontend.run([str(st)], use_cache=False)
    if not theirs.ok:
        return "Beremiz's ST refused: " + cause(theirs.diags.errors[0].message)
    ours = frontend.run([str(proj)], use_cache=False)
    names_ours = {e.path.upper(): e.path for e in Compilation(ours.project).plan.table}
    common = [e.path for e in Compilation(theirs.project).plan.table
              if e.path.upper() in names_ours and
              not any(part.startswith("_") for part in e.path.split("."))]
    periods = [t.interval_ns for c in ours.project.configurations for r in c.resources
               for t in r.tasks.values() if t.interval_ns]
    step = min(periods)
    a = interp.run(ours.project, step * (cycles - 1), watch=common)
    b = interp.run(theirs.project, step * (cycles - 1), watch=common)
    for k in range(cycles):
        va, vb = a.values_at(k * step), b.values_at(k * step)
        diff = [n for n in vb if not same(va.get(n), vb.get(n))]
        if diff:
            n = diff[0]
            return (f"differ after cycle {k + 1}: {n} ours {va.get(n)!r}, Beremiz's "
                    f"{vb.get(n)!r} ({len(diff)} variables)")
    return f"same ({len(common)} variables, {cycles} cycles)"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("paths", nargs="*", type=Path)
    ap.add_argument("--cycles", type=int, default=20)
    ap.add_argument("--engines", default="c,interp")
    ap.add_argument("--list", action="store_true", help="print the first error of each project")
    ap.add_argument("--generator", action="store_true",
                    help="compare with Beremiz's PLCGenerator's ST (a full Beremiz checkout)")
    ap.add_argument("--smoke", action="store_true",
                    help="this repository's tests/plcopen/projects, 3 cycles")
    args = ap.parse_args(argv)
    if args.smoke:
        args.paths = args.paths or [ROOT / "tests" / "plcopen" / "projects"]
        args.cycles = 3
    if not args.paths:
        ap.error("name a Beremiz checkout or a directory of plc.xml projects")
    engines = [e.strip() for e in args.engines.split(",") if e.strip()]
    for p in args.paths:
        xsd = p / "plcopen" / "tc6_xml_v201.xsd"
        if xsd.is_file() and "IEC2KMOD_TC6_XSD" not in os.environ:
            os.environ["IEC2KMOD_TC6_XSD"] = str(xsd)
    print(f"schema: {os.environ.get('IEC2KMOD_TC6_XSD') or 'none (structural checks only)'}")
    counts = {True: Counter(), False: Counter()}
    gen_counts = Counter()
    failed = False
    for root in args.paths:
        for proj in projects(root):
            ext = extensions(proj)
            iec = not ext
            result, why, detail, secs = run_one(proj, args.cycles, engines)
            counts[iec][(result, why)] += 1
            rel = shown(root, proj)
            tag = "IEC only" if iec else "ext: " + ",".join(ext)
            print(f"{str(rel):50} {tag:28} {result}{': ' + why if why else ''} ({secs:.1f} s)")
            if args.list and detail:
                print(f"    {detail}")
            if args.generator and result in ("runs", "runs (faults)") and \
                    (root / "PLCGenerator.py").is_file():
                import tempfile
                with tempfile.TemporaryDirectory() as tmp:
                    verdict = compare_generator(root, proj, args.cycles, Path(tmp))
                gen_counts[verdict.split(" (")[0].split(":")[0]] += 1
                print(f"    Beremiz's generator: {verdict}")
            if iec and result not in ("runs", "runs (faults)", "no configuration") or \
                    result == "engines differ":
                failed = True
    for iec in (True, False):
        total = sum(counts[iec].values())
        print(f"\n{'IEC-only projects' if iec else 'projects with extensions'}: {total}")
        for (result, why), n in sorted(counts[iec].items(), key=lambda kv: (-kv[1], kv[0])):
            print(f"  {n:3}  {result}{': ' + why if why else ''}")
    if gen_counts:
        print("\nagainst Beremiz's generator: " +
              ", ".join(f"{n} {k}" for k, n in sorted(gen_counts.items())))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
