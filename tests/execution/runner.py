"""Execution test runner: IEC sources with their expected values inside.

A case is one source file under ``cases/<area>/`` (``.st`` or ``.il``) that
declares exactly one PROGRAM, plus any TYPEs, FUNCTIONs and
FUNCTION_BLOCKs it needs.  The runner wraps the programs of an area into
one configuration -- one periodic task per program, the instance named like
the program -- so that an area is one simulator build (compile time
dominates).  POU and type names are therefore unique over an area.

A case that declares its own CONFIGURATION runs alone, as written; its
checkpoint cycles count the fastest task's cycles and its paths are the
simulator's paths (``r.inst.x``).

Annotations are comments in the source:

    (* @interval T#100ms *)      task interval (default T#10ms)
    (* INPUT at cycle 3: start = TRUE; level = 12 *)
                                 values written before that cycle runs
    (* EXPECT after 3 cycles: x = 6; s = 'abc'; t.Q = TRUE *)
                                 values after the Nth cycle (N >= 1)
    (* EXPECT FAULT in cycle 4 at line 12: division by zero *)
                                 the task stops in cycle 4 with a runtime
                                 error at that line of this file
                                 (text: part of the fault's name)

Several EXPECT blocks make several checkpoints; a block may span lines.
Paths are relative to the program instance (``x``, ``fb.Q``, ``a[1,2]``,
``rec.name``).  Values are IEC literals: TRUE, -5, 16#FF, 2.5, T#1s,
'text', "wide", DT#..., or an enumeration value name.  REAL/LREAL compare
with a relative tolerance of 1E-6 (write ``x == 0.1`` for an exact
comparison).  A case without EXPECT FAULT must not fault.

ST/IL pairs live in ``pairs/``: ``<name>.st`` declares PROGRAM <name>_st,
``<name>.il`` PROGRAM <name>_il, with the same VAR_INPUT/VAR_OUTPUT
interface.  Both run for many cycles on the same pseudo-random inputs
(deterministic seed) and their traces must be identical.
"""

from __future__ import annotations

import math
import os
import random
import re
from dataclasses import dataclass, field
from pathlib import Path

from iec2kmod import frontend, sim
from iec2kmod.checks.types import Elementary, EnumT, SubrangeT, concrete
from iec2kmod.literals import LiteralError, classify

HERE = Path(__file__).resolve().parent
CASES = HERE / "cases"
PAIRS = HERE / "pairs"
DEFAULT_INTERVAL = 10_000_000
SANITIZER_REPORT = re.compile(r"runtime error|Sanitizer|^==\d+==|SUMMARY:", re.M)

_COMMENT = re.compile(r"\(\*(.*?)\*\)", re.S)
_EXPECT = re.compile(r"^\s*EXPECT\s+after\s+(\d+)\s+cycles?\s*:(.*)$", re.S | re.I)
_FAULT = re.compile(r"^\s*EXPECT\s+FAULT\s+in\s+cycle\s+(\d+)\s+at\s+line\s+(\d+)\s*:(.*)$",
                    re.S | re.I)
_INPUT = re.compile(r"^\s*INPUT\s+at\s+cycle\s+(\d+)\s*:(.*)$", re.S | re.I)
_INTERVAL = re.compile(r"^\s*@interval\s+(\S+)\s*$", re.I)
_PROGRAM = re.compile(r"^\s*PROGRAM\s+([A-Za-z_]\w*)", re.M | re.I)
_CONFIG = re.compile(r"^\s*CONFIGURATION\b", re.M | re.I)


class CaseError(Exception):
    """A malformed case file."""


@dataclass
class Check:
    path: str
    text: str          # the expected value as written
    exact: bool = False


@dataclass
class Case:
    path: Path
    area: str
    program: str | None           # None: the file has its own configuration
    interval_ns: int = DEFAULT_INTERVAL
    checkpoints: list = field(default_factory=list)   # (cycle, [Check])
    faults: list = field(default_factory=list)        # (cycle, line, text)
    inputs: list = field(default_factory=list)        # (cycle, path, text)

    @property
    def name(self) -> str:
        return f"{self.area}/{self.path.name}"

    @property
    def standalone(self) -> bool:
        return self.program is None

    @property
    def last_cycle(self) -> int:
        cycles = [c for c, _ in self.checkpoints] + [c for c, _, _ in self.faults]
        return max(cycles)

    def full_path(self, p: str) -> str:
        return p if self.standalone else f"{self.program}.{p}"


