# SPDX-License-Identifier: MIT
"""The benchmarks that boot the QEMU guest, at their smoke size (``--smoke``),
so that none rots unseen: each must exit 0 and print its figures.  The
host-only benchmarks are in tests/benchmarks/test_benchmarks_smoke.py.

A guest boot (and its first commands) costs 30-70 s on the loaded CI
machine, and the seven scripts asked for eight guests of two kinds: the
icount guest (one vCPU, virtual time) and the TCG guest (two vCPUs).  Here
each script runs in this process as its ``python3 benchmarks/NAME.py
--smoke`` would (its own ``__main__``, arguments, output, exit status), with
``iec2kmod.testing.vm.Guest`` standing for a guest of this module's pool:
the script's ``Guest(...)`` call is checked against the real signature, its
``start()`` hands it the pool's running guest of the same kind (booted once,
again only when a script leaves it dead), its ``close()`` gives it back
(``plc-manager stop`` when the script left its configuration loaded; a
guest that still has modules after that is closed, the next script gets a
new one).  The scripts' work directories are made in
the pool's guest work directory, which every pool guest mounts.  Every pool
guest has a parallel port (its file is not the script's: guest.parallel), so
irq_latency's icount guest is the one of jitter, scale and soak.  Running a
script on its own (``python3 benchmarks/jitter.py --smoke``) boots its own
guest as before."""

from __future__ import annotations

import inspect
import os
import runpy
import signal
import sys
import tempfile
import time
from pathlib import Path

import pytest

import iec2kmod.testing.vm as vm
from kmod_helpers import kernel_modules, loaded_modules

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from test_benchmarks_smoke import BENCH, NUM, QEMU_ONLY, ROOT, check_figures  # noqa: E402

pytestmark = pytest.mark.qemu

SCRIPT_TIMEOUT = 1800     # s, per script (it was the subprocess timeout)

GUEST = {
    "swap_latency": [rf"^load \(total, tasks running\) +{NUM} +{NUM} +{NUM} +{NUM}$",
                     rf"^    command -> new body running +{NUM} +{NUM}",
                     r"^overruns of the 10 tasks during 3 swaps: 0 \(1 loads, 3 swaps\)$"],
    "netlink_fuzz": [r"^netlink fuzz: seed 1, 500 messages in .*; 0 accepted that must not "
                     r"be; 0 unanswered",
                     r"^round 1 \(seed 1\): \d+ s, 0 problems$",
                     r"^plc-manager stop: exit 0; modules left: none$"],
    "irq_latency": [rf"^IEC task onack \(PRIO 0\) +\d+ +{NUM} +{NUM} +{NUM} +{NUM} +"
                    r"\(\d+ IRQ 7 entries, 0 merged\)$",
                    rf"^kthread irqwake +\d+ +{NUM} +{NUM} +{NUM} +{NUM} +"
                    r"\(\d+ IRQ 7 entries, 0 merged\)$",
                    r"^plc: own: .* acks (\d+) of \1 STROBE-low writes$",
                    r"^kthread: own: .* irqs (\d+) of \1 STROBE-low writes$",
                    rf"^median ratio plc/kthread: {NUM}$"],
    "jitter": [rf"^iec2kmod ms1 alone \(overruns 0\) +n= +\d+ +min +{NUM} +median +{NUM}",
               r"^cyclictest loaded \(FIFO 48\) +n= +\d+ ",
               rf"^timerlat unloaded .* p99 +{NUM}",
               rf"^FPU cost: 100-iteration loop +DINT avg {NUM} us, +LREAL avg {NUM} us"],
    "netlink_flood": [rf"^idle +{NUM} +\d+ +\d+ +{NUM} +{NUM} +{NUM} +{NUM}$",
                      rf"^flood +{NUM} +\d+ +\d+ +{NUM} +{NUM} +{NUM} +{NUM}$",
                      rf"^commands: 200 in {NUM} s",
                      r"^additional overruns under the flood: \d+ \(target 0\)"],
    "soak": [r"^swaps: 3 under the 1 ms task \(icount\) .*; overruns 0 over \d+ cycles",
             r"^ +command to new body running: min .* modules left \[\]$",
             r"^cycles: 2 load/stop, modules back to 0 after each; Slab first \d+",
             r"^kills: 2 SIGKILLs "],
    "serve_load": [r"^250 variables subscribed \(100 ms\), 10 writes/s asked, "
                   rf"{NUM} s, guest clock tcg$",
                   rf"^server CPU: {NUM}% of one CPU$",
                   rf"^notifications: {NUM}/s; writes done {NUM}/s \(\d+ behind schedule\)$",
                   rf"^cycle end -> client \(ms\) +p50 +{NUM} +p99 +{NUM} +max +{NUM} "
                   r"+\(n=\d+\)$",
                   # on a loaded machine a 6 s run may see no write come back
                   rf"^write -> echo notified \(ms\) +(p50 +{NUM} +p99 +{NUM} +max +{NUM} "
                   r"+\(n=\d+\)|no sample \(n=0\))$",
                   r"^task t10: alone \d+ cycles, \d+ overruns; with the server \d+ cycles, "
                   r"\d+ overruns$"],
    "io_user_latency": [r"^user I/O loop through the Python reference daemon, 60 cycles per "
                        r"interval, guest clock: tcg$",
                        r"^ +20ms +\d+/ *[\d.]+/ *\d+/ *\d+ +[\d.]+% +\d+ +[\d.]+/ *[\d.]+/"],
    "plcopen_kernel": [r"^ld_rungs\.xml +same: \d+ variables after 100 ms",
                       r"^kernel log clean$",
                       r"^1 of 1 IEC-only projects ran in the kernel as simulated "],
    "scale": [rf"^ +4 +\d+ +{NUM} +{NUM} +{NUM} +configuration x1: ",
              rf"^  load \(command, tasks running\) min +{NUM} ",
              rf"^  stop \(command, all removed\) +min +{NUM} "],
}


