#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Sets up this machine (scripts/setup.sh) and runs the main job on an
# example project.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
./scripts/setup.sh
EXAMPLE=${1:-examples/two_resources}
echo "[demo] iec2kmod check $EXAMPLE"
iec2kmod check "$EXAMPLE"
echo "[demo] every example:"
for d in examples/*/; do
    printf '  %-32s' "$d"
    iec2kmod check "$d" >/dev/null 2>&1 && echo ok || { echo FAILED; iec2kmod check "$d"; exit 1; }
done
