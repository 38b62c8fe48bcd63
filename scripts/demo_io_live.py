# SPDX-License-Identifier: MIT
"""The live part of scripts/demo_io.sh: boot the PREEMPT_RT guest with
comedi_test, load examples/tank_io with plc-manager and show its I/O moving:
the bindings and last samples in `plc-manager status`, the device's
channels as user space reads them (/dev/comedi0, the COMEDI_INSN ioctl),
a forced output reaching the device, the safe state on stop.

    python3 scripts/demo_io_live.py WORKDIR PROJECT_DIR
"""

from __future__ import annotations

import shlex
import sys
import time

from iec2kmod.iomap import phys_of
from iec2kmod.testing.vm import Guest, GuestError

T0 = time.monotonic()
COMEDI = ("comedi", "kcomedilib", "comedi_test")

# one INSN_READ per channel "subdevice.channel" through /dev/comedi0
READ_CHANNELS = r"""
import ctypes, fcntl, os, sys
class Insn(ctypes.Structure):
    _fields_ = [("insn", ctypes.c_uint), ("n", ctypes.c_uint),
                ("data", ctypes.POINTER(ctypes.c_uint)), ("subdev", ctypes.c_uint),
                ("chanspec", ctypes.c_uint), ("unused", ctypes.c_uint * 3)]
COMEDI_INSN = (2 << 30) | (ctypes.sizeof(Insn) << 16) | (ord("d") << 8) | 12
fd = os.open("/dev/comedi0", os.O_RDWR)
out = []
for spec in sys.argv[1:]:
    sub, chan = map(int, spec.split("."))
    data = (ctypes.c_uint * 1)()
    fcntl.ioctl(fd, COMEDI_INSN, Insn(0x04000000, 1, data, sub, chan, (0, 0, 0)))
    out.append(data[0])
print(" ".join(map(str, out)))
"""


def say(msg: str) -> None:
    print(f"[demo-io {time.monotonic() - T0:5.0f}s] {msg}", flush=True)


def main() -> int:
    workdir, project = sys.argv[1:]
    say("booting Debian's PREEMPT_RT kernel in QEMU (TCG) with comedi, kcomedilib and "
        "comedi_test (/dev/comedi0: 8 AI, 8 AO channels, 16 bits, +-10 V)")
    g = Guest(workdir, console_log=f"{workdir}/guest-console.log", extra_modules=COMEDI)
    try:
        g.start()
        g.start_pyserver()
        mark = g.log_mark()
        say("/proc/comedi in the guest:")
        for line in g.run("cat /proc/comedi").output.splitlines()[:3]:
            print(f"  {line}")

        def pm(*args, timeout=300):
            print(f"\n  guest# plc-manager {' '.join(shlex.quote(str(a)) for a in args)}",
                  flush=True)
            r = g.pyrun(script="plc-manager", argv=[str(a) for a in args], timeout=timeout)
            for line in r.output.rstrip().splitlines():
                print(f"  {line}")
            if r.exit_code != 0:
                raise SystemExit(f"[demo-io] plc-manager {args[0]} failed "
                                 f"(exit {r.exit_code})")
            return r.output

        def device(what: str) -> None:
            r = g.pyrun(code=READ_CHANNELS, argv=["0.0", "0.1", "1.0", "1.1"], timeout=60)
            if r.exit_code != 0:
                raise SystemExit(f"[demo-io] reading /dev/comedi0 failed: {r.output}")
            raw = [int(x) for x in r.output.split()]
            volts = "  ".join(f"{n} {v:6d} = {phys_of(-10.0, 10.0, 16, v):+8.4f} V"
                              for n, v in zip(("AI0 level", "AI1 valve", "AO0 level",
                                               "AO1 valve"), raw))
            print(f"  /dev/comedi0 ({what}): {volts}", flush=True)

        say("load: the I/O map's device is checked first (/dev/comedi0, /proc/comedi), "
            "then the modules go in and the tasks start")
        pm("load", project)
        say("the level climbs from 2 V toward the 6 V setpoint, as user space reads the "
            "device (AI n reads back AO n: comedi_test's loopback)")
        for i in range(4):
            device(f"t+{i * 1.5:.1f} s")
            time.sleep(1.5)
        say("status: the I/O bindings and the sample each last exchanged with the device")
        pm("status")
        say("force the valve by its address: 2.5 V reaches AO 1 as a 16-bit sample")
        pm("force", "%QD4", "2.5")
        time.sleep(1.0)
        device("valve forced")
        pm("read", "%QD4", "%ID4", "%ID0", "Tank.setpoint")
        say("stop: the valve goes to its safe 0 V (32768), the level output holds")
        pm("unforce", "--all")
        pm("stop", "--keep-loaded")
        device("stopped")
        pm("stop")
        g.check_kernel_log(since=mark)
        say("kernel log clean: no WARNING, BUG, Oops or 'scheduling while atomic'")
    except GuestError as e:
        print(f"[demo-io] the guest failed: {e}", file=sys.stderr)
        return 1
    finally:
        g.close()
    say("done")
    return 0


if __name__ == "__main__":
    sys.exit(main())