def split_items(text: str) -> list[str]:
    """Splits 'a = 1; s = 'x;y'' at semicolons outside quotes."""
    out, cur, quote, escape = [], [], None, False
    for ch in text:
        if quote:
            cur.append(ch)
            if escape:
                escape = False
            elif ch == "$":
                escape = True
            elif ch == quote:
                quote = None
        elif ch in "'\"":
            quote = ch
            cur.append(ch)
        elif ch == ";":
            out.append("".join(cur))
            cur = []
        else:
            cur.append(ch)
    out.append("".join(cur))
    return [x.strip() for x in out if x.strip()]


def _assignments(text, where):
    out = []
    for item in split_items(text):
        m = re.match(r"^([A-Za-z_%][\w.,\[\]%+-]*)\s*(==|=)\s*(.+)$", item, re.S)
        if not m:
            raise CaseError(f"{where}: cannot read '{item}' (write path = value)")
        out.append(Check(m.group(1), m.group(3).strip(), m.group(2) == "=="))
    return out


def load_case(path: Path, area: str) -> Case:
    text = path.read_text(encoding="utf-8")
    programs = _PROGRAM.findall(text)
    standalone = bool(_CONFIG.search(text))
    if not standalone and len(programs) != 1:
        raise CaseError(f"{path}: a case declares exactly one PROGRAM ({len(programs)} found)")
    case = Case(path, area, None if standalone else programs[0])
    for m in _COMMENT.finditer(text):
        body = m.group(1)
        line = text.count("\n", 0, m.start()) + 1
        where = f"{path}:{line}"
        if mm := _FAULT.match(body):
            case.faults.append((int(mm.group(1)), int(mm.group(2)), mm.group(3).strip()))
        elif mm := _EXPECT.match(body):
            case.checkpoints.append((int(mm.group(1)), _assignments(mm.group(2), where)))
        elif mm := _INPUT.match(body):
            for c in _assignments(mm.group(2), where):
                case.inputs.append((int(mm.group(1)), c.path, c.text))
        elif mm := _INTERVAL.match(body):
            case.interval_ns = sim.parse_time(mm.group(1))
        elif re.match(r"^\s*(EXPECT|INPUT)\b", body, re.I):
            raise CaseError(f"{where}: malformed annotation: {body.strip()[:60]}")
    if not case.checkpoints and not case.faults:
        raise CaseError(f"{path}: no EXPECT block")
    if any(c < 1 for c, _ in case.checkpoints) or any(c < 1 for c, _, _ in case.faults):
        raise CaseError(f"{path}: cycles count from 1")
    return case


def discover(root: Path = CASES) -> list[Case]:
    cases = []
    for area in sorted(p for p in root.iterdir() if p.is_dir()):
        for f in sorted(area.iterdir()):
            if f.suffix.lower() in (".st", ".il"):
                cases.append(load_case(f, area.name))
    return cases


# ------------------------------------------------------------------ values
def parse_value(text: str):
    """('bool'|'int'|'real'|'string'|'enum'|'nan'|'inf', value) of a literal."""
    s = text.strip()
    sign = 1
    if s[:1] in "+-" and not s.startswith(("'", '"')):
        sign, s = (-1 if s[0] == "-" else 1), s[1:].strip()
    if s.upper() in ("NAN",):
        return "nan", None
    if s.upper() in ("INF", "INFINITY"):
        return "real", sign * math.inf
    try:
        kind, value, _ = classify(s)
    except (LiteralError, ValueError):
        if re.fullmatch(r"[A-Za-z_]\w*(#[A-Za-z_]\w*)?", s):
            return "enum", s.split("#")[-1].upper()
        raise CaseError(f"cannot read the value '{text}'") from None
    if kind == "bool":
        return "bool", bool(value)
    if kind in ("int", "time", "date", "tod", "dt"):
        return "int", sign * int(value)
    if kind == "real":
        return "real", sign * float(value)
    if kind in ("string", "wstring"):
        return "string", value
    raise CaseError(f"unsupported value '{text}'")


