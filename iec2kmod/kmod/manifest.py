"""The manifest of a kbuild tree (manifest.json): what plc-manager needs
to load, swap and address a configuration's modules."""

from __future__ import annotations

import hashlib
import json

from .. import __version__
from ..checks.types import EnumT, StringT, concrete
from ..codegen import cnames as N


def manifest_digest(manifest: dict) -> str:
    """The manifest's own checksum, so that plc-manager refuses a manifest
    edited by hand: sha256 of its canonical JSON without "digest" and
    "kernel_release" (`iec2kmod build` adds that one).  plc-manager has the
    same function (manager/project.py; a unit test compares them)."""
    body = {k: v for k, v in manifest.items() if k not in ("digest", "kernel_release")}
    return hashlib.sha256(json.dumps(body, sort_keys=True,
                                     separators=(",", ":")).encode()).hexdigest()[:32]


def manifest_of(cfg, plan, config_mod, prog_modules, res_modules, source_hash, iface_hash):
    tasks_by_res = {}
    for tp in plan.tasks:
        tasks_by_res.setdefault(tp.resource, []).append({
            "name": tp.name, "interval_ns": tp.interval_ns, "priority": tp.priority,
            "single": tp.single.path if tp.single else None,
            "programs": [ip.path for ip in tp.instances]})
    variables = []
    for e in plan.table:
        variables.append({"path": e.path, "type": getattr(e.type, "name", "?"),
                          "kind": e.kind, "size": e.size, "writable": e.writable,
                          "owner": e.owner, **_value_info(e.type)})
    return {
        "format": 1,
        "generator": f"iec2kmod {__version__}",
        "configuration": cfg.name,
        "source_hash": source_hash,
        "interface_hash": iface_hash,
        "modules": ([{"name": config_mod, "kind": "configuration", "dir": config_mod,
                      "depends": []}] +
                    [dict(m, depends=[config_mod]) for m in prog_modules] +
                    [dict(m, depends=[config_mod] + [p["name"] for p in prog_modules])
                     for m in res_modules]),
        "load_order": [config_mod] + [m["name"] for m in prog_modules] +
                      [m["name"] for m in res_modules],
        "resources": [{"name": m["resource"], "module": m["name"], "cpu": m["cpu"],
                       "tasks": tasks_by_res.get(m["resource"], [])} for m in res_modules],
        "program_types": [{"name": m["program_type"], "slot": m["slot"], "module": m["name"],
                           "build_id": m["build_id"], "interface_hash": m["interface_hash"],
                           "uses_fpu": m["uses_fpu"], "interface": m["interface"]}
                          for m in prog_modules],
        "instances": [{"path": ip.path, "type": ip.pou.name, "resource": ip.resource,
                       "task": ip.task} for ip in plan.instances],
        "variables": variables,
        # a located variable's address names it too (plc-manager read %IW2)
        "addresses": {a: p for a, p in sorted(getattr(cfg, "addresses", {}).items())
                      if p.upper() in {v["path"].upper() for v in variables}},
        # the I/O map (iec2kmod/iomap.py): per resource, its devices and bindings
        "io": {io.resource: io.manifest()
               for _, io in sorted((getattr(cfg, "io", None) or {}).items())},
        # VAR_ACCESS: what an outside client (plc-manager serve) may see and change
        "access": access_paths(cfg, variables),
    }


def access_paths(cfg, variables):
    """The configuration's access paths as manifest paths: name, path (a
    variable of the table, or the prefix of an aggregate's members),
    access (READ_ONLY / READ_WRITE) and the variable's type.  A path
    without its resource names the only resource's variable; an address
    names its located variable."""
    paths = {v["path"].upper(): v for v in variables}
    resources = [r.name for r in cfg.resources]
    addresses = {a.upper(): p for a, p in getattr(cfg, "addresses", {}).items()}
    out = []
    for name, path, _target, direction in cfg.access:
        if path.startswith("%"):
            cands = [addresses.get(path.upper(), path)]
        else:
            cands = [path] + ([f"{resources[0]}.{path}"] if len(resources) == 1 else [])
        hit = next((paths[c.upper()] for c in cands if c.upper() in paths), None)
        if hit is not None:
            out.append({"name": name, "path": hit["path"], "access": direction,
                        "type": hit["type"]})
            continue
        # an aggregate: its members are the table's entries under the path
        for c in cands:
            pre = c.upper()
            members = [v for v in variables
                       if v["path"].upper().startswith((pre + ".", pre + "["))]
            if members:
                first = members[0]["path"]
                out.append({"name": name, "path": first[:len(c)], "access": direction,
                            "type": "aggregate"})
                break
    return out


def manifest_text(manifest) -> str:
    """The manifest as JSON, indented, with one line per variable (the
    variable table is most of it: 23,000 entries in a plant-sized
    configuration, which json's indenting encoder takes a third of a second
    to write)."""
    parts = []
    for key, value in manifest.items():
        if key == "variables" and value:
            body = ",\n".join("    " + json.dumps(v) for v in value)
            text = f"[\n{body}\n  ]"
        else:
            text = json.dumps(value, indent=2).replace("\n", "\n  ")
        parts.append(f"  {json.dumps(key)}: {text}")
    return "{\n" + ",\n".join(parts) + "\n}\n"


def _value_info(t):
    """What plc-manager needs to check a value written to a variable: the
    elementary type, a subrange's bounds, an enumeration's values, a
    string's length."""
    from ..checks.types import Elementary, SubrangeT
    t = concrete(t)
    info = {}
    if isinstance(t, SubrangeT):
        info["range"] = [t.low, t.high]
        t = t.elem
    if isinstance(t, EnumT):
        info["base"] = N.enum_base(t).name
        info["enum"] = {name: value for name, value in sorted(t.values.values(),
                                                               key=lambda x: x[1])}
    elif isinstance(t, StringT):
        info["base"] = "WSTRING" if t.wide else "STRING"
        info["length"] = t.length
    elif isinstance(t, Elementary):
        info["base"] = t.name
    return info
