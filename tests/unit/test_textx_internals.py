"""The textX internals iec2kmod/parse/parser.py (FastBuilder, fast_paths) and
iec2kmod/parse/stfast.py rely on are there.  pyproject.toml pins textX to the
range they were verified on; a textX outside it that lacks one fails here,
naming what is missing, before any parse goes wrong in a subtler way
(tests/unit/test_fast_builder.py then compares the models built)."""

from __future__ import annotations

from importlib import metadata

import pytest


def missing_internals() -> list[str]:
    """What parser.py and stfast.py use of textX and Arpeggio that this
    installation lacks ([] when everything is there)."""
    missing = []

    def need(ok, what):
        if not ok:
            missing.append(what)

    try:
        from textx import const, lang
        for name in ("MULT_ONEORMORE", "MULT_ZEROORMORE", "RULE_ABSTRACT", "RULE_MATCH",
                     "MULT_ASSIGN_ERROR"):
            need(hasattr(const, name), f"textx.const.{name}")
        need(hasattr(lang, "BASE_TYPE_NAMES"), "textx.lang.BASE_TYPE_NAMES")
        need(hasattr(lang, "python_type"), "textx.lang.python_type")
        import arpeggio
        need(hasattr(arpeggio, "Terminal") and hasattr(arpeggio, "EndOfFile"),
             "arpeggio.Terminal / arpeggio.EndOfFile")
    except ImportError as exc:
        return [f"import: {exc}"]

    from iec2kmod.parse.parser import FAST_PATHS, metamodel
    mm = metamodel()
    need(hasattr(mm, "_obj_processors"), "metamodel._obj_processors")
    need(hasattr(getattr(mm, "_parser_blueprint", None), "clone"),
         "metamodel._parser_blueprint.clone()")
    need(hasattr(mm, "auto_init_attributes"), "metamodel.auto_init_attributes")
    for name in FAST_PATHS:
        rule = getattr(mm[name], "_tx_peg_rule", None)
        need(rule is not None, f"class {name}._tx_peg_rule (fast_paths)")
        need(hasattr(rule, "regex"), f"class {name}._tx_peg_rule.regex (fast_paths, stfast)")
    classes = [c for c in mm if hasattr(c, "_tx_attrs")]
    need(len(classes) > 50, "metaclass._tx_attrs (FastBuilder)")
    for cls in classes:
        need(hasattr(cls, "_tx_type") and hasattr(cls, "_tx_fqn"),
             f"{cls.__name__}._tx_type / _tx_fqn")
        for attr in cls._tx_attrs.values():
            for field in ("name", "mult", "cls", "bool_assignment"):
                need(hasattr(attr, field), f"{cls.__name__}._tx_attrs[...].{field}")
        peg = getattr(cls, "_tx_peg_rule", None)
        need(peg is not None, f"{cls.__name__}._tx_peg_rule")
        if peg is not None and cls._tx_type not in (const.RULE_ABSTRACT, const.RULE_MATCH):
            need(getattr(peg, "_tx_class", None) is cls,
                 f"{cls.__name__}._tx_peg_rule._tx_class (FastBuilder dispatch)")
    # the assignment rules FastBuilder recognises by name and _attr_name
    seen, assignments = set(), []

    def walk(rule, depth=0):
        if id(rule) in seen or depth > 60:
            return
        seen.add(id(rule))
        if getattr(rule, "rule_name", "").startswith("__asgn"):
            assignments.append(rule)
            need(hasattr(rule, "_attr_name"), f"assignment rule {rule.rule_name}._attr_name")
        for n in getattr(rule, "nodes", []):
            walk(n, depth + 1)
    for cls in classes[:20]:
        walk(cls._tx_peg_rule)
    need(len(assignments) > 20, "assignment rules named __asgn_* (FastBuilder)")
    return sorted(set(missing))


def test_textx_internals_present():
    missing = missing_internals()
    version = metadata.version("textX")
    assert not missing, (
        f"textX {version} lacks internals iec2kmod/parse/parser.py and iec2kmod/parse/stfast.py use: "
        f"{', '.join(missing)}.  pyproject.toml pins textX to the versions verified; install "
        f"one of them (pip install 'textX>=4.0,<4.5') or port FastBuilder to this version.")


def test_the_check_sees_a_missing_internal(monkeypatch):
    """Removing one internal is reported by name (the check can fail)."""
    from iec2kmod.parse.parser import FAST_PATHS, metamodel
    cls = metamodel()[FAST_PATHS[0]]
    monkeypatch.delattr(cls, "_tx_peg_rule")
    assert f"class {FAST_PATHS[0]}._tx_peg_rule (fast_paths)" in missing_internals()


def test_pin_covers_the_installed_version():
    """The installed textX lies in the range pyproject.toml declares."""
    import re
    import tomllib
    from pathlib import Path
    deps = tomllib.loads((Path(__file__).resolve().parents[2] / "pyproject.toml")
                        .read_text())["project"]["dependencies"]
    spec = [d for d in deps if d.lower().startswith("textx")]
    assert spec, "textX is a core dependency"
    lo = re.search(r">=\s*([\d.]+)", spec[0])
    hi = re.search(r"<\s*([\d.]+)", spec[0])
    assert lo and hi, f"textX must be pinned to a range (>=A,<B), not {spec[0]!r}"

    def v(s):
        return tuple(int(x) for x in s.split(".")[:3])
    installed = v(metadata.version("textX"))
    if not v(lo.group(1)) <= installed < v(hi.group(1)):
        pytest.fail(f"textX {metadata.version('textX')} is outside {spec[0]!r}")
