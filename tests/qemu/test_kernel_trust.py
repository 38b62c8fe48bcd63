# SPDX-License-Identifier: MIT
"""QEMU tier: the kernel is the trust boundary (issue 23).

Every case of "What was found" (items 1 to 5) sent the way any client
could, with raw generic netlink and raw sysfs writes (tests/qemu/rawnl.py),
never through plc-manager, against tests/qemu/projects/trust loaded and
running in the PREEMPT_RT guest:

1. root without capabilities: the control file, the status file and
   netlink are all refused (EPERM), and the tasks keep running;
2. VAR_GLOBAL CONSTANT, VAR CONSTANT and FB outputs refuse VAR_SET and
   VAR_FORCE (EACCES), and the program keeps seeing the constants;
3. a STRING[10] refuses 11 characters (its C object has room for them);
4. a subrange refuses a value out of it, an enumeration a value not in it
   (ERANGE), and the task that indexes an array with it does not fault;
5. PATH and NAME strings with bytes after their NUL, control writes with
   a NUL, a second line or a word too many, a variable named twice: all
   refused; 18 SINGLE variables raised in one VAR_SET wake all 18 tasks.

The kernel log stays clean (the guest fixture checks it).
"""

from __future__ import annotations

import errno
import json
import textwrap
import time
from pathlib import Path

import pytest

from kmod_helpers import gen_and_build, load, status, sysfs, unload

pytestmark = pytest.mark.qemu
HERE = Path(__file__).resolve().parent
PROJECT = HERE / "projects" / "trust"
N_EVENTS = 18


@pytest.fixture(scope="module")
def built(guest_workdir):
    out = Path(guest_workdir) / "trust"
    manifest = gen_and_build(PROJECT, out)
    return out, manifest


def gpy(guest, body: str, timeout: float = 120) -> dict:
    """Python in the guest with rawnl imported; returns its dict `out`."""
    code = ("import errno, json, os, struct, sys, time\n"
            f"sys.path.insert(0, {str(HERE)!r})\n"
            "from rawnl import *\n"
            "out = {}\n" + textwrap.dedent(body) +
            "\nprint('RESULT ' + json.dumps(out))\n")
    r = guest.pyrun(code, timeout=timeout)
    lines = [ln for ln in r.output.splitlines() if ln.startswith("RESULT ")]
    assert r.exit_code == 0 and lines, r.output
    return json.loads(lines[-1][len("RESULT "):])


@pytest.fixture
def plc(guest, built):
    tree, manifest = built
    load(guest, tree, manifest)
    r = guest.run(f"echo start all > {sysfs(manifest)}/control")
    assert r.exit_code == 0, r.output
    ctl = f"{sysfs(manifest)}/control"
    deadline = time.monotonic() + 30
    while status(guest, manifest)["tasks"]["plc.fast"]["state"] != "running":
        assert time.monotonic() < deadline, status(guest, manifest)["text"]
        time.sleep(0.2)
    yield {"manifest": manifest, "control": ctl, "status": f"{sysfs(manifest)}/status"}
    unload(guest, manifest)


def running(guest, plc) -> dict:
    tasks = status(guest, plc["manifest"])["tasks"]
    return {name: t["state"] for name, t in tasks.items()}


# 1 ---------------------------------------------------------------------------

def test_root_without_capabilities_controls_nothing(guest, plc):
    out = gpy(guest, f"""
        drop_capabilities()
        for cmd in (b"stop all\\n", b"clear all\\n", b"start all\\n"):
            out[cmd.decode().strip()] = sysfs_write({plc['control']!r}, cmd)
        try:
            open({plc['status']!r}).read()
            out["status"] = 0
        except OSError as e:
            out["status"] = e.errno
        nl = Genl()
        out["nl_status"] = nl.cmd("IEC_CMD_STATUS")[0]
        out["nl_get"] = nl.cmd("IEC_CMD_VAR_GET", var("ticks"))[0]
        out["nl_stop"] = nl.cmd("IEC_CMD_RES_STOP")[0]
    """)
    assert out == {"stop all": errno.EPERM, "clear all": errno.EPERM,
                   "start all": errno.EPERM, "status": errno.EPERM,
                   "nl_status": errno.EPERM, "nl_get": errno.EPERM,
                   "nl_stop": errno.EPERM}, out
    states = running(guest, plc)
    assert set(states.values()) == {"running"}, states
    st = status(guest, plc["manifest"])
    assert all(s["module"] != "-" for s in st["slots"].values()), st["text"]


