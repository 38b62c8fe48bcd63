# SPDX-License-Identifier: MIT
"""QEMU (TCG) guest harness: boot Debian's PREEMPT_RT kernel once, run commands
in it, insert modules built on the host, run the host's Python in it.

See :mod:`iec2kmod.testing.vm.guest` and, for pytest, :mod:`iec2kmod.testing.vm.pytest_fixtures`.
"""

from .guest import (KERNEL_LOG_PATTERNS, CommandFailed, CommandResult, Guest,
                    GuestBootError, GuestCommandTimeout, GuestDied, GuestError,
                    GuestTimeout, KernelLogError, KernelLogRead, kernel_log_problems)
from .kernel import (KernelImage, VMSetupError, check_prerequisites, find_kernel,
                     pvh_vmlinux)

__all__ = [
    "Guest", "GuestError", "GuestBootError", "GuestDied", "GuestTimeout",
    "GuestCommandTimeout", "CommandFailed", "KernelLogError", "KernelLogRead", "CommandResult",
    "KERNEL_LOG_PATTERNS", "kernel_log_problems", "KernelImage", "VMSetupError",
    "check_prerequisites", "find_kernel", "pvh_vmlinux",
]
