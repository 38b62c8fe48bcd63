# SPDX-License-Identifier: MIT
"""The timing diagrams of TON, TOF and TP from IEC 61131-3, as step tables.

This module is an oracle written from the standard, not from any
implementation: it shares nothing with kmod_templates/runtime/iec_std_fb.c
nor with the automata of tests/reference/timers.py.  Each table transcribes
one diagram of "Standard timer function blocks - timing diagrams"
(IEC 61131-3 ed.2 2.5.2.3.4, drawn under Table 38; ed.3 6.6.3.5.5, the
figure under the table of timer function blocks: the same three diagrams).
Each diagram draws IN, Q and ET over time with the instants t0 .. t5 marked;
a row below is one instant of the diagram (or a point inside one of its
ramps) and says which feature of the drawing it comes from.

Reading the diagrams as a cyclic program sees them: the FB is called once
per cycle; IN is sampled at the call; Q and ET are read right after the
call.  The rows put every instant of the diagram on a 10 ms grid with
PT = 50 ms, so that "t0 + PT" is a call.  ET is the time elapsed since the
instant its ramp starts (a straight line from 0 in the drawing) and is
capped at PT (the flat top of the drawing).

A row ``Row(t, IN, Q, ET, why)`` means: IN has this value from t (ms) until
the next row's t; at the call at t the FB shows Q and ET (ms).  Between two
rows IN does not change, so calling the FB more often than the rows (every
cycle of a task) must still give the rows' values.

DOCUMENTED_CHOICES are not from the standard: it draws no diagram and says
nothing for PT = 0, a negative PT, or PT changed while a timer runs.  They
are the project's choices, written down in README.md ("Timers where the
standard is silent") and tested as such.
"""

from __future__ import annotations

from dataclasses import dataclass

PT_MS = 50
GRID_MS = 10


@dataclass(frozen=True)
class Row:
    t: int            # ms since the table's origin
    IN: bool          # IN from t until the next row
    Q: bool           # expected after the call at t
    ET: int           # ms, expected after the call at t
    why: str          # the diagram and its feature this row comes from
    PT: int = PT_MS   # ms, PT from t until the next row


F, T = False, True

# TON diagram: IN pulses t0..t1 (longer than PT), t2..t3 (shorter than
# PT), t4..t5 (longer than PT).  Q rises at t0+PT and t4+PT and falls with
# IN at t1 and t5; ET ramps from each rising edge of IN, stays at PT while
# IN stays TRUE, and drops to 0 when IN falls (also at t3, below PT).
TON_DIAGRAM = [
    Row(0, F, F, 0, "TON diagram, before t0: IN FALSE -> Q FALSE, ET = 0"),
    Row(20, T, F, 0, "TON t0: IN rises -> ET starts its ramp from 0, Q stays FALSE"),
    Row(40, T, F, 20, "TON t0..t0+PT: ET = t - t0 rises while IN is TRUE, Q FALSE"),
    Row(60, T, F, 40, "TON t0..t0+PT: ET below PT, Q still FALSE"),
    Row(70, T, T, 50, "TON t0+PT: ET reaches PT -> Q rises"),
    Row(90, T, T, 50, "TON t0+PT..t1: ET holds at PT, Q TRUE while IN stays TRUE"),
    Row(110, F, F, 0, "TON t1: IN falls -> Q falls and ET drops to 0 at once"),
    Row(130, F, F, 0, "TON t1..t2: IN FALSE -> Q FALSE, ET = 0"),
    Row(150, T, F, 0, "TON t2: IN rises again -> a new ramp from 0"),
    Row(170, T, F, 20, "TON t2..t3: ET rises"),
    Row(180, F, F, 0, "TON t3 < t2+PT: IN drops before PT -> Q stays FALSE, ET resets to 0"),
    Row(200, F, F, 0, "TON t2+PT passes with IN FALSE: Q never rose for the short pulse"),
    Row(230, T, F, 0, "TON t4: IN rises -> ramp from 0"),
    Row(270, T, F, 40, "TON t4..t4+PT: ET rises"),
    Row(280, T, T, 50, "TON t4+PT: ET reaches PT -> Q rises"),
    Row(320, T, T, 50, "TON t4+PT..t5: ET holds at PT while IN stays TRUE"),
    Row(330, F, F, 0, "TON t5: IN falls -> Q FALSE, ET = 0"),
    Row(360, F, F, 0, "TON after t5: nothing runs while IN is FALSE"),
]

