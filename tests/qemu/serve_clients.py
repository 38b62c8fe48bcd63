# SPDX-License-Identifier: MIT
"""Real clients against `plc-manager serve` (run in the guest by
tests/qemu/test_serve.py; also usable by hand):

    python3 serve_clients.py JSON      (see main)

Prints one JSON object of what each client saw; the test asserts on it."""

import asyncio
import json
import os
import signal
import socket
import sys
import time


def modbus(port: int) -> dict:
    from pymodbus.client import ModbusTcpClient
    out = {}
    c = ModbusTcpClient("127.0.0.1", port=port, timeout=10)
    assert c.connect()
    try:
        seen = []
        for _ in range(5):
            seen.append(c.read_holding_registers(10, count=1).registers[0])     # %QW10 count
            time.sleep(0.1)
        out["count_seen"] = seen
        # tick toggles every 10 ms cycle: read until both of its states were
        # seen (a loaded TCG guest can answer several reads on one parity)
        ticks = set()
        deadline = time.monotonic() + 20
        while len({t[1] for t in ticks}) < 2 and time.monotonic() < deadline:
            ticks.add(tuple(c.read_coils(0, count=2).bits[:2]))                # %QX0.0 motor, tick
            time.sleep(0.013)
        out["coil_states"] = sorted(map(list, ticks))
        r = c.write_register(1024, 21)                                         # %MW0 sp
        out["write_sp"] = not r.isError()
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            doubled = c.read_holding_registers(1024, count=2).registers       # sp, %MW1
            if doubled[1] == 42:
                break
            time.sleep(0.05)
        out["sp_doubled"] = doubled
        out["access_count"] = c.read_holding_registers(8192, count=1).registers[0]
        out["label_regs"] = c.read_holding_registers(8195, count=5).registers       # LABEL
        r = c.write_registers(8193, [5, 0xFFFF])                               # SETPOINT, LEVEL
        out["write_access"] = not r.isError()
        out["after_access"] = c.read_holding_registers(8193, count=2).registers
        r = c.write_register(10, 1)                                            # %QW10: output
        out["write_output"] = getattr(r, "exception_code", None)
        r = c.write_coil(0, True)                                              # %QX0.0: output
        out["write_coil"] = getattr(r, "exception_code", None)
        r = c.read_holding_registers(60000, count=3)
        out["bad_address"] = getattr(r, "exception_code", None)
        r = c.read_discrete_inputs(0, count=1)
        out["di0"] = r.bits[0]
    finally:
        c.close()
    # a client that goes away in the middle of a request: half a frame
    s = socket.create_connection(("127.0.0.1", port), timeout=5)
    s.sendall(bytes([0, 1, 0, 0, 0, 6, 1, 3, 0]))
    s.close()
    s = socket.create_connection(("127.0.0.1", port), timeout=5)
    s.sendall(bytes([0, 2, 0, 0, 0, 6, 1, 3, 0, 10, 0, 100]))   # 100 registers, reset at once
    s.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, b"\x01\x00\x00\x00\x00\x00\x00\x00")
    s.close()
    c = ModbusTcpClient("127.0.0.1", port=port, timeout=10)
    assert c.connect()
    out["after_disconnects"] = not c.read_holding_registers(10, count=1).isError()
    c.close()
    out["concurrent"] = asyncio.run(concurrent(port, 50))
    return out


async def concurrent(port: int, n: int) -> dict:
    from pymodbus.client import AsyncModbusTcpClient

    async def one(i):
        c = AsyncModbusTcpClient("127.0.0.1", port=port, timeout=30)
        await c.connect()
        ok = 0
        try:
            for _ in range(3):
                r = await c.read_holding_registers(8192, count=1)
                ok += not r.isError()
        finally:
            c.close()
        return ok

    t = time.monotonic()
    got = await asyncio.gather(*(one(i) for i in range(n)), return_exceptions=True)
    return {"clients": n, "ok": sum(g for g in got if isinstance(g, int)),
            "errors": [repr(g) for g in got if not isinstance(g, int)][:3],
            "seconds": round(time.monotonic() - t, 2)}