def test_every_guest_benchmark_is_here():
    assert set(GUEST) == QEMU_ONLY | {"scale"}


_REAL_GUEST = vm.Guest
_KIND_DEFAULTS = {k: v.default for k, v in inspect.signature(_REAL_GUEST).parameters.items()
                  if v.default is not inspect.Parameter.empty}
# what does not make two guests different for a benchmark: every pool guest
# has a parallel port (LPT1, on a file of the pool's, guest.parallel), so a
# script that asks for one (irq_latency) shares the guest of its kind
_NOT_KIND = ("console_log", "boot_timeout", "parallel")


class GuestPool:
    """Running guests by kind (the Guest arguments but the work directory,
    the console log and the boot timeout), all on one work directory."""

    def __init__(self, workdir: Path):
        self.workdir = os.path.realpath(workdir)
        self.guests: dict = {}
        self.modules: dict = {}       # id(guest): its kernel modules after the boot
        self.boots = 0

    @staticmethod
    def kind(kw) -> tuple:
        full = {**_KIND_DEFAULTS, **kw}
        if full["icount"]:
            full["smp"] = 1           # as Guest does
        return tuple(sorted((k, repr(v)) for k, v in full.items() if k not in _NOT_KIND))

    def take(self, kw):
        key = self.kind(kw)
        g = self.guests.get(key)
        if g is None or g._proc is None or g._proc.poll() is not None or g._dead_reason:
            if g is not None:
                g.close()
            g = _REAL_GUEST(self.workdir, **{k: v for k, v in kw.items() if k not in _NOT_KIND},
                            console_log=os.path.join(self.workdir, f"console-{len(self.guests)}"
                                                     f"-{self.boots}.log"),
                            parallel=os.path.join(self.workdir, f"lpt1-{self.boots}.bin"))
            g.start()
            self.boots += 1
            self.guests[key] = g
            self.modules[id(g)] = kernel_modules(g)
        return g

    def give_back(self, g):
        """A script may end with its configuration loaded (on its own, the
        power-off ends it): stop it as plc-manager does; a guest that still
        has modules of ours, or other modules than after its boot (a driver
        the script loaded), then is closed (the next script boots a new
        one)."""
        if loaded_modules(g):
            g.pyrun(script="plc-manager", argv=["stop"], timeout=300)
        if loaded_modules(g) or kernel_modules(g) != self.modules[id(g)]:
            key = next(k for k, v in self.guests.items() if v is g)
            del self.guests[key]
            g.close()

    def close(self):
        for g in self.guests.values():
            g.close()
        self.guests.clear()