# 2 ---------------------------------------------------------------------------

READ_ONLY = {"GLIM": "=h", "plc.probe.K": "=h", "plc.probe.acc.total": "=i",
             "plc.probe.tmr.Q": "=B"}


def test_constants_and_fb_outputs_refuse_write_and_force(guest, plc):
    out = gpy(guest, f"""
        nl = Genl()
        for path, fmt in {READ_ONLY!r}.items():
            v = struct.pack(fmt, 1)
            out["set " + path] = nl.cmd("IEC_CMD_VAR_SET", var(path, v))[0]
            out["force " + path] = nl.cmd("IEC_CMD_VAR_FORCE", var(path, v))[0]
        time.sleep(0.2)
        out["seen_glim"] = nl.get_int("seen_glim")
        out["seen_k"] = nl.get_int("seen_k")
        out["unforce"] = nl.cmd("IEC_CMD_VAR_UNFORCE", attr("IEC_A_ALL", b""))[0]
        out["glim"] = nl.get_int("GLIM")
        out["k"] = nl.get_int("plc.probe.K")
    """)
    for path in READ_ONLY:
        assert out["set " + path] == errno.EACCES, (path, out)
        assert out["force " + path] == errno.EACCES, (path, out)
    assert (out["seen_glim"], out["seen_k"], out["glim"], out["k"]) == (100, 7, 100, 7), out
    assert out["unforce"] == 0, out


# 3 ---------------------------------------------------------------------------

def test_string_length_is_checked_against_its_declaration(guest, plc):
    out = gpy(guest, """
        nl = Genl()
        for path in ("glabel", "plc.probe.name"):
            out["11 " + path] = nl.cmd("IEC_CMD_VAR_SET", var(path, string_value("A" * 11)))[0]
            out["10 " + path] = nl.cmd("IEC_CMD_VAR_SET", var(path, string_value("B" * 10)))[0]
            v = nl.get(path)[path]
            n = struct.unpack_from("=H", v)[0]
            out["read " + path] = v[2:2 + n].decode()
        # the length must agree with the characters (no NUL inside)
        bad = struct.pack("=H", 3) + b"a\\0b\\0"
        out["nul inside"] = nl.cmd("IEC_CMD_VAR_SET", var("glabel", bad))[0]
    """)
    for path in ("glabel", "plc.probe.name"):
        assert out["11 " + path] == errno.EMSGSIZE, out
        assert out["10 " + path] == 0, out
        assert out["read " + path] == "B" * 10, out
    assert out["nul inside"] == errno.EINVAL, out


# 4 ---------------------------------------------------------------------------