async def opcua(url: str, cert: str, key: str) -> dict:
    from asyncua import Client, ua
    from asyncua.crypto.security_policies import SecurityPolicyBasic256Sha256
    out = {}

    async def client(user=None, password=None, secure=True):
        # under TCG a request can take seconds: the client's health probe
        # (1 s by default) would call the connection lost
        c = Client(url, timeout=60, watchdog_intervall=30)
        c.session_timeout = 60000
        if secure:
            await c.set_security(SecurityPolicyBasic256Sha256, cert, key,
                                 mode=ua.MessageSecurityMode.SignAndEncrypt)
        if user:
            c.set_user(user)
            c.set_password(password)
        return c

    async def refused(c):
        try:
            await c.connect()
        except Exception as e:                     # noqa: BLE001 - any refusal
            return type(e).__name__
        await c.disconnect()
        return None

    # clients that go away mid-message or send garbage: the server goes on
    from urllib.parse import urlparse
    u = urlparse(url)
    for junk in (b"HELF\x40\x00\x00\x00\x00\x00", b"HELF\x08\x00\x00\x00" + b"x" * 64):
        s = socket.create_connection((u.hostname, u.port), timeout=5)
        s.sendall(junk)
        s.close()
    t = time.monotonic()
    out["wrong_password"] = await refused(await client("op", "not-the-password"))
    out["anonymous"] = await refused(await client())
    out["unencrypted"] = await refused(await client("op", "operator-pw", secure=False))
    out["t_refusals"] = round(time.monotonic() - t, 1)
    t = time.monotonic()
    c = await client("op", "operator-pw")
    await c.connect()
    out["t_connect"] = round(time.monotonic() - t, 1)
    try:
        ns = await c.get_namespace_index("urn:iec2kmod:Station")
        root = c.get_node(ua.NodeId("Station", ns))
        out["browse"] = sorted([(await n.read_browse_name()).Name
                                for n in await root.get_children()])
        task = c.get_node(ua.NodeId("main/cyc/", ns))
        out["browse_task"] = sorted([(await n.read_browse_name()).Name
                                     for n in await task.get_children()])
        count = c.get_node(ua.NodeId("access:COUNT", ns))
        level = c.get_node(ua.NodeId("access:LEVEL", ns))
        label = c.get_node(ua.NodeId("access:LABEL", ns))
        out["label"] = await label.read_value()
        out["state"] = await c.get_node(ua.NodeId("main.cyc/State", ns)).read_value()

        async def status_of(node, variant):
            try:
                await node.write_value(variant)
                return "Good"
            except ua.UaStatusCodeError as e:
                return type(e).__name__

        out["write_level"] = await status_of(level, ua.Variant(99, ua.VariantType.Int16))
        out["write_count"] = await status_of(count, ua.Variant(1, ua.VariantType.Int16))
        out["write_level_double"] = await status_of(level, ua.Variant(1.5, ua.VariantType.Double))
        out["write_label_long"] = await status_of(label, ua.Variant("much too long",
                                                                    ua.VariantType.String))
        out["write_label"] = await status_of(label, ua.Variant("ok", ua.VariantType.String))
        got = []

        lat = []

        class H:
            def datachange_notification(self, node, val, data):
                got.append((time.monotonic(), val))
                # SourceTimestamp: the end of the task's cycle (the kernel's)
                import datetime
                st = data.monitored_item.Value.SourceTimestamp
                if st is not None:
                    st = st if st.tzinfo else st.replace(tzinfo=datetime.timezone.utc)
                    lat.append((datetime.datetime.now(datetime.timezone.utc) - st)
                               .total_seconds() * 1000)

        sub = await c.create_subscription(10, H())
        await sub.subscribe_data_change(count)
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline and len({v for _, v in got}) < 4:
            await asyncio.sleep(0.2)
        await sub.delete()
        out["notifications"] = len(got)
        out["distinct"] = len({v for _, v in got})
        # the first notification is the node's value when the subscription
        # was made (its cycle may be long past): the others are the poller's
        out["cycle_end_to_client_ms"] = sorted(round(x, 1) for x in lat[1:])
        deadline = time.monotonic() + 5
        while time.monotonic() < deadline:
            out["level_back"] = await level.read_value()
            out["label_back"] = await label.read_value()
            if out["level_back"] == 99 and out["label_back"] == "ok":
                break
            await asyncio.sleep(0.1)
    finally:
        await c.disconnect()
    c = await client("viewer", "viewer-pw")
    await c.connect()
    try:
        ns = await c.get_namespace_index("urn:iec2kmod:Station")
        level = c.get_node(ua.NodeId("access:LEVEL", ns))
        out["viewer_read"] = await level.read_value()
        try:
            await level.write_value(ua.Variant(5, ua.VariantType.Int16))
            out["viewer_write"] = "Good"
        except ua.UaStatusCodeError as e:
            out["viewer_write"] = type(e).__name__
    finally:
        await c.disconnect()
    return out


