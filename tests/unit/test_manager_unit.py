# SPDX-License-Identifier: MIT
"""plc-manager without a kernel: IEC literals (parse, range and type checks,
bytes both ways, display), the netlink numbers against iec_nl.h, interface
comparison, swap candidates, and the commands' answers when nothing is
loaded or the input is bad."""

import json
import re
import struct
import subprocess
import sys
from pathlib import Path

import pytest

from plc_manager import netlink, project, values
from plc_manager.errors import UsageError
from plc_manager.values import VarType

pytestmark = pytest.mark.unit
ROOT = Path(__file__).resolve().parents[2]


def V(kind, size, type_="?", **kw):
    return VarType(path="x", kind=kind, size=size, type=type_, **kw)


INT = V("i", 2, "INT", base="INT")
UDINT = V("u", 4, "UDINT", base="UDINT")
BYTE = V("u", 1, "BYTE", base="BYTE")
BOOL = V("b", 1, "BOOL", base="BOOL")
REAL = V("f", 4, "REAL", base="REAL")
LREAL = V("f", 8, "LREAL", base="LREAL")
TIME = V("t", 8, "TIME", base="TIME")
TOD = V("t", 8, "TOD", base="TOD")
DATE = V("t", 8, "DATE", base="DATE")
DT = V("t", 8, "DT", base="DT")
PCT = V("i", 2, "Percent", base="INT", range=(0, 100))
MODE = V("e", 4, "Mode", base="DINT", enum={"IDLE": 0, "FILL": 1, "DRAIN": 2})
S16 = V("s", 20, "STRING[16]", base="STRING", length=16)
WS = V("w", 512, "WSTRING", base="WSTRING", length=254)


@pytest.mark.parametrize("var,text,value", [
    (INT, "42", 42), (INT, "-32768", -32768), (INT, "INT#7", 7), (INT, "16#7F_FF", 32767),
    (INT, "2#1010", 10), (INT, "8#17", 15), (INT, "1_000", 1000),
    (UDINT, "4294967295", 4294967295), (BYTE, "16#FF", 255),
    (BOOL, "TRUE", True), (BOOL, "false", False), (BOOL, "1", True), (BOOL, "BOOL#0", False),
    (REAL, "1.5", 1.5), (REAL, "-2.5E3", -2500.0), (REAL, "3", 3.0), (LREAL, "LREAL#1e300", 1e300),
    (TIME, "T#1h2m3s4ms5us6ns", 3_723_004_005_006), (TIME, "TIME#-5s", -5_000_000_000),
    (TIME, "t#1.5s", 1_500_000_000), (TIME, "T#20ms", 20_000_000), (TIME, "LT#1d", 86_400 * 10**9),
    (TOD, "TOD#12:00:00.5", 43_200_500_000_000), (DATE, "D#1970-01-02", 86_400 * 10**9),
    (DT, "DT#1970-01-01-00:00:01", 10**9),
    (PCT, "100", 100), (MODE, "fill", 1), (MODE, "Mode#DRAIN", 2),
    (S16, "'a$'b$N'", "a'b\n"), (S16, "plain text", "plain text"), (S16, "'$41'", "A"),
    (WS, '"w$0416"', "w\u0416"),
])
def test_literals_parse(var, text, value):
    assert values.parse(var, text) == value
    # and they survive the trip through the kernel's bytes
    got = values.decode(var, values.encode(var, values.parse(var, text)))
    assert got == pytest.approx(value) if isinstance(value, float) else got == value


@pytest.mark.parametrize("var,text,why", [
    (INT, "40000", "out of range -32768..32767"),
    (INT, "TRUE", "wrong type"), (INT, "1.5", "wrong type"), (INT, "DINT#5", "wrong type"),
    (INT, "abc", "not an integer"), (INT, "", "empty"), (INT, "T#5s", "wrong type"),
    (UDINT, "-1", "out of range"), (BYTE, "256", "out of range"),
    (BOOL, "2", "wrong type"), (BOOL, "yes", "wrong type"),
    (REAL, "1e39", "out of range"), (REAL, "TRUE", "wrong type"), (REAL, "x", "wrong type"),
    (TIME, "5", "wrong type"), (TIME, "T#5", "not a duration"), (TIME, "TOD#12:00:00", "wrong type"),
    (TOD, "TOD#25:00:00", "not a time of day"), (DATE, "D#2024-13-01", "not a date"),
    (PCT, "101", "out of range 0..100"), (PCT, "-1", "out of range 0..100"),
    (MODE, "PURPLE", "one of IDLE, FILL, DRAIN"), (MODE, "1", "one of"),
    (MODE, "Color#FILL", "wrong type"),
    (S16, "'seventeen chars!!'", "string too long: 17 characters, at most 16"),
    (S16, "'it's'", "must be written $'"), (S16, "'\u0416'", "characters 0..255"),
    (S16, '"wide"', "quoted with '"), (S16, "'bad $Z'", "bad $ escape"),
])
def test_literals_refused_with_a_reason(var, text, why):
    with pytest.raises(UsageError) as e:
        values.parse(var, text)
    assert why in str(e.value)
    assert "\n" not in str(e.value)


