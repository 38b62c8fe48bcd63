"""Pointer members (VAR_EXTERNAL at every depth, a program's VAR_IN_OUT)
are bound by construction: the front end's binding table and the struct
layout cover each other, the generator refuses to emit otherwise (exit 70),
and the generated code checks at initialisation that no pointer is NULL
(the simulator exits, the kernel module refuses to load)."""

from pathlib import Path

import pytest

from iec2kmod import cli, sim
from iec2kmod.parse import frontend
from iec2kmod.checks import config as checks_config
from iec2kmod.codegen import plan as plan_mod
from iec2kmod.codegen.pou import pointer_members

pytestmark = pytest.mark.unit
ROOT = Path(__file__).resolve().parents[2]
DEEP = ROOT / "tests" / "execution" / "cases" / "config" / "fb_external_depth.st"
MINIMAL = ROOT / "tests" / "execution" / "cases" / "config" / "fb_external_minimal.st"


def _project(path):
    result = frontend.run([str(path)], use_cache=False)
    assert result.ok, result.diagnostics
    return result.project


def test_the_table_covers_every_pointer_member_at_every_depth():
    plan = plan_mod.build_plan(_project(DEEP))
    deep = next(ip for ip in plan.instances if ip.path == "r1.d")
    bound = {b.member: b for b in deep.bindings}
    assert set(bound) == {c for c, _, _ in pointer_members(deep.pou)}
    # depth 3, through an array of FB instances, and the program's own parts
    assert bound["v_top.v_inner.v_inner.v_g"].target.c_name == "g_g"
    assert bound["v_top.v_spare[*].v_inner.v_step"].counts == (4,)
    assert bound["v_leaf.v_k"].program_member == "v_k"
    assert bound["v_io"].target.c_name == "g_h"
    assert bound["v_leaf.v_a"].is_array
    assert len(deep.bindings) == 1 + 1 + 6 + 6 + 6   # io, top.g, three Leafs


def _drop_nested_bindings(monkeypatch):
    """The bug of issue 8: only the program's own externals recorded."""
    real = checks_config.ConfigChecker._bind

    def only_top(self, pou, scope, r, inst, stack, src, steps):
        real(self, pou, scope, r, inst, stack, src, steps)
        inst.bindings[:] = [b for b in inst.bindings if len(b.steps) == 1]

    monkeypatch.setattr(checks_config.ConfigChecker, "_bind", only_top)


def test_gen_refuses_an_incomplete_table(monkeypatch, tmp_path, capsys):
    _drop_nested_bindings(monkeypatch)
    rc = cli.main(["gen", str(MINIMAL), "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert rc == cli.EXIT_INTERNAL, err
    assert "BindingError" in err and "R.I" in err and "'v_x.v_g'" in err
    assert not (tmp_path / "out" / "manifest.json").exists()


def test_the_simulator_refuses_a_null_pointer(monkeypatch, tmp_path):
    """Past the generator's check (disabled here), the generated code's own
    check stops the simulator before any task runs."""
    _drop_nested_bindings(monkeypatch)
    monkeypatch.setattr(plan_mod, "check_bindings", lambda ip: None)
    with pytest.raises(sim.InternalError, match=r"pointer member R\.I\.X\.G is not bound"):
        sim.run(_project(MINIMAL), 30_000_000, build_dir=tmp_path)


def test_the_kernel_module_checks_its_pointers_at_init(monkeypatch, tmp_path):
    from iec2kmod import kmod
    _drop_nested_bindings(monkeypatch)
    monkeypatch.setattr(plan_mod, "check_bindings", lambda ip: None)
    kmod.generate_tree(_project(MINIMAL), tmp_path / "tree")
    main = next((tmp_path / "tree").glob("iec_c_r_r/main.c")).read_text()
    assert 'if (!inst_r_i.v_x.v_g)\n\t\treturn "R.I.X.G";' in main
    assert "pointer member %s is not bound; not loading" in main


INOUT_CALL = """FUNCTION_BLOCK Acc
  VAR_IN_OUT x : INT; END_VAR
  x := x + 1;
END_FUNCTION_BLOCK
FUNCTION Inc : INT
  VAR_IN_OUT x : INT; END_VAR
  x := x + 1; Inc := x;
END_FUNCTION
PROGRAM P
  VAR a : Acc; n : INT; m : INT; END_VAR
  a(x := n);
  m := Inc(x := n);
END_PROGRAM
CONFIGURATION C
  TASK t (INTERVAL := T#10ms, PRIORITY := 1);
  PROGRAM p WITH t : P;
END_CONFIGURATION
"""


@pytest.mark.parametrize("callee", ["Acc", "Inc"])
def test_a_call_that_leaves_a_var_in_out_unbound_is_not_emitted(callee, tmp_path):
    """A call sets every VAR_IN_OUT pointer of its callee; the front end
    requires the connection, and the emitter refuses a call without one
    rather than run the body on the previous call's target (or none)."""
    from iec2kmod.codegen import generate
    from iec2kmod.codegen.expr import BindingError
    src = tmp_path / "inout.st"
    src.write_text(INOUT_CALL)
    project = _project(src)
    body = next(p for p in project.pous.values() if p.name == "P").node.body
    call = next(s for s in _walk(body) if getattr(s, "bound", None) and
                s.name.upper() == {"Acc": "A", "Inc": "INC"}[callee])
    call.bound.clear()
    with pytest.raises(BindingError, match="leaves VAR_IN_OUT x unbound"):
        generate(project)


def _walk(node, seen=None):
    seen = set() if seen is None else seen
    if id(node) in seen or node is None or isinstance(node, (str, int, float, bool)):
        return
    seen.add(id(node))
    yield node
    if isinstance(node, (list, tuple)):
        items = node
    elif hasattr(node, "__slots__"):
        items = [getattr(node, k, None) for c in type(node).__mro__
                 for k in getattr(c, "__slots__", ()) if k not in ("target", "symbol", "type")]
    else:
        items = []
    for x in items:
        yield from _walk(x, seen)
