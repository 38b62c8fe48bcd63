# SPDX-License-Identifier: MIT
"""A module directory make cannot name in M= (white space, ':', '#', '$') is
refused before make runs, with the path and the character: make split
'build/OpenPLC Runtime v4/src' at the space and failed deep in kbuild."""

import pytest

from iec2kmod import kbuild


@pytest.mark.parametrize("name", ["with space", "a:b", "x#y", "d$z"])
def test_a_path_make_cannot_take_is_refused(tmp_path, name):
    d = tmp_path / name
    d.mkdir()
    with pytest.raises(kbuild.KbuildError, match="kbuild cannot build in .*: its path holds"):
        kbuild.build_modules(str(d), kdir=str(tmp_path))