def test_bytes_layout_matches_the_c_objects():
    assert values.encode(INT, -2) == struct.pack("<h", -2)
    assert values.encode(UDINT, 7) == struct.pack("<I", 7)
    assert values.encode(REAL, 1.5) == struct.pack("<f", 1.5)
    assert values.encode(LREAL, 1.5) == struct.pack("<d", 1.5)
    assert values.encode(TIME, -1) == struct.pack("<q", -1)
    assert values.encode(MODE, 2) == struct.pack("<i", 2)
    # STRING: u16 length, the characters, the terminating NUL
    assert values.encode(S16, "ab") == b"\x02\x00ab\x00"
    assert values.encode(WS, "a") == b"\x01\x00a\x00\x00\x00"
    assert values.decode(S16, b"\x02\x00ab\x00garbage") == "ab"


@pytest.mark.parametrize("var,value,text", [
    (BOOL, True, "TRUE"), (INT, -5, "-5"), (BYTE, 255, "16#FF"), (REAL, 25.0, "25.0"),
    (TIME, 1_500_000_000, "T#1s500ms"), (TIME, 0, "T#0s"), (TOD, 43_200_500_000_000,
                                                              "TOD#12:00:00.5"),
    (DATE, 0, "D#1970-01-01"), (DT, 10**9, "DT#1970-01-01-00:00:01"),
    (MODE, 1, "FILL"), (S16, "it's", "'it$'s'"), (WS, "x", '"x"'),
])
def test_values_shown_as_iec_literals(var, value, text):
    assert values.text(var, value) == text


def test_netlink_numbers_match_the_kernel_header():
    h = (ROOT / "kmod_templates" / "kernel" / "iec_nl.h").read_text()

    def enum(name):
        body = re.search(r"enum %s \{(.*?)\};" % name, h, re.S).group(1)
        return [m for m in re.findall(r"^\s*(\w+)(?:\s*=\s*\d+)?,", body, re.M)
                if not m.startswith("__")]

    assert enum("iec_nl_cmd") == netlink.COMMANDS
    assert enum("iec_nl_attr") == [name for name, _ in netlink.ATTRIBUTES]
    assert f'"{netlink.FAMILY}"' in h
    assert re.search(r"IEC_NL_VALUE_MAX\s+%d\b" % netlink.VALUE_MAX, h)
    assert re.search(r"IEC_NL_MAX_VARS\s+%d\b" % netlink.MAX_VARS, h)
    assert re.search(r"IEC_NL_MAX_FORCES\s+%d\b" % netlink.MAX_FORCES, h)
    assert len(netlink.FAMILY) <= 15


def test_netlink_messages_round_trip():
    M = netlink._msg_class()
    m = M()
    m["cmd"] = netlink.CMD["IEC_CMD_VAR_SET"]
    m["version"] = 1
    m["attrs"] = [netlink.Client._sel("a", b"\x01\x00"), netlink.Client._sel("main.c1.count")]
    m["header"]["type"] = 0x20
    m.encode()
    # nested attributes carry NLA_F_NESTED (strict validation wants it)
    first = struct.unpack_from("HH", m.data, 20)
    assert first[1] == 0x8000 | [n for n, _ in netlink.ATTRIBUTES].index("IEC_A_VAR")
    d = M(m.data)
    d.decode()
    vs = netlink._flat(d)["IEC_A_VAR"]
    assert [netlink._flat(v).get("IEC_A_PATH") for v in vs] == ["a", "main.c1.count"]
    assert netlink._flat(vs[0])["IEC_A_VALUE"] == b"\x01\x00"


