"""The front end as a pipeline of named passes:

    parse       files -> iec2kmod.ast units (textX), in parallel over files
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

from . import __version__
from .diagnostics import Diagnostic, Diagnostics, SourceFile


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


def collect_files(paths) -> list[str]:
    """Expands directories into their .st/.il/.iec files, sorted."""
    out = []
    for p in paths:
        path = Path(p)
        if path.is_dir():
            found = sorted(str(f) for f in path.rglob("*")
                           if f.suffix.lower() in (".st", ".il", ".iec", ".txt") and f.is_file())
            if not found:
                raise InputError(f"{p}: no .st, .il or .iec files in this directory")
            out += found
        elif path.is_file():
            out.append(str(path))
        elif path.exists():
            raise InputError(f"{p}: not a regular file")
        else:
            raise InputError(f"{p}: no such file or directory")
    if not out:
        raise InputError("no input files")
    return out


def _read(path: str) -> SourceFile:
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


_TOP_END = re.compile(r"'(?:[^'$\n]|\$.)*'|\"(?:[^\"$\n]|\$.)*\"|\(\*.*?\*\)|//[^\n]*|\{[^}]*\}|"
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


def _merge(src: SourceFile, results):
    """One unit from the parsed parts of a file, pointing at the real text."""
    from . import ast
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
    return (unit if ok else None), items


def _fingerprint() -> str:
    """Identifies this compiler build: its version and its sources."""
    h = hashlib.sha256(__version__.encode())
    root = Path(__file__).resolve().parent
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


def _parse_parallel(sources, jobs, total):
    parts = []  # (file index, part)
    for i, s in enumerate(sources):
        share = max(1, round(2 * jobs * len(s.text) / total))
        parts += [(i, p) for p in split_source(s, share)]
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor  # only here: a cache hit needs none
    ctx = multiprocessing.get_context("fork")
    # biggest parts first so the cores finish together
    order = sorted(range(len(parts)), key=lambda k: -len(parts[k][1].text.lstrip()))
    with ProcessPoolExecutor(max_workers=jobs, mp_context=ctx) as pool:
        done = dict(zip(order, pool.map(_parse_one, [parts[k][1] for k in order])))
    out = []
    for i, s in enumerate(sources):
        out.append(_merge(s, [done[k] for k in range(len(parts)) if parts[k][0] == i]))
    return out


def run(paths, use_cache: bool = True, jobs: int | None = None) -> FrontEndResult:
    """Parses and checks a project: every diagnostic is collected."""
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    sources = [_read(p) for p in collect_files(paths)]
    timings["read"] = time.perf_counter() - t0

    key = None
    if use_cache:
        h = hashlib.sha256(_fingerprint().encode())
        for s in sources:
            h.update(s.path.encode() + b"\0" + s.text.encode() + b"\0")
        key = h.hexdigest()
        cached = _load_cached(key)
        if cached is not None:
            diags = Diagnostics()
            diags.items = cached
            timings["cache"] = time.perf_counter() - t0
            return FrontEndResult([], diags, None, timings, cached=True)

    diags = Diagnostics()
    t = time.perf_counter()
    parsed = parse_all(sources, jobs)
    timings["parse"] = time.perf_counter() - t
    units = []
    for unit, items in parsed:
        for d in items:
            diags.items.append(d)
        if unit is not None:
            units.append(unit)

    project = None
    if not diags.errors:
        from .checks import check_project
        project = check_project(units, diags, timings)
    if key is not None:
        _store_cached(key, diags.items)
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