# TOF diagram: IN pulses t0..t1, t2..t3, t4..t5, the gap t3..t4 shorter
# than PT.  Q rises with IN at t0 and t2 and falls PT after IN fell (t1+PT,
# t5+PT), not at t3+PT because IN came back at t4; ET ramps from each
# falling edge of IN, holds at PT while IN stays FALSE, drops to 0 when IN
# rises.
TOF_DIAGRAM = [
    Row(0, F, F, 0, "TOF diagram, before t0: IN FALSE and no falling edge yet -> Q FALSE, ET = 0"),
    Row(20, T, T, 0, "TOF t0: IN rises -> Q rises at once, ET = 0"),
    Row(50, T, T, 0, "TOF t0..t1: IN TRUE -> Q TRUE, ET stays 0"),
    Row(60, F, T, 0, "TOF t1: IN falls -> ET starts its ramp from 0, Q stays TRUE"),
    Row(80, F, T, 20, "TOF t1..t1+PT: ET = t - t1 rises, Q TRUE"),
    Row(100, F, T, 40, "TOF t1..t1+PT: ET below PT, Q still TRUE"),
    Row(110, F, F, 50, "TOF t1+PT: ET reaches PT -> Q falls"),
    Row(140, F, F, 50, "TOF t1+PT..t2: ET holds at PT while IN stays FALSE"),
    Row(150, T, T, 0, "TOF t2: IN rises -> Q rises, ET resets to 0"),
    Row(180, F, T, 0, "TOF t3: IN falls -> ramp from 0, Q stays TRUE"),
    Row(200, F, T, 20, "TOF t3..t4: ET rises"),
    Row(210, T, T, 0, "TOF t4 < t3+PT: IN rises before PT -> Q never falls, ET resets to 0"),
    Row(230, T, T, 0, "TOF t3+PT passes with IN TRUE: Q stays TRUE"),
    Row(260, F, T, 0, "TOF t5: IN falls -> ramp from 0"),
    Row(300, F, T, 40, "TOF t5..t5+PT: ET rises, Q TRUE"),
    Row(310, F, F, 50, "TOF t5+PT: ET reaches PT -> Q falls"),
    Row(360, F, F, 50, "TOF after t5+PT: ET holds at PT while IN stays FALSE"),
]