def test_interface_changes_are_named():
    old = [{"name": "count", "section": "VAR_OUTPUT", "type": "DINT"},
           {"name": "algo", "section": "VAR_OUTPUT", "type": "INT"},
           {"name": "cycles", "section": "VAR", "type": "UDINT"}]
    assert project.interface_changes(old, old) == []
    new = old + [{"name": "extra", "section": "VAR", "type": "INT"}]
    assert project.interface_changes(old, new) == ["variable added: extra : INT (VAR)"]
    assert project.interface_changes(new, old) == ["variable removed: extra : INT (VAR)"]
    retyped = [dict(old[0], type="LINT")] + old[1:]
    assert project.interface_changes(old, retyped) == ["variable retyped: count : DINT -> LINT"]
    moved = [dict(old[0], section="VAR")] + old[1:]
    assert project.interface_changes(old, moved) == [
        "variable count moved from VAR_OUTPUT to VAR"]
    assert project.interface_changes(old, old[::-1])[0].startswith("variables reordered")


def run(*args, env=None):
    import os
    e = dict(os.environ, PLC_MANAGER_STATE_DIR="/nonexistent-plc-manager-state")
    e.update(env or {})
    p = subprocess.run([sys.executable, "-m", "plc_manager.cli", *args], capture_output=True,
                       text=True, timeout=120, env=e, cwd=ROOT)
    return p.returncode, p.stdout, p.stderr


def test_cli_bad_input_one_line_no_traceback(tmp_path):
    (tmp_path / "empty").mkdir()
    (tmp_path / "bad").mkdir()
    (tmp_path / "bad" / "manifest.json").write_text("{not json")
    (tmp_path / "file.txt").write_text("x")
    cases = [
        (["load", str(tmp_path / "empty")], "no manifest.json"),
        (["load", str(tmp_path / "missing")], "no such directory"),
        (["load", str(tmp_path / "bad")], "unreadable manifest"),
        (["swap", str(tmp_path / "file.txt")], None),
        (["read", "x"], None),
        (["status"], None),
    ]
    for argv, want in cases:
        rc, out, err = run(*argv)
        assert rc == 1, (argv, rc, out, err)
        assert len(err.strip().splitlines()) == 1, (argv, err)
        assert "Traceback" not in err
        if want:
            assert want in err, (argv, err)
    rc, out, err = run("write")
    assert rc == 2 and "usage:" in err


def test_swap_candidates_from_a_project(tmp_path):
    m = {"configuration": "Plant", "load_order": [], "modules": [], "variables": [],
         "program_types": [
             {"name": "Counter", "module": "iec_p_counter_b", "build_id": "b",
              "interface_hash": "1" * 16, "interface": []},
             {"name": "Mixer", "module": "iec_p_mixer_a", "build_id": "a",
              "interface_hash": "2" * 16, "interface": []}]}
    m["digest"] = project.manifest_digest(m)
    (tmp_path / "manifest.json").write_text(json.dumps(m))
    got = project.swap_candidates(str(tmp_path), {"COUNTER": "a", "MIXER": "a"})
    assert [(c.type_name, c.build_id, c.module) for c in got] == [("Counter", "b",
                                                                  "iec_p_counter_b")]
    assert got[0].ko == tmp_path / "iec_p_counter_b" / "iec_p_counter_b.ko"
    assert project.swap_candidates(str(tmp_path), {"COUNTER": "b", "MIXER": "a"}) == []


def test_modinfo_of_truncated_or_corrupt_files_is_a_module_error(tmp_path):
    """A truncated or corrupt .ko given to load/swap is a clear ModuleError
    (one line from plc-manager, exit 1), never struct.error escaping as an
    internal error (issue 9)."""
    import random
    import shutil
    from plc_manager import kmod
    elf = shutil.which("true") or "/bin/true"
    data = open(elf, "rb").read()
    assert data[:4] == b"\x7fELF"
    rng = random.Random(9)
    cuts = sorted({0, 3, 63, 64, 65, 200, len(data) // 2, len(data) - 1} |
                  {rng.randrange(len(data)) for _ in range(40)})
    variants = [data[:n] for n in cuts]
    for _ in range(40):   # a few bytes of the headers flipped
        b = bytearray(data)
        for _ in range(3):
            b[rng.randrange(0x20, 0x40)] ^= 0xFF
        variants.append(bytes(b))
    variants.append(data)  # a whole ELF file that is no module
    for k, v in enumerate(variants):
        p = tmp_path / f"bad{k}.ko"
        p.write_bytes(v)
        with pytest.raises(kmod.ModuleError):
            kmod.modinfo(str(p))