async def life(url: str, cert: str, key: str, port: int, build: str, fixed: str) -> dict:
    """The PLC's life under one OPC UA session: a task stopped on a fault
    (its variables flagged BadOutOfService, frozen; its State and Fault say
    why), `swap --restart` to a build with the same interface (the same node
    ids, the task running the new body), `stop` (BadServerHalted, writes
    refused, Modbus exception 04) and `load` (Good again on the same
    session).  The manager's commands run in this process (ops, in a
    thread), so the session stays open throughout."""
    from asyncua import Client, ua
    from asyncua.crypto.security_policies import SecurityPolicyBasic256Sha256
    from pymodbus.client import ModbusTcpClient
    from plc_manager import ops
    out = {}
    c = Client(url, timeout=60, watchdog_intervall=30)
    c.session_timeout = 120000
    await c.set_security(SecurityPolicyBasic256Sha256, cert, key,
                         mode=ua.MessageSecurityMode.SignAndEncrypt)
    c.set_user("op")
    c.set_password("operator-pw")
    await c.connect()
    mb = ModbusTcpClient("127.0.0.1", port=port, timeout=10)
    assert mb.connect()

    def code(dv):
        return ua.StatusCode(dv.StatusCode.value).name

    async def status_of(node, variant):
        try:
            await node.write_value(variant)
            return "Good"
        except ua.UaStatusCodeError as e:
            return type(e).__name__

    async def until(what, pred, timeout=60.0):
        """Polls *pred* (async, returns a value or None) until it answers."""
        t = time.monotonic()
        while True:
            got = await pred()
            if got is not None:
                out["t_" + what] = round(time.monotonic() - t, 1)
                return got
            if time.monotonic() - t > timeout:
                raise AssertionError(f"{what}: not within {timeout} s; so far {out}")
            await asyncio.sleep(0.2)

    async def ids(ns):
        """Every node id of our namespace reachable from the configuration
        (browsed), with its browse name."""
        root = c.get_node(ua.NodeId("Station", ns))
        seen, level = {root.nodeid.to_string(): root}, [root]
        while level:                   # one Browse request a level of the tree
            nxt = []
            for _, res in await c.browse_nodes(level):
                for ref in res.References:
                    nid = ref.NodeId
                    if nid.NamespaceIndex == ns and nid.to_string() not in seen:
                        seen[nid.to_string()] = c.get_node(nid)
                        nxt.append(seen[nid.to_string()])
            level = nxt
        names = await c.read_attributes(list(seen.values()), ua.AttributeIds.BrowseName)
        return {k: dv.Value.Value.Name for k, dv in zip(seen, names)}

    async def same_ids(before):
        """The node ids browsed before are there with the same browse names
        (one Read of them all)."""
        nodes = [c.get_node(ua.NodeId.from_string(k)) for k in before]
        got = await c.read_attributes(nodes, ua.AttributeIds.BrowseName)
        return all(dv.StatusCode.is_good() and dv.Value.Value.Name == before[k]
                   for k, dv in zip(before, got))

    try:
        ns = await c.get_namespace_index("urn:iec2kmod:Station")
        out["ns"] = ns
        node = {k: c.get_node(ua.NodeId(sid, ns)) for k, sid in (
            ("count", "main.p.count"), ("doubled", "main.p.doubled"),
            ("state", "main.cyc/State"), ("fault", "main.cyc/Fault"),
            ("divisor", "access:DIVISOR"), ("level", "access:LEVEL"),
            ("mode", "access:MODE"))}
        before = await ids(ns)
        out["n_ids"] = len(before)
        # an enumeration: a DataType of its own, Int32 values, ordinals checked
        dt = await node["mode"].read_data_type()
        out["mode_type"] = [dt.to_string(), (await c.get_node(dt).read_browse_name()).Name,
                            (await c.get_node(dt).get_parent()).nodeid.to_string()]
        out["mode_strings"] = [x.Text for x in await c.get_node(
            ua.NodeId("type:Mode/EnumStrings", ns)).read_value()]
        out["mode_value"] = await node["mode"].read_value()
        out["mode_write_bad"] = await status_of(node["mode"], ua.Variant(3, ua.VariantType.Int32))
        out["mode_write"] = await status_of(node["mode"], ua.Variant(2, ua.VariantType.Int32))
        out["mode_back"] = await node["mode"].read_value()

        seen = []

        class H:
            def datachange_notification(self, n, val, data):
                seen.append((code(data.monitored_item.Value), val))

        sub = await c.create_subscription(50, H())
        await sub.subscribe_data_change(node["count"])

        # a fault: the task stops, its values are frozen and flagged
        out["write_divisor"] = await status_of(node["divisor"],
                                               ua.Variant(0, ua.VariantType.Int16))

        async def state_is(want):
            v = await node["state"].read_value()
            return v if v == want else None

        await until("fault", lambda: state_is("fault"))
        out["fault_text"] = await node["fault"].read_value()
        dvs = []
        for _ in range(2):
            dvs.append(await node["count"].read_data_value(raise_on_bad_status=False))
            await asyncio.sleep(0.5)
        out["faulted_reads"] = [code(dv) for dv in dvs]
        async def notified_fault():
            return True if any(s == "BadOutOfService" for s, _ in seen) else None

        await until("notified_fault", notified_fault, 30)
        regs = []
        for _ in range(2):
            regs.append(mb.read_holding_registers(10, count=1).registers[0])    # %QW10 count
            time.sleep(0.3)
        out["faulted_modbus"] = regs
        # swap --restart: a build with the same interface, the task runs again
        t = time.monotonic()
        await asyncio.to_thread(ops.swap, fixed, restart=True)
        out["t_swap"] = round(time.monotonic() - t, 1)
        await until("running_after_swap", lambda: state_is("running"))

        async def good_count():
            dv = await node["count"].read_data_value(raise_on_bad_status=False)
            return dv.Value.Value if dv.StatusCode.is_good() else None

        a = await until("good_after_swap", good_count)
        await asyncio.sleep(0.5)
        out["counting_after_swap"] = [a, await good_count()]

        async def doubled_is(want):
            v = await node["doubled"].read_value()
            return v if v == want else None

        # sp is 5 (written through Modbus): the new body gives 3 * 5
        out["tripled"] = await until("tripled", lambda: doubled_is(15), 20)
        out["same_ids_after_swap"] = await same_ids(before)
        # stop: every value says BadServerHalted, writes are refused
        t = time.monotonic()
        await asyncio.to_thread(ops.stop)
        out["t_stop"] = round(time.monotonic() - t, 1)

        async def halted():
            dv = await node["count"].read_data_value(raise_on_bad_status=False)
            return code(dv) if dv.StatusCode.value == ua.StatusCodes.BadServerHalted else None

        await until("halted", halted, 30)
        out["halted_state"] = await node["state"].read_value()
        out["halted_write"] = await status_of(node["level"], ua.Variant(3, ua.VariantType.Int16))
        r = mb.read_holding_registers(10, count=1)
        out["halted_modbus"] = getattr(r, "exception_code", None)
        # load again: the values come back on the same session, same node ids
        t = time.monotonic()
        await asyncio.to_thread(ops.load, build)
        out["t_load"] = round(time.monotonic() - t, 1)
        await until("running_after_load", lambda: state_is("running"))
        a = await until("good_after_load", good_count)
        await asyncio.sleep(0.5)
        out["counting_after_load"] = [a, await good_count()]
        out["divisor_after_load"] = await node["divisor"].read_value()
        out["same_ids_after_load"] = await same_ids(before)
        out["level_write_after_load"] = await status_of(node["level"],
                                                        ua.Variant(8, ua.VariantType.Int16))
        r = mb.read_holding_registers(8194, count=1)                        # LEVEL
        out["level_modbus_after_load"] = None if r.isError() else r.registers[0]
        out["notified"] = sorted({s for s, _ in seen})
        await sub.delete()
    finally:
        mb.close()
        await c.disconnect()
    return out


