# SPDX-License-Identifier: MIT
"""What the manifest does not carry, read from the project's sources with
iec2kmod's front end: the configuration's access paths (VAR_ACCESS, with
READ_ONLY / READ_WRITE) and the addresses of named located variables
(``belt_count AT %MW100 : INT``), both as manifest paths."""

from __future__ import annotations

from typing import Dict, List, Tuple

from ..errors import UsageError
from .model import AccessPath


def read(sources: str, manifest: dict) -> Tuple[List[AccessPath], Dict[str, str]]:
    try:
        from iec2kmod.parse import frontend
    except ImportError:
        raise UsageError("--sources needs the iec2kmod package (the compiler's front end) "
                         "to read the access paths") from None
    r = frontend.run([sources], use_cache=False)
    if r.diags.errors or r.project is None:
        first = r.diags.errors[0] if r.diags.errors else None
        raise UsageError(f"{sources}: the sources do not check"
                         + (f": {first}" if first else ""))
    cfgs = [c for c in r.project.configurations
            if c.name.lower() == manifest["configuration"].lower()]
    if not cfgs:
        raise UsageError(f"{sources}: no configuration {manifest['configuration']} "
                         f"(the running one)")
    cfg = cfgs[0]
    paths = {v["path"].lower(): v["path"] for v in manifest["variables"]}
    resources = [r_["name"] for r_ in manifest.get("resources", [])]
    located: Dict[str, str] = {}

    def var_paths(var) -> List[str]:
        owner = var.owner
        kind = type(owner).__name__
        if kind == "ConfigInfo":
            return [var.name]
        if kind == "ResourceInfo":
            return [f"{owner.name}.{var.name}"]
        # a program's variable: one per instance of the program type
        return [f"{i['path']}.{var.name}" for i in manifest.get("instances", [])
                if i["type"].lower() == getattr(owner, "name", "").lower()]

    def found(p: str):
        return paths.get(p.lower())

    for var in list(cfg.globals.values()) + [g for r_ in cfg.resources
                                             for g in r_.globals.values()]:
        if getattr(var, "location", None):
            for p in var_paths(var):
                if found(p):
                    located[var.location.upper()] = found(p)
    for pou in r.project.pous.values() if hasattr(r.project, "pous") else []:
        for var in getattr(pou, "vars", {}).values():
            if getattr(var, "location", None) and type(pou).__name__ == "POUInfo":
                for p in var_paths(var):
                    if found(p):
                        located.setdefault(var.location.upper(), found(p))

    access: List[AccessPath] = []
    for name, path, target, direction in cfg.access:
        cands = [path]
        if len(resources) == 1:
            cands.append(f"{resources[0]}.{path}")
        if path.startswith("%"):
            hit = located.get(path.upper()) or found(path)
        else:
            hit = next((found(c) for c in cands if found(c)), None)
        if hit is None:
            raise UsageError(f"{sources}: access path {name} ({path}) is not in the running "
                             f"configuration's variable table")
        access.append(AccessPath(name=name, path=hit, read_write=direction == "READ_WRITE"))
    return access, located