# TP diagram: a rising edge of IN starts a pulse of Q exactly PT long
# (t0, t2, t4).  IN held longer than PT (t0..t1, t4..t5) does not lengthen
# it and keeps ET at PT until IN falls; IN pulsing during a running pulse
# (just after t2) neither shortens nor restarts it, and at t2+PT, IN being
# FALSE, ET drops to 0 with Q.
TP_DIAGRAM = [
    Row(0, F, F, 0, "TP diagram, before t0: IN FALSE -> Q FALSE, ET = 0"),
    Row(20, T, T, 0, "TP t0: IN rises -> Q rises, ET starts its ramp from 0"),
    Row(40, T, T, 20, "TP t0..t0+PT: ET = t - t0 rises, Q TRUE"),
    Row(70, T, F, 50, "TP t0+PT: ET reaches PT -> Q falls although IN is still TRUE"),
    Row(90, T, F, 50, "TP t0+PT..t1: ET holds at PT while IN stays TRUE"),
    Row(100, F, F, 0, "TP t1: IN falls after the pulse -> ET drops to 0"),
    Row(150, T, T, 0, "TP t2: IN rises -> a new pulse, ET from 0"),
    Row(160, F, T, 10, "TP t2..t2+PT: IN falls during the pulse -> ignored, Q TRUE, ET runs on"),
    Row(170, T, T, 20, "TP t2..t2+PT: IN rises again during the pulse -> ignored, ET not restarted"),
    Row(180, F, T, 30, "TP t2..t2+PT: IN pulses during a running pulse are ignored"),
    Row(190, F, T, 40, "TP t2..t2+PT: ET keeps rising"),
    Row(200, F, F, 0, "TP t2+PT: pulse ends with IN FALSE -> Q falls and ET drops to 0"),
    Row(220, F, F, 0, "TP t2+PT..t4: IN FALSE -> Q FALSE, ET = 0"),
    Row(250, T, T, 0, "TP t4: IN rises -> a new pulse"),
    Row(280, T, T, 30, "TP t4..t4+PT: ET rises"),
    Row(300, T, F, 50, "TP t4+PT: the pulse is PT long, not as long as IN -> Q falls"),
    Row(320, T, F, 50, "TP t4+PT..t5: ET holds at PT while IN stays TRUE"),
    Row(330, F, F, 0, "TP t5: IN falls -> ET drops to 0"),
    Row(360, F, F, 0, "TP after t5: IN FALSE -> Q FALSE, ET = 0"),
]

DIAGRAMS = {"TON": TON_DIAGRAM, "TOF": TOF_DIAGRAM, "TP": TP_DIAGRAM}


def _choice(rows, pt):
    return [Row(r.t, r.IN, r.Q, r.ET, r.why, pt) for r in rows]


# The project's choices where the standard is silent (README.md, "Timers
# where the standard is silent").  PT = 0: the delay is over in the cycle
# that starts it; a negative PT is PT = 0 (ET is never negative); PT is read
# at every call and compared with the elapsed time, and an expired timer
# stays expired (showing ET = the current PT) until IN changes.
_PT0 = {
    "TON": [
        Row(0, F, F, 0, "choice PT<=0: TON idle"),
        Row(10, T, T, 0, "choice PT<=0: TON Q rises in the cycle IN rises, ET = 0"),
        Row(40, T, T, 0, "choice PT<=0: TON Q stays TRUE, ET = PT = 0"),
        Row(50, F, F, 0, "choice PT<=0: TON Q falls with IN"),
    ],
    "TOF": [
        Row(0, F, F, 0, "choice PT<=0: TOF idle"),
        Row(10, T, T, 0, "choice PT<=0: TOF Q rises with IN"),
        Row(30, F, F, 0, "choice PT<=0: TOF Q falls in the cycle IN falls, ET = 0"),
        Row(60, F, F, 0, "choice PT<=0: TOF stays off"),
    ],
    "TP": [
        Row(0, F, F, 0, "choice PT<=0: TP idle"),
        Row(10, T, F, 0, "choice PT<=0: TP gives no pulse on a rising edge"),
        Row(30, F, F, 0, "choice PT<=0: TP IN falls, still no pulse"),
        Row(40, T, F, 0, "choice PT<=0: TP a second edge, no pulse"),
    ],
}

