"""The generated side of the I/O map (issue 26, kmod/tree.py _io_of and
resource_main.c.j2): the resource module's device and binding tables, each
task's bound inputs and outputs, and where the device access sits in the
copies: inputs read before copy-in's image lock and stored under it,
outputs staged under copy-out's lock and written after it (a provider may
sleep; the image lock is a raw spinlock).  What the kernel cannot do yet
is a gen error, not a silent module.  REAL scaling: the iomap's Python
mirror (phys_of, raw_of) of the kernel's arithmetic."""

import json
import os
import struct
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.unit
ROOT = Path(__file__).resolve().parents[2]
PROJECT = ROOT / "tests" / "qemu" / "projects" / "io_comedi"
PLANT = ROOT / "tests" / "unit" / "iomap" / "plant.st"
TANK_IO = ROOT / "examples" / "tank_io"

from iec2kmod.iomap import phys_of, raw_of  # noqa: E402
from plc_manager.io import phys_of as manager_phys_of  # noqa: E402


def gen(tmp_path, *files):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    out = tmp_path / "out"
    p = subprocess.run([sys.executable, "-m", "iec2kmod", "gen", *map(str, files), "-o",
                        str(out)], env=env, capture_output=True, text=True, timeout=300)
    return p, out


def _between(text, start, end):
    i = text.index(start)
    return text[i:text.index(end, i)]


def test_the_resource_module_reads_and_writes_its_devices_outside_the_lock(tmp_path):
    p, out = gen(tmp_path, PROJECT)
    assert p.returncode == 0, p.stderr
    main = (out / "iec_rig_r_bench" / "main.c").read_text()
    assert '{ .name = "daq", .prov = &iec_io_comedi, .minor = 0 },' in main
    assert '.address = "%QW0", .channel = "daq.1.0", .dev = 0, .subdev = 1, .chan = 0, ' \
           '.kind = IEC_IO_AO, .input = 0, .range = 0, .hold = 0, .maxdata = 65535U, ' \
           '.safe = 1234U, .var = &res_image.g_bench_aout0' in main
    assert '.address = "%QW2", .channel = "daq.1.1"' in main and ".hold = 1," in main
    assert "static const u16 task0_io_in[] = { 0, 1 };" in main
    assert "static const u16 task0_io_out[] = { 2, 3 };" in main
    assert ".io_safe = task0_io_safe," in main
    cin = _between(main, "static void task0_copy_in(", "\n}\n")
    order = [cin.index(s) for s in ("iec_io_read(", "iec2kmod_image_lock();", "iec_io_store(",
                                    "iec2kmod_force_globals();", "task0_image.g_bench_ain0 =",
                                    "iec2kmod_image_unlock();")]
    assert order == sorted(order), cin
    cout = _between(main, "static void task0_copy_out(", "\n}\n")
    order = [cout.index(s) for s in ("iec2kmod_image_lock();", "res_image.g_bench_aout0 =",
                                     "iec2kmod_force_globals();", "iec_io_stage(",
                                     "iec2kmod_image_unlock();", "iec_io_write(")]
    assert order == sorted(order), cout
    init = _between(main, "static int __init resource_init(", "\n}\n")
    assert init.index("iec_io_open(&io)") < init.index("iec_resource_init(&resource)")
    assert "iec_io_exit(&io);" in _between(main, "static void __exit resource_exit(", "\n}\n")
    # the configuration module and a resource without a map know nothing of it
    assert "iec_io" not in (out / "iec_rig_config" / "main.c").read_text()


def test_a_task_asks_only_the_devices_its_bindings_use(tmp_path):
    """projects/io_user: devices fb and mon (user) and daq (comedi); task
    fast reads all three and writes fb and daq.  Each direction carries the
    devices it uses, once each, which the cycle asks for cycle_in() and
    cycle_out() (iec_io.c) instead of walking the bindings every cycle;
    init makes the user devices reachable last, exit withdraws them
    first."""
    p, out = gen(tmp_path, ROOT / "tests" / "qemu" / "projects" / "io_user")
    assert p.returncode == 0, p.stderr
    main = (out / "iec_rig_r_bench" / "main.c").read_text()
    assert "static const u16 task0_io_in_devs[] = { 0, 1, 2 };" in main
    assert "static const u16 task0_io_out_devs[] = { 0, 2 };" in main
    assert "\t.devs = task0_io_out_devs,\n" in main
    cin = _between(main, "static void task0_copy_in(", "\n}\n")
    assert "iec_io_read(&io, t, &task0_in);" in cin
    assert "iec_io_write(&io, t, &task0_out);" in main
    init = _between(main, "static int __init resource_init(", "\n}\n")
    order = [init.index(s) for s in ("iec_io_open(&io)", "iec_resource_init(&resource)",
                                     "iec_io_irq_on(&io, &resource)", "iec_io_expose(&io)",
                                     "return 0;", "iec_io_settle(&io, base);")]
    assert order == sorted(order), init
    leave = _between(main, "static void __exit resource_exit(", "\n}\n")
    assert leave.index("iec_io_withdraw(&io);") < leave.index("iec_io_irq_off(&io);"), leave


