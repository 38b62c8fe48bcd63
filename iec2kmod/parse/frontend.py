"""The front end as a pipeline of named passes:

    parse       files -> iec2kmod.ast units (textX; the common ST statements by
                the hand-written iec2kmod/parse/stfast.py), in parallel over files
    declare     build the symbol tables: types, POUs, configurations
    resolve     name resolution and type checking of every POU body
    configure   configurations, resources, tasks, program instances
    lint        warnings (unused variables)

Every pass adds to one Diagnostics collector; code generation starts only
when it holds no error.  Timings per pass are kept for the benchmark.
"""

from __future__ import annotations

import hashlib
import os
import re
import pickle
import time
from dataclasses import dataclass, field
from pathlib import Path

from .. import __version__
from ..diagnostics import Diagnostic, Diagnostics, SourceFile
from .lexical import SKIP_ALL
from .stfast import POU_END, body_tokens, statement_cuts


@dataclass
class FrontEndResult:
    units: list
    diags: Diagnostics
    project: object = None          # checks.Project when parsing succeeded
    timings: dict = field(default_factory=dict)
    cached: bool = False

    @property
    def ok(self) -> bool:
        return not self.diags.errors


class InputError(Exception):
    """A file cannot be read (usage or I/O error, exit code 2)."""


SOURCE_SUFFIXES = (".st", ".il", ".iec")
MAP_SUFFIXES = (".iomap",)        # the I/O map (iec2kmod/iomap.py), read after the checks


def collect_files(paths, ignored=None) -> list[str]:
    """Expands directories into their .st/.il/.iec files, sorted; the
    other files of a directory are not sources (appended to `ignored`,
    for a note).  A file named on the command line must be a source."""
    out = []
    for p in paths:
        path = Path(p)
        if path.is_dir() and (path / "plc.xml").is_file():
            out.append(str(path / "plc.xml"))   # a Beremiz/OpenPLC project (issue 28)
        elif path.is_dir():
            files = sorted(f for f in path.rglob("*") if f.is_file())
            found = [str(f) for f in files if f.suffix.lower() in SOURCE_SUFFIXES]
            maps = [str(f) for f in files if f.suffix.lower() in MAP_SUFFIXES]
            if ignored is not None:
                # the files a project directory also holds (notes, a
                # README.txt): only a name that looks like text is worth a
                # note, not every build artefact
                ignored += [str(f) for f in files if f.suffix.lower() == ".txt"]
            if not found:
                raise InputError(f"{p}: no .st, .il or .iec files in this directory")
            out += found + maps
        elif path.is_file():
            if path.suffix.lower() not in SOURCE_SUFFIXES + MAP_SUFFIXES + (".xml",):
                raise InputError(f"{p}: not a source file (sources are .st, .il or .iec files, "
                                 f"or a PLCopen .xml project); an I/O map is a .iomap file")
            out.append(str(path))
        elif path.exists():
            raise InputError(f"{p}: not a regular file")
        else:
            raise InputError(f"{p}: no such file or directory")
    if not out or all(Path(f).suffix.lower() in MAP_SUFFIXES for f in out):
        raise InputError("no input files" if not out else
                         "no source files: an I/O map binds the located variables of sources")
    return out


def _read(path: str) -> SourceFile:
    if path.lower().endswith(".xml"):           # PLCopen TC6 XML: iec2kmod/plcopen
        from ..plcopen import read_xml
        return read_xml(path)
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise InputError(f"{path}: {exc.strerror or exc}") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        text = data.decode("latin-1")
    return SourceFile(path, text)


def _parse_one(src: SourceFile):
    from .parser import parse_source
    diags = Diagnostics()
    unit = parse_source(src, diags)
    return unit, diags.items


_TOP_END = re.compile(SKIP_ALL + "|"
                      r"\b(END_FUNCTION_BLOCK|END_FUNCTION|END_PROGRAM|END_TYPE|"
                      r"END_CONFIGURATION)\b", re.S | re.I)


