# SPDX-License-Identifier: MIT
"""Independent Python reference models of the IEC 61131-3 runtime."""
