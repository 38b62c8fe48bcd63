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


# Seconds spent per tier (the folder under tests/), printed at the end of
# every run so CI's log shows where its time goes (issue 24): the setup,
# call and teardown of each test, a session fixture (a guest boot, an image
# build) counted in the tier of the first test that asked for it.
_TIER_TIME: dict = {}
_TIER_TESTS: dict = {}


def _tier(nodeid: str) -> str:
    parts = nodeid.split("::", 1)[0].split("/")
    return parts[1] if len(parts) > 2 and parts[0] == "tests" else parts[0]


def pytest_runtest_logreport(report):
    tier = _tier(report.nodeid)
    _TIER_TIME[tier] = _TIER_TIME.get(tier, 0.0) + report.duration
    if report.when == "call" or (report.when == "setup" and report.outcome != "passed"):
        _TIER_TESTS[tier] = _TIER_TESTS.get(tier, 0) + 1


def pytest_terminal_summary(terminalreporter):
    if not _TIER_TIME:
        return
    rows = sorted(_TIER_TIME.items(), key=lambda kv: -kv[1])
    terminalreporter.write_sep("-", "seconds per tier (setup + call + teardown)")
    for tier, secs in rows:
        terminalreporter.write_line(f"{tier:<14} {secs:8.1f} s  {_TIER_TESTS.get(tier, 0):5d} tests")
