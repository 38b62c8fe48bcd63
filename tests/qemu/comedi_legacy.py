# SPDX-License-Identifier: MIT
"""Guest-side helpers (run with Guest.pyrun) for comedi's legacy devices:
attach a driver to /dev/comediN with the COMEDI_DEVCONFIG ioctl (what
comedilib's comedi_config does; comedi must be loaded with
comedi_num_legacy_minors=N), and read/write digital lines with
COMEDI_INSN INSN_BITS.  Usage in the guest:

    comedi_legacy.py config /dev/comedi0 comedi_parport 0x378 [irq]
    comedi_legacy.py detach /dev/comedi0
    comedi_legacy.py bits /dev/comedi0 SUBDEV MASK BITS     # prints the lines
"""

import ctypes
import fcntl
import os
import sys


def _iow(nr, size):
    return (1 << 30) | (size << 16) | (ord("d") << 8) | nr


def _iowr(nr, size):
    return (3 << 30) | (size << 16) | (ord("d") << 8) | nr


class DevConfig(ctypes.Structure):
    _fields_ = [("board_name", ctypes.c_char * 20), ("options", ctypes.c_int * 32)]


class Insn(ctypes.Structure):
    _fields_ = [("insn", ctypes.c_uint), ("n", ctypes.c_uint),
                ("data", ctypes.POINTER(ctypes.c_uint)), ("subdev", ctypes.c_uint),
                ("chanspec", ctypes.c_uint), ("unused", ctypes.c_uint * 3)]


COMEDI_DEVCONFIG = _iow(0, ctypes.sizeof(DevConfig))
COMEDI_INSN = (2 << 30) | (ctypes.sizeof(Insn) << 16) | (ord("d") << 8) | 12
INSN_BITS = 0x04000000 | 0x08000000 | 2


def config(path, board, *options):
    cfg = DevConfig()
    cfg.board_name = board.encode()
    for i, o in enumerate(options):
        cfg.options[i] = int(o, 0)
    fd = os.open(path, os.O_RDWR)
    try:
        fcntl.ioctl(fd, COMEDI_DEVCONFIG, cfg)
    finally:
        os.close(fd)


def detach(path):
    """COMEDI_DEVCONFIG with a NULL argument: the driver lets the device go."""
    fd = os.open(path, os.O_RDWR)
    try:
        fcntl.ioctl(fd, COMEDI_DEVCONFIG, 0)
    finally:
        os.close(fd)


def bits(fd, subdev, mask, value):
    data = (ctypes.c_uint * 2)(mask, value)
    fcntl.ioctl(fd, COMEDI_INSN, Insn(INSN_BITS, 2, data, subdev, 0))
    return data[1]


if __name__ == "__main__":
    cmd, path, *rest = sys.argv[1:]
    if cmd == "config":
        config(path, *rest)
    elif cmd == "detach":
        detach(path)
    elif cmd == "bits":
        fd = os.open(path, os.O_RDWR)
        print(bits(fd, *(int(x, 0) for x in rest)))
    else:
        sys.exit(f"unknown command {cmd}")