def test_subrange_and_enumeration_values_are_checked(guest, plc):
    out = gpy(guest, """
        nl = Genl()
        cases = [("plc.probe.idx", 100), ("plc.probe.idx", -1), ("gidx", 3),
                 ("plc.probe.colour", 99), ("gcolour", 3), ("gcolour", -1)]
        for path, v in cases:
            size = len(nl.get(path)[path])
            fmt = {1: "=b", 2: "=h", 4: "=i", 8: "=q"}[size]
            out[f"set {path} {v}"] = nl.cmd("IEC_CMD_VAR_SET", var(path, struct.pack(fmt, v)))[0]
            out[f"force {path} {v}"] = nl.cmd("IEC_CMD_VAR_FORCE",
                                              var(path, struct.pack(fmt, v)))[0]
        out["ok idx"] = nl.cmd("IEC_CMD_VAR_SET", var("plc.probe.idx", struct.pack("=h", 2)))[0]
        size = len(nl.get("plc.probe.colour")["plc.probe.colour"])
        fmt = {1: "=b", 2: "=h", 4: "=i", 8: "=q"}[size]
        out["ok colour"] = nl.cmd("IEC_CMD_VAR_SET",
                                  var("plc.probe.colour", struct.pack(fmt, 2)))[0]
        time.sleep(0.3)
        out["pick"] = nl.get_int("pick")
    """)
    for k, v in out.items():
        if k.startswith(("set ", "force ")):
            assert v == errno.ERANGE, (k, out)
    assert (out["ok idx"], out["ok colour"], out["pick"]) == (0, 0, 30), out
    states = running(guest, plc)
    assert set(states.values()) == {"running"}, states


# 5 ---------------------------------------------------------------------------

def test_strict_parsing_of_strings_control_and_duplicates(guest, plc):
    out = gpy(guest, f"""
        nl = Genl()
        out["path garbage"] = nl.cmd("IEC_CMD_VAR_GET",
                                     var(raw_path=b"ticks\\0garbage\\0"))[0]
        out["path exact"] = nl.cmd("IEC_CMD_VAR_GET", var(raw_path=b"ticks\\0"))[0]
        out["name garbage"] = nl.cmd("IEC_CMD_RES_STOP", attr("IEC_A_NAME", b"plc\\0x\\0"))[0]
        for data in (b"stop all\\0garbage", b"stop all\\nstop all\\n", b"stop all garbage\\n",
                     b"stop  all\\n", b"stop all\\n\\n", b"stop\\n", b"halt all\\n",
                     b"run all 0\\n", b"run all 5x\\n"):
            out[repr(data)] = sysfs_write({plc['control']!r}, data)
        v = struct.pack("=h", 5)
        out["set twice"] = nl.cmd("IEC_CMD_VAR_SET", var("spare", v), var("spare", v))[0]
        out["force twice"] = nl.cmd("IEC_CMD_VAR_FORCE", var("spare", v), var("spare", v))[0]
        out["forced"] = [a for t, a in nl.cmd("IEC_CMD_STATUS")[1][0]
                         if t == A["IEC_A_NFORCED"]][0].hex()
    """)
    assert out.pop("path garbage") == errno.EINVAL, out
    assert out.pop("path exact") == 0, out
    assert out.pop("name garbage") == errno.EINVAL, out
    assert out.pop("set twice") == errno.EINVAL, out
    assert out.pop("force twice") == errno.EINVAL, out
    assert out.pop("forced") == "00000000", out
    assert out == {k: errno.EINVAL for k in out}, out
    states = running(guest, plc)
    assert set(states.values()) == {"running"}, states
    # one trailing newline is allowed, and no newline at all
    out = gpy(guest, f"""
        out["stop"] = sysfs_write({plc['control']!r}, b"stop plc\\n")
        out["start"] = sysfs_write({plc['control']!r}, b"start plc")
    """)
    assert out == {"stop": 0, "start": 0}, out


def test_every_event_of_one_request_wakes_its_task(guest, plc):
    out = gpy(guest, f"""
        nl = Genl()
        hits = [f"plc.on{{i}}.hits" for i in range({N_EVENTS})]
        before = {{p: struct.unpack("=i", v)[0] for p, v in nl.get(*hits).items()}}
        out["set"] = nl.cmd("IEC_CMD_VAR_SET",
                            *(var(f"ev{{i}}", b"\\1") for i in range({N_EVENTS})))[0]
        deadline = time.monotonic() + 10
        while True:
            now = {{p: struct.unpack("=i", v)[0] for p, v in nl.get(*hits).items()}}
            out["woken"] = sorted(p for p in hits if now[p] > before[p])
            if len(out["woken"]) == len(hits) or time.monotonic() > deadline:
                break
            time.sleep(0.1)
    """)
    assert out["set"] == 0, out
    assert out["woken"] == sorted(f"plc.on{i}.hits" for i in range(N_EVENTS)), out