def wait_for_server(url: str, timeout: float) -> float:
    """Waits until the OPC UA port accepts a connection (serve opens it
    last); returns the seconds waited."""
    from urllib.parse import urlparse
    u = urlparse(url)
    t = time.monotonic()
    while True:
        try:
            socket.create_connection((u.hostname, u.port), timeout=5).close()
            return time.monotonic() - t
        except OSError:
            if time.monotonic() - t > timeout:
                raise
            time.sleep(0.1)


def kernel_facts() -> dict:
    """What the kernel holds (plc-manager read) and the end of the task's
    last cycle (IEC_A_LAST_END_NS, CLOCK_REALTIME) beside the clock."""
    import contextlib
    import io
    from plc_manager import cli
    from plc_manager.netlink import Client
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        rc = cli.main(["read", "--json", "level", "sp", "label"])
    assert rc == 0, buf.getvalue()
    c = Client()
    try:
        end = c.status().tasks()[0].last_end_ns
    finally:
        c.close()
    return {"read": {v["path"]: v["value"] for v in json.loads(buf.getvalue())},
            "last_end_ns": end, "now_ns": time.time_ns()}


def fork_serve(argv, log):
    """`plc-manager serve ARGV` (plc_manager.cli.main) in a child process,
    its output to *log*; it starts when the returned go() is called (the
    child is forked before this process opens any netlink socket)."""
    from plc_manager import cli
    sys.stdout.flush()
    sys.stderr.flush()
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:
        rc = 1
        try:
            os.close(w)
            start = os.read(r, 1)
            fd = os.open(log, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
            os.dup2(fd, 1)
            os.dup2(fd, 2)
            if start == b"g":
                rc = cli.main(argv)
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(rc)
    os.close(r)
    state = {"w": w}

    def go(really=True):
        if state["w"] is not None:
            if really:
                os.write(state["w"], b"g")
            os.close(state["w"])
            state["w"] = None

    return pid, go


def stop_serve(pid) -> object:
    """SIGTERM, then its exit code (or why none)."""
    t = time.monotonic()
    try:
        os.kill(pid, signal.SIGTERM)
    except ProcessLookupError:
        pass
    while True:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            return os.waitstatus_to_exitcode(status)
        if time.monotonic() - t > 60:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            return "killed: no exit within 60 s of SIGTERM"
        time.sleep(0.1)


def openplc(port: int) -> dict:
    """examples/openplc_modbus driven over Modbus (OpenPLC's mapping): the
    HMI's coils and setpoint register written by the client, the field
    inputs (%IX, discrete inputs: read-only on Modbus) set with plc-manager
    write as a field device would; the program's outputs seen changing."""
    import contextlib
    import io
    from pymodbus.client import ModbusTcpClient
    from plc_manager import cli
    out = {}

    def field(addr, value):
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):
            assert cli.main(["write", addr, value]) == 0, buf.getvalue()

    c = ModbusTcpClient("127.0.0.1", port=port, timeout=10)
    assert c.connect()

    def until(what, fn, want, timeout=20.0):
        t = time.monotonic()
        while True:
            got = fn()
            if got == want or time.monotonic() - t > timeout:
                out[what] = got
                return got
            time.sleep(0.05)

    try:
        motor_lamp = lambda: c.read_coils(0, count=2).bits[:2]      # noqa: E731
        out["idle"] = motor_lamp()
        out["write_sp"] = not c.write_register(1, 50).isError()          # %QW1 speed_sp
        out["write_start"] = not c.write_coil(2, True).isError()         # %QX0.2 hmi_start
        until("started", motor_lamp, [True, True])
        until("drive", lambda: c.read_holding_registers(1, count=2).registers, [50, 13800])
        out["starts"] = c.read_holding_registers(1024, count=1).registers[0]   # %MW0
        out["hmi_start_cleared"] = c.read_coils(2, count=1).bits[0]
        field("%IX0.1", "TRUE")                                          # stop_pb
        out["di"] = c.read_discrete_inputs(0, count=2).bits[:2]
        until("stopped_by_field", lambda: motor_lamp()[0], False)
        out["drive_stopped"] = c.read_holding_registers(2, count=1).registers[0]
        field("%IX0.1", "FALSE")
        field("%IX0.0", "TRUE")                                          # start_pb
        until("started_by_field", lambda: motor_lamp()[0], True)
        until("starts_2", lambda: c.read_holding_registers(1024, count=1).registers[0], 2)
        out["write_stop"] = not c.write_coil(3, True).isError()          # %QX0.3 hmi_stop
        until("stopped_by_hmi", lambda: motor_lamp()[0], False)
        r = c.write_register(0, 1)                                       # nothing at %QW0
        out["nothing_there"] = getattr(r, "exception_code", None)
    finally:
        c.close()
    return out


