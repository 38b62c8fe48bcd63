"""The structure of the stages after checking (issue 24): one Compilation
made by the driver, a code generator that depends on no solver, one source
of truth for the execution model."""

import ast as pyast
import re
import subprocess
import sys
from pathlib import Path

import pytest

from iec2kmod import cli, compilation, execmodel
from iec2kmod.parse import frontend
from iec2kmod.codegen import plan as plan_mod

pytestmark = pytest.mark.unit
ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"


def _project(example):
    res = frontend.run([str(EXAMPLES / example)], use_cache=False)
    assert res.ok, [d.format() for d in res.diags.sorted()]
    return res.project


# ------------------------------------------------------- one lowering
def test_sim_vcd_builds_the_plan_once(tmp_path, monkeypatch, capsys):
    """`sim --vcd` (and --csv) used to build the plan a second time for the
    VCD's variable kinds: now the Compilation's plan serves every writer.
    Counted on the Plan objects made, however build_plan was imported."""
    made = []
    real = plan_mod.Plan

    def counting(*args, **kwargs):
        made.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(plan_mod, "Plan", counting)
    monkeypatch.setenv("IEC2KMOD_CACHE", str(tmp_path / "cache"))
    rc = cli.main(["sim", str(EXAMPLES / "elevator"), "--cycles", "2",
                   "--vcd", str(tmp_path / "out.vcd"), "--csv", str(tmp_path / "out.csv")])
    assert rc == 0, capsys.readouterr().err
    assert (tmp_path / "out.vcd").read_text().startswith("$date iec2kmod sim")
    assert len(made) == 1


def test_instance_plans_point_at_their_checked_instances():
    project = _project("two_resources")
    plan = compilation.Compilation(project).plan
    insts = [inst for r in project.configurations[0].resources for inst in r.programs]
    assert len(plan.instances) == len(insts) >= 2
    for ip, inst in zip(plan.instances, insts):
        assert ip.inst is inst
        assert ip.path.split(".")[-1] == inst.name


def test_the_module_split_is_data_the_writer_follows(tmp_path):
    """The manifest written from a Compilation names the modules its split
    decided, in the split's order."""
    from iec2kmod.kmod import generate_tree
    comp = compilation.Compilation(_project("two_resources"))
    mp = comp.modules
    manifest = generate_tree(comp, tmp_path / "tree")
    names = manifest["load_order"]
    assert names[0] == mp.config_module
    assert names[-len(mp.resources):] == [m.name for m in mp.resources]
    progs = names[1:len(names) - len(mp.resources)]
    assert [p.rsplit("_", 1)[0] for p in progs] == \
        [m.name("x").rsplit("_", 1)[0] for m in mp.programs]
    assert manifest["interface_hash"] == mp.iface_hash
    assert [t["interface_hash"] for t in manifest["program_types"]] == \
        [m.iface_hash for m in mp.programs]


def test_build_plan_is_called_in_one_place_of_the_product():
    calls = []
    for f in sorted((ROOT / "iec2kmod").rglob("*.py")):
        for node in pyast.walk(pyast.parse(f.read_text())):
            if isinstance(node, pyast.Call) and getattr(node.func, "id", None) == "build_plan" \
                    or isinstance(node, pyast.Call) and \
                    getattr(node.func, "attr", None) == "build_plan":
                calls.append(f"{f.relative_to(ROOT)}:{node.lineno}")
    assert calls == [c for c in calls if c.startswith("iec2kmod/compilation.py:")] and \
        len(calls) == 1, calls


# ---------------------------------------- the generator depends on no solver
def _imports(path, package):
    """Absolute names of what a module imports (modules and names from them)."""
    out = []
    for node in pyast.walk(pyast.parse(path.read_text())):
        if isinstance(node, pyast.ImportFrom):
            base = package.split(".")
            base = base[:len(base) - node.level + 1] if node.level else []
            mod = ".".join(base + ([node.module] if node.module else []))
            out += [mod] + [f"{mod}.{a.name}" for a in node.names]
        elif isinstance(node, pyast.Import):
            out += [a.name for a in node.names]
    return out


