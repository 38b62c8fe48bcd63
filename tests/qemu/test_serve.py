# SPDX-License-Identifier: MIT
"""QEMU tier: `plc-manager serve` in the PREEMPT_RT guest on loopback, with
tests/qemu/projects/serve running (a 10 ms task counting, toggling a coil,
doubling a setpoint), driven by real clients (tests/qemu/serve_clients.py:
pymodbus and asyncua, the host's Python in the guest):

* Modbus: registers and coils that change with the program, a holding
  register the program uses (%MW0 -> doubled in %MW1), access paths at
  8192.., an output written (exception 04), an address with nothing
  (02), clients that go away in the middle of a request, 50 concurrent
  clients;
* OPC UA (Basic256Sha256 SignAndEncrypt, users file): a wrong password,
  anonymous and an unencrypted session refused; browse; writes allowed
  (READ_WRITE access paths) and refused (BadNotWritable, BadTypeMismatch,
  BadOutOfRange, BadUserAccessDenied for the read-only user); a
  subscription sees the counter change;
* SIGTERM stops the server cleanly; the kernel log stays clean.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest

from kmod_helpers import gen_and_build

pytestmark = pytest.mark.qemu
HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
PROJECT = HERE / "projects" / "serve"


@pytest.fixture(scope="module")
def station(guest_workdir, kdir):
    base = Path(guest_workdir) / "serve"
    base.mkdir(exist_ok=True)
    build = base / "build"
    gen_and_build(PROJECT, build)
    # keys made on the host (RSA key generation under TCG is slow)
    from plc_manager.serve.opcua import add_user, ensure_certificate, ensure_shelf
    pki = base / "pki"
    ensure_shelf(pki)      # asyncua's standard address space (minutes to build under TCG)
    ensure_certificate(pki / "server-cert.der", pki / "server-key.pem",
                       "urn:iec2kmod:Station", "127.0.0.1")
    ensure_certificate(pki / "client-cert.der", pki / "client-key.pem",
                       "urn:iec2kmod:test-client", "localhost")
    users = base / "users"
    if users.exists():
        users.unlink()
    # scrypt at N=2**12 (the default 2**14 costs seconds per login under TCG)
    add_user(str(users), "op", "write", "operator-pw", n=2 ** 12)
    add_user(str(users), "viewer", "read", "viewer-pw", n=2 ** 12)
    return build, pki, users, base


def test_serve_with_real_clients(guest, station):
    build, pki, users, base = station
    log = base / "serve.log"
    pidf = base / "serve.pid"
    guest.run("ip link set lo up 2>/dev/null || ifconfig lo 127.0.0.1 up", 30)
    rc, out = guest.pyrun(script="plc-manager", argv=["load", str(build)], timeout=300)
    assert rc == 0, out
    py = guest.python_exe
    t0 = time.monotonic()
    try:
        r = guest.run(
            f"{py} -m plc_manager.cli serve --modbus 127.0.0.1:5020 "
            f"--opcua opc.tcp://127.0.0.1:4841 --users {users} "
            f"--cert-dir {pki} >{log} 2>&1 & echo $! >{pidf}", 30, chroot=True, cwd=str(ROOT))
        assert r.exit_code == 0, r.output
        # the clients start at once: their imports run while serve starts,
        # then they wait for its OPC UA port (opened last)
        r = guest.pyrun(code=(HERE / "serve_clients.py").read_text(),
                        argv=["5020", "opc.tcp://127.0.0.1:4841",
                              str(pki / "client-cert.der"), str(pki / "client-key.pem"),
                              "240"],
                        timeout=540)
        text = log.read_text() if log.exists() else ""
        assert r.exit_code == 0, r.output + "\n--- serve log:\n" + text
        res = json.loads(r.output.strip().splitlines()[-1])
        t_start = time.monotonic() - t0
        assert "serving Station" in text, text
        assert "modbus tcp://127.0.0.1:5020: 2 coils, 1 discrete inputs" in text, text
        assert "4 access paths" in text and "Basic256Sha256 SignAndEncrypt" in text, text
        mb, ua = res["modbus"], res["opcua"]
        print(f"serve and clients {t_start:.1f} s; clients {res['seconds']}; "
              f"opc ua refusals {ua['t_refusals']} s, connect {ua['t_connect']} s; "
              f"50 modbus clients {mb['concurrent']['seconds']} s")

        # Modbus: the program's values change, a register drives the program
        assert len(set(mb["count_seen"])) >= 3, mb
        assert [False, False] in mb["coil_states"] and [False, True] in mb["coil_states"], mb
        assert mb["write_sp"] and mb["sp_doubled"] == [21, 42], mb
        assert mb["access_count"] > 0
        assert mb["label_regs"] == [4, 0x7075, 0x6D70, 0, 0], mb        # 'pump', STRING[8]
        assert mb["write_access"] and mb["after_access"] == [5, 0xFFFF], mb
        assert mb["write_output"] == 4 and mb["write_coil"] == 4, mb
        assert mb["bad_address"] == 2 and mb["di0"] is False, mb
        assert mb["after_disconnects"], mb
        assert mb["concurrent"]["ok"] == 150, mb["concurrent"]

        # OPC UA
        assert ua["wrong_password"] and ua["anonymous"] and ua["unencrypted"], ua
        assert {"main", "Globals", "AccessPaths", "Build", "DirectVariables"} <= \
            set(ua["browse"]), ua
        assert {"p", "State", "Cycles", "Overruns"} <= set(ua["browse_task"]), ua
        assert ua["state"] == "running" and ua["label"] == "pump", ua
        assert ua["write_level"] == "Good" and ua["write_label"] == "Good", ua
        assert ua["write_count"] == "BadNotWritable", ua
        assert ua["write_level_double"] == "BadTypeMismatch", ua
        assert ua["write_label_long"] == "BadOutOfRange", ua
        assert ua["level_back"] == 99 and ua["label_back"] == "ok", ua
        assert ua["distinct"] >= 4, ua
        # stamped with the cycle's end (the kernel's), before the client got it
        lat = ua["cycle_end_to_client_ms"]
        assert lat and 0 <= lat[0] and lat[-1] < 30000, lat
        assert ua["viewer_read"] == 99 and ua["viewer_write"] == "BadUserAccessDenied", ua

        # the kernel saw the writes (through plc-manager read)
        rc, out = guest.pyrun(script="plc-manager", argv=["read", "--json", "level", "sp",
                                                          "label"], timeout=120)
        got = {v["path"]: v["value"] for v in json.loads(out)}
        assert got == {"level": 99, "sp": 5, "label": "ok"}, out
        # the kernel reports the end of the task's last cycle (IEC_A_LAST_END_NS,
        # CLOCK_REALTIME): what serve stamps values with
        r = guest.pyrun(code="import time\nfrom plc_manager.netlink import Client\n"
                             "c = Client(); t = c.status().tasks()[0]; c.close()\n"
                             "print(t.last_end_ns, time.time_ns())", timeout=120)
        end, now_ns = map(int, r.output.split()[-2:])
        assert 0 < now_ns - end < 5 * 10**9, r.output
    finally:
        guest.run(f"kill -TERM $(cat {pidf}) 2>/dev/null", 10)
        deadline = time.monotonic() + 60
        while guest.run(f"kill -0 $(cat {pidf}) 2>/dev/null", 10).exit_code == 0:
            assert time.monotonic() < deadline, "serve did not stop on SIGTERM"
            time.sleep(0.5)
        guest.pyrun(script="plc-manager", argv=["stop"], timeout=300)
    text = log.read_text()
    assert "stopped:" in text and "Traceback" not in text, text
    print(text.strip().splitlines()[-1])