def main() -> None:
    """python3 serve_clients.py JSON: {"build", "fixed", "openplc" (builds),
    "log", "serve": [argv of plc-manager], "modbus": PORT, "url", "cert",
    "key", "timeout"}.

    One process does it all, so the guest imports asyncua and pymodbus once
    (tens of seconds under TCG): it imports them, forks `plc-manager serve`
    (plc_manager.cli.main, output to "log"; forked before any netlink
    socket exists here), loads the build, lets serve start, runs the
    clients, then the PLC's life (fault, swap, stop, load), stops serve
    with SIGTERM and unloads the configuration; then the same with
    examples/openplc_modbus and a Modbus-only serve."""
    cfg = json.loads(sys.argv[1])
    t0 = time.monotonic()
    import asyncua  # noqa: F401
    import pymodbus.client  # noqa: F401
    import pymodbus.server  # noqa: F401
    import plc_manager.serve.modbus  # noqa: F401
    import plc_manager.serve.opcua  # noqa: F401
    from plc_manager import ops
    times = {"imports": round(time.monotonic() - t0, 1)}
    pid, go = fork_serve(cfg["serve"], cfg["log"])
    res = {}
    loaded = False
    try:
        t = time.monotonic()
        ops.load(cfg["build"])
        loaded = True
        times["load"] = round(time.monotonic() - t, 1)
        go()
        times["serve_start"] = round(wait_for_server(cfg["url"], cfg["timeout"]), 1)
        t = time.monotonic()
        res["modbus"] = modbus(cfg["modbus"])
        times["modbus"] = round(time.monotonic() - t, 1)
        t = time.monotonic()
        res["opcua"] = asyncio.run(opcua(cfg["url"], cfg["cert"], cfg["key"]))
        times["opcua"] = round(time.monotonic() - t, 1)
        res["kernel"] = kernel_facts()
        t = time.monotonic()
        res["life"] = asyncio.run(life(cfg["url"], cfg["cert"], cfg["key"], cfg["modbus"],
                                       cfg["build"], cfg["fixed"]))
        times["life"] = round(time.monotonic() - t, 1)
    finally:
        go(False)                      # serve gives up if it never started
        t = time.monotonic()
        res["serve_exit"] = stop_serve(pid)
        times["serve_stop"] = round(time.monotonic() - t, 1)
        if loaded:
            ops.stop()
            res["unloaded"] = True
    # an OpenPLC-style program driven over Modbus alone
    t = time.monotonic()
    port = cfg["modbus"] + 1
    pid, go = fork_serve(["serve", "--modbus", f"127.0.0.1:{port}"], cfg["log"] + ".openplc")
    loaded = False
    try:
        ops.load(cfg["openplc"])
        loaded = True
        go()
        wait_for_server(f"opc.tcp://127.0.0.1:{port}", cfg["timeout"])
        res["openplc"] = openplc(port)
    finally:
        go(False)
        res["openplc_serve_exit"] = stop_serve(pid)
        if loaded:
            ops.stop()
            res["openplc_unloaded"] = True
    times["openplc"] = round(time.monotonic() - t, 1)
    times["total"] = round(time.monotonic() - t0, 1)
    res["seconds"] = times
    print(json.dumps(res))


if __name__ == "__main__":
    main()
