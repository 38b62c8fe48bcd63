"""kbuild tier, issue 26: a resource module with an I/O map (the comedi
provider, kmod_templates/kernel/iec_io*.c) builds against the 6.1
PREEMPT_RT headers with W=1 and sparse, zero warnings, and links against
kcomedilib (the project the QEMU test tests/qemu/test_io_comedi.py runs);
the user-space provider alone needs no comedi, and beside comedi in one
resource (tests/qemu/projects/io_user) builds clean too."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import pytest

ROOT = Path(__file__).resolve().parents[2]
PROJECT = ROOT / "tests" / "qemu" / "projects" / "io_comedi"
TANK_IO = ROOT / "examples" / "tank_io"


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "iec2kmod.cli", *args], cwd=ROOT,
                          capture_output=True, text=True, timeout=1800)


def _gen(project, tree: Path) -> None:
    p = _cli("gen", str(project), "-o", str(tree))
    assert p.returncode == 0, p.stderr


def _build_sparse(tree: Path):
    """iec2kmod build --sparse (W=1 and sparse): it succeeds with 0 sparse
    warnings; the run, for more checks."""
    p = _cli("build", str(tree), "--sparse")
    assert p.returncode == 0, p.stderr[-3000:]
    assert "sparse: 0 warnings" in p.stdout, p.stdout
    return p


def _depends(ko: Path) -> str:
    """modinfo's depends line of a module."""
    return subprocess.run(["/sbin/modinfo", "-F", "depends", str(ko)], capture_output=True,
                          text=True, timeout=60).stdout


@pytest.mark.kbuild
def test_an_io_resource_builds_with_zero_warnings(tmp_path):
    _gen(PROJECT, tmp_path / "t")
    main = (tmp_path / "t" / "iec_rig_r_bench" / "main.c").read_text()
    assert '#include "iec_io_comedi.c"' in main
    _build_sparse(tmp_path / "t")
    ko = tmp_path / "t" / "iec_rig_r_bench" / "iec_rig_r_bench.ko"
    info = _depends(ko)
    assert "kcomedilib" in info.split("\n")[0].split(","), info


@pytest.mark.kbuild
def test_an_interrupt_resource_builds_with_zero_warnings(tmp_path):
    """projects/io_parport: resource Events has only an INTERRUPT (the
    comedi provider's threaded IRQ), resource Lights only outputs."""
    project = ROOT / "tests" / "qemu" / "projects" / "io_parport"
    _gen(project, tmp_path / "t")
    main = (tmp_path / "t" / "iec_crossing_r_events" / "main.c").read_text()
    assert "static struct iec_io_irq io_irqs[]" in main
    assert 'ret = iec_io_irq_on(&io, &resource);' in main
    _build_sparse(tmp_path / "t")


@pytest.mark.kbuild
def test_the_irq_benchmark_module_builds_with_zero_warnings(tmp_path):
    from iec2kmod import kbuild
    d = tmp_path / "irq_kthread"
    shutil.copytree(ROOT / "benchmarks" / "irq_kthread", d)
    r = kbuild.build_modules(str(d), sparse=True).check()
    assert r.warnings() == [], r.output
    assert (d / "irqwake.ko").is_file()


USER_PROJECT = ROOT / "tests" / "qemu" / "projects" / "io_user"


def user_only(dest: Path) -> Path:
    """projects/io_user without its comedi device (DEVICE daq and its two
    bindings): %IW12 and %QW12 stay located, unbound."""
    dest.mkdir(parents=True)
    shutil.copy(USER_PROJECT / "loop.st", dest)
    lines = (USER_PROJECT / "loop.iomap").read_text().splitlines()
    kept = [ln for ln in lines if "daq" not in ln]
    assert len(lines) - len(kept) == 3, lines      # DEVICE daq, %IW12, %QW12
    (dest / "loop.iomap").write_text("\n".join(kept) + "\n")
    return dest


@pytest.mark.kbuild
def test_a_user_io_resource_builds_with_zero_warnings(tmp_path):
    """The user-space provider (iec_io_user.c: misc device, mmap of
    vmalloc_user memory, poll) under W=1 and sparse; alone (io_user without
    its comedi device) it needs no comedi."""
    _gen(user_only(tmp_path / "src"), tmp_path / "t")
    main = (tmp_path / "t" / "iec_rig_r_bench" / "main.c").read_text()
    assert '#include "iec_io_user.c"' in main and "iec_io_comedi.c" not in main
    p = _build_sparse(tmp_path / "t")
    assert "warning:" not in p.stdout + p.stderr, (p.stdout + p.stderr)[-3000:]
    ko = tmp_path / "t" / "iec_rig_r_bench" / "iec_rig_r_bench.ko"
    info = _depends(ko)
    assert "kcomedilib" not in info, info


@pytest.mark.kbuild
def test_a_user_and_comedi_resource_builds_with_zero_warnings(tmp_path):
    """projects/io_user as tests/qemu/test_io_user.py runs it: one task
    bound to the user provider and to comedi, both providers in one
    module, zero warnings with W=1 and sparse, linked against kcomedilib."""
    _gen(USER_PROJECT, tmp_path / "t")
    main = (tmp_path / "t" / "iec_rig_r_bench" / "main.c").read_text()
    assert '#include "iec_io_user.c"' in main and '#include "iec_io_comedi.c"' in main
    p = _build_sparse(tmp_path / "t")
    assert "warning:" not in p.stdout + p.stderr, (p.stdout + p.stderr)[-3000:]
    ko = tmp_path / "t" / "iec_rig_r_bench" / "iec_rig_r_bench.ko"
    info = _depends(ko)
    assert "kcomedilib" in info.split("\n")[0].split(","), info


@pytest.mark.kbuild
def test_real_scaling_uses_the_fpu_only_in_iec_io_real(tmp_path):
    """examples/tank_io (REALs in volts): zero warnings with W=1 and sparse,
    and no FPU/SIMD register outside iec_io_real.c's two functions, which
    iec_io.c calls between kernel_fpu_begin() and kernel_fpu_end()."""
    from test_execution_kbuild import fpu_outside_sections
    _gen(TANK_IO, tmp_path / "t")
    _build_sparse(tmp_path / "t")
    assert fpu_outside_sections(tmp_path / "t") == []
    dis = subprocess.run(["objdump", "-d", str(tmp_path / "t" / "iec_plant_r_tank" /
                                               "iec_plant_r_tank.ko")],
                         capture_output=True, text=True, timeout=120).stdout
    assert "%xmm" in dis          # the scaling is there, and allowed where it is