def test_codegen_imports_no_verify_interp_or_z3():
    """Anywhere in a codegen module, at the top or inside a function."""
    bad = re.compile(r"^(?:iec2kmod\.(?:verify|interp)|z3)(?:\.|$)")
    found = [f"{f.name}: {mod}" for f in sorted((ROOT / "iec2kmod" / "codegen").glob("*.py"))
             for mod in _imports(f, "iec2kmod.codegen") if bad.match(mod)]
    assert found == []
    # the check sees such an import where it would be
    assert sorted(m for m in _imports(ROOT / "iec2kmod" / "compilation.py", "iec2kmod")
                  if bad.match(m)) == ["iec2kmod.verify.idempotent",
                                       "iec2kmod.verify.idempotent.Prover", "z3"]


def test_generating_selective_code_loads_no_solver():
    """The generator's modules, imported and run on a settled plan, bring
    neither the verifier, the interpreter nor z3 with them."""
    code = (
        "import sys\n"
        "from iec2kmod.parse import frontend\n"
        "from iec2kmod.codegen import generate\n"
        "from iec2kmod.codegen.plan import build_plan\n"
        "from iec2kmod.codegen.selective import SelectivePlan\n"
        f"p = frontend.run([{str(EXAMPLES / 'tank_level')!r}], use_cache=False).project\n"
        "sel = SelectivePlan(p, 'all')\n"
        "sel.settle({q.key: (None, 'not asked') for q in sel.questions})\n"
        "generate(p, selective=sel); build_plan(p)\n"
        "print(sorted(m for m in sys.modules if m.startswith(('iec2kmod.verify', "
        "'iec2kmod.interp', 'z3'))))\n")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert p.returncode == 0, p.stderr
    assert p.stdout.strip() == "[]"


def test_an_unsettled_selective_plan_is_refused():
    from iec2kmod.codegen import generate
    from iec2kmod.codegen.selective import SelectivePlan
    project = _project("tank_level")
    sel = SelectivePlan(project, "all")
    assert sel.questions and not sel.settled
    with pytest.raises(ValueError, match="not answered"):
        generate(project, selective=sel)


def test_gen_selective_without_z3_refuses(tmp_path, monkeypatch, capsys):
    """The layout of tank_level's Hysteresis depends on z3's proof: without
    z3 `gen --selective` says so instead of writing another layout."""
    monkeypatch.setitem(sys.modules, "z3", None)       # import z3 -> ImportError
    rc = cli.main(["gen", str(EXAMPLES / "tank_level"), "-o", str(tmp_path / "t"),
                   "--selective"])
    err = capsys.readouterr().err
    assert rc == cli.EXIT_USAGE
    assert "needs z3-solver" in err and "Hysteresis" in err
    assert not (tmp_path / "t" / "manifest.json").exists()


def test_gen_selective_with_another_z3_refuses(tmp_path, monkeypatch, capsys):
    import z3
    monkeypatch.setattr(z3, "get_version_string", lambda: "4.8.0")
    rc = cli.main(["gen", str(EXAMPLES / "pid_loop"), "-o", str(tmp_path / "t"),
                   "--selective"])
    assert rc == cli.EXIT_USAGE
    assert "z3 4.8.0 is installed" in capsys.readouterr().err


def test_gen_selective_without_a_question_needs_no_z3(tmp_path, monkeypatch, capsys):
    """No block reaches the proof: the same tree with or without z3."""
    rc = cli.main(["gen", str(EXAMPLES / "elevator"), "-o", str(tmp_path / "a"), "--selective"])
    assert rc == 0
    monkeypatch.setitem(sys.modules, "z3", None)
    rc = cli.main(["gen", str(EXAMPLES / "elevator"), "-o", str(tmp_path / "b"), "--selective"])
    assert rc == 0, capsys.readouterr().err
    a, b = tmp_path / "a", tmp_path / "b"
    files = sorted(p.relative_to(a) for p in a.rglob("*") if p.is_file())
    assert files == sorted(p.relative_to(b) for p in b.rglob("*") if p.is_file())
    assert all((a / f).read_bytes() == (b / f).read_bytes() for f in files)


