# SPDX-License-Identifier: MIT
"""Load of `plc-manager serve` on the PLC, in the PREEMPT_RT guest.

A configuration with N (default 1,000) DINT globals (one OPC UA node
each) and a 10 ms task that changes N/10 of them each cycle (every variable changes once per 100 ms) and copies `w` into
`echo`, built on the host, run in a QEMU guest:

  1. the tasks alone for --seconds: cycles and overruns;
  2. `plc-manager serve --opcua ... --period-min 100` and one asyncua
     client (Basic256Sha256 SignAndEncrypt, a `write` user) subscribed to
     the N variables and to `echo` with a 100 ms publishing interval,
     writing `w` (a sequence number) --writes times per second, for
     --seconds: the server's CPU (utime+stime from /proc, % of one CPU),
     notifications per second, latency cycle end -> client (the value's
     SourceTimestamp, the end of the task's cycle that produced it as the
     kernel reports it, to its arrival, same clock), latency write -> the program's echo notified (a write
     call started -> the notification of echo = that number: one cycle,
     one poll, one publishing interval), p50/p99/max, and the tasks'
     overruns beside run 1.

The client runs in the same guest as the server (they share its CPUs):
figures of the whole, not of the server alone.

    python benchmarks/serve_load.py [--vars 1000] [--writes 100] [--seconds 20]
        [--clock tcg|icount]
    python benchmarks/serve_load.py --smoke   (CI: 250 variables, 10 writes/s, 6 s)
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def project(n: int) -> str:
    """n DINT globals v0.. (one OPC UA node each), a 10 ms task that adds
    1 to those of index = cycle mod 10 (each changes once per 100 ms) and
    copies w into echo."""
    glob = "".join(f"        v{i} : DINT;\n" for i in range(n))
    ext = "".join(f"v{i} : DINT; " for i in range(n))
    branches = "".join(f"    {r}: " + " ".join(f"v{i} := v{i} + 1;" for i in range(r, n, 10))
                       + "\n" for r in range(min(10, n)))
    return f"""PROGRAM Churn
VAR_EXTERNAL {ext}w : DINT; echo : DINT; END_VAR
VAR k : DINT; END_VAR
CASE k MOD 10 OF
{branches}END_CASE;
k := k + 1;
echo := w;
END_PROGRAM