# the read-only monitor role ---------------------------------------------------

MONITOR_GID = 4242


def test_monitor_group_reads_and_nothing_else(guest, built):
    """monitor_gid=GID at load: that group's members read (status file,
    STATUS, VAR_GET, VAR_LIST) without any capability; every write and
    control is refused (EPERM); another user reads nothing."""
    tree, manifest = built
    order = manifest["load_order"]
    for k, name in enumerate(order):
        arg = f" monitor_gid={MONITOR_GID}" if k == 0 else ""
        r = guest.run(f"insmod {tree / name / (name + '.ko')}{arg}")
        assert r.exit_code == 0, r.output
    ctl, st = f"{sysfs(manifest)}/control", f"{sysfs(manifest)}/status"
    try:
        assert guest.run(f"echo start all > {ctl}").exit_code == 0
        body = f"""
            def reads():
                r = {{}}
                try:
                    r["status file"] = "configuration trust" in open({st!r}).read()
                except OSError as e:
                    r["status file"] = e.errno
                nl = Genl()
                r["STATUS"] = nl.cmd("IEC_CMD_STATUS")[0]
                r["VAR_GET"] = nl.cmd("IEC_CMD_VAR_GET", var("ticks"))[0]
                err, replies = nl.cmd("IEC_CMD_VAR_LIST", dump=True)
                r["VAR_LIST"] = err or len(replies)
                r["VAR_SET"] = nl.cmd("IEC_CMD_VAR_SET", var("spare", b"\\1\\0"))[0]
                r["VAR_FORCE"] = nl.cmd("IEC_CMD_VAR_FORCE", var("spare", b"\\1\\0"))[0]
                r["RES_STOP"] = nl.cmd("IEC_CMD_RES_STOP")[0]
                r["SLOT_CLEAR"] = nl.cmd("IEC_CMD_SLOT_CLEAR")[0]
                r["control"] = sysfs_write({ctl!r}, b"stop all\\n")
                return r
            if os.fork() == 0:
                become(65534, [65534])
                print("OTHER " + json.dumps(reads()), flush=True)
                os._exit(0)
            os.wait()
            become(65534, [{MONITOR_GID}])
            out.update(reads())
        """
        code = ("import errno, json, os, struct, sys, time\n"
                f"sys.path.insert(0, {str(HERE)!r})\n"
                "from rawnl import *\n"
                "out = {}\n" + textwrap.dedent(body) +
                "\nprint('RESULT ' + json.dumps(out))\n")
        r = guest.pyrun(code, timeout=120)
        assert r.exit_code == 0, r.output
        lines = {ln.split(" ", 1)[0]: json.loads(ln.split(" ", 1)[1])
                 for ln in r.output.splitlines() if ln.startswith(("RESULT ", "OTHER "))}
        mon, other = lines["RESULT"], lines["OTHER"]
        # the control file is 0200 root: a user is refused by its mode already
        denied = {"control": errno.EACCES,
                  **{k: errno.EPERM for k in ("VAR_SET", "VAR_FORCE", "RES_STOP", "SLOT_CLEAR")}}
        assert mon.pop("status file") is True, mon
        assert (mon.pop("STATUS"), mon.pop("VAR_GET")) == (0, 0), mon
        assert mon.pop("VAR_LIST") > 20, mon
        assert mon == denied, mon
        assert other == {"status file": errno.EPERM, "STATUS": errno.EPERM,
                         "VAR_GET": errno.EPERM, "VAR_LIST": errno.EPERM, **denied}, other
        states = {n: t["state"] for n, t in status(guest, manifest)["tasks"].items()}
        assert set(states.values()) == {"running"}, states
    finally:
        unload(guest, manifest)