def split_source(src: SourceFile, pieces: int) -> list[SourceFile]:
    """Cuts a file after top-level END_* keywords into about ``pieces``
    parts of similar size.  Each part keeps the offsets of the whole file:
    the text before it is blanked (newlines kept), so positions, lines and
    columns of every node and diagnostic stay those of the real file."""
    text = src.text
    if pieces <= 1 or len(text) < 20000:
        return [src]
    cuts = [m.end() for m in _TOP_END.finditer(text) if m.group(1)]
    target = len(text) / pieces
    bounds = [0]
    for c in cuts:
        if c - bounds[-1] >= target and len(text) - c > target / 2:
            bounds.append(c)
    bounds.append(len(text))
    if len(bounds) <= 2:
        return [src]
    parts = []
    for a, b in zip(bounds, bounds[1:]):
        blank = re.sub(r"[^\n]", " ", text[:a])
        parts.append(SourceFile(src.path, blank + text[a:b]))
    return parts


def split_statements(src: SourceFile, pieces: int):
    """Cuts the ST body of the one POU in src between top-level statements
    into about ``pieces`` parts, for parsing one large POU on every core.
    Part 0 keeps the whole text but the other parts' statements; part k > 0
    keeps only the POU's header and declarations, its own statements and
    the END keyword; everything else is blanked (newlines kept), so every
    position is the real one.  None when src is not one POU with an ST body
    of enough statements (anything unexpected: no cut, a serial parse)."""
    text = src.text
    toks = body_tokens(text)
    pous = [t for t in toks if t[2] in ("PROGRAM", "FUNCTION_BLOCK", "FUNCTION")]
    ends = [t for t in toks if t[2] in POU_END]
    if len(pous) != 1 or len(ends) != 1 or \
            any(t[2] in ("TYPE", "CONFIGURATION", "ACTION", "METHOD", "USING") for t in toks):
        return None
    head, end = pous[0], ends[0]
    cuts = statement_cuts([t for t in toks if head[1] <= t[0] < end[0]])
    if cuts is None or len(cuts) - 1 < 4 * pieces:
        return None
    body_start, cuts = cuts[0], cuts[1:]
    target = (end[0] - body_start) / pieces
    bounds = [body_start]
    for c in cuts:
        if c - bounds[-1] >= target and end[0] - c > target / 2:
            bounds.append(c)
    bounds.append(end[0])
    if len(bounds) <= 2:
        return None

    def blank(t):
        return re.sub(r"[^\n]", " ", t)
    parts = [SourceFile(src.path, text[:bounds[1]] + blank(text[bounds[1]:end[0]]) +
                        text[end[0]:])]
    for a, b in zip(bounds[1:], bounds[2:]):
        parts.append(SourceFile(src.path, blank(text[:head[0]]) + text[head[0]:body_start] +
                                blank(text[body_start:a]) + text[a:b] +
                                blank(text[b:end[0]]) + text[end[0]:end[1]] +
                                blank(text[end[1]:])))
    return parts


def _merge_statements(src: SourceFile, results):
    """One unit from the parts of split_statements(); None when a part
    did not give what the cut promised (the caller parses serially)."""
    if any(u is None or any(d.severity == "error" for d in items) for u, items in results):
        return None
    first = results[0][0]
    if len(first.pous) != 1 or first.pous[0].language != "ST":
        return None
    pou = first.pous[0]
    seen = set()
    items = []
    for u, part_items in results:
        if u is not results[0][0]:
            if len(u.pous) != 1 or u.types or u.configurations or \
                    u.pous[0].language != "ST" or u.pous[0].name != pou.name:
                return None
            pou.body.extend(u.pous[0].body)
        for d in part_items:       # the header's warnings come from every part
            key = (d.line, d.col, d.severity, d.message)
            if key not in seen:
                seen.add(key)
                items.append(d)
    return first, items


