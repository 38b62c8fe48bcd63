"""Semantic checks: the passes after parsing.  ``check_project`` runs them in
order, collecting every diagnostic, and returns the checked Project
(checks/symbols.py).

1. 'declare' (declare.py): user types (types.py) and POU interfaces into
   the project's symbol tables, their constant expressions and initial
   values evaluated and checked (consts.py, by fold.py's rules), the steps
   of SFC bodies declared (sfc.py); before it, the direct variables of each
   PROGRAM named (direct.py).
2. 'resolve' (body.py, ``BodyChecker``): every POU body typed and its names
   resolved.  body.py holds the statements; expr.py names, expressions and
   assignment compatibility; calls.py calls and argument binding; il.py
   Instruction List; sfc.py SFC.  The standard functions and function
   blocks are in stdlib.py, and settle.py gives the standard calls on
   untyped values their type once the statement around them is checked.
3. 'configure' (config.py, and ``check_recursion`` here): configurations,
   resources, program instances and their connections; tasks in tasks.py,
   the rules of located variables (one address, one variable) in
   located.py.
4. 'lint' (``lint`` here): unused variables."""

from __future__ import annotations

import time

from .body import BodyChecker
from .config import ConfigChecker
from .declare import Declarer
from .direct import name_direct_variables
from .symbols import Project
from .types import FBType


def check_project(units, diags, timings=None) -> Project:
    timings = timings if timings is not None else {}
    project = Project(units=units)
    decl = Declarer(project, diags)
    name_direct_variables(units, diags)

    t = time.perf_counter()
    decl.declare_types(units)
    decl.declare_pous(units)
    timings["declare"] = time.perf_counter() - t

    t = time.perf_counter()
    for pou in project.pous.values():
        BodyChecker(project, decl, diags, pou).check()
    timings["resolve"] = time.perf_counter() - t

    t = time.perf_counter()
    check_recursion(project, diags)
    ConfigChecker(project, decl, diags).check(units)
    timings["configure"] = time.perf_counter() - t

    t = time.perf_counter()
    lint(project, diags)
    timings["lint"] = time.perf_counter() - t
    return project


def check_recursion(project, diags):
    """No POU may call or contain itself, directly or indirectly."""
    graph = {}
    for pou in project.pous.values():
        deps = set(k for k in pou.calls if k in project.pous)
        for v in pou.vars.values():
            if isinstance(v.type, FBType) and not v.type.pou.standard:
                deps.add(v.type.pou.key)
        graph[pou.key] = deps
    state = {}
    reported = set()

    def visit(key, path):
        state[key] = 1
        for dep in sorted(graph.get(key, ())):
            if state.get(dep) == 1:
                cycle = path[path.index(dep):] + [dep] if dep in path else [key, dep]
                first = project.pous[cycle[0]]
                if frozenset(cycle) not in reported:
                    reported.add(frozenset(cycle))
                    names = " -> ".join(project.pous[k].name for k in cycle)
                    diags.error(first.src, first.node.pos,
                                f"recursion is not allowed: {names}")
            elif state.get(dep) is None:
                visit(dep, path + [dep])
        state[key] = 2

    for key in sorted(graph):
        if state.get(key) is None:
            visit(key, [key])


def lint(project, diags):
    for pou in project.pous.values():
        for v in pou.vars.values():
            if v.used or v.location or v.section in ("VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT",
                                                     "RESULT"):
                continue
            if v.section == "VAR_GLOBAL":
                continue
            what = {"VAR_EXTERNAL": "external variable", "VAR_TEMP": "temporary variable"}.get(
                v.section, "variable")
            diags.warning(pou.src, v.pos, f"unused {what} '{v.name}'")
    for cfg in project.configurations:
        for g in cfg.globals.values():
            if not g.used and not g.location:
                diags.warning(cfg.src, g.pos, f"unused global variable '{g.name}'")
        for r in cfg.resources:
            for g in r.globals.values():
                if not g.used and not g.location:
                    diags.warning(cfg.src, g.pos, f"unused global variable '{g.name}'")
