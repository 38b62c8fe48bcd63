#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Real I/O, end to end (issue 26; README "Real I/O"): examples/tank_io, a PI
# tank level loop whose level input and valve output are REALs in volts,
# bound by tank_io.iomap to comedi_test (the comedi driver that simulates a
# DAQ card at /dev/comedi0), runs in Debian's PREEMPT_RT kernel in QEMU:
#   1. iec2kmod check and gen examples/tank_io, build its modules;
#   2. boot the guest with comedi, kcomedilib and comedi_test; in it:
#      plc-manager load (which checks /dev/comedi0 first), status with the
#      I/O bindings and their last samples, the device's channels read from
#      user space while the level climbs, the valve forced by its address
#      (%QD4) and seen on the device, stop (the valve's safe 0 V).
# Run scripts/setup.sh first (scripts/demo.sh does).  About two minutes on a
# 2-core machine.  IEC2KMOD_DEMO_DIR sets the work directory (default
# /tmp/iec2kmod-demo-io; no whitespace).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
PY=${PYTHON:-python3}
T0=$SECONDS
step() { printf '\n[demo-io %4ds] == %s\n' "$((SECONDS - T0))" "$*"; }

WORK=${IEC2KMOD_DEMO_DIR:-/tmp/iec2kmod-demo-io}
case "$WORK" in *[[:space:]]*) echo "IEC2KMOD_DEMO_DIR must not contain whitespace" >&2; exit 2 ;; esac
rm -rf "$WORK"
mkdir -p "$WORK"

step "1/2 check, compile and build examples/tank_io (its I/O map: tank_io.iomap)"
sed 's/^/  /' examples/tank_io/tank_io.iomap
"$PY" -m iec2kmod.cli check examples/tank_io
"$PY" -m iec2kmod.cli gen examples/tank_io -o "$WORK/tank"
"$PY" -m iec2kmod.cli build "$WORK/tank"

step "2/2 run it on comedi_test: PREEMPT_RT kernel in QEMU, plc-manager inside"
"$PY" -m compileall -q manager >/dev/null 2>&1 || true
"$PY" scripts/demo_io_live.py "$WORK" "$WORK/tank"

step "done in $((SECONDS - T0)) s"