class PoolGuest:
    """What a benchmark gets for ``Guest(workdir, **kw)`` in this module."""

    pool: GuestPool = None

    def __init__(self, workdir, **kw):
        inspect.signature(_REAL_GUEST).bind(workdir, **kw)      # the real call's arguments
        real = os.path.realpath(workdir)
        if not real.startswith(self.pool.workdir + os.sep):
            raise AssertionError(f"{real} is not under the shared guest's work directory "
                                 f"{self.pool.workdir} (make it with tempfile)")
        self._kw, self._g = kw, None

    def start(self):
        self._g = self.pool.take(self._kw)
        return self

    def close(self, timeout: float = 15.0):
        g, self._g = self._g, None
        if g is not None:
            self.pool.give_back(g)

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.close()

    def __getattr__(self, name):
        if self.__dict__.get("_g") is None:
            raise vm.GuestError(f"guest not started (Guest.{name})")
        return getattr(self._g, name)


@pytest.fixture(scope="module")
def guest_pool(tmp_path_factory):
    pool = GuestPool(tmp_path_factory.mktemp("bench_guests"))
    old = os.environ.get("PYTHONPATH")
    # as `python3 benchmarks/NAME.py` from the README: this tree's packages,
    # also in the guest (which takes PYTHONPATH at its boot)
    os.environ["PYTHONPATH"] = os.pathsep.join(
        [str(ROOT / ".pypath"), str(ROOT), old or ""]).rstrip(os.pathsep)
    yield pool
    print(f"\nbenchmark smoke runs: {pool.boots} guest boots")
    pool.close()
    if old is None:
        del os.environ["PYTHONPATH"]
    else:
        os.environ["PYTHONPATH"] = old


def _timeout(signum, frame):
    raise TimeoutError(f"the benchmark ran longer than {SCRIPT_TIMEOUT} s")


def run_in_process(script: str, *extra: str, pool: GuestPool) -> tuple:
    """(exit status, seconds) of ``benchmarks/SCRIPT.py --smoke EXTRA`` run
    in this process with the pool's guests; its output goes to fd 1/2."""
    path = BENCH / f"{script}.py"
    saved = (list(sys.path), sys.argv, tempfile.tempdir, set(sys.modules))
    sys.argv = [str(path), "--smoke", *extra]
    tempfile.tempdir = pool.workdir
    PoolGuest.pool = pool
    vm.Guest = PoolGuest
    old_alarm = signal.signal(signal.SIGALRM, _timeout)
    signal.alarm(SCRIPT_TIMEOUT)
    t0 = time.monotonic()
    code = 0
    try:
        runpy.run_path(str(path), run_name="__main__")
    except SystemExit as e:
        if e.code not in (None, 0):
            code = e.code if isinstance(e.code, int) else 1
            if not isinstance(e.code, int):
                print(e.code, file=sys.stderr)
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old_alarm)
        vm.Guest = _REAL_GUEST
        sys.path[:], sys.argv, tempfile.tempdir = saved[0], saved[1], saved[2]
        # the scripts' own modules (benchmarks/*.py imported by another) go
        # with them: the next script imports its own copy, as in a process
        for name in set(sys.modules) - saved[3]:
            f = getattr(sys.modules[name], "__file__", None) or ""
            if f.startswith(str(BENCH) + os.sep):
                del sys.modules[name]
        sys.stdout.flush()
        sys.stderr.flush()
    return code, time.monotonic() - t0


@pytest.mark.parametrize("script", sorted(GUEST))
def test_guest_benchmark_smoke(script, guest_pool, capfd):
    extra = ("--guest", "4") if script == "scale" else ()
    code, secs = run_in_process(script, *extra, pool=guest_pool)
    out, err = capfd.readouterr()
    assert code == 0, f"{script} --smoke: exit {code} after {secs:.0f} s\n" \
                      f"{out[-3000:]}\n{err[-3000:]}"
    check_figures(script, out, GUEST[script])
