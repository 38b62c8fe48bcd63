"""Kernel module names fit the kernel's limit (MODULE_NAME_LEN - 1 = 55
characters; modpost refuses a longer one): long configuration, resource and
program names are valid IEC and used to give modules that did not build
(found with the differential campaign's cases)."""

import json

import pytest

from iec2kmod import kmod
from iec2kmod.parse import frontend

pytestmark = pytest.mark.unit

LONG = "a_configuration_name_that_is_long_enough_to_overflow_it"
SOURCE = f"""
PROGRAM a_program_type_whose_name_is_long_as_well_one
VAR x : INT; END_VAR
  x := x + 1;
END_PROGRAM
PROGRAM a_program_type_whose_name_is_long_as_well_two
VAR y : INT; END_VAR
  y := y + 2;
END_PROGRAM
CONFIGURATION {LONG}
  RESOURCE a_resource_with_a_long_name_too_number_one ON PLC
    TASK t (INTERVAL := T#10ms, PRIORITY := 1);
    PROGRAM i WITH t : a_program_type_whose_name_is_long_as_well_one;
  END_RESOURCE
  RESOURCE a_resource_with_a_long_name_too_number_two ON PLC
    TASK t (INTERVAL := T#10ms, PRIORITY := 1);
    PROGRAM j WITH t : a_program_type_whose_name_is_long_as_well_two;
  END_RESOURCE
END_CONFIGURATION
"""


def _tree(tmp_path, name):
    src = tmp_path / f"{name}.st"
    src.write_text(SOURCE)
    result = frontend.run([str(src)], use_cache=False)
    assert result.ok, result.diagnostics
    out = tmp_path / name
    kmod.generate_tree(result.project, out)
    return out, json.loads((out / "manifest.json").read_text())


def test_long_names_give_module_names_the_kernel_accepts(tmp_path):
    out, manifest = _tree(tmp_path, "one")
    names = [m["name"] for m in manifest["modules"]]
    assert len(names) == 5 and len(set(names)) == 5, names
    for m in manifest["modules"]:
        assert len(m["name"]) <= kmod.MODULE_NAME_MAX, m["name"]
        assert m["name"].startswith("iec_a_configuration_name"), m["name"]
        kbuild = (out / m["dir"] / "Kbuild").read_text()
        assert f"obj-m := {m['name']}.o" in kbuild
    programs = [m for m in manifest["modules"] if m["kind"] == "program"]
    # the build id still ends a program module's name (a new build, a new name)
    assert all(m["name"].endswith("_" + m["build_id"]) for m in programs)
    # deterministic: the same sources give the same names
    _, again = _tree(tmp_path, "two")
    assert [m["name"] for m in again["modules"]] == names


def test_short_names_are_unchanged():
    assert kmod._modname("plant_p_counter", "_0123abcd") == "iec_plant_p_counter_0123abcd"
    assert kmod._modname("plant", "_config") == "iec_plant_config"
    long = kmod._modname("x" * 80, "_config")
    assert len(long) == kmod.MODULE_NAME_MAX and long.endswith("_config")
    assert kmod._modname("x" * 80 + "a", "_config") != long
