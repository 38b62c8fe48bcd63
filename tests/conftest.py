# SPDX-License-Identifier: MIT
"""Settings for every tier.

Module builds go through the content-addressed build cache
(iec2kmod/buildcache.py) under $IEC2KMOD_CACHE/kbuild unless
IEC2KMOD_BUILD_CACHE is set (``off`` builds every time): a tree whose
sources, headers, compiler and make arguments did not change since a
previous run is restored with the output (warnings included) that its real
build printed.  Subprocesses (``iec2kmod build``) inherit the setting."""

import os


def pytest_configure(config):
    if "IEC2KMOD_BUILD_CACHE" not in os.environ:
        base = os.environ.get("IEC2KMOD_CACHE", "/var/cache/iec2kmod")
        os.environ["IEC2KMOD_BUILD_CACHE"] = os.path.join(base, "kbuild")
