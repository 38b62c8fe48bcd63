#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Runs every test tier: unit, execution, kbuild, container, QEMU.
# A tier whose prerequisites are missing fails and says what to install
# (run scripts/setup.sh); nothing is skipped silently.
#
#   scripts/test.sh              every tier, in two lanes side by side
#   scripts/test.sh ARGS...      one pytest run with ARGS (e.g. tests/unit -k name)
#
# The two lanes are independent pytest runs of disjoint test sets: the QEMU
# tier (a single-threaded TCG guest most of the time) beside every other
# tier (compilers, z3, the interpreter), so both cores work.  Each lane has
# its own --basetemp; lane 1 reports as it runs, lane 2's report follows
# when it has finished, and the script fails when either fails.
set -uo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
PY=${PYTHON:-python3}

if [ "$#" -gt 0 ]; then
    exec "$PY" -m pytest -q "$@"
fi

tmp=$(mktemp -d "${TMPDIR:-/tmp}/iec2kmod-test.XXXXXX")
t0=$(date +%s)
"$PY" -m pytest -q --basetemp="$tmp/qemu" tests/qemu > "$tmp/qemu.log" 2>&1 &
qemu_pid=$!
echo "=================== lane 1: unit, execution, kbuild, container, verify ... (tests/ without tests/qemu) ==================="
"$PY" -m pytest -q --basetemp="$tmp/rest" -p no:cacheprovider --ignore=tests/qemu tests
rest_rc=$?
t_rest=$(( $(date +%s) - t0 ))
echo "=================== lane 2: QEMU tier (tests/qemu; lane 1 took ${t_rest} s, waiting for lane 2) ==================="
wait "$qemu_pid"; qemu_rc=$?
t_all=$(( $(date +%s) - t0 ))
cat "$tmp/qemu.log"
echo "=================== lanes: tests/ without qemu exit $rest_rc in ${t_rest} s; tests/qemu exit $qemu_rc; all done in ${t_all} s ==================="
if [ "$rest_rc" = 0 ] && [ "$qemu_rc" = 0 ]; then
    rm -rf "$tmp"
    exit 0
fi
echo "(logs and test directories kept in $tmp)"
exit 1
