# SPDX-License-Identifier: MIT
"""``python -m iec2kmod.testing.vm check | prepare | run | shell``

check    list missing prerequisites of the QEMU guest (exit 1 if any)
prepare  check, then extract the PVH-bootable kernel once (used by setup.sh)
run      boot a guest, run one command (``--chroot``: in the host root, e.g.
         ``plc-manager``), print its output, power off; exit with its status
shell    boot a guest and run the lines typed on stdin one by one
"""

from __future__ import annotations

import argparse
import shlex
import sys
import tempfile
import time

from .guest import Guest, GuestError
from .kernel import VMSetupError, check_prerequisites, find_kernel, pvh_vmlinux


def _guest(a) -> Guest:
    workdir = a.workdir or tempfile.mkdtemp(prefix="iec2kmod-guestwork-")
    g = Guest(workdir, icount=a.icount, smp=a.smp, memory=a.memory, parallel=a.parallel)
    t0 = time.monotonic()
    g.start()
    print(f"[vm] guest up in {time.monotonic() - t0:.1f} s (work dir {g.workdir})",
          file=sys.stderr, flush=True)
    return g


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m iec2kmod.testing.vm", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    sub.add_parser("check")
    sub.add_parser("prepare")
    for name in ("run", "shell"):
        p = sub.add_parser(name)
        p.add_argument("--workdir", help="host directory shared read-write (default: new tmp dir)")
        p.add_argument("--chroot", action="store_true", help="run in the host root (chroot)")
        p.add_argument("--icount", action="store_true", help="-icount shift=0,sleep=off, 1 CPU")
        p.add_argument("--smp", type=int, default=2)
        p.add_argument("--memory", type=int, default=1024)
        p.add_argument("--timeout", type=float, default=600)
        p.add_argument("--parallel", metavar="FILE",
                       help="an ISA parallel port (LPT1, 0x378, IRQ 7) writing to FILE")
        if name == "run":
            p.add_argument("command", nargs=argparse.REMAINDER)
    a = ap.parse_args(argv)
    try:
        if a.cmd in ("check", "prepare"):
            problems = check_prerequisites()
            for p in problems:
                print(f"missing: {p}")
            if problems:
                return 1
            k = find_kernel()
            print(f"[vm] kernel {k.release}: {k.vmlinuz}")
            if a.cmd == "prepare":
                v = pvh_vmlinux(k)
                print(f"[vm] PVH kernel: {v}" if v else
                      "[vm] no PVH entry in this kernel: booting the bzImage (slower)")
            return 0
        if a.cmd == "run":
            cmd = a.command[1:] if a.command[:1] == ["--"] else a.command
            if not cmd:
                ap.error("run: no command given")
            g = _guest(a)
            try:
                t0 = time.monotonic()
                rc, out = g.run(" ".join(cmd) if len(cmd) == 1 else shlex.join(cmd),
                                a.timeout, chroot=a.chroot)
                sys.stdout.write(out)
                print(f"[vm] exit {rc} after {time.monotonic() - t0:.2f} s", file=sys.stderr)
                g.check_kernel_log()
                return rc
            finally:
                g.close()
        g = _guest(a)
        try:
            prompt = "guest(chroot)$ " if a.chroot else "guest$ "
            while True:
                try:
                    line = input(prompt)
                except EOFError:
                    break
                if line.strip():
                    rc, out = g.run(line, a.timeout, chroot=a.chroot)
                    sys.stdout.write(out)
                    if rc:
                        print(f"[exit {rc}]")
        finally:
            g.close()
        return 0
    except (GuestError, VMSetupError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
