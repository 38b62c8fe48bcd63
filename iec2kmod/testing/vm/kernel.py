# SPDX-License-Identifier: MIT
"""Find what the QEMU guest needs on the host: the extracted PREEMPT_RT kernel
image (made by scripts/setup.sh), qemu-system-x86_64 and a static busybox."""

from __future__ import annotations

import dataclasses
import os
import shutil
import struct
from typing import List, Optional

from ... import kbuild

SETUP_HINT = "run scripts/setup.sh"


class VMSetupError(RuntimeError):
    """Something the guest needs is missing on the host; the message says what
    to install or run."""


def cache_dir() -> str:
    return os.environ.get("IEC2KMOD_CACHE", "/var/cache/iec2kmod")


@dataclasses.dataclass(frozen=True)
class KernelImage:
    release: str          # e.g. 6.1.0-56-rt-amd64
    root: str             # extracted package root
    vmlinuz: str
    moddir: str           # <root>/lib/modules/<release>/kernel
    config: Optional[str]


def find_kernel(release: Optional[str] = None) -> KernelImage:
    """The extracted kernel image matching the installed RT headers (or
    *release*), from ``$IEC2KMOD_CACHE/kernel/<release>`` (default cache
    ``/var/cache/iec2kmod``).  ``$IEC2KMOD_KERNEL_DIR`` overrides the directory."""
    if release is None:
        try:
            release = kbuild.kernel_release()
        except kbuild.KbuildError as e:
            raise VMSetupError(str(e)) from None
    root = os.environ.get("IEC2KMOD_KERNEL_DIR") or os.path.join(cache_dir(), "kernel", release)
    vmlinuz = os.path.join(root, "boot", f"vmlinuz-{release}")
    moddir = os.path.join(root, "lib", "modules", release, "kernel")
    if not os.path.isfile(vmlinuz) or not os.path.isdir(moddir):
        raise VMSetupError(
            f"the PREEMPT_RT kernel image {release} is not extracted (missing {vmlinuz} "
            f"or {moddir}): {SETUP_HINT} (it runs 'apt-get download linux-image-{release}' "
            f"and extracts it into {os.path.join(cache_dir(), 'kernel', release)})")
    config = os.path.join(root, "boot", f"config-{release}")
    return KernelImage(release, root, vmlinuz, moddir, config if os.path.isfile(config) else None)


def _has_pvh_note(elf: bytes) -> bool:
    """True if the ELF image has XEN_ELFNOTE_PHYS32_ENTRY (18), the PVH entry
    point that lets QEMU boot the uncompressed kernel directly."""
    if elf[:4] != b"\x7fELF" or elf[4] != 2:
        return False
    (e_phoff,) = struct.unpack_from("<Q", elf, 0x20)
    e_phentsize, e_phnum = struct.unpack_from("<HH", elf, 0x36)
    for i in range(e_phnum):
        p_type, _fl, p_off, _va, _pa, p_filesz = struct.unpack_from(
            "<IIQQQQ", elf, e_phoff + i * e_phentsize)
        if p_type != 4:          # PT_NOTE
            continue
        pos, end = p_off, p_off + p_filesz
        while pos + 12 <= end:
            namesz, descsz, ntype = struct.unpack_from("<III", elf, pos)
            name = elf[pos + 12:pos + 12 + namesz].rstrip(b"\0")
            if name == b"Xen" and ntype == 18:
                return True
            pos += 12 + ((namesz + 3) & ~3) + ((descsz + 3) & ~3)
    return False


def _decompress_bzimage(data: bytes) -> Optional[bytes]:
    if data[0x202:0x206] != b"HdrS":
        return None
    setup_sects = data[0x1F1] or 4
    off, length = struct.unpack_from("<II", data, 0x248)
    payload = data[(setup_sects + 1) * 512 + off:][:length]
    if payload[:6] == b"\xfd7zXZ\0":
        import lzma
        return lzma.LZMADecompressor(format=lzma.FORMAT_XZ).decompress(payload)
    if payload[:2] == b"\x1f\x8b":
        import zlib
        return zlib.decompressobj(16 + zlib.MAX_WBITS).decompress(payload)
    return None                # zstd/lz4/...: not in the standard library


def pvh_vmlinux(kernel: KernelImage) -> Optional[str]:
    """The uncompressed kernel (ELF with a PVH entry note) extracted from the
    bzImage and cached beside it (or in ~/.cache/iec2kmod), or None when that is
    not possible.  QEMU boots it directly, which skips the firmware's real-mode
    setup and the in-guest decompression: about 3-4 s less per boot under TCG."""
    name = f"vmlinux-{kernel.release}.pvh"
    st = os.stat(kernel.vmlinuz)
    stamp = f"{st.st_size}-{int(st.st_mtime)}"
    places = [os.path.join(kernel.root, "boot"),
              os.path.join(os.path.expanduser("~"), ".cache", "iec2kmod")]
    for d in places:
        p = os.path.join(d, name)
        try:
            with open(p + ".stamp") as f:
                if f.read().strip() == stamp and os.path.isfile(p):
                    return p
        except OSError:
            pass
    try:
        with open(kernel.vmlinuz, "rb") as f:
            elf = _decompress_bzimage(f.read())
    except (OSError, EOFError, ValueError, struct.error):
        return None
    if not elf or not _has_pvh_note(elf):
        return None
    for d in places:
        try:
            os.makedirs(d, exist_ok=True)
            p = os.path.join(d, name)
            tmp = f"{p}.tmp{os.getpid()}"
            with open(tmp, "wb") as f:
                f.write(elf)
            os.replace(tmp, p)
            with open(p + ".stamp", "w") as f:
                f.write(stamp + "\n")
            return p
        except OSError:
            continue
    return None


def find_qemu() -> str:
    q = shutil.which("qemu-system-x86_64")
    if not q:
        raise VMSetupError(
            "qemu-system-x86_64 not found: apt-get install qemu-system-x86 (or " + SETUP_HINT + ")")
    return q


def _is_static_elf(path: str) -> bool:
    with open(path, "rb") as f:
        data = f.read(1 << 16)
    if data[:4] != b"\x7fELF" or data[4] != 2:
        return False
    (e_phoff,) = struct.unpack_from("<Q", data, 0x20)
    e_phentsize, e_phnum = struct.unpack_from("<HH", data, 0x36)
    for i in range(e_phnum):
        (p_type,) = struct.unpack_from("<I", data, e_phoff + i * e_phentsize)
        if p_type == 3:     # PT_INTERP: dynamically linked
            return False
    return True


def find_busybox() -> str:
    for p in (os.environ.get("IEC2KMOD_BUSYBOX"), "/bin/busybox", "/usr/bin/busybox"):
        if p and os.path.isfile(p):
            if _is_static_elf(p):
                return p
            raise VMSetupError(
                f"{p} is not statically linked: apt-get install busybox-static (or {SETUP_HINT})")
    raise VMSetupError(f"busybox not found: apt-get install busybox-static (or {SETUP_HINT})")


def check_prerequisites() -> List[str]:
    """Every missing prerequisite of the QEMU tier, each as one line saying what
    to do; empty when all is there."""
    problems = []
    for fn in (find_qemu, find_busybox, find_kernel):
        try:
            fn()
        except VMSetupError as e:
            problems.append(str(e))
    return problems