def test_z3_is_pinned_to_the_version_the_layouts_were_proved_with():
    text = (ROOT / "pyproject.toml").read_text()
    m = re.search(r'"z3-solver==([0-9.]+)"', text)
    assert m, "z3-solver is not pinned in pyproject.toml"
    pinned = m.group(1).split(".")
    want = compilation.Z3_VERSION.split(".")
    assert pinned[:len(want)] == want and set(pinned[len(want):]) <= {"0"}


# ------------------------------------------------------ execution model
def test_the_c_loop_budget_default_is_the_execution_models():
    text = (ROOT / "kmod_templates" / "runtime" / "iec_fault.h").read_text()
    m = re.search(r"#define IEC_LOOP_BUDGET_DEFAULT\s+(\d+)U", text)
    assert m and int(m.group(1)) == execmodel.LOOP_BUDGET


def test_one_loop_budget_and_table_limit():
    """Every user of the execution model's numbers has them from it."""
    from iec2kmod import interp
    from iec2kmod.interp import machine
    from iec2kmod.codegen import body as codegen_body
    from iec2kmod.verify import encode
    assert interp.LOOP_BUDGET is execmodel.LOOP_BUDGET
    # the C emitter charges a constant FOR loop to the budget up to the
    # budget; the verifier's unrolling stops at it
    assert codegen_body.LOOP_BUDGET is encode.LOOP_BUDGET is execmodel.LOOP_BUDGET
    assert machine.kind_of is plan_mod.kind_of is execmodel.kind_of
    assert machine.MAX_TABLE_ELEMENTS is plan_mod.MAX_TABLE_ELEMENTS
    for f in (ROOT / "iec2kmod").rglob("*.py"):
        if f.name == "execmodel.py":
            continue
        text = f.read_text()
        assert not re.search(r"^\s*(?:LOOP_BUDGET|DEFAULT_LOOP_BUDGET|SIM_ITERATION_NS|"
                             r"MAX_TABLE_ELEMENTS)\s*=", text, re.M), f
        assert not re.search(r"^def kind_of\b", text, re.M), f


def test_kernel_and_simulator_tasks_get_the_execution_models_budget(tmp_path):
    """The interpreter counts against execmodel.LOOP_BUDGET; the kernel's
    and the simulator's tasks are given the same (this replaces the
    comparison of two copies in tests/execution/test_cases_vm.py)."""
    from iec2kmod import interp
    from iec2kmod.kmod import generate_tree
    from iec2kmod.sim import render_sim
    comp = compilation.Compilation(_project("two_resources"))
    generate_tree(comp, tmp_path)
    mains = [p.read_text() for p in tmp_path.glob("*_r_*/main.c")]
    assert len(mains) == 2
    for text in mains:
        budgets = re.findall(r"\.loop_budget = (\d+),", text)
        assert budgets and set(budgets) == {str(execmodel.LOOP_BUDGET)}
    files, _ = render_sim(comp)
    rows = re.findall(r"task_\d+, (\d+)U, ", files["sim_project.c"])
    assert rows and set(rows) == {str(execmodel.LOOP_BUDGET)}
    assert interp.LOOP_BUDGET == execmodel.LOOP_BUDGET


def test_build_rewrites_the_manifest_as_gen_wrote_it(tmp_path):
    """`iec2kmod build` adds kernel_release and writes the manifest with the
    writer of kmod/manifest.py (it imported a name the split of kmod moved:
    caught only by building)."""
    import json
    from iec2kmod.kmod import build, generate_tree
    generate_tree(_project("elevator"), tmp_path)
    before = (tmp_path / "manifest.json").read_text()
    build._write_manifest(tmp_path, json.loads(before))
    assert (tmp_path / "manifest.json").read_text() == before
