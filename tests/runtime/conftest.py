# SPDX-License-Identifier: MIT
"""Fixtures for the runtime tests; helpers live in rt_helpers.py."""
import pytest

from rt_helpers import Builder


@pytest.fixture(scope="session")
def builder(tmp_path_factory):
    return Builder(tmp_path_factory.mktemp("rtbuild"))