def matches(actual, check: Check) -> bool:
    kind, exp = parse_value(check.text)
    if kind == "nan":
        return isinstance(actual, float) and math.isnan(actual)
    if kind == "enum":
        return isinstance(actual, str) and actual.upper() == exp
    if kind == "bool":
        return isinstance(actual, bool) and actual == exp
    if kind == "string":
        return isinstance(actual, str) and actual == exp
    if isinstance(actual, bool):
        return kind == "int" and int(actual) == exp
    if isinstance(actual, float):
        if check.exact or math.isinf(exp) or exp == 0:
            return actual == exp or (exp == 0 and abs(actual) < 1e-12 and not check.exact)
        return math.isclose(actual, exp, rel_tol=1e-6, abs_tol=1e-12)
    if isinstance(actual, int):
        return kind == "int" and actual == exp
    return False


# ------------------------------------------------------------------- runs
def build_root() -> Path:
    base = os.environ.get("IEC2KMOD_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "iec2kmod")
    return Path(base)


def _fmt_time(ns: int) -> str:
    return f"T#{ns}ns" if ns % 1_000_000 else f"T#{ns // 1_000_000}ms"


def wrapper_config(name: str, cases) -> str:
    """A configuration with one task and one instance per case program."""
    lines = [f"(* generated by tests/execution/runner.py: {name} *)",
             f"CONFIGURATION exec_{name}"]
    for c in cases:
        lines.append(f"    TASK t_{c.program} (INTERVAL := {_fmt_time(c.interval_ns)}, "
                     f"PRIORITY := 1);")
    for c in cases:
        lines.append(f"    PROGRAM {c.program} WITH t_{c.program} : {c.program};")
    lines.append("END_CONFIGURATION")
    return "\n".join(lines) + "\n"


def check_project(paths):
    try:
        res = frontend.run([str(p) for p in paths], use_cache=False)
    except Exception as exc:  # noqa: BLE001 - a crash of the front end is a case failure
        raise CaseError(f"the front end crashed: {type(exc).__name__}: {exc}") from exc
    if not res.ok:
        msgs = "\n".join(d.format() for d in res.diags.sorted() if d.severity == "error")
        raise CaseError(f"the front end rejected the sources:\n{msgs}")
    return res.project


@dataclass
class GroupRun:
    cases: list
    result: object = None          # sim.SimResult
    error: str | None = None
    task_of: dict = field(default_factory=dict)   # case name -> task name


def run_group(name: str, cases, sanitize=False) -> GroupRun:
    """Builds and runs cases as one simulation (standalone cases: one each)."""
    run = GroupRun(cases)
    try:
        out = build_root() / "exec"
        out.mkdir(parents=True, exist_ok=True)
        if len(cases) == 1 and cases[0].standalone:
            c = cases[0]
            project = check_project([c.path])
            periods = [t.interval_ns for r in project.configurations[0].resources
                       for t in r.tasks.values() if t.interval_ns]
            c.interval_ns = min(periods)
            run.task_of[c.name] = None
            paths = [c.path]
        else:
            cfg = out / f"{name}_config.st"
            text = wrapper_config(name, cases)
            if not cfg.exists() or cfg.read_text() != text:
                cfg.write_text(text)
            paths = [c.path for c in cases] + [cfg]
            project = check_project(paths)
            for c in cases:
                run.task_of[c.name] = f"t_{c.program}"
        end = max((c.last_cycle - 1) * c.interval_ns for c in cases)
        watch, events = [], []
        for c in cases:
            for _, checks in c.checkpoints:
                watch += [c.full_path(k.path) for k in checks]
            for cycle, p, v in c.inputs:
                events.append(((cycle - 1) * c.interval_ns, c.full_path(p), v))
        watch = list(dict.fromkeys(watch))
        trace = None
        if events:
            trace = out / f"{name}{'_san' if sanitize else ''}.{os.getpid()}.csv"
            trace.write_text("".join(f"{t}ns,{p},{v}\n" for t, p, v in events))
        try:
            run.result = sim.run(project, end, watch=watch or None, inputs=str(trace) if trace
                                 else None, sanitize=sanitize, build_dir=build_root() / "sim")
        finally:
            if trace:
                trace.unlink(missing_ok=True)
    except (CaseError, sim.SimError, sim.InternalError) as exc:
        run.error = f"{type(exc).__name__}: {exc}"
    return run


def verify(case: Case, run: GroupRun, sanitize=False) -> list[str]:
    """Mismatches of one case against a group's run (empty: all good)."""
    if run.error:
        return [run.error]
    res = run.result
    problems = []
    if sanitize and SANITIZER_REPORT.search(res.stderr or ""):
        problems.append(f"sanitizer report:\n{res.stderr[:3000]}")
    task = run.task_of.get(case.name)
    faults = [f for f in res.faults if task is None or f[1] == task]
    for cycle, line, text in case.faults:
        t = (cycle - 1) * case.interval_ns
        ok = [f for f in faults if f[0] == t and f[5] == line and
              Path(f[4]).resolve() == case.path.resolve() and text.lower() in f[2].lower()]
        if not ok:
            problems.append(f"expected fault '{text}' in cycle {cycle} at line {line}; got "
                            + (", ".join(f"'{f[2]}' at {Path(f[4]).name}:{f[5]} t={f[0]}"
                                         for f in faults) or "no fault"))
    if not case.faults:
        for f in faults:
            problems.append(f"unexpected runtime error at {f[4]}:{f[5]}: {f[2]} (t={f[0]} ns)")
    for cycle, checks in case.checkpoints:
        vals = res.values_at((cycle - 1) * case.interval_ns)
        for k in checks:
            key = case.full_path(k.path)
            actual = next((v for n, v in vals.items() if n.upper() == key.upper()), "<none>")
            try:
                ok = matches(actual, k)
            except CaseError as exc:
                problems.append(str(exc))
                continue
            if not ok:
                problems.append(f"after {cycle} cycles: {k.path} = {actual!r}, expected {k.text}")
    return problems


# ------------------------------------------------------------------ pairs
@dataclass
class Pair:
    name: str
    st: Path
    il: Path
    cycles: int = 300
    inputs: list = field(default_factory=list)    # VAR_INPUT names (set by run_pairs)
    outputs: list = field(default_factory=list)   # VAR_OUTPUT names (set by run_pairs)


def discover_pairs(root: Path = PAIRS) -> list[Pair]:
    out = []
    for st in sorted(root.glob("*.st")):
        il = st.with_suffix(".il")
        if not il.exists():
            raise CaseError(f"{st}: no IL partner {il.name}")
        out.append(Pair(st.stem, st, il))
    return out


def random_value(rng: random.Random, t):
    """A trace literal for an input of type t: edge values now and then."""
    t = concrete(t)
    if isinstance(t, SubrangeT):
        return str(rng.randint(t.low, t.high))
    if isinstance(t, EnumT):
        return rng.choice([n for n, _ in t.values.values()])
    assert isinstance(t, Elementary), t
    if t.cat == "bool":
        return rng.choice(["TRUE", "FALSE"])
    if t.cat in ("sint", "uint", "bit"):
        signed = t.cat == "sint"
        lo = -(1 << (t.bits - 1)) if signed else 0
        hi = (1 << (t.bits - 1)) - 1 if signed else (1 << t.bits) - 1
        r = rng.random()
        if r < 0.1:
            return str(rng.choice([lo, hi, 0, 1, hi - 1, lo + 1 if signed else 2]))
        if r < 0.6:
            return str(max(lo, min(hi, rng.randint(-20 if signed else 0, 20))))
        return str(rng.randint(lo, hi))
    if t.cat == "real":
        r = rng.random()
        if r < 0.1:
            return rng.choice(["0.0", "-0.5", "0.5", "1.5", "2.5", "-2.5", "100.0"])
        return repr(round(rng.uniform(-200, 200), 3))
    if t.cat == "time":
        return f"T#{rng.randint(0, 2000)}ms"
    raise CaseError(f"no random input for type {t.name}")


def pair_inputs(pair: Pair, project, cycles: int, interval: int):
    """(t, input name, literal) events: every input changes now and then."""
    rng = random.Random(f"iec2kmod-pair-{pair.name}")
    pou = project.pous[f"{pair.name}_st".upper()]
    events = []
    for cycle in range(cycles):
        for v in pou.inputs:
            if cycle == 0 or rng.random() < 0.35:
                events.append((cycle * interval, v.name, random_value(rng, v.type)))
    return events


def run_pairs(pairs, sanitize=False, interval=DEFAULT_INTERVAL):
    """Runs every pair in one simulation: {pair name: (st trace, il trace)} or raises."""
    out = build_root() / "exec"
    out.mkdir(parents=True, exist_ok=True)
    fake = [Case(p.st, "pairs", f"{p.name}_st") for p in pairs] + \
           [Case(p.il, "pairs", f"{p.name}_il") for p in pairs]
    cfg = out / "pairs_config.st"
    text = wrapper_config("pairs", fake)
    if not cfg.exists() or cfg.read_text() != text:
        cfg.write_text(text)
    project = check_project([p.st for p in pairs] + [p.il for p in pairs] + [cfg])
    cycles = max(p.cycles for p in pairs)
    rows, watch = [], []
    iface = {}
    for p in pairs:
        pou = project.pous[f"{p.name}_st".upper()]
        p.inputs = [v.name for v in pou.inputs]
        p.outputs = [v.name for v in pou.outputs]
        names = p.inputs + p.outputs
        iface[p.name] = names
        for suffix in ("st", "il"):
            watch += [f"{p.name}_{suffix}.{n}" for n in names]
        for t, n, v in pair_inputs(p, project, p.cycles, interval):
            rows += [f"{t}ns,{p.name}_st.{n},{v}\n", f"{t}ns,{p.name}_il.{n},{v}\n"]
    trace = out / f"pairs{'_san' if sanitize else ''}.{os.getpid()}.csv"
    trace.write_text("".join(rows))
    try:
        res = sim.run(project, (cycles - 1) * interval, watch=watch, inputs=str(trace),
                      sanitize=sanitize, build_dir=build_root() / "sim")
    finally:
        trace.unlink(missing_ok=True)
    traces = {}
    for p in pairs:
        tr = {}
        for suffix in ("st", "il"):
            prefix = f"{p.name}_{suffix}.".upper()
            tr[suffix] = [(t, res.names[i][len(prefix):].upper(), v) for t, i, v in res.changes
                          if res.names[i].upper().startswith(prefix)]
        traces[p.name] = (tr["st"], tr["il"])
    return res, traces, iface


MIN_OUTPUT_CHANGES = 10        # changes of all outputs together, over a pair's run
MIN_CHANGES_PER_OUTPUT = 2     # every output goes and comes back at least once


def output_changes(trace, outputs) -> dict:
    """{output: number of changes} in a pair's trace; the first report of a
    variable (its initial value) is not a change, and inputs do not count."""
    wanted = {n.upper() for n in outputs}
    seen, count = set(), {n.upper(): 0 for n in outputs}
    for _, n, _ in trace:
        if n not in wanted:
            continue
        if n in seen:
            count[n] += 1
        seen.add(n)
    return count


def pair_problems(pair: Pair, st, il) -> list[str]:
    """Why a pair's traces do not prove ST == IL (empty: they do): the
    outputs must show behaviour, and the two traces must be identical."""
    if not pair.outputs:
        return [f"{pair.name}: no VAR_OUTPUT (or run_pairs has not run it)"]
    problems = []
    changes = output_changes(st, pair.outputs)
    if sum(changes.values()) < MIN_OUTPUT_CHANGES:
        problems.append(f"{pair.name}: the outputs change {sum(changes.values())} times in "
                        f"{pair.cycles} cycles (at least {MIN_OUTPUT_CHANGES}): {changes}; "
                        "make the inputs drive them")
    idle = {n: c for n, c in changes.items() if c < MIN_CHANGES_PER_OUTPUT}
    if idle:
        problems.append(f"{pair.name}: outputs that change fewer than "
                        f"{MIN_CHANGES_PER_OUTPUT} times: {idle}")
    if st != il:
        diff = next(k for k, (a, b) in enumerate(zip(st + [None], il + [None])) if a != b)
        problems.append(f"{pair.name}: traces differ at change {diff}: ST {st[diff:diff + 3]} "
                        f"IL {il[diff:diff + 3]}")
    return problems
