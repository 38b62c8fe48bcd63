# SPDX-License-Identifier: MIT
"""The live part of scripts/demo.sh: boot Debian's PREEMPT_RT kernel in QEMU,
run plc-manager inside it (the host's Python through the guest's chroot),
and show load, live status and variables, a hot swap, and stop.

    python3 scripts/demo_live.py WORKDIR PROJECT_DIR VARIANT_DIR WATCH_VAR...
"""

from __future__ import annotations

import shlex
import sys
import time

from iec2kmod.testing.vm import Guest, GuestError

T0 = time.monotonic()


def say(msg: str) -> None:
    print(f"[demo {time.monotonic() - T0:5.0f}s] {msg}", flush=True)


def main() -> int:
    workdir, project, variant, *watch = sys.argv[1:]
    say("booting Debian's PREEMPT_RT kernel in QEMU (TCG)")
    g = Guest(workdir, console_log=f"{workdir}/guest-console.log")
    try:
        g.start()
        say(f"guest up in {g.boot_seconds or 0:.1f} s: "
            f"{g.run('uname -r; cat /sys/kernel/realtime').output.split()[0]}, "
            f"PREEMPT_RT")
        say("starting the host's Python in the guest (imports pyroute2 once, ~20 s "
            "under emulation)")
        g.start_pyserver()
        mark = g.log_mark()

        def pm(*args, timeout=300):
            print(f"\n  guest# plc-manager {' '.join(shlex.quote(str(a)) for a in args)}",
                  flush=True)
            r = g.pyrun(script="plc-manager", argv=[str(a) for a in args], timeout=timeout)
            for line in r.output.rstrip().splitlines():
                print(f"  {line}")
            sys.stdout.flush()
            if r.exit_code != 0:
                raise SystemExit(f"[demo] plc-manager {args[0]} failed (exit {r.exit_code})")
            return r.output

        say("load the configuration: configuration module, program types, resources; "
            "start the tasks")
        pm("load", project)
        say("live status")
        pm("status")
        say("live variables (the phase timer runs)")
        pm("watch", *watch, "--interval", "1.5", "--count", "3")
        say("a pedestrian presses the button (write an input, IEC literal)")
        pm("write", "%IX0.0", "TRUE")
        pm("read", "plc.crossing.ped_request", "plc.crossing.phase", "%IX0.0")
        say("hot swap to the rebuilt 'rush hour' variant (shorter phases, same interface): "
            "the light keeps its phase and timers")
        pm("swap", variant)
        say("the same light, now in rush-hour phases")
        pm("watch", *watch, "--interval", "1.5", "--count", "4")
        pm("status")
        say("stop: stop the tasks, remove every module")
        pm("stop")
        rc = g.run("grep -c '^iec_' /proc/modules").output.strip()
        say(f"modules of the configuration still loaded: {rc}")
        g.check_kernel_log(since=mark)
        say("kernel log clean: no WARNING, BUG, Oops or 'scheduling while atomic'")
    except GuestError as e:
        print(f"[demo] the guest failed: {e}", file=sys.stderr)
        return 1
    finally:
        g.close()
    say("done")
    return 0


if __name__ == "__main__":
    sys.exit(main())
