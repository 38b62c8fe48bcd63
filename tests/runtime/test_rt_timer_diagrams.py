# SPDX-License-Identifier: MIT
"""The C timers (kmod_templates/runtime/iec_std_fb.c, through ctypes)
against the standard's timing diagrams transcribed in
tests/reference/timer_diagrams.py, and against the project's documented
choices where the standard is silent.  The same tables run through whole
programs and every simulation engine in tests/execution/test_engine_timer_diagrams.py."""
import ctypes as C

import pytest

from reference import timer_diagrams as td
from rt_helpers import rt
from test_rt_fb import Ctx, Timer, wrap64

pytestmark = pytest.mark.execution

MS = 1_000_000


@pytest.fixture(scope="module")
def lib(builder):
    return C.CDLL(str(builder.build(rt("iec_std_fb.c"), shared=True)))


def drive(lib, fn, rows, cycle_ms, t0_ns):
    """Calls the FB once per cycle over the table; the mismatches."""
    body = getattr(lib, fn)
    fb, ctx, bad = Timer(), Ctx(), []
    for t, IN, PT, row in td.calls(rows, cycle_ms):
        ctx.now_ns = wrap64(t0_ns + t * MS)
        fb.in_, fb.pt = IN, PT * MS
        body(C.byref(fb), C.byref(ctx))
        if row is not None and (bool(fb.q), fb.et) != (row.Q, row.ET * MS):
            bad.append(f"t={t} ms IN={int(IN)} PT={PT} ms: C gives Q={bool(fb.q)} "
                       f"ET={fb.et / MS:g} ms, expected Q={row.Q} ET={row.ET} ms "
                       f"({row.why})")
    return bad


def test_tables_are_well_formed():
    assert set(td.DIAGRAMS) == {"TON", "TOF", "TP"}
    for name, (kind, rows) in td.TABLES.items():
        td.check_table_is_well_formed(rows)
        assert len(td.calls(rows)) > len(rows) or name.endswith(("zero", "negative"))


@pytest.mark.parametrize("table", sorted(td.TABLES))
@pytest.mark.parametrize("cycle_ms", [10, 5, 1])
@pytest.mark.parametrize("t0_ns", [0, 2**63 - 120 * MS, -77 * MS])
@pytest.mark.parametrize("suffix", ["", "_ltime"])
def test_c_timer_follows_the_diagram(lib, table, cycle_ms, t0_ns, suffix):
    kind, rows = td.TABLES[table]
    bad = drive(lib, f"iec_fb_{kind.lower()}{suffix}", rows, cycle_ms, t0_ns)
    assert not bad, f"{table}, cycle {cycle_ms} ms:\n" + "\n".join(bad)


def test_the_oracle_catches_a_misread_timer(lib):
    """The tables fail a timer that reads the diagram wrongly: TP driven as
    TON (a pulse as long as IN), TOF driven as TON."""
    assert drive(lib, "iec_fb_ton", td.TP_DIAGRAM, 10, 0)
    assert drive(lib, "iec_fb_ton", td.TOF_DIAGRAM, 10, 0)
    assert drive(lib, "iec_fb_tp", td.TON_DIAGRAM, 10, 0)
