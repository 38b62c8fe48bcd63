# SPDX-License-Identifier: MIT
"""Real clients against `plc-manager serve` (run in the guest by
tests/qemu/test_serve.py; also usable by hand):

    python3 serve_clients.py MODBUS_PORT OPCUA_URL CLIENT_CERT CLIENT_KEY

Prints one JSON object of what each client saw; the test asserts on it."""

import asyncio
import json
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


def wait_for_server(url: str, timeout: float) -> float:
    """The clients' libraries imported while the server starts (both take
    tens of seconds under TCG), then wait until the OPC UA port accepts a
    connection (serve opens it last); returns the seconds waited."""
    import asyncua  # noqa: F401
    import pymodbus.client  # noqa: F401
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
            time.sleep(0.3)


def main() -> None:
    port, url, cert, key = int(sys.argv[1]), sys.argv[2], sys.argv[3], sys.argv[4]
    waited = wait_for_server(url, float(sys.argv[5]) if len(sys.argv) > 5 else 0.0)
    t0 = time.monotonic()
    res = {"modbus": modbus(port)}
    t1 = time.monotonic()
    res["opcua"] = asyncio.run(opcua(url, cert, key))
    res["seconds"] = {"waited": round(waited, 1), "modbus": round(t1 - t0, 1),
                      "opcua": round(time.monotonic() - t1, 1)}
    print(json.dumps(res))


if __name__ == "__main__":
    main()
