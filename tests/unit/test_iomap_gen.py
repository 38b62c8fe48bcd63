"""The generated side of the I/O map (issue 26, kmod/tree.py _io_of and
resource_main.c.j2): the resource module's device and binding tables, each
task's bound inputs and outputs, and where the device access sits in the
copies: inputs read before copy-in's image lock and stored under it,
outputs staged under copy-out's lock and written after it (a provider may
sleep; the image lock is a raw spinlock).  What the kernel cannot do yet
is a gen error, not a silent module."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.unit
ROOT = Path(__file__).resolve().parents[2]
PROJECT = ROOT / "tests" / "qemu" / "projects" / "io_comedi"
PLANT = ROOT / "tests" / "unit" / "iomap" / "plant.st"


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


def test_a_real_binding_is_refused_by_gen(tmp_path):
    m = tmp_path / "plant.iomap"
    m.write_text("RESOURCE Station\nDEVICE daq : comedi comedi_test\n%ID8 : daq.0.1\n")
    p, out = gen(tmp_path, PLANT, m)
    assert p.returncode == 2
    assert f"{m}:3:1: %ID8 is REAL: the kernel runtime does not scale to REAL yet" in p.stderr
    assert "Traceback" not in p.stderr


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