_PT_CHANGE = {
    "TON": [
        Row(0, T, F, 0, "choice PT change: TON starts timing"),
        Row(20, T, F, 20, "choice PT change: TON timing at PT = 50"),
        Row(30, T, F, 30, "choice PT change: TON PT raised to 100 while timing extends the delay",
            100),
        Row(60, T, F, 60, "choice PT change: TON still timing past the old PT", 100),
        Row(100, T, T, 100, "choice PT change: TON expires at the new PT", 100),
        Row(110, T, T, 40, "choice PT change: TON expired; PT lowered -> Q stays TRUE, ET = new PT",
            40),
        Row(120, F, F, 0, "choice PT change: TON IN falls -> reset", 40),
        Row(130, T, F, 0, "choice PT change: TON starts timing again", 50),
        Row(150, T, F, 20, "choice PT change: TON timing", 50),
        Row(160, T, T, 20, "choice PT change: TON PT lowered below ET -> expires at this call, "
            "ET = new PT", 20),
        Row(170, T, T, 90, "choice PT change: TON expired; PT raised -> Q stays TRUE, ET = new PT",
            90),
    ],
    "TOF": [
        Row(0, T, T, 0, "choice PT change: TOF on"),
        Row(10, F, T, 0, "choice PT change: TOF IN falls, timing at PT = 50"),
        Row(30, F, T, 20, "choice PT change: TOF timing"),
        Row(40, F, T, 30, "choice PT change: TOF PT raised to 100 extends the delay", 100),
        Row(90, F, T, 80, "choice PT change: TOF still TRUE past the old PT", 100),
        Row(110, F, F, 100, "choice PT change: TOF falls at the new PT", 100),
        Row(120, F, F, 70, "choice PT change: TOF expired; ET shows the current PT", 70),
        Row(130, T, T, 0, "choice PT change: TOF on again", 50),
        Row(140, F, T, 0, "choice PT change: TOF IN falls", 50),
        Row(160, F, T, 20, "choice PT change: TOF timing", 50),
        Row(170, F, F, 10, "choice PT change: TOF PT lowered below ET -> Q falls, ET = new PT",
            10),
    ],
    "TP": [
        Row(0, T, T, 0, "choice PT change: TP pulse starts at PT = 50"),
        Row(20, T, T, 20, "choice PT change: TP pulse running"),
        Row(30, F, T, 30, "choice PT change: TP PT raised to 100 lengthens the running pulse",
            100),
        Row(90, F, T, 90, "choice PT change: TP still TRUE past the old PT", 100),
        Row(100, F, F, 0, "choice PT change: TP pulse ends at the new PT, IN FALSE -> ET 0", 100),
        Row(110, T, T, 0, "choice PT change: TP new pulse", 50),
        Row(130, T, T, 20, "choice PT change: TP pulse running", 50),
        Row(140, T, F, 10, "choice PT change: TP PT lowered below ET ends the pulse, ET = new PT",
            10),
        Row(150, T, F, 60, "choice PT change: TP expired with IN TRUE; ET shows the current PT",
            60),
        Row(160, F, F, 0, "choice PT change: TP IN falls -> ET 0", 60),
    ],
}

DOCUMENTED_CHOICES = {}
for _k in ("TON", "TOF", "TP"):
    DOCUMENTED_CHOICES[f"{_k}_PT_zero"] = (_k, _choice(_PT0[_k], 0))
    DOCUMENTED_CHOICES[f"{_k}_PT_negative"] = (_k, _choice(_PT0[_k], -20))
    DOCUMENTED_CHOICES[f"{_k}_PT_changed"] = (_k, _PT_CHANGE[_k])

# every table: name -> (FB, rows)
TABLES = {f"{k}_diagram": (k, rows) for k, rows in DIAGRAMS.items()}
TABLES.update(DOCUMENTED_CHOICES)


def calls(rows, cycle_ms=GRID_MS):
    """The calls of a task with period cycle_ms that sees this table:
    [(t_ms, IN, PT_ms, row or None)], one per cycle from 0 to the last row;
    row is the table row to check at that call."""
    by_t = {r.t: r for r in rows}
    assert len(by_t) == len(rows), "two rows at the same instant"
    assert all(r.t % cycle_ms == 0 for r in rows), "a row is not on the cycle grid"
    assert [r.t for r in rows] == sorted(by_t), "rows out of order"
    out, cur = [], rows[0]
    for t in range(0, rows[-1].t + 1, cycle_ms):
        if t in by_t:
            cur = by_t[t]
        out.append((t, cur.IN, cur.PT, by_t.get(t)))
    return out


def check_table_is_well_formed(rows):
    """Guards the tables themselves: a row inside a ramp must lie on it."""
    for r in rows:
        assert 0 <= r.ET, r
        assert r.ET <= max(r.PT, 0), r
