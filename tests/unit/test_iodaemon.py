"""The reference daemon's side of the user I/O protocol (manager/iodaemon.py,
kmod_templates/kernel/iec_io_user.c), host side: a plain file laid out as
the documented shared memory (built here from the documented offsets, not
with the daemon's code) stands for the device."""

import struct
import time

import pytest

from iec2kmod.iomap import USER_TYPES
from plc_manager import iodaemon
from plc_manager.iodaemon import ProtocolError, UserDevice

pytestmark = pytest.mark.unit

INPUTS = [("%IX0.0", 1), ("%IW4", 3), ("", 0), ("%ID8", 11)]        # BOOL INT - REAL
OUTPUTS = [("%QX0.0", 1), ("%QW2", 3), ("%QD4", 11), ("%QD8", 7)]   # BOOL INT REAL UDINT


def layout(magic=0x55434549, version=1, out_seq=0, in_seq=0, status=0):
    """The shared memory of iec_io_user.c's comment, offset by offset."""
    n_in, n_out = len(INPUTS), len(OUTPUTS)
    desc_off = 128
    in_off = desc_off + 32 * (n_in + n_out)
    in_stride = (8 + 4 * n_in + 7) // 8 * 8
    out_off = in_off + 2 * in_stride
    out_stride = (24 + 4 * n_out + 7) // 8 * 8
    size = 4096
    buf = bytearray(size)
    struct.pack_into("<IHHIIIIIIIIQIIII", buf, 0, magic, version, 128, n_in, n_out, in_off,
                     in_stride, out_off, out_stride, desc_off, 400, 20_000_000, out_seq, 0,
                     status, size)
    struct.pack_into("<I", buf, 64, in_seq)
    for i, (addr, t) in enumerate(INPUTS + OUTPUTS):
        struct.pack_into("<24sHHI", buf, desc_off + 32 * i, addr.encode(), t, 0, 0)
    return buf, in_off, in_stride, out_off, out_stride


def out_record(buf, off, cycle, in_tag, flags, slots):
    struct.pack_into(f"<QQII{len(slots)}I", buf, off, cycle, in_tag, flags, 0, *slots)


def device(tmp_path, buf):
    p = tmp_path / "dev"
    p.write_bytes(bytes(buf))
    return UserDevice(str(p)), p


REAL_2_5 = struct.unpack("<I", struct.pack("<f", 2.5))[0]


def test_the_daemon_reads_the_documented_layout(tmp_path):
    buf, *_ = layout()
    dev, _ = device(tmp_path, buf)
    with dev:
        assert (dev.n_in, dev.n_out, dev.stale_ms, dev.interval_ns) == (4, 4, 400, 20_000_000)
        assert [(s.index, s.address, s.type) for s in dev.inputs] == [
            (0, "%IX0.0", "BOOL"), (1, "%IW4", "INT"), (2, "", ""), (3, "%ID8", "REAL")]
        assert [s.type for s in dev.outputs] == ["BOOL", "INT", "REAL", "UDINT"]


@pytest.mark.parametrize("seq,record", [(4, 0), (7, 1)])
def test_outputs_come_from_the_record_the_sequence_names(tmp_path, seq, record):
    buf, _, _, out_off, out_stride = layout(out_seq=seq)
    good = [1, 0xFFFFFFFB, REAL_2_5, 0xFFFFFFFF]
    other = [0, 5, 0, 1]
    out_record(buf, out_off + record * out_stride, 42, 41, 0, good)
    out_record(buf, out_off + (1 - record) * out_stride, 43, 42, 0, other)  # being written
    dev, _ = device(tmp_path, buf)
    with dev:
        o = dev.read_outputs()
    assert (o.cycle, o.in_tag, o.safe) == (42, 41, False)
    assert o.values == {"%QX0.0": True, "%QW2": -5, "%QD4": 2.5, "%QD8": 4294967295}


def test_inputs_are_a_latch_update(tmp_path):
    buf, in_off, in_stride, *_ = layout(in_seq=10)
    dev, path = device(tmp_path, buf)
    with dev:
        dev.write_inputs([1, iodaemon.encode("INT", -300), 0, iodaemon.encode("REAL", 2.5)],
                         tag=77)
        dev.mm.flush()
        assert dev.current_inputs() == [1, 0xFFFFFED4, 0, REAL_2_5]
    data = path.read_bytes()
    assert struct.unpack_from("<I", data, 64)[0] == 12        # two increments: even again
    for k in (0, 1):                                          # both records whole
        assert struct.unpack_from("<Q4I", data, in_off + k * in_stride) == \
            (77, 1, 0xFFFFFED4, 0, REAL_2_5)


def test_rules_map_outputs_to_inputs(tmp_path):
    buf, _, _, out_off, _ = layout(out_seq=2)
    out_record(buf, out_off, 9, 8, 0, [1, 0xFFFFFFFB, REAL_2_5, 7])
    dev, _ = device(tmp_path, buf)
    with dev:
        rules = iodaemon.parse_rules(dev, ["%IW4=%QW2-1", "%ID8=%QD4*2", "%IX0.0=FALSE"])
        raw = iodaemon.answer(dev, rules, dev.read_outputs())
        assert raw[:2] == [0, 0xFFFFFFFA] and iodaemon.decode("REAL", raw[3]) == 5.0
        with pytest.raises(ValueError, match="%QW9 is not an output slot"):
            iodaemon.parse_rules(dev, ["%IW4=%QW9"])
        with pytest.raises(ValueError, match="%IW0 is not an input slot"):
            iodaemon.parse_rules(dev, ["%IW0=%QW2"])
        with pytest.raises(ValueError, match="expected %I"):
            iodaemon.parse_rules(dev, ["%IW4 <- %QW2"])


