# SPDX-License-Identifier: MIT
"""plc-manager's saved state: a small file every swap rewrites, and the
manifest copy written once by load and read only when a command needs it
(manager/project.py State)."""

import json

import pytest

from plc_manager import project
from plc_manager.errors import PLCError
from plc_manager.project import State

pytestmark = pytest.mark.unit


def _manifest(n_vars=2000):
    return {"configuration": "Plant", "interface_hash": "i" * 16, "source_hash": "s" * 16,
            "program_types": [{"name": "Counter", "module": "iec_plant_p_counter_a",
                               "build_id": "a", "ko": "/old/a.ko"},
                              {"name": "Mixer", "module": "iec_plant_p_mixer_1",
                               "build_id": "1"}],
            "variables": [{"path": f"plant.g{i}", "kind": "i"} for i in range(n_vars)]}


class FakeProject:
    configuration = "Plant"
    path = "/proj"

    def __init__(self):
        self.m = _manifest()


@pytest.fixture
def sdir(tmp_path, monkeypatch):
    monkeypatch.setattr(project, "state_dir", lambda: tmp_path)
    return tmp_path


def test_a_swap_rewrites_only_the_small_file(sdir):
    State.create(FakeProject()).save()
    big = sdir / "plant.manifest.json"
    small = sdir / "plant.json"
    assert big.stat().st_size > 50_000 and small.stat().st_size < 500
    before = big.read_bytes()

    s = State.load("Plant")
    assert (s.interface_hash, s.source_hash) == ("i" * 16, "s" * 16)
    assert s._manifest is None                       # not read by a swap
    s.record("COUNTER", "iec_plant_p_counter_b", "b", "/new/b.ko")
    s.save()
    assert big.read_bytes() == before                # the manifest copy is not rewritten
    assert s._manifest is None and small.stat().st_size < 500

    # what a later command sees: the manifest with the swapped build
    t = {p["name"]: p for p in State.load("Plant").manifest["program_types"]}
    assert t["Counter"] == {"name": "Counter", "module": "iec_plant_p_counter_b",
                            "build_id": "b", "ko": "/new/b.ko"}
    assert t["Mixer"]["build_id"] == "1"
    # a record while the manifest is in memory applies at once
    s2 = State.load("Plant")
    m = s2.manifest
    s2.record("mixer", "iec_plant_p_mixer_2", "2", None)
    assert m["program_types"][1]["module"] == "iec_plant_p_mixer_2"


def test_the_one_file_state_of_earlier_versions_is_read_and_converted(sdir):
    (sdir / "plant.json").write_text(json.dumps(
        {"configuration": "Plant", "project": "/proj", "manifest": _manifest(10)}))
    s = State.load("Plant")
    assert s.interface_hash == "i" * 16 and len(s.manifest["variables"]) == 10
    s.save()
    assert "manifest" not in json.loads((sdir / "plant.json").read_text())
    assert len(State.load("Plant").manifest["variables"]) == 10


def test_a_lost_manifest_copy_is_a_clear_error_and_remove_takes_both(sdir):
    State.create(FakeProject()).save()
    (sdir / "plant.manifest.json").unlink()
    with pytest.raises(PLCError, match="copy of the manifest.*cannot be read"):
        State.load("Plant").manifest
    State.create(FakeProject()).save()
    State.remove("Plant")
    assert list(sdir.iterdir()) == []
    assert State.load("Plant") is None


def test_load_copies_the_manifest_file_as_it_was_read(sdir, tmp_path):
    p = FakeProject()
    p.text = json.dumps(p.m, indent=1)          # not what json.dumps would write
    State.create(p).save()
    assert (sdir / "plant.manifest.json").read_text() == p.text