CONFIGURATION Load
    VAR_GLOBAL
{glob}        w : DINT;
        echo : DINT;
    END_VAR
    RESOURCE r ON CPU0
        TASK t10 (INTERVAL := T#10ms, PRIORITY := 5);
        PROGRAM p WITH t10 : Churn;
    END_RESOURCE
    VAR_ACCESS
        W : w : DINT READ_WRITE;
    END_VAR
END_CONFIGURATION
"""


GUEST_CODE = r'''
import asyncio, json, os, signal, subprocess, sys, time
build, src, pki, users, n, writes, seconds = sys.argv[1:8]
n, writes, seconds = int(n), int(writes), float(seconds)
from plc_manager import ops
from plc_manager.netlink import Client

def task():
    with Client() as c:
        t = c.status().tasks()[0]
        return t.cycles, t.overruns

ops.load(build)
res = {}
try:
    time.sleep(1)
    c0, o0 = task(); time.sleep(seconds); c1, o1 = task()
    res["alone"] = {"cycles": c1 - c0, "overruns": o1 - o0}
    log = open(os.path.join(os.path.dirname(build), "serve.log"), "w")
    p = subprocess.Popen([sys.executable, "-m", "plc_manager.cli", "serve", "--opcua",
                          "opc.tcp://127.0.0.1:4850", "--users", users,
                          "--cert-dir", pki, "--period-min", "100"], stdout=log,
                         stderr=subprocess.STDOUT)
    logp = os.path.join(os.path.dirname(build), "serve.log")
    deadline = time.monotonic() + 300
    while "serving" not in open(logp).read():
        assert p.poll() is None and time.monotonic() < deadline, open(logp).read()
        time.sleep(0.2)
    res["serve_log"] = open(logp).read()

    def cpu():
        f = open(f"/proc/{p.pid}/stat").read().rsplit(")", 1)[1].split()
        return (int(f[11]) + int(f[12])) / os.sysconf("SC_CLK_TCK")

    async def client():
        from asyncua import Client as UaClient, ua
        from asyncua.crypto.security_policies import SecurityPolicyBasic256Sha256
        cl = UaClient("opc.tcp://127.0.0.1:4850", timeout=60, watchdog_intervall=30)
        await cl.set_security(SecurityPolicyBasic256Sha256, os.path.join(pki, "client-cert.der"),
                              os.path.join(pki, "client-key.pem"),
                              mode=ua.MessageSecurityMode.SignAndEncrypt)
        cl.set_user("op"); cl.set_password("operator-pw")
        await cl.connect()
        ns = await cl.get_namespace_index("urn:iec2kmod:Load")
        lat, echo_lat, count = [], [], [0]
        sent = {}
        from datetime import datetime, timezone
        echo_id = ua.NodeId("echo", ns).to_string()

        class H:
            def datachange_notification(self, node, val, data):
                now = time.monotonic()
                count[0] += 1
                if node.nodeid.to_string() == echo_id:
                    t = sent.pop(val, None)
                    if t is not None:
                        echo_lat.append((now - t) * 1000)
                    return
                st = data.monitored_item.Value.SourceTimestamp
                if st is not None:
                    lat.append((datetime.now(timezone.utc) - st.replace(tzinfo=timezone.utc)
                                if st.tzinfo is None else datetime.now(timezone.utc) - st)
                               .total_seconds() * 1000)

        sub = await cl.create_subscription(100, H())
        names = [f"v{i}" for i in range(n)]
        nodes = [cl.get_node(ua.NodeId(nm, ns)) for nm in names]
        for i in range(0, n, 200):
            await sub.subscribe_data_change(nodes[i:i + 200], queuesize=1)
        await sub.subscribe_data_change(cl.get_node(ua.NodeId("echo", ns)))
        await asyncio.sleep(3)
        lat.clear(); count[0] = 0
        wnode = cl.get_node(ua.NodeId("access:W", ns))
        c0, o0 = await asyncio.to_thread(task); u0 = cpu(); t0 = time.monotonic()
        k = 1
        next_t = time.monotonic()
        late_writes = 0
        while time.monotonic() - t0 < seconds:
            sent[k] = time.monotonic()
            await wnode.write_value(ua.Variant(k, ua.VariantType.Int32))
            k += 1
            next_t += 1.0 / writes
            d = next_t - time.monotonic()
            if d > 0:
                await asyncio.sleep(d)
            else:
                late_writes += 1
        dt = time.monotonic() - t0
        u1 = cpu(); c1, o1 = await asyncio.to_thread(task)
        await asyncio.sleep(1)
        await cl.disconnect()
        return {"seconds": dt, "cpu_s": u1 - u0, "notifications": count[0], "lat": lat,
                "echo_lat": echo_lat, "writes": k - 1, "late_writes": late_writes,
                "cycles": c1 - c0, "overruns": o1 - o0, "unanswered_echo": len(sent)}

    try:
        res["served"] = asyncio.run(client())
    finally:
        p.send_signal(signal.SIGTERM)
        p.wait(120)
    res["serve_log"] = open(logp).read()
finally:
    ops.stop()
print("RESULT " + json.dumps(res))
'''


def pct(xs, q):
    xs = sorted(xs)
    if not xs:
        return float("nan")
    return xs[min(len(xs) - 1, int(round(q * (len(xs) - 1))))]


def shelf_read_figures(pki: Path, runs: int = 5) -> None:
    """serve's start reads asyncua's standard address space from a shelf:
    its index by plc_manager's reader against dbm.dumb's own (ms, on the
    host; a test checks they give the same records)."""
    import dbm.dumb
    from plc_manager.serve.opcua import _DumbShelfReader
    base = next((str(p) for p in pki.iterdir() if p.name.endswith("-aspace")), None)
    if base is None or not Path(base + ".dir").is_file():
        print("shelf index read: not a dbm.dumb shelf here")
        return
    for name, opener in (("plc_manager", _DumbShelfReader),
                         ("dbm.dumb", lambda b: dbm.dumb.open(b, "r"))):
        xs = []
        for _ in range(runs):
            t = time.perf_counter()
            opener(base).close()
            xs.append(1000 * (time.perf_counter() - t))
        xs.sort()
        print(f"shelf index read, {name}: min {xs[0]:.1f} / median {xs[len(xs) // 2]:.1f} / "
              f"max {xs[-1]:.1f} ms ({runs} runs)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--vars", type=int, default=1000)
    ap.add_argument("--writes", type=int, default=100)
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--clock", choices=("tcg", "icount"), default="tcg")
    ap.add_argument("--smoke", action="store_true",
                    help="CI size: 250 variables, 10 writes/s, 6 s a run (figures not worth "
                         "comparing)")
    a = ap.parse_args()
    if a.smoke:
        a.vars, a.writes, a.seconds = 250, 10, 6.0
    from iec2kmod.testing.vm import Guest
    from plc_manager.serve.opcua import add_user, ensure_certificate, ensure_shelf
    work = Path(tempfile.mkdtemp(prefix="serve_load-"))
    src = work / "src"
    src.mkdir()
    (src / "load.st").write_text(project(a.vars))
    build = work / "build"
    for cmd in (["gen", str(src), "-o", str(build)], ["build", str(build)]):
        subprocess.run([sys.executable, "-m", "iec2kmod.cli", *cmd], cwd=ROOT, check=True,
                       capture_output=True, text=True)
    pki = work / "pki"
    ensure_shelf(pki)
    shelf_read_figures(pki)
    ensure_certificate(pki / "server-cert.der", pki / "server-key.pem", "urn:iec2kmod:Load",
                       "127.0.0.1")
    ensure_certificate(pki / "client-cert.der", pki / "client-key.pem", "urn:bench", "localhost")
    users = work / "users"
    add_user(str(users), "op", "write", "operator-pw")
    g = Guest(str(work), icount=(a.clock == "icount"), console_log=str(work / "console.log"))
    try:
        g.start()
        g.run("ip link set lo up 2>/dev/null || ifconfig lo 127.0.0.1 up", 30)
        r = g.pyrun(GUEST_CODE, argv=[str(build), str(src), str(pki), str(users), str(a.vars),
                                      str(a.writes), str(a.seconds)], timeout=3600)
        if r.exit_code != 0 or "RESULT " not in r.output:
            sys.exit(f"the benchmark failed in the guest:\n{r.output[-4000:]}")
        res = json.loads(r.output.split("RESULT ", 1)[1])
        g.check_kernel_log()
    finally:
        g.close()
    s, al = res["served"], res["alone"]
    print(f"{a.vars} variables subscribed (100 ms), {a.writes} writes/s asked, "
          f"{s['seconds']:.1f} s, guest clock {a.clock}")
    print(res["serve_log"].strip())
    print(f"server CPU: {100 * s['cpu_s'] / s['seconds']:.0f}% of one CPU")
    print(f"notifications: {s['notifications'] / s['seconds']:.0f}/s; writes done "
          f"{s['writes'] / s['seconds']:.0f}/s ({s['late_writes']} behind schedule)")
    for name, xs in (("cycle end -> client (ms)", s["lat"]), ("write -> echo notified (ms)",
                                                        s["echo_lat"])):
        if not xs:
            print(f"{name:30} no sample (n=0)")
        else:
            print(f"{name:30} p50 {statistics.median(xs):8.1f}  p99 {pct(xs, 0.99):8.1f}  "
                  f"max {max(xs):8.1f}  (n={len(xs)})")
    print(f"task t10: alone {al['cycles']} cycles, {al['overruns']} overruns; "
          f"with the server {s['cycles']} cycles, {s['overruns']} overruns")
    print(f"work directory: {work}")


if __name__ == "__main__":
    os.environ.setdefault("PYTHONPATH", f"{ROOT}/.pypath:{ROOT}")
    main()
