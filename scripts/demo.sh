#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The main job, end to end, on a fresh Debian bookworm machine (as root):
#   1. set everything up (scripts/setup.sh);
#   2. check every example project;
#   3. compile examples/traffic_light and build its kernel modules;
#   4. rebuild a variant of it with another algorithm ("rush hour" phases);
#   5. boot Debian's PREEMPT_RT kernel in QEMU, and inside it:
#      plc-manager load, status, watch and write variables, swap to the
#      variant while the PLC runs, stop; check the kernel log.
# Real I/O (a tank level loop on the comedi_test driver, plc-manager status
# with its bindings, a forced output seen on the device): scripts/demo_io.sh.
# A few minutes on a 2-core machine.  IEC2KMOD_DEMO_DIR sets the work
# directory (default /tmp/iec2kmod-demo; no whitespace).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
PY=${PYTHON:-python3}
T0=$SECONDS
step() { printf '\n[demo %4ds] == %s\n' "$((SECONDS - T0))" "$*"; }

step "1/5 setup (scripts/setup.sh)"
./scripts/setup.sh

step "2/5 iec2kmod check, every example"
EXAMPLE=${1:-examples/two_resources}
iec2kmod check "$EXAMPLE"
for d in examples/*/; do
    printf '  %-32s' "$d"
    iec2kmod check "$d" >/dev/null 2>&1 && echo ok || { echo FAILED; iec2kmod check "$d"; exit 1; }
done

WORK=${IEC2KMOD_DEMO_DIR:-/tmp/iec2kmod-demo}
case "$WORK" in *[[:space:]]*) echo "IEC2KMOD_DEMO_DIR must not contain whitespace" >&2; exit 2 ;; esac
rm -rf "$WORK"
mkdir -p "$WORK/src_rush"

step "3/5 compile examples/traffic_light and build its modules (kbuild, W=1)"
iec2kmod gen examples/traffic_light -o "$WORK/crossing"
iec2kmod build "$WORK/crossing"

step "4/5 rebuild a variant: 'rush hour' phases (same interface, another algorithm)"
sed -e 's/phase_time := T#[23]s;/phase_time := T#1s;/' \
    -e 's/SEL(ped_request, T#30s, T#10s)/SEL(ped_request, T#6s, T#3s)/' \
    -e 's/phase_time := T#20s;/phase_time := T#4s;/' \
    -e 's/phase_time := T#12s;/phase_time := T#3s;/' \
    -e 's/phase_time := T#5s;/phase_time := T#2s;/' \
    examples/traffic_light/traffic_light.st > "$WORK/src_rush/traffic_light.st"
if cmp -s examples/traffic_light/traffic_light.st "$WORK/src_rush/traffic_light.st"; then
    echo "the variant is identical to the example (edit scripts/demo.sh)" >&2; exit 1
fi
diff examples/traffic_light/traffic_light.st "$WORK/src_rush/traffic_light.st" | sed 's/^/  /' || true
iec2kmod gen "$WORK/src_rush" -o "$WORK/crossing_rush"
iec2kmod build "$WORK/crossing_rush"

step "5/5 run it for real: PREEMPT_RT kernel in QEMU, plc-manager inside"
"$PY" -m compileall -q manager >/dev/null 2>&1 || true
"$PY" scripts/demo_live.py "$WORK" "$WORK/crossing" "$WORK/crossing_rush" \
    plc.crossing.phase plc.crossing.phase_time plc.crossing.phase_timer.ET \
    %QX0.2 %QX0.1 %QX0.5

step "done in $((SECONDS - T0)) s"
echo "Real I/O in the guest (examples/tank_io on comedi_test): ./scripts/demo_io.sh"