def test_an_output_no_task_writes_is_in_no_task_list(tmp_path):
    (tmp_path / "p").mkdir()
    st = (PROJECT / "loop.st").read_text().replace("  aout1 := setp;\n", "")
    st = st.replace("aout0 : UINT; aout1 : UINT;", "aout0 : UINT;")
    (tmp_path / "p" / "loop.st").write_text(st)
    (tmp_path / "p" / "loop.iomap").write_text((PROJECT / "loop.iomap").read_text())
    p, out = gen(tmp_path, tmp_path / "p")
    assert p.returncode == 0, p.stderr
    main = (out / "iec_rig_r_bench" / "main.c").read_text()
    assert "static const u16 task0_io_out[] = { 2 };" in main


def test_a_real_binding_is_scaled_in_an_fpu_object(tmp_path):
    """A REAL on an analog channel: the binding carries the range's IEEE
    bits, the module gets iec_io_real.c with the FPU flags (and only that
    object), the manifest marks the module uses_fpu (the kbuild tier's
    FPU-register check), and a SAFE value in volts becomes its sample."""
    p, out = gen(tmp_path, TANK_IO)
    assert p.returncode == 0, p.stderr
    main = (out / "iec_plant_r_tank" / "main.c").read_text()
    assert '.address = "%ID0", .channel = "daq.0.0"' in main
    assert ".phys = 1, .scale = { .lo = 0xc024000000000000ULL, .hi = 0x4024000000000000ULL, " \
           ".maxdata = 65535U }" in main
    # SAFE 0.0 (volts) on -10..10 V: (0 + 10) * 65535 / 20 + 0.5 = 32768.0
    assert '.address = "%QD4", .channel = "daq.1.1"' in main and ".safe = 32768U" in main
    assert main.index("#define IEC_IO_PHYS 1") < main.index('#include "iec_io.c"')
    kbuild = (out / "iec_plant_r_tank" / "Kbuild").read_text()
    assert "iec_plant_r_tank-y := main.o iec_io_real.o\n" in kbuild
    assert "CFLAGS_iec_io_real.o += -mhard-float" in kbuild
    assert "CFLAGS_main.o" not in kbuild
    m = json.loads((out / "manifest.json").read_text())
    res = next(x for x in m["modules"] if x["kind"] == "resource")
    assert res.get("uses_fpu") is True
    # the integer-only map has no FPU object
    p, out2 = gen(tmp_path / "b", PROJECT)
    assert p.returncode == 0, p.stderr
    assert "iec_io_real" not in (out2 / "iec_rig_r_bench" / "Kbuild").read_text()
    # (its main.c calls no scaling function: none would link)
    assert "IEC_IO_PHYS" not in (out2 / "iec_rig_r_bench" / "main.c").read_text()


def test_phys_of_and_raw_of_invert_each_other():
    """Every 16-bit sample of a -10..10 V channel survives REAL and back;
    halves round up, out of range and NaN clamp."""
    for raw in range(0, 65536):
        assert raw_of(-10.0, 10.0, 16, phys_of(-10.0, 10.0, 16, raw)) == raw
    assert phys_of(-10.0, 10.0, 16, 0) == -10.0 and phys_of(-10.0, 10.0, 16, 65535) == 10.0
    assert raw_of(-10.0, 10.0, 16, 0.0) == 32768          # 32767.5 rounds up
    assert raw_of(-10.0, 10.0, 16, -11.0) == 0 and raw_of(-10.0, 10.0, 16, 1e30) == 65535
    assert raw_of(-10.0, 10.0, 16, float("nan")) == 0
    assert raw_of(-10.0, 10.0, 16, float("inf")) == 65535
    # a REAL is the nearest binary32 of the binary64 value; an LREAL is that value
    v = -10.0 + 12345 * 20.0 / 65535
    assert phys_of(-10.0, 10.0, 16, 12345, "LREAL") == v
    assert phys_of(-10.0, 10.0, 16, 12345) == struct.unpack("<f", struct.pack("<f", v))[0]
    # plc-manager's copy computes the same bits
    for raw in (0, 1, 12345, 32767, 65534, 65535):
        for t in ("REAL", "LREAL"):
            assert manager_phys_of(-5.0, 5.0, 16, raw, t) == phys_of(-5.0, 5.0, 16, raw, t)


def test_a_program_located_variable_is_refused_by_gen(tmp_path):
    (tmp_path / "p").mkdir()
    (tmp_path / "p" / "prog.st").write_text(
        "PROGRAM P\n  VAR lvl AT %IW0 : UINT; out : UINT; END_VAR\n  out := lvl;\n"
        "END_PROGRAM\nCONFIGURATION C\n  RESOURCE R ON CPU0\n"
        "    TASK t (INTERVAL := T#10ms, PRIORITY := 1);\n    PROGRAM p1 WITH t : P;\n"
        "  END_RESOURCE\nEND_CONFIGURATION\n")
    (tmp_path / "p" / "prog.iomap").write_text("DEVICE daq : comedi comedi_test\n"
                                               "%IW0 : daq.0.0\n")
    p, out = gen(tmp_path, tmp_path / "p")
    assert p.returncode == 2, p.stderr
    assert "%IW0 is a program's located variable (R.p1.lvl): the kernel binds devices " \
           "to globals and program connections only" in p.stderr