def test_a_foreign_file_is_refused(tmp_path):
    buf, *_ = layout(magic=0x12345678)
    with pytest.raises(ProtocolError, match="not an iec2kmod user device"):
        device(tmp_path, buf)
    buf, *_ = layout(version=2)
    with pytest.raises(ProtocolError, match="protocol version 2; this daemon knows 1"):
        device(tmp_path, buf)
    with pytest.raises(ProtocolError, match="less than a header"):
        device(tmp_path, bytearray(64))


def test_encoding_and_the_type_codes():
    assert iodaemon.encode("INT", -1) == 0xFFFFFFFF and iodaemon.decode("INT", 0xFFFFFFFF) == -1
    assert iodaemon.encode("UDINT", -5) == 0 and iodaemon.encode("UINT", 1 << 40) == 0xFFFFFFFF
    assert iodaemon.decode("BOOL", 2) is True and iodaemon.encode("BOOL", 0) == 0
    assert iodaemon.decode("REAL", iodaemon.encode("REAL", -0.75)) == -0.75
    assert {v: k for k, v in USER_TYPES.items()} == iodaemon.TYPES


def test_the_cli_reports_a_missing_device(capsys):
    assert iodaemon.main([str("/nonexistent/iec_io_x")]) == 2
    assert "no such device" in capsys.readouterr().err
    assert iodaemon.device_path("rig.bench.fb") == "/dev/iec_io_rig_bench_fb"


def test_register_rules_are_checked(tmp_path):
    buf, *_ = layout()
    dev, _ = device(tmp_path, buf)
    with dev:
        regs = iodaemon.parse_registers(dev, ["%IW4=hr100", "%ID8=ir:4", "%IX0.0=di3",
                                              "%QD4=hr200", "%QX0.0=co5"])
        assert [(r.slot.address, r.input, r.table, r.at, r.count) for r in regs] == [
            ("%IW4", True, "hr", 100, 1), ("%ID8", True, "ir", 4, 2),
            ("%IX0.0", True, "di", 3, 1), ("%QD4", False, "hr", 200, 2),
            ("%QX0.0", False, "co", 5, 1)]
        for spec, msg in (("%QW2=ir4", "ir is read-only"), ("%IW4=co1", "coils and discrete"),
                          ("%IW9=hr1", "not a slot"), ("%IW4=xx1", "expected %I")):
            with pytest.raises(ValueError, match=msg):
                iodaemon.parse_registers(dev, [spec])


def test_a_modbus_server_closes_the_loop(tmp_path):
    """Against pymodbus' own TCP server on localhost: the outputs of a record
    are written to holding registers and coils, then the inputs read back
    from the same registers (an echo through the server)."""
    import asyncio
    import socket
    import threading
    from pymodbus.client import ModbusTcpClient
    from pymodbus.datastore import (ModbusDeviceContext, ModbusSequentialDataBlock,
                                    ModbusServerContext)
    from pymodbus.server import ModbusTcpServer

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    ctx = ModbusServerContext(devices=ModbusDeviceContext(
        hr=ModbusSequentialDataBlock(1, [0] * 300), co=ModbusSequentialDataBlock(1, [0] * 16),
        di=ModbusSequentialDataBlock(1, [0] * 16), ir=ModbusSequentialDataBlock(1, [0] * 16)),
        single=True)
    loop = asyncio.new_event_loop()
    ready = threading.Event()
    holder = {}

    async def serve():
        holder["server"] = ModbusTcpServer(ctx, address=("127.0.0.1", port))
        ready.set()
        await holder["server"].serve_forever()

    t = threading.Thread(target=lambda: loop.run_until_complete(serve()), daemon=True)
    t.start()
    assert ready.wait(10)
    buf, _, _, out_off, _ = layout(out_seq=2)
    # outputs: %QX0.0 TRUE, %QW2 -5, %QD4 2.5, %QD8 70000
    out_record(buf, out_off, 9, 8, 0, [1, 0xFFFFFFFB, REAL_2_5, 70000])
    dev, _ = device(tmp_path, buf)
    client = ModbusTcpClient("127.0.0.1", port=port, timeout=2)
    try:
        deadline = time.monotonic() + 10
        while not client.connect():
            assert time.monotonic() < deadline, "the server did not start"
            time.sleep(0.1)
        with dev:
            regs = iodaemon.parse_registers(dev, [
                "%QW2=hr10", "%QD4=hr20", "%QX0.0=co3",          # outputs to the server
                "%IW4=hr10", "%ID8=hr20", "%IX0.0=co3"])         # and back
            raw = dev.current_inputs()
            iodaemon.modbus_exchange(client, 1, regs, dev.read_outputs(), raw)
            assert client.read_holding_registers(10, count=1).registers == [0xFFFB]
            assert client.read_holding_registers(20, count=2).registers == \
                [REAL_2_5 >> 16, REAL_2_5 & 0xFFFF]                # high word first
            assert iodaemon.decode("INT", raw[1]) == -5
            assert iodaemon.decode("REAL", raw[3]) == 2.5 and raw[0] == 1
            with pytest.raises(iodaemon.ModbusError):              # beyond the block
                iodaemon.modbus_exchange(client, 1, iodaemon.parse_registers(
                    dev, ["%IW4=hr5000"]), None, raw)
    finally:
        client.close()
        asyncio.run_coroutine_threadsafe(holder["server"].shutdown(), loop).result(10)
        t.join(10)
