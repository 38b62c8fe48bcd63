# SPDX-License-Identifier: MIT
"""Pieces of the guest harness that need no guest: the cpio writer, module
dependency order, kernel-log matching, the kbuild helper's errors."""

import os
import stat
import subprocess

import pytest

from iec2kmod import kbuild
from iec2kmod.vm import kernel_log_problems
from iec2kmod.vm.initramfs import CpioWriter, ModuleIndex
from iec2kmod.vm.kernel import find_kernel, VMSetupError


def test_cpio_newc_archive_is_read_by_gnu_cpio(tmp_path):
    w = CpioWriter()
    w.add_dirs("a/b")
    w.add_file("a/b/f.txt", b"hello\n", 0o640)
    w.add_file("a/odd", b"x" * 5, 0o755)          # lengths that need padding
    w.add_symlink("a/link", "b/f.txt")
    w.add_chardev("a/null", 1, 3, 0o666)
    data = w.finish()
    assert len(data) % 512 == 0
    with pytest.raises(ValueError):
        w.add_file("late", b"")
    out = tmp_path / "x"
    out.mkdir()
    p = subprocess.run(["cpio", "-i", "-d", "--no-absolute-filenames", "--quiet"],
                       input=data, cwd=out, capture_output=True)
    assert p.returncode == 0, p.stderr
    assert (out / "a/b/f.txt").read_bytes() == b"hello\n"
    assert stat.S_IMODE(os.stat(out / "a/b/f.txt").st_mode) == 0o640
    assert (out / "a/odd").read_bytes() == b"xxxxx"
    assert os.readlink(out / "a/link") == "b/f.txt"
    st = os.lstat(out / "a/null")
    assert stat.S_ISCHR(st.st_mode) and os.major(st.st_rdev) == 1 and os.minor(st.st_rdev) == 3


def test_cpio_rejects_duplicates():
    w = CpioWriter()
    w.add_dir("d")
    with pytest.raises(ValueError):
        w.add_dir("d")


def test_module_load_order_puts_dependencies_first():
    try:
        k = find_kernel()
    except VMSetupError as e:
        pytest.fail(str(e), pytrace=False)
    idx = ModuleIndex(k.moddir)
    order = idx.load_order(["9p", "9pnet_virtio", "virtio_pci"])
    for mod in order:
        for dep in idx.depends(mod):
            assert order.index(dep) < order.index(mod)
    assert {"9p", "9pnet", "netfs", "virtio", "virtio_ring", "virtio_pci"} <= set(order)
    with pytest.raises(KeyError, match="no_such_module"):
        idx.load_order(["no_such_module"])


def test_kernel_log_patterns():
    log = ("[ 1.0] ok line\n"
           "[ 2.0] WARNING: CPU: 1 PID: 7 at foo.c:3 bar+0x1\n"
           "[ 2.1] Call Trace:\n"
           "[ 3.0] BUG: scheduling while atomic: x/1/0x00000002\n"
           "[ 4.0] BUG: sleeping function called from invalid context at y.c:1\n"
           "[ 5.0] Oops: 0000 [#1] PREEMPT_RT SMP\n"
           "[ 6.0] iec2kmod: harmless\n")
    bad = kernel_log_problems(log)
    assert len(bad) == 5 and "ok line" not in " ".join(bad)
    assert kernel_log_problems(log, allow=[r"foo\.c", r"Call Trace"]) == bad[2:]


def test_kbuild_errors_name_what_to_do(tmp_path, monkeypatch):
    monkeypatch.setenv("IEC2KMOD_KDIR", str(tmp_path))
    with pytest.raises(kbuild.KbuildError, match="not a kbuild directory"):
        kbuild.find_kdir()
    monkeypatch.delenv("IEC2KMOD_KDIR")
    with pytest.raises(kbuild.KbuildError, match="apt-get install linux-headers-rt-amd64"):
        kbuild.find_kdir(release="0.0.0-no-such-rt-amd64")
    with pytest.raises(kbuild.KbuildError, match="does not exist"):
        kbuild.build_modules(str(tmp_path / "missing"))
    (tmp_path / "notko").write_bytes(b"not an elf")
    with pytest.raises(kbuild.KbuildError, match="not a kernel module"):
        kbuild.modinfo(str(tmp_path / "notko"))


def test_kbuild_clean(tmp_path):
    (tmp_path / "Kbuild").write_text("obj-m := nothing.o\n")
    (tmp_path / "stale.o").write_text("")
    (tmp_path / ".stale.o.cmd").write_text("")
    res = kbuild.clean_modules(str(tmp_path))
    assert res.ok, res.output
    assert not (tmp_path / "stale.o").exists()
