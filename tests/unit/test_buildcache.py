# SPDX-License-Identifier: MIT
"""The build cache (iec2kmod/buildcache.py): keyed by what a build reads,
independent of where the tree lives, restoring exactly what the build wrote
and replaying its output."""

import os

import pytest

from iec2kmod import buildcache


def _tree(d, body="int x;\n"):
    (d / "m").mkdir(parents=True)
    (d / "Kbuild").write_text("obj-y := m/\n")
    (d / "m" / "a.c").write_text(body)
    (d / "manifest.json").write_text("{}")
    return d


def _fake_build(d):
    (d / "m" / "a.o").write_bytes(b"\x7fELF-object")
    (d / "m" / "m.ko").write_bytes(b"\x7fELF-module")
    (d / "Module.symvers").write_text("")
    return f"make -C /kdir M={d}\n  CC [M]  {d}/m/a.o\n{d}/m/a.c:1:5: warning: x unused\n"


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("IEC2KMOD_BUILD_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache"


def test_the_key_follows_inputs_not_places_or_products(tmp_path, cache):
    a = _tree(tmp_path / "a")
    b = _tree(tmp_path / "b")
    k = buildcache.key(str(a), ["gcc=1"], ["W=1", "modules"])
    assert k == buildcache.key(str(b), ["gcc=1"], ["W=1", "modules"])
    _fake_build(a)
    (a / "manifest.json").write_text('{"kernel_release": "x"}')
    assert buildcache.key(str(a), ["gcc=1"], ["W=1", "modules"]) == k
    assert buildcache.key(str(a), ["gcc=2"], ["W=1", "modules"]) != k
    assert buildcache.key(str(a), ["gcc=1"], ["W=1", "C=1", "modules"]) != k
    (b / "m" / "a.c").write_text("int y;\n")
    assert buildcache.key(str(b), ["gcc=1"], ["W=1", "modules"]) != k
    (b / "m" / "a.c").write_text("int x;\n")
    (b / "m" / "extra.h").write_text("")
    assert buildcache.key(str(b), ["gcc=1"], ["W=1", "modules"]) != k


def test_a_stored_build_is_restored_elsewhere_with_its_output(tmp_path, cache):
    a = _tree(tmp_path / "a")
    k = buildcache.key(str(a), [], ["modules"])
    assert buildcache.restore(k, str(a)) is None
    before = buildcache.snapshot(str(a))
    out = _fake_build(a)
    buildcache.store(k, str(a), before, out)
    b = _tree(tmp_path / "b")
    code, replay = buildcache.restore(k, str(b))
    assert code == 0
    assert replay == out.replace(str(a), str(b))
    assert (b / "m" / "m.ko").read_bytes() == b"\x7fELF-module"
    assert (b / "m" / "a.o").exists() and (b / "Module.symvers").exists()
    # what the build did not write is not in the entry
    assert (b / "m" / "a.c").read_text() == "int x;\n"


def test_without_the_variable_nothing_is_cached(tmp_path, monkeypatch):
    for v in ("", "off"):
        monkeypatch.setenv("IEC2KMOD_BUILD_CACHE", v)
        assert buildcache.cache_dir() is None
        a = _tree(tmp_path / f"t{v}")
        k = buildcache.key(str(a), [], [])
        buildcache.store(k, str(a), {}, "")
        assert buildcache.restore(k, str(a)) is None


def test_the_oldest_entries_are_evicted(tmp_path, cache, monkeypatch):
    monkeypatch.setattr(buildcache, "MAX_ENTRIES", 2)
    keys = []
    for i in range(3):
        t = _tree(tmp_path / f"t{i}", body=f"int x{i};\n")
        k = buildcache.key(str(t), [], [])
        before = buildcache.snapshot(str(t))
        buildcache.store(k, str(t), before, _fake_build(t))
        os.utime(buildcache._entry(k), (1000 + i, 1000 + i))
        keys.append(k)
    buildcache._evict(str(cache))
    assert [buildcache.restore(k, str(tmp_path / "x")) is not None for k in keys] == \
        [False, True, True]


def test_generated_trees_do_not_depend_on_where_the_project_lies(tmp_path):
    """What a tree says it was generated from (comments, the source hash)
    names the sources relative to their directory: the same project in two
    places gives byte-identical trees (and so one build cache entry)."""
    import shutil
    import subprocess
    import sys
    root = __import__("pathlib").Path(__file__).resolve().parents[2]
    trees = []
    for place in ("a", "b/deeper"):
        src = tmp_path / place / "two_resources"
        shutil.copytree(root / "examples" / "two_resources", src)
        out = tmp_path / f"out_{len(trees)}"
        p = subprocess.run([sys.executable, "-m", "iec2kmod.cli", "gen", str(src), "-o", str(out)],
                           cwd=root, capture_output=True, text=True)
        assert p.returncode == 0, p.stderr
        trees.append(out)
    files = sorted(str(f.relative_to(trees[0])) for f in trees[0].rglob("*") if f.is_file())
    assert files
    for rel in files:
        a, b = (trees[0] / rel).read_bytes(), (trees[1] / rel).read_bytes()
        assert a == b, rel
        assert str(tmp_path).encode() not in a, rel


def test_a_file_named_by_a_make_argument_counts_by_its_content(tmp_path, cache):
    """KBUILD_EXTRA_SYMBOLS=/tmp/<random>/Module.symvers (benchmarks/soak.py's
    second build): the same symbols in another directory give the same key,
    other symbols another key."""
    a = _tree(tmp_path / "a")
    s1, s2 = tmp_path / "x" / "Module.symvers", tmp_path / "y" / "Module.symvers"
    for s in (s1, s2):
        s.parent.mkdir()
        s.write_text("0x1234\tiec_sym\tiec_cfg\tEXPORT_SYMBOL_GPL\t\n")
    k1 = buildcache.key(str(a), ["gcc=1"], [f"KBUILD_EXTRA_SYMBOLS={s1}", "modules"])
    assert k1 == buildcache.key(str(a), ["gcc=1"], [f"KBUILD_EXTRA_SYMBOLS={s2}", "modules"])
    s2.write_text("0x9999\tiec_sym\tiec_cfg\tEXPORT_SYMBOL_GPL\t\n")
    assert k1 != buildcache.key(str(a), ["gcc=1"], [f"KBUILD_EXTRA_SYMBOLS={s2}", "modules"])
