# SPDX-License-Identifier: MIT
# QEMU-tier fixtures; the session guest is shared with any other conftest that
# imports the same fixtures (one boot per pytest session).
from iec2kmod.testing.vm.pytest_fixtures import (  # noqa: F401
    guest, guest_factory, guest_session, guest_tmp_path, guest_workdir, kdir)
