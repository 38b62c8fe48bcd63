# SPDX-License-Identifier: MIT
"""plc-manager's errors: each carries the one line the user sees."""


class PLCError(Exception):
    """A refused or failed operation; ``str(e)`` is the message."""

    exit_code = 1


class NotLoaded(PLCError):
    """No configuration module is loaded."""


class UsageError(PLCError):
    """Bad input on the command line (unknown variable, bad value...)."""