def _merge(src: SourceFile, results):
    """One unit from the parsed parts of a file, pointing at the real text."""
    from .. import ast
    items = []
    unit = ast.SourceUnit(0, src=src, types=[], pous=[], configurations=[])
    ok = True
    for part_unit, part_items in results:
        for d in part_items:
            items.append(Diagnostic(d.path, d.line, d.col, d.severity, d.message,
                                    src.line_text(d.line)))
        if part_unit is None:
            ok = False
            continue
        for name in ("types", "pous", "configurations"):
            for node in getattr(part_unit, name):
                node.src = src
                getattr(unit, name).append(node)
    if ok:      # the pragmas of the whole file (each part saw only its own)
        from .lexical import attach
        attach(unit)
    return (unit if ok else None), items


def _fingerprint() -> str:
    """Identifies this compiler build: its version and its sources."""
    h = hashlib.sha256(__version__.encode())
    root = Path(__file__).resolve().parent.parent      # the iec2kmod package
    for f in sorted(root.rglob("*")):
        if f.suffix in (".py", ".tx") and "__pycache__" not in f.parts:
            h.update(f.name.encode())
            h.update(f.read_bytes())
    return h.hexdigest()


def cache_dir() -> Path:
    base = os.environ.get("IEC2KMOD_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "iec2kmod")
    return Path(base)


def parse_all(sources: list[SourceFile], jobs: int | None = None):
    """Parses every file, using every core: big files are cut at top-level
    declarations so that one large file also spreads over the cores."""
    import gc
    from .parser import fast_builder, metamodel
    metamodel()  # build once, before forking, so workers inherit it
    fast_builder()
    jobs = jobs or os.cpu_count() or 1
    total = sum(len(s.text) for s in sources)
    # The parse and the unpickling of its results allocate millions of
    # objects that stay alive; the cyclic GC would only rescan them (forked
    # workers inherit the disabled GC).
    gc_was_enabled = gc.isenabled()
    gc.disable()
    try:
        if jobs <= 1 or total < 40000:
            return [_parse_one(s) for s in sources]
        return _parse_parallel(sources, jobs, total)
    finally:
        if gc_was_enabled:
            gc.enable()


def _weight(src: SourceFile) -> int:
    """What parsing a part costs, about: its characters less the blanks
    that stand for the rest of its file."""
    t = src.text
    return len(t) - t.count(" ") - t.count("\n")


def _parse_many(sources):
    return [_parse_one(s) for s in sources]


def _parse_parallel(sources, jobs, total):
    parts = []  # (file index, piece index, part): pieces of one part are one POU's body
    pieces = {}  # (file index, piece index) -> the part they were cut from
    for i, s in enumerate(sources):
        share = max(1, round(2 * jobs * len(s.text) / total))
        for p in split_source(s, share):
            n = len(pieces)
            # one POU too big for an even share: its statements on every core
            cut = split_statements(p, max(2, round(jobs * _weight(p) / total))) \
                if _weight(p) * jobs > total and len(p.text) >= 20000 else None
            pieces[(i, n)] = p
            parts += [(i, n, q) for q in (cut or [p])]
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor  # only here: a cache hit needs none
    ctx = multiprocessing.get_context("fork")
    # the parts shared out over the cores, biggest first onto the least
    # loaded, so that the cores finish together; this process parses the
    # first share itself (its results need no pickling)
    weight = [_weight(p[2]) for p in parts]
    shares: list[list[int]] = [[] for _ in range(jobs)]
    loads = [0] * jobs
    for k in sorted(range(len(parts)), key=lambda k: -weight[k]):
        b = loads.index(min(loads))
        shares[b].append(k)
        loads[b] += weight[k]
    others = [s for s in shares[1:] if s]
    done = {}
    with ProcessPoolExecutor(max_workers=max(1, len(others)), mp_context=ctx) as pool:
        futures = [pool.submit(_parse_many, [parts[k][2] for k in s]) for s in others]
        for k in shares[0]:
            done[k] = _parse_one(parts[k][2])
        for s, f in zip(others, futures):
            done.update(zip(s, f.result()))
    out = []
    for i, s in enumerate(sources):
        results = []
        for (fi, n), p in pieces.items():
            if fi != i:
                continue
            got = [done[k] for k in range(len(parts)) if parts[k][:2] == (i, n)]
            if len(got) > 1:
                got = _merge_statements(p, got)
                # a cut the parser did not agree with (a syntax error, IL, ...):
                # the part again in one piece, for its own diagnostics
                results.append(got if got is not None else _parse_one(p))
            else:
                results.append(got[0])
        out.append(_merge(s, results))
    return out


def run(paths, use_cache: bool = True, jobs: int | None = None,
        strict: bool = False) -> FrontEndResult:
    """Parses and checks a project: every diagnostic is collected; strict:
    the warnings of diagnostics.STRICT_RULES are errors."""
    result = _run(paths, use_cache, jobs)
    if any(str(p).lower().endswith(".xml") for p in collect_files(paths)):
        from ..plcopen import remap            # generated lines -> the XML's (issue 28)
        result.diags.items = [remap(d) for d in result.diags.items]
    if strict:
        result.diags.make_strict()
        if result.diags.errors:
            result.project = None
    return result


def _run(paths, use_cache, jobs) -> FrontEndResult:
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    ignored = []
    sources = [_read(p) for p in collect_files(paths, ignored)]
    timings["read"] = time.perf_counter() - t0
    notes = [Diagnostic(p, 1, 1, "note", "ignored: not a source file (sources are .st, .il "
                                         "or .iec files)") for p in ignored]
    if any(s.path.lower().endswith(".xml") for s in sources):
        from ..plcopen import xml_diagnostics
        notes += xml_diagnostics([s.path for s in sources])
        if any(d.severity == "error" for d in notes):
            diags = Diagnostics()
            diags.items = notes
            return FrontEndResult([], diags, None, timings)

    key = None
    if use_cache:
        h = hashlib.sha256(_fingerprint().encode())
        for s in sources:
            h.update(s.path.encode() + b"\0" + s.text.encode() + b"\0")
        key = h.hexdigest()
        cached = _load_cached(key)
        if cached is not None:
            diags = Diagnostics()
            diags.items = notes + list(cached)
            timings["cache"] = time.perf_counter() - t0
            return FrontEndResult([], diags, None, timings, cached=True)

    diags = Diagnostics()
    diags.items.extend(notes)
    t = time.perf_counter()
    maps = [s for s in sources if Path(s.path).suffix.lower() in MAP_SUFFIXES]
    parsed = parse_all([s for s in sources if s not in maps], jobs)
    timings["parse"] = time.perf_counter() - t
    units = []
    for unit, items in parsed:
        for d in items:
            diags.items.append(d)
        if unit is not None:
            units.append(unit)

    project = None
    if not diags.errors:
        import gc
        from ..checks import check_project
        # the checks allocate as they walk the millions of parsed objects,
        # which the cyclic collector would rescan again and again (half of
        # the check time of a 10,000-line POU); they make no garbage cycles
        gc_was_enabled = gc.isenabled()
        gc.disable()
        try:
            project = check_project(units, diags, timings)
            if maps and project is not None and not diags.errors:
                from ..iomap import check_maps
                t = time.perf_counter()
                check_maps(project, maps, diags)
                timings["iomap"] = time.perf_counter() - t
        finally:
            if gc_was_enabled:
                gc.enable()
    if key is not None:
        _store_cached(key, [d for d in diags.items if d not in notes])
    return FrontEndResult(units, diags, project, timings)


def _load_cached(key: str):
    path = cache_dir() / "check" / key
    try:
        with open(path, "rb") as f:
            items = pickle.load(f)
    except (OSError, pickle.PickleError, EOFError, AttributeError, ImportError):
        return None
    if not all(isinstance(d, Diagnostic) for d in items):
        return None
    return items


def _store_cached(key: str, items) -> None:
    path = cache_dir() / "check" / key
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        with open(tmp, "wb") as f:
            pickle.dump(list(items), f, protocol=pickle.HIGHEST_PROTOCOL)
        os.replace(tmp, path)
    except OSError:
        pass  # a cache that cannot be written is only slower
