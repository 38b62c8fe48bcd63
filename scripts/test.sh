#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Runs every test tier: unit, execution, kbuild, container, QEMU.
# A tier whose prerequisites are missing fails and says what to install
# (run scripts/setup.sh); nothing is skipped silently.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
exec "${PYTHON:-python3}" -m pytest -q "$@"
