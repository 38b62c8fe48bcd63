"""`python3 -m iec2kmod ...` is the `iec2kmod` command (useful from a
source tree or a git worktree that is not the installed one)."""

import sys

from iec2kmod.cli import main

sys.exit(main())
