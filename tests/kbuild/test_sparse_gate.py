"""kbuild tier: the sparse gate of `iec2kmod build --sparse` can fail.  A
module with a known sparse finding (a __user pointer dereferenced) must
come back with that warning, and the same module without it with none."""

from __future__ import annotations

import pytest

from iec2kmod import kbuild

SRC = """// SPDX-License-Identifier: GPL-2.0-only OR MIT
#include <linux/module.h>

static int peek(int %s *p)
{
	return *p;
}

static int __init sg_init(void)
{
	return peek(NULL);
}

module_init(sg_init);
MODULE_LICENSE("Dual MIT/GPL");
"""


def _build(tmp_path, annotation):
    d = tmp_path / ("bad" if annotation else "good")
    d.mkdir()
    (d / "sg.c").write_text(SRC % annotation if annotation else SRC.replace(" %s", ""))
    (d / "Kbuild").write_text("obj-m += sg.o\n")
    return kbuild.build_modules(str(d), sparse=True, jobs=1)


@pytest.mark.kbuild
def test_sparse_reports_a_user_pointer_dereference(tmp_path):
    bad = _build(tmp_path, "__user")
    assert bad.ok, bad.output
    assert any("dereference of noderef expression" in w for w in bad.warnings()), bad.output
    good = _build(tmp_path, "")
    assert good.ok, good.output
    assert good.warnings() == [], good.output
