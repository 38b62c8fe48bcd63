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
                                 error at that line of this file; the text
                                 is the fault's name, exactly (FAULT_NAMES)

The keywords are written exactly so (EXPECT, FAULT, INPUT in capitals,
after/in/at/cycle(s)/line and @interval in lower case) and only in
``(* *)`` comments.  A comment -- or a line of one -- that starts with a
word close to EXPECT, INPUT or @interval (EXPECTED, Expect, INPUTS,
// EXPECT, { EXPECT }, EXPECT at 3 cycles, ...) and is not a well-formed
annotation fails the case: a typo never drops a check silently.

Several EXPECT blocks make several checkpoints; a block may span lines.
Paths are relative to the program instance (``x``, ``fb.Q``, ``a[1,2]``,
``rec.name``).  Values are IEC literals of the variable's type, exactly:
TRUE/FALSE for BOOL (not 1/0), integers for integer and bit-string types,
2.5 / NaN / Inf for REAL/LREAL, T#1s or LTIME#5ns for TIME/LTIME, D#...,
TOD#..., DT#... for the date types, 'text' for STRING, "wide" for
WSTRING, a value name (or Type#name) for an enumeration.  REAL/LREAL
compare with a relative tolerance of 1E-6 (write ``x == 0.1`` for an exact
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

from iec2kmod import sim
from iec2kmod.parse import frontend
from iec2kmod.codegen.plan import build_plan
from iec2kmod.located import addresses_of
from iec2kmod.checks.types import Elementary, EnumT, StringT, SubrangeT, concrete
from iec2kmod.parse.literals import LiteralError, classify

HERE = Path(__file__).resolve().parent
CASES = HERE / "cases"
PAIRS = HERE / "pairs"
DEFAULT_INTERVAL = 10_000_000
SANITIZER_REPORT = re.compile(r"runtime error|Sanitizer|^==\d+==|SUMMARY:", re.M)

# the annotations, written exactly so (case-sensitive)
_EXPECT = re.compile(r"^\s*EXPECT\s+after\s+(\d+)\s+cycles?\s*:(.*)$", re.S)
_FAULT = re.compile(r"^\s*EXPECT\s+FAULT\s+in\s+cycle\s+(\d+)\s+at\s+line\s+(\d+)\s*:(.*)$",
                    re.S)
_INPUT = re.compile(r"^\s*INPUT\s+at\s+cycle\s+(\d+)\s*:(.*)$", re.S)
_INTERVAL = re.compile(r"^\s*@interval\s+(\S+)\s*$")
_USAGE = ("write 'EXPECT after N cycles: path = value; ...', 'EXPECT FAULT in cycle N at "
          "line L: <fault name>', 'INPUT at cycle N: path = value; ...' or '@interval T#...' "
          "in a (* *) comment")
_PROGRAM = re.compile(r"^\s*PROGRAM\s+([A-Za-z_]\w*)", re.M | re.I)
_CONFIG = re.compile(r"^\s*CONFIGURATION\b", re.M | re.I)


class CaseError(Exception):
    """A malformed case file."""


def _fault_names() -> tuple:
    """The runtime's fault names (iec_fault_name() in iec_fault.h)."""
    from iec2kmod.resources import templates_root
    KT = templates_root()
    text = (KT / "runtime" / "iec_fault.h").read_text()
    body = text[text.index("iec_fault_name("):]
    body = body[:body.index("\n}\n")]
    names = tuple(n for n in re.findall(r'return\s+"([^"]+)"', body)
                  if n not in ("none", "unknown fault"))
    assert len(names) >= 5, names
    return names


FAULT_NAMES = _fault_names()


def iec_comments(text: str):
    """(style, body, line of the comment start, line of the body start) of
    every comment of an IEC source: style '(*', '//' or '{'.  String
    literals are skipped, so "'(* x *)'" is no comment."""
    i, n = 0, len(text)
    while i < n:
        ch = text[i]
        if ch in "'\"":
            j = i + 1
            while j < n and text[j] != ch:
                j += 2 if text[j] == "$" else 1
            i = j + 1
            continue
        two = text[i:i + 2]
        if two == "(*":
            end = text.find("*)", i + 2)
            end = n if end < 0 else end
            yield "(*", text[i + 2:end], text.count("\n", 0, i) + 1
            i = end + 2
        elif two == "//":
            end = text.find("\n", i)
            end = n if end < 0 else end
            yield "//", text[i + 2:end], text.count("\n", 0, i) + 1
            i = end
        elif ch == "{":
            end = text.find("}", i + 1)
            end = n if end < 0 else end
            yield "{", text[i + 1:end], text.count("\n", 0, i) + 1
            i = end + 1
        else:
            i += 1


def _osa(a: str, b: str) -> int:
    """Edit distance with adjacent transpositions (optimal string alignment)."""
    d = [[max(i, j) if not i or not j else 0 for j in range(len(b) + 1)]
         for i in range(len(a) + 1)]
    for i in range(1, len(a) + 1):
        for j in range(1, len(b) + 1):
            cost = a[i - 1] != b[j - 1]
            d[i][j] = min(d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost)
            if i > 1 and j > 1 and a[i - 1] == b[j - 2] and a[i - 2] == b[j - 1]:
                d[i][j] = min(d[i][j], d[i - 2][j - 2] + 1)
    return d[-1][-1]


_LEAD = re.compile(r"^[\s*]*(@?)\s*([A-Za-z_]\w*)?(.*)$", re.S)


def looks_like_directive(line: str) -> bool:
    """True if a comment (or a line of one) starts like an annotation: a
    word close to EXPECT or INPUT, '@', or 'interval' before a time; a
    path in an assignment (``expected_x = 3``) is not one."""
    m = _LEAD.match(line)
    at, word, rest = m.group(1), m.group(2) or "", m.group(3)
    if at:
        return True
    if not word or re.match(r"\s*(==?(?!>)|:=|\.|\[|,)", rest):
        return False
    w = word.upper()
    if w.startswith(("EXPECT", "INPUT")) or _osa(w, "EXPECT") <= 1 or _osa(w, "INPUT") <= 1:
        return True
    return w.startswith("INTERVAL") and bool(re.match(r"\s*[:=]?\s*(T#|TIME#|\d)", rest, re.I))


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
        # an address located by a program's variable (declared, unnamed or
        # implied by a statement) is that variable's path
        located = getattr(self, "located", {}).get(p.upper())
        if located:
            return located
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
    items = split_items(text)
    if not items:
        raise CaseError(f"{where}: the annotation lists no values (write path = value; ...)")
    for item in items:
        m = re.match(r"^([A-Za-z_%][\w.,\[\]%+-]*)\s*(==|=)\s*(.+)$", item, re.S)
        if not m:
            raise CaseError(f"{where}: cannot read '{item}' (write path = value)")
        c = Check(m.group(1), m.group(3).strip(), m.group(2) == "==")
        try:
            parse_value(c.text)
        except CaseError as exc:
            raise CaseError(f"{where}: {exc}") from None
        out.append(c)
    return out


def _malformed(where, what):
    return CaseError(f"{where}: malformed annotation '{' '.join(what.split())[:70]}': {_USAGE}")


def load_case(path: Path, area: str) -> Case:
    text = path.read_text(encoding="utf-8")
    programs = _PROGRAM.findall(text)
    standalone = bool(_CONFIG.search(text))
    if not standalone and len(programs) != 1:
        raise CaseError(f"{path}: a case declares exactly one PROGRAM ({len(programs)} found)")
    case = Case(path, area, None if standalone else programs[0])
    intervals = 0
    for style, body, line in iec_comments(text):
        where = f"{path}:{line}"
        lines = body.split("\n")
        if style != "(*":
            for k, ln in enumerate(lines):
                if looks_like_directive(ln):
                    raise CaseError(f"{path}:{line + k}: an annotation in a '{style}' comment is "
                                    f"not read: {_USAGE}")
            continue
        # a directive-like line later in a comment (two annotations in one
        # comment, or one after a description) would be read as values or not at all
        for k, ln in enumerate(lines[1:], 1):
            if looks_like_directive(ln):
                raise CaseError(f"{path}:{line + k}: an annotation must start its own (* *) "
                                f"comment: '{' '.join(ln.split())[:70]}'")
        if mm := _FAULT.match(body):
            cycle, fline, name = int(mm.group(1)), int(mm.group(2)), " ".join(mm.group(3).split())
            if name not in FAULT_NAMES:
                raise CaseError(f"{where}: EXPECT FAULT needs the fault's exact name, one of "
                                f"{', '.join(repr(n) for n in FAULT_NAMES)} (got '{name}')")
            case.faults.append((cycle, fline, name))
        elif mm := _EXPECT.match(body):
            case.checkpoints.append((int(mm.group(1)), _assignments(mm.group(2), where)))
        elif mm := _INPUT.match(body):
            for c in _assignments(mm.group(2), where):
                case.inputs.append((int(mm.group(1)), c.path, c.text))
        elif mm := _INTERVAL.match(body):
            if standalone:
                raise CaseError(f"{where}: @interval in a case with its own CONFIGURATION is not "
                                "used (its tasks set their intervals)")
            try:
                case.interval_ns = sim.parse_time(mm.group(1))
            except sim.SimError as exc:
                raise CaseError(f"{where}: {exc}") from None
            intervals += 1
            if case.interval_ns <= 0 or intervals > 1:
                raise CaseError(f"{where}: one @interval, greater than zero")
        elif looks_like_directive(lines[0]):
            raise _malformed(where, body)
    if not case.checkpoints and not case.faults:
        raise CaseError(f"{path}: no EXPECT block")
    if any(c < 1 for c, _ in case.checkpoints) or any(c < 1 for c, _, _ in case.faults) or \
            any(c < 1 for c, _, _ in case.inputs):
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
def literal(text: str):
    """(kind, value, type prefix or None) of an expected value: kind is one
    of bool, int, real, nan, time, date, tod, dt, string, wstring, enum."""
    s = text.strip()
    sign = 1
    if s[:1] in "+-" and not s.startswith(("'", '"')):
        sign, s = (-1 if s[0] == "-" else 1), s[1:].strip()
    if s.upper() in ("NAN",):
        return "nan", None, None
    if s.upper() in ("INF", "INFINITY"):
        return "real", sign * math.inf, None
    try:
        kind, value, prefix = classify(s)
    except (LiteralError, ValueError):
        if sign == 1 and re.fullmatch(r"[A-Za-z_]\w*", s):
            return "enum", s.upper(), None
        raise CaseError(f"cannot read the value '{text}'") from None
    if kind == "enum":
        if sign != 1 or not re.fullmatch(r"[A-Za-z_]\w*", str(value)):
            raise CaseError(f"cannot read the value '{text}'")
        return "enum", str(value).upper(), prefix.upper()
    if prefix == "BOOL" and kind == "int" and value in (0, 1):
        kind, value = "bool", bool(value)
    if kind in ("bool", "string", "wstring"):
        if sign != 1:
            raise CaseError(f"cannot read the value '{text}'")
        return kind, value, prefix
    if kind in ("int", "time", "date", "tod", "dt"):
        return kind, sign * int(value), prefix
    if kind == "real":
        return "real", sign * float(value), prefix
    raise CaseError(f"unsupported value '{text}'")


def parse_value(text: str):
    """('bool'|'int'|'real'|'string'|'enum'|'nan', value) of a literal
    (times and dates are 'int' nanoseconds)."""
    kind, value, _ = literal(text)
    if kind in ("time", "date", "tod", "dt"):
        return "int", value
    if kind == "wstring":
        return "string", value
    return kind, value


# the literal kinds a variable of each category takes
_KINDS = {"bool": ("bool",), "sint": ("int",), "uint": ("int",), "bit": ("int",),
          "real": ("real", "nan"), "time": ("time",), "date": ("date",), "tod": ("tod",),
          "dt": ("dt",), "string": ("string",), "wstring": ("wstring",), "enum": ("enum",)}
_EXAMPLE = {"bool": "TRUE or FALSE", "sint": "an integer", "uint": "an integer",
            "bit": "an integer (16#FF)", "real": "2.5, NaN or Inf", "time": "T#1s or LTIME#5ns",
            "date": "D#2024-01-31", "tod": "TOD#12:00:00", "dt": "DT#2024-01-31-12:00:00",
            "string": "'text'", "wstring": '"text"', "enum": "one of its value names"}


def type_problem(check: Check, vtype) -> str | None:
    """Why check's value is not a literal of the variable's type (None: it is)."""
    t = concrete(vtype)
    if isinstance(t, SubrangeT):
        t = concrete(t.elem)
    if isinstance(t, EnumT):
        cat = "enum"
    elif isinstance(t, StringT):
        cat = "wstring" if t.wide else "string"
    elif isinstance(t, Elementary):
        cat = t.cat
    else:
        return f"{check.path} is a {getattr(t, 'name', t)}, not an elementary value"
    kind, value, prefix = literal(check.text)
    if kind not in _KINDS[cat]:
        return (f"{check.path} is {t.name}: the expected value {check.text} is not a literal of "
                f"that type (it reads as {kind}; write {_EXAMPLE[cat]})")
    if cat == "enum":
        if prefix and prefix != t.name.upper():
            return f"{check.path} is {t.name}: {check.text} names another type"
        if value not in t.values:
            return f"{check.path} is {t.name}: {check.text} is not one of its values " \
                   f"({', '.join(n for n, _ in t.values.values())})"
    elif prefix and cat not in ("time", "date", "tod", "dt"):
        base = ("WSTRING" if t.wide else "STRING") if isinstance(t, StringT) else t.name
        if prefix.upper() != base.upper():
            return f"{check.path} is {t.name}: {check.text} is typed {prefix}"
    if check.exact and cat != "real":
        return f"{check.path} is {t.name}: '==' (exact) is for REAL/LREAL values only"
    return None


def matches(actual, check: Check, vtype=None) -> bool:
    """Whether a simulated value equals the expected one.  With the
    variable's IEC type (vtype), a literal of another type is an error
    (CaseError): TRUE is not 1, 'RED' is not the enumeration value RED."""
    if vtype is not None and (why := type_problem(check, vtype)):
        raise CaseError(why)
    kind, exp, _ = literal(check.text)
    if kind == "nan":
        return isinstance(actual, float) and math.isnan(actual)
    if kind == "enum":
        return isinstance(actual, str) and actual.upper() == exp
    if kind == "bool":
        return isinstance(actual, bool) and actual == exp
    if kind in ("string", "wstring"):
        return isinstance(actual, str) and actual == exp
    if isinstance(actual, bool):
        return False
    if isinstance(actual, float):
        if kind != "real" and vtype is not None:
            return False
        if check.exact or math.isinf(exp) or exp == 0:
            return actual == exp or (exp == 0 and abs(actual) < 1e-12 and not check.exact)
        return math.isclose(actual, exp, rel_tol=1e-6, abs_tol=1e-12)
    if isinstance(actual, int):
        return kind in ("int", "time", "date", "tod", "dt") and actual == exp
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
    types: dict = field(default_factory=dict)     # upper-case variable path -> IEC type


def simulate(project, end, watch=None, inputs=None, sanitize=False, engine="c"):
    """One run of the compiled C simulator or (engine "vm") of the reference
    interpreter, iec2kmod.interp; both give a result of the same shape."""
    if engine == "vm":
        from iec2kmod import interp
        try:
            return interp.run(project, end, watch=watch, inputs=inputs)
        except interp.InterpError as exc:
            raise sim.SimError(str(exc)) from None
    return sim.run(project, end, watch=watch, inputs=inputs, sanitize=sanitize,
                   build_dir=build_root() / "sim")


def run_group(name: str, cases, sanitize=False, engine="c", extra_sources=()) -> GroupRun:
    """Builds and runs cases as one simulation (standalone cases: one each);
    *extra_sources*: more files of the project (a library the cases use)."""
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
            paths = [c.path for c in cases] + [cfg] + list(extra_sources)
            project = check_project(paths)
            for c in cases:
                run.task_of[c.name] = f"t_{c.program}"
        run.types = {e.path.upper(): e.type for e in build_plan(project).table}
        addresses = {a.upper(): path for a, path in addresses_of(project).items()
                     if path.upper() in run.types and a.upper() not in run.types}
        for c in cases:
            c.located = addresses
        for c in cases:         # INPUT values are typed like EXPECT values
            for cycle, p, v in c.inputs:
                vtype = run.types.get(c.full_path(p).upper())
                why = f"no variable {p}" if vtype is None else type_problem(Check(p, v), vtype)
                if why:
                    raise CaseError(f"{c.path}: INPUT at cycle {cycle}: {why}")
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
            trace = out / f"{name}{'_san' if sanitize else ''}_{engine}.{os.getpid()}.csv"
            trace.write_text("".join(f"{t}ns,{p},{v}\n" for t, p, v in events))
        try:
            run.result = simulate(project, end, watch=watch or None,
                                  inputs=str(trace) if trace else None, sanitize=sanitize,
                                  engine=engine)
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
              Path(f[4]).resolve() == case.path.resolve() and f[2] == text]
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
            if key.upper() not in run.types:
                problems.append(f"after {cycle} cycles: no variable {k.path}")
                continue
            try:
                ok = matches(actual, k, run.types[key.upper()])
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


def run_pairs(pairs, sanitize=False, interval=DEFAULT_INTERVAL, engine="c"):
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
    trace = out / f"pairs{'_san' if sanitize else ''}_{engine}.{os.getpid()}.csv"
    trace.write_text("".join(rows))
    try:
        res = simulate(project, (cycles - 1) * interval, watch=watch, inputs=str(trace),
                       sanitize=sanitize, engine=engine)
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
