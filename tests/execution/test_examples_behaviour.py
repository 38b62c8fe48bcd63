"""Every example does what its README and comments say: each is run with
`iec2kmod sim` (the CLI, with an input trace where the example needs
inputs) and its recorded CSV output is checked against behaviour read from
the example's sources and README -- phase sequences and times, hysteresis
thresholds, interlocks, counters, alarms, event tasks.

Times: a value in the CSV is the value after the task cycle that started
at that time; a task with interval I runs at 0, I, 2I, ..."""

from __future__ import annotations

import csv
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.execution

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES_ROOT = ROOT / "examples"       # the harness test points it at broken copies
EXAMPLES = sorted(p.name for p in (ROOT / "examples").iterdir() if p.is_dir())
assert len(EXAMPLES) >= 12, f"only {len(EXAMPLES)} example projects under {ROOT / 'examples'}"
S = 1_000_000_000
MS = 1_000_000


class Trace:
    """The CSV written by `iec2kmod sim --csv`: values by time."""

    def __init__(self, path: Path):
        with open(path, newline="") as fh:
            rows = list(csv.reader(fh))
        self.names = [n.upper() for n in rows[0][1:]]
        self.rows = [(int(r[0]), r[1:]) for r in rows[1:]]
        assert self.rows, "no values recorded"

    def _col(self, name):
        return self.names.index(name.upper())

    def at(self, name, t_ns):
        """The value of name after the cycles that started at or before t."""
        k = self._col(name)
        value = None
        for t, vals in self.rows:
            if t > t_ns:
                break
            value = vals[k]
        return value

    def changes(self, name, start=0, end=None):
        """[(t, value)]: the value at start, then every change until end."""
        k = self._col(name)
        out = []
        for t, vals in self.rows:
            if end is not None and t > end:
                break
            if t <= start:
                out[:] = [(start, vals[k])]
            elif not out or out[-1][1] != vals[k]:
                out.append((t, vals[k]))
        return out

    def first(self, name, value, after=0):
        """The first time at or after `after` where name has value (None: never)."""
        k = self._col(name)
        prev = None
        for t, vals in self.rows:
            if t <= after:
                prev = vals[k]
                continue
            if prev == value:
                return after
            if vals[k] == value:
                return t
            prev = vals[k]
        return after if prev == value else None

    def each_row(self, *names):
        cols = [self._col(n) for n in names]
        for t, vals in self.rows:
            yield (t, *[vals[c] for c in cols])


def simulate(tmp_path, example, duration, watch, inputs=()):
    """Runs examples/<example> for `duration` with input events
    (time, variable, value) and returns the CSV trace of `watch`."""
    args = [sys.executable, "-m", "iec2kmod.cli", "sim", str(EXAMPLES_ROOT / example),
            "--duration", duration, "--watch", ",".join(watch), "--csv", str(tmp_path / "out.csv")]
    if inputs:
        trace = tmp_path / "inputs.csv"
        trace.write_text("time,variable,value\n" +
                         "".join(f"{t},{n},{v}\n" for t, n, v in inputs))
        args += ["--inputs", str(trace)]
    p = subprocess.run(args, cwd=ROOT, capture_output=True, text=True, timeout=900)
    assert p.returncode == 0, p.stderr[-3000:]
    assert "runtime error" not in p.stderr, p.stderr
    return Trace(tmp_path / "out.csv")


def pulse(name, t_ms, width_ms):
    """A TRUE pulse of an input: (t, name, TRUE), (t + width, name, FALSE)."""
    return [(f"{t_ms}ms", name, "TRUE"), (f"{t_ms + width_ms}ms", name, "FALSE")]


BEHAVIOUR = {}


def behaviour(example):
    def register(fn):
        BEHAVIOUR.setdefault(example, []).append(fn)
        return fn
    return register


def test_every_example_has_a_behaviour_test():
    assert sorted(BEHAVIOUR) == EXAMPLES


# examples broken on purpose (a test of these tests): each still runs
# without a fault -- all that was checked before -- and its behaviour test
# must now fail
MUTANTS = {
    "traffic_light": ("traffic_light.st", "SEL(ped_request, T#30s, T#10s)",
                      "SEL(ped_request, T#25s, T#10s)"),
    "tank_level": ("tank_level.st", "stop_level := 85.0", "stop_level := 90.0"),
    "motor_il": ("star_delta.il", "STAR_TIME     : TIME := T#6s", "STAR_TIME     : TIME := T#5s"),
    "elevator": ("elevator.st", "IF door_opened AND NOT door_time.Q AND NOT light_curtain",
                 "IF door_opened AND NOT light_curtain"),
    "watchdog_event": ("watchdog.st", "PT := T#500ms", "PT := T#800ms"),
    "alarm_handler": ("alarms.st", "first_out := NOT any_latched AND NOT new_alarm",
                      "first_out := NOT new_alarm"),
}


@pytest.mark.parametrize("example", sorted(MUTANTS))
def test_behaviour_tests_fail_on_a_broken_example(tmp_path, monkeypatch, example):
    name, old, new = MUTANTS[example]
    broken = tmp_path / "examples" / example
    broken.mkdir(parents=True)
    for f in (ROOT / "examples" / example).iterdir():
        text = f.read_text()
        if f.name == name:
            assert text.count(old) == 1, (name, old)
            text = text.replace(old, new)
        (broken / f.name).write_text(text)
    # the old check passes: it runs, without a fault
    p = subprocess.run([sys.executable, "-m", "iec2kmod.cli", "sim", str(broken),
                        "--duration", "20s"], cwd=ROOT, capture_output=True, text=True,
                       timeout=900)
    assert p.returncode == 0 and "runtime error" not in p.stderr, p.stderr
    monkeypatch.setattr(sys.modules[__name__], "EXAMPLES_ROOT", tmp_path / "examples")
    failed = 0
    for k, check in enumerate(BEHAVIOUR[example]):
        run_dir = tmp_path / f"run{k}"
        run_dir.mkdir()
        try:
            check(run_dir)
        except AssertionError:
            failed += 1
    assert failed >= 1, f"no behaviour test of {example} noticed: {old} -> {new}"


# ----------------------------------------------------------- traffic_light
TL = "plc.crossing."
TL_LAMPS = ["%QX0.0", "%QX0.1", "%QX0.2", "%QX0.3", "%QX0.4", "%QX0.5", "%QX0.6", "%QX0.7"]


def _tl_lamps_follow_the_phase(tr):
    """main/side: exactly one of red, yellow, green; pedestrians: walk xor don't walk."""
    for t, phase, *lamps in tr.each_row(TL + "phase", *TL_LAMPS):
        m_red, m_yel, m_grn, s_red, s_yel, s_grn, walk, dont = [v == "TRUE" for v in lamps]
        assert m_grn == (phase == "PH_MAIN_GREEN") and m_yel == (phase == "PH_MAIN_YELLOW"), t
        assert s_grn == (phase == "PH_SIDE_GREEN") and s_yel == (phase == "PH_SIDE_YELLOW"), t
        assert m_red == (not m_grn and not m_yel) and s_red == (not s_grn and not s_yel), t
        assert walk == (phase == "PH_PED_WALK") and dont == (not walk), t
        assert not (m_grn and s_grn), t


@behaviour("traffic_light")
def test_traffic_light_phase_sequence_and_times(tmp_path):
    tr = simulate(tmp_path, "traffic_light", "125s", [TL + "phase"] + TL_LAMPS)
    # main green 30 s, yellow 3 s, all red 2 s, side green 20 s, yellow 3 s, all red 2 s
    assert tr.changes(TL + "phase") == [
        (0, "PH_MAIN_GREEN"), (30 * S, "PH_MAIN_YELLOW"), (33 * S, "PH_ALL_RED_1"),
        (35 * S, "PH_SIDE_GREEN"), (55 * S, "PH_SIDE_YELLOW"), (58 * S, "PH_ALL_RED_2"),
        (60 * S, "PH_MAIN_GREEN"), (90 * S, "PH_MAIN_YELLOW"), (93 * S, "PH_ALL_RED_1"),
        (95 * S, "PH_SIDE_GREEN"), (115 * S, "PH_SIDE_YELLOW"), (118 * S, "PH_ALL_RED_2"),
        (120 * S, "PH_MAIN_GREEN")]
    _tl_lamps_follow_the_phase(tr)


@behaviour("traffic_light")
def test_traffic_light_pedestrian_request(tmp_path):
    # the button is pressed 4 s into the main green phase
    tr = simulate(tmp_path, "traffic_light", "90s", [TL + "phase", TL + "ped_request"] + TL_LAMPS,
                  pulse("%IX0.0", 4000, 300))
    # the request shortens main green to 10 s and inserts walk (12 s) and clear (5 s)
    assert tr.changes(TL + "phase") == [
        (0, "PH_MAIN_GREEN"), (10 * S, "PH_MAIN_YELLOW"), (13 * S, "PH_PED_WALK"),
        (25 * S, "PH_PED_CLEAR"), (30 * S, "PH_ALL_RED_1"), (32 * S, "PH_SIDE_GREEN"),
        (52 * S, "PH_SIDE_YELLOW"), (55 * S, "PH_ALL_RED_2"), (57 * S, "PH_MAIN_GREEN"),
        (87 * S, "PH_MAIN_YELLOW"), (90 * S, "PH_ALL_RED_1")]     # served: no walk phase now
    # latched on the rising edge, cleared at the end of the clear phase
    assert tr.changes(TL + "ped_request") == [(0, "FALSE"), (4 * S, "TRUE"), (30 * S, "FALSE")]
    _tl_lamps_follow_the_phase(tr)


@behaviour("traffic_light")
def test_traffic_light_night_mode_flashes_yellow_at_1hz(tmp_path):
    tr = simulate(tmp_path, "traffic_light", "12s", [TL + "phase"] + TL_LAMPS,
                  [("2s", "plc.night_switch", "TRUE"), ("8s", "plc.night_switch", "FALSE")])
    yellow = tr.changes("%QX0.1", 2 * S, 8 * S - 1)
    assert yellow == tr.changes("%QX0.4", 2 * S, 8 * S - 1)      # both yellows together
    # on 500 ms, off 500 ms
    toggles = [t for t, _ in yellow[1:]]
    assert [b - a for a, b in zip(toggles, toggles[1:])] == [500 * MS] * (len(toggles) - 1)
    assert len(toggles) >= 10
    for lamp in ["%QX0.0", "%QX0.2", "%QX0.3", "%QX0.5", "%QX0.6", "%QX0.7"]:
        assert tr.changes(lamp, 2 * S, 8 * S - 1) == [(2 * S, "FALSE")], lamp
    # back to day mode: a new cycle from main green, 30 s
    assert tr.changes(TL + "phase", 8 * S) == [(8 * S, "PH_MAIN_GREEN")]
    assert tr.at("%QX0.2", 8 * S) == "TRUE" and tr.at("%QX0.3", 8 * S) == "TRUE"


# -------------------------------------------------------------- tank_level
def _raw(pct):
    """The raw analog value (0..27648) of a level in percent."""
    return round(pct * 27648 / 100)


@behaviour("tank_level")
def test_tank_level_pump_hysteresis(tmp_path):
    # the configuration overrides the setpoints: start below 25 %, stop above 85 %
    levels = [(0, 36.0), (2, 24.9), (4, 54.0), (6, 84.9), (8, 85.2), (10, 54.0), (12, 25.1),
              (14, 24.9), (16, 50.0)]
    tr = simulate(tmp_path, "tank_level", "20s", ["%QX0.0", "%QD4", "%QX0.3"],
                  [("0s", "%IX0.0", "TRUE")] +
                  [(f"{t}s", "%IW64", _raw(p)) for t, p in levels])
    # in the band the pump keeps its state; it starts below 25 % and stops above 85 %
    assert tr.changes("%QX0.0") == [(0, "FALSE"), (2 * S, "TRUE"), (8 * S, "FALSE"),
                                    (14 * S, "TRUE")]
    assert abs(float(tr.at("%QD4", 6 * S)) - 84.9) < 0.01       # level in percent for the HMI
    assert tr.changes("%QX0.3") == [(0, "FALSE")]


@behaviour("tank_level")
def test_tank_level_dry_run_and_high_alarm(tmp_path):
    # the pump starts at 1 s but the level does not rise: after 2 minutes of
    # pumping the dry-run alarm latches and stops the pump until reset
    tr = simulate(tmp_path, "tank_level", "175s", ["%QX0.0", "%QX0.1", "%QX0.3"],
                  [("0s", "%IX0.0", "TRUE"), ("0s", "%IW64", _raw(50)),
                   ("1s", "%IW64", _raw(20))] + pulse("%IX0.2", 140_000, 200) +
                  [("141s", "%IW64", _raw(60)), ("150s", "%IW64", _raw(97)),
                   ("160s", "%IW64", _raw(60))])
    dry = tr.changes("%QX0.3")
    assert [v for _, v in dry] == ["FALSE", "TRUE", "FALSE"], dry
    # the timer runs from the scan after the pump started
    assert dry[1][0] == 1 * S + 100 * MS + 120 * S and dry[2][0] == 140 * S
    pump = tr.changes("%QX0.0", 0, 149 * S)
    assert pump == [(0, "FALSE"), (1 * S, "TRUE"), (dry[1][0], "FALSE"), (140 * S, "TRUE")]
    # high-high alarm after 5 s above 95 %, gone when the level is back
    assert tr.changes("%QX0.1") == [(0, "FALSE"), (155 * S, "TRUE"), (160 * S, "FALSE")]


# ---------------------------------------------------------------- motor_il
@behaviour("motor_il")
def test_star_delta_sequence_interlock_and_fault(tmp_path):
    k = ["%QX0.0", "%QX0.1", "%QX0.2", "%QX0.3"]        # main, star, delta, fault lamp
    tr = simulate(tmp_path, "motor_il", "36s", k,
                  [("0s", "%IX0.1", "TRUE"), ("0s", "%IX0.2", "TRUE")] +   # NC contacts closed
                  pulse("%IX0.0", 1000, 100) +                             # START
                  [("20s", "%IX0.1", "FALSE"), ("20.2s", "%IX0.1", "TRUE")] +  # STOP (NC opens)
                  pulse("%IX0.0", 25_000, 100) +
                  [("30s", "%IX0.2", "FALSE"), ("31s", "%IX0.2", "TRUE")] +  # overload trips
                  pulse("%IX0.3", 33_000, 100))                            # RESET
    # start: main + star; after the 6 s star time star drops, 80 ms later delta
    assert tr.changes("%QX0.0", 0, 29 * S) == [(0, "FALSE"), (1 * S, "TRUE"), (20 * S, "FALSE"),
                                               (25 * S, "TRUE")]
    assert tr.changes("%QX0.1", 0, 19 * S) == [(0, "FALSE"), (1 * S, "TRUE"), (7 * S, "FALSE")]
    assert tr.changes("%QX0.2", 0, 19 * S) == [(0, "FALSE"), (7 * S + 80 * MS, "TRUE")]
    # STOP drops everything
    for c in k[:3]:
        assert tr.at(c, 20 * S) == "FALSE", c
    # never star and delta together
    for t, star, delta in tr.each_row("%QX0.1", "%QX0.2"):
        assert not (star == "TRUE" and delta == "TRUE"), t
    # the overload drops the contactors and latches the fault: the lamp
    # flashes until RESET, and the motor stays off until the next START
    for c in k[:3]:
        assert tr.changes(c, 30 * S) == [(30 * S, "FALSE")], c
    lamp = tr.changes("%QX0.3", 29 * S)
    assert lamp[0] == (29 * S, "FALSE")
    assert len([v for t, v in lamp if 30 * S <= t < 33 * S]) >= 5, lamp
    assert tr.at("%QX0.3", 33 * S) == "FALSE" and tr.changes("%QX0.3", 33 * S) == [
        (33 * S, "FALSE")]


# ---------------------------------------------------------- watchdog_event
def _heartbeat(start_ms, end_ms):
    """The station's heartbeat bit toggling every 100 ms from start to end."""
    return [(f"{t}ms", "plc.heartbeat_in", "TRUE" if (t - start_ms) % 200 == 0 else "FALSE")
            for t in range(start_ms, end_ms, 100)] + [(f"{end_ms}ms", "plc.heartbeat_in", "FALSE")]


@behaviour("watchdog_event")
def test_watchdog_counts_beats_and_logs_a_lost_link(tmp_path):
    tr = simulate(tmp_path, "watchdog_event", "10s",
                  ["plc.beat_count", "%QX0.0", "%QX0.1", "plc.fault_total", "plc.fault_text",
                   "fault_log[1].beats", "fault_log[2].beats", "log_index"],
                  [("0s", "%IX0.2", "TRUE")] + _heartbeat(0, 4900) + _heartbeat(7000, 8100))
    # the event task counts every rising edge: 25 beats up to 4.8 s, 6 from 7.0 s
    assert tr.at("plc.beat_count", 4900 * MS) == "25"
    assert tr.at("plc.beat_count", 10 * S) == "31"
    beats = tr.changes("plc.beat_count", 0, 4900 * MS)
    assert [t for t, _ in beats[1:]] == [k * 200 * MS for k in range(1, 25)], beats
    # no beat for 500 ms after the last one (4.8 s, seen by the 4.81 s scan): link lost
    assert tr.changes("%QX0.0") == [(0, "TRUE"), (5310 * MS, "FALSE"), (7 * S, "TRUE"),
                                    (8510 * MS, "FALSE")]
    # the commands are passed on only while the link is OK
    assert tr.changes("%QX0.1") == tr.changes("%QX0.0")
    assert tr.changes("plc.fault_total") == [(0, "0"), (5310 * MS, "1"), (8510 * MS, "2")]
    # the logging event task runs once per loss
    assert tr.changes("plc.fault_text") == [(0, ""), (5310 * MS, "Heartbeat lost, event 1"),
                                            (8510 * MS, "Heartbeat lost, event 2")]
    assert tr.at("fault_log[1].beats", 10 * S) == "25"
    assert tr.at("fault_log[2].beats", 10 * S) == "31"
    assert tr.at("log_index", 10 * S) == "2"


# -------------------------------------------------------- conveyor_counter
@behaviour("openplc_modbus")
def test_openplc_modbus_latch_lamp_and_drive(tmp_path):
    """The HMI's coils are momentary (the program clears them once seen), a
    start lights the warning lamp for 2 s and counts in %MW0, the drive
    command follows the setpoint while the motor runs, a high level or a
    stop (field or HMI) stops it."""
    P = "Res0.instance0."
    tr = simulate(tmp_path, "openplc_modbus", "6s",
                  [P + n for n in ("motor", "warn_lamp", "hmi_start", "drive_cmd", "starts")],
                  [("0s", "%QW1", "50"), ("100ms", "%QX0.2", "TRUE"),
                   ("1s", "%QW1", "120"),
                   ("3s", "%QX0.3", "TRUE"),
                   ("3500ms", "%IX0.0", "TRUE"), ("3600ms", "%IX0.0", "FALSE"),
                   ("4500ms", "%IW1", "950"), ("5s", "%IW1", "10"),
                   ("5200ms", "%IX0.0", "TRUE")])
    assert tr.changes(P + "hmi_start") == [(0, "FALSE")]        # seen within its cycle, cleared
    assert tr.changes(P + "motor") == [(0, "FALSE"), (100 * MS, "TRUE"), (3 * S, "FALSE"),
                                    (3500 * MS, "TRUE"), (4500 * MS, "FALSE"),
                                    (5200 * MS, "TRUE")]
    assert tr.changes(P + "warn_lamp", 0, 3 * S) == [(0, "FALSE"), (100 * MS, "TRUE"),
                                              (2100 * MS, "FALSE")]
    assert tr.changes(P + "drive_cmd", 0, 4 * S) == [(0, "0"), (100 * MS, "13800"),
                                            (1 * S, "27600"), (3 * S, "0"),
                                            (3500 * MS, "27600")]
    assert tr.changes(P + "starts") == [(0, "0"), (100 * MS, "1"), (3500 * MS, "2"),
                                  (5200 * MS, "3")]


@behaviour("conveyor_counter")
def test_conveyor_counts_boxes_batches_and_jams(tmp_path):
    entries = [e for k in range(24) for e in pulse("%IX0.2", 200 + 100 * k, 40)]
    exits = [e for k in range(24) for e in pulse("%IX0.3", 3000 + 100 * k, 40)]
    tr = simulate(tmp_path, "conveyor_counter", "13s",
                  ["%QX0.0", "%QX0.1", "%QX0.3", "%QX0.4", "%QX0.5", "plc.belt_count",
                   "%MW102", "%MW104"],
                  [("0s", "%IX0.1", "TRUE")] + pulse("%IX0.0", 100, 50) + entries + exits +
                  pulse("%IX0.4", 6000, 100) + pulse("%IX0.0", 6500, 50) +
                  [("7s", "%IX0.3", "TRUE"), ("12s", "%IX0.3", "FALSE")] +   # a box stuck
                  pulse("%IX0.5", 12_500, 50))
    # up at the entry eye, down at the exit eye
    on_belt = [int(v) for _, v in tr.changes("plc.belt_count", 0, 6 * S)]
    assert on_belt == list(range(25)) + list(range(23, -1, -1)), on_belt
    assert [int(v) for _, v in tr.changes("%MW102", 0, 5900 * MS)] == list(range(25))
    # the drive slows down as the belt fills: 0..4 fast (3), 5..9 (2), 10..15 (1), else creep
    for t, n, b0, b1 in tr.each_row("plc.belt_count", "%QX0.4", "%QX0.5"):
        n = int(n)
        preset = 3 if 0 <= n <= 4 else 2 if 5 <= n <= 9 else 1 if 10 <= n <= 15 else 0
        assert (b0 == "TRUE", b1 == "TRUE") == (preset % 2 == 1, preset >= 2), (t, n)
    # the 24th box completes the batch (exit at 5.3 s): the lamp lights and the
    # belt stops on the next scan; the pallet change starts the next batch and
    # counts down the order
    assert tr.changes("%QX0.1", 0, 6900 * MS) == [(0, "FALSE"), (5300 * MS, "TRUE"),
                                                  (6 * S, "FALSE")]
    assert tr.changes("%MW104", 0, 12 * S) == [(0, "10"), (6 * S, "9")]
    # the belt runs from START to the full batch, and from the next START
    # until the box has blocked the exit eye for 4 s
    assert tr.changes("%QX0.0") == [(0, "FALSE"), (100 * MS, "TRUE"), (5305 * MS, "FALSE"),
                                    (6500 * MS, "TRUE"), (11005 * MS, "FALSE")]
    assert tr.changes("%QX0.3") == [(0, "FALSE"), (11 * S, "TRUE"), (12500 * MS, "FALSE")]
    # RESET clears the counters and reloads the order
    assert tr.at("%MW102", 13 * S) == "0" and tr.at("%MW104", 13 * S) == "10"
    assert tr.at("plc.belt_count", 13 * S) == "0"


# ----------------------------------------------------------- alarm_handler
@behaviour("alarm_handler")
def test_alarm_sequence_first_out_horn_and_trip(tmp_path):
    tr = simulate(tmp_path, "alarm_handler", "9s",
                  ["%QX0.0", "%QX0.1", "%QX0.2", "%MW50", "display", "alarms[2].count",
                   "alarms[3].count"],
                  [("1s", "%ID8", 4),           # alarm 3: SUCTION PRESS LOW (no trip)
                   ("2s", "%ID8", 5)] +         # + alarm 1: LUBE OIL PRESS LOW TRIP
                  pulse("%IX0.0", 3000, 200) +   # ACK (acknowledges on release)
                  [("4s", "%ID8", 0),           # both back to normal
                   ("5s", "%ID8", 2),           # alarm 2: DISCHARGE TEMP HIGH TRIP
                   ("6s", "%ID8", 0)] +         # back to normal, not acknowledged
                  pulse("%IX0.0", 7000, 200) + pulse("%IX0.1", 8000, 500))
    # first-out: the first alarm of a burst, kept until acknowledged and normal
    assert tr.changes("%MW50") == [(0, "0"), (1 * S, "3"), (4 * S, "0"), (5 * S, "2"),
                                   (7200 * MS, "0")]
    assert tr.changes("display") == [(0, ""), (1 * S, "SUCTION PRESS LOW"), (4 * S, ""),
                                     (5 * S, "DISCHARGE TEMP HIGH TRIP"), (7200 * MS, "")]
    # the horn sounds on each new alarm until ACK is pressed
    assert tr.changes("%QX0.0") == [(0, "FALSE"), (1 * S, "TRUE"), (3 * S, "FALSE"),
                                    (5 * S, "TRUE"), (7 * S, "FALSE")]
    # a latched TRIP alarm removes the compressor permit
    assert tr.changes("%QX0.2") == [(0, "TRUE"), (2 * S, "FALSE"), (4 * S, "TRUE"),
                                    (5 * S, "FALSE"), (7200 * MS, "TRUE")]
    # the common lamp flashes while unacknowledged, is steady while active
    # and acknowledged, off when all is normal; lamp test lights it
    assert len(tr.changes("%QX0.1", 1 * S, 3200 * MS - 1)) >= 4
    assert tr.changes("%QX0.1", 3200 * MS, 4 * S - 1) == [(3200 * MS, "TRUE")]
    assert tr.changes("%QX0.1", 4 * S, 5 * S - 1) == [(4 * S, "FALSE")]
    assert len(tr.changes("%QX0.1", 5 * S, 7200 * MS - 1)) >= 4
    assert tr.changes("%QX0.1", 7200 * MS, 8 * S - 1) == [(7200 * MS, "FALSE")]
    assert tr.changes("%QX0.1", 8 * S, 9 * S) == [(8 * S, "TRUE"), (8500 * MS, "FALSE")]
    assert tr.at("alarms[2].count", 9 * S) == "1" and tr.at("alarms[3].count", 9 * S) == "1"


# ------------------------------------------------------------- batch_mixer
@behaviour("batch_mixer")
def test_batch_runs_the_rinse_recipe_and_rejects_a_bad_one(tmp_path):
    tr = simulate(tmp_path, "batch_mixer", "120s",
                  ["%QB0", "%QX1.0", "%QX1.1", "%QX1.2", "%MW12", "status_text"],
                  [("0s", "plc.selected_recipe", 2), ("0s", "%IW4", 0)] +  # 'Rinse'
                  pulse("%IX0.0", 1000, 200) +                            # START
                  [("5s", "%IW4", 10000), ("10s", "%IW4", 20000),          # 100 kg, 200 kg
                   ("110s", "%IW4", 50),                                   # drained: 0.5 kg
                   ("115s", "plc.selected_recipe", 0)] +                  # no such recipe
                  pulse("%IX0.0", 116_000, 200))
    # step 1: dose 200 kg of ingredient 4 (valve bit 3) -- start, check, step start, run
    # step 2: mix for 90 s (agitator); step 3: drain (valve bit 7) until below 1 kg
    assert tr.changes("%QB0") == [(0, "0"), (1200 * MS, "8"), (10 * S, "0"),
                                  (100500 * MS, "128"), (110 * S, "0")]
    agitator = tr.changes("%QX1.0")
    assert agitator == [(0, "FALSE"), (10200 * MS, "TRUE"), (100300 * MS, "FALSE")]
    assert tr.changes("%QX1.1") == [(0, "FALSE")]                    # no heating step
    assert tr.changes("%MW12") == [(0, "0"), (1100 * MS, "1"), (10100 * MS, "2"),
                                   (100400 * MS, "3")]
    assert tr.changes("%QX1.2") == [(0, "FALSE"), (1100 * MS, "TRUE"), (110200 * MS, "FALSE")]
    assert tr.changes("status_text") == [(0, "Idle"), (1100 * MS, "Running Rinse"),
                                         (110200 * MS, "Rinse complete"),
                                         (116100 * MS, "Recipe rejected")]


# ---------------------------------------------------------------- elevator
@behaviour("elevator")
def test_elevator_serves_calls_in_its_direction_and_holds_the_door(tmp_path):
    floor = "%IB2"              # bit f-1: the car is level with floor f
    door_closed, door_opened, curtain = "%IX3.0", "%IX3.1", "%IX3.2"
    tr = simulate(tmp_path, "elevator", "31s",
                  ["plc.car1.state", "%QX0.0", "%QX0.1", "%QX0.2", "%QX0.3", "%QB1", "%QB2",
                   "%QB3"],
                  [("0s", floor, 1), ("0s", door_closed, "TRUE"),
                   ("1s", "%IB1", 4), ("1.1s", "%IB1", 0),                # car call: floor 3
                   ("3s", floor, 0), ("4s", floor, 2), ("5s", floor, 0), ("6s", floor, 4),
                   ("6.5s", door_closed, "FALSE"), ("7s", door_opened, "TRUE")] +
                  pulse(curtain, 12_500, 100) +                           # someone steps in
                  [("18s", door_opened, "FALSE"), ("18.5s", door_closed, "TRUE"),
                   ("19s", "%IB0", 1), ("19.1s", "%IB0", 0),              # hall call: floor 1
                   ("19.5s", "%IB1", 8), ("19.6s", "%IB1", 0),            # car call: floor 4
                   ("20s", floor, 0), ("21s", floor, 2), ("22s", floor, 0), ("23s", floor, 1),
                   ("23.2s", door_closed, "FALSE"), ("23.5s", door_opened, "TRUE"),
                   ("29s", door_opened, "FALSE"), ("29.5s", door_closed, "TRUE"),
                   ("30s", floor, 0)])
    # up from floor 1 to the car call at 3, passing floor 2 without stopping
    assert tr.changes("%QX0.0", 0, 29 * S) == [(0, "FALSE"), (1 * S, "TRUE"), (6 * S, "FALSE")]
    # the door opens at floor 3, stays open for the 5 s pulse once fully open,
    # re-opens for the light curtain (a new 5 s), then closes
    assert tr.changes("plc.car1.state", 0, 19 * S - 1) == [
        (0, "CAR_IDLE"), (1 * S, "CAR_MOVING"), (6 * S, "CAR_DOOR_OPEN"),
        (12 * S, "CAR_DOOR_CLOSING"), (12500 * MS, "CAR_DOOR_OPEN"),
        (17520 * MS, "CAR_DOOR_CLOSING"), (18500 * MS, "CAR_IDLE")]
    assert tr.changes("%QX0.2", 0, 19 * S) == [(0, "FALSE"), (6 * S, "TRUE"), (7 * S, "FALSE")]
    assert tr.changes("%QX0.3", 0, 19 * S) == [(0, "FALSE"), (12 * S, "TRUE"),
                                               (12500 * MS, "FALSE"), (17520 * MS, "TRUE"),
                                               (18500 * MS, "FALSE")]
    # the car call lamp goes out when the call is served
    assert tr.changes("%QB2", 0, 19 * S) == [(0, "0"), (1 * S, "4"), (6020 * MS, "0")]
    # then down to the hall call at 1: the car call at 4, made on the way
    # down, waits until the car has served floor 1 and reversed
    assert tr.changes("%QX0.1") == [(0, "FALSE"), (19 * S, "TRUE"), (23 * S, "FALSE")]
    assert tr.changes("%QB1") == [(0, "0"), (19 * S, "1"), (23020 * MS, "0")]
    # (door closed at 29.5 s: idle; the next scan finds the call and starts)
    assert tr.changes("%QX0.0", 23 * S) == [(23 * S, "FALSE"), (29520 * MS, "TRUE")]
    assert tr.at("%QB2", 29520 * MS) == "8"
    # the floor indicator shows 1, 2, 3 (7-segment codes), and 2, 1 on the way down
    assert [v for _, v in tr.changes("%QB3")] == ["6", "91", "79", "91", "6"]


# ---------------------------------------------------------------- pid_loop
@behaviour("pid_loop")
def test_pid_reaches_the_setpoint_without_windup_and_transfers_bumplessly(tmp_path):
    tr = simulate(tmp_path, "pid_loop", "1800s", ["bath_temp", "%QW2", "%QX0.0"],
                  [("0s", "%IX0.0", "TRUE"),
                   ("1200s", "%IW2", 500), ("1200s", "%IX0.0", "FALSE"),   # manual, 50.0 %
                   ("1500s", "%IX0.0", "TRUE")])                          # back to auto
    temps = [(t, float(v)) for t, v in tr.changes("bath_temp", 0, 1200 * S)]
    # full heater at the start, from 20 degC towards the 55 degC setpoint
    assert tr.at("%QW2", 0) == "27648" and temps[0] == (0, 20.0)
    # anti-windup: the overshoot stays small although the heater saturated for long
    assert max(v for _, v in temps) < 55.5
    assert abs(float(tr.at("bath_temp", 1190 * S)) - 55.0) < 0.05
    # steady state: 0.6 K/% * heater = 35 K above ambient, 58.3 % = 16128 counts
    assert abs(int(tr.at("%QW2", 1190 * S)) - 16128) < 30
    ready = tr.changes("%QX0.0", 0, 1199 * S)
    assert [v for _, v in ready] == ["FALSE", "TRUE"] and ready[1][0] < 200 * S, ready
    # manual: the output is the potentiometer value exactly, the bath cools towards 50 degC
    assert tr.changes("%QW2", 1200 * S, 1499 * S) == [(1200 * S, "13824")]
    assert 50.0 < float(tr.at("bath_temp", 1499 * S)) < 50.6
    # bumpless transfer: the first automatic output continues from the manual one
    assert abs(int(tr.at("%QW2", 1500 * S)) - 13824) < 277          # less than 1 %
    assert tr.at("%QX0.0", 1800 * S) == "TRUE"


# ----------------------------------------------------------------- tank_io
@behaviour("tank_io")
def test_tank_io_controls_the_level_in_volts(tmp_path):
    """The simulator has no device: the I/O map's addresses are plain
    located variables the input trace sets (in volts, as the kernel's REAL
    scaling gives them); the model integrates the valve read back."""
    tr = simulate(tmp_path, "tank_io", "3s",
                  ["Tank.valve", "Tank.level_tx", "Tank.high_alarm", "Tank.ctl.integ"],
                  [("0s", "%ID0", "2.0"), ("0s", "%ID4", "5.0"), ("2s", "%ID0", "9.5")])
    # PI: 2 * (6 - 2) + 0.4; the model: 2 + 0.04 * 5 - 0.02 * 2
    assert abs(float(tr.at("Tank.valve", 0)) - 8.4) < 1e-5
    assert abs(float(tr.at("Tank.level_tx", 0)) - 2.16) < 1e-5
    # the valve saturates at 10 V, the integral stays within 0..10
    assert float(tr.at("Tank.valve", 1900 * MS)) == 10.0
    assert all(0.0 <= float(i) <= 10.0 for _, i in tr.each_row("Tank.ctl.integ"))
    assert tr.changes("Tank.high_alarm") == [(0, "FALSE"), (2 * S, "TRUE")]
    # above the setpoint the valve closes within three cycles
    assert 0.0 < float(tr.at("Tank.valve", 2 * S)) < 1.0
    assert tr.changes("Tank.valve", 2200 * MS, 3 * S) == [(2200 * MS, "0.0")]
    # the model's level rises towards 0.04 * 5 / 0.02 = 10 V
    levels = [float(v) for _, v in tr.each_row("Tank.level_tx")]
    assert levels == sorted(levels) and 5.5 < levels[-1] < 10.0


# ----------------------------------------------------------- two_resources
@behaviour("two_resources")
def test_bottling_line_fills_caps_and_stops_on_either_emergency_event(tmp_path):
    tr = simulate(tmp_path, "two_resources", "12s",
                  ["line_enable", "estop_active", "estop_station", "bottles_filled",
                   "bottles_capped", "cpu0.filler_trips", "cpu1.capper_trips",
                   "%QX0.0", "%QX0.1", "%QX4.0", "%QX4.1"],
                  [("0s", "%IX4.4", "TRUE")] +                         # STOP is NC
                  pulse("%IX4.3", 500, 1000) +                         # START (1 s task)
                  [("2s", "%IW10", 1000), ("2s", "%IX0.0", "TRUE"),    # bottle, tare 100 g
                   ("3s", "%IW10", 5999), ("3.5s", "%IW10", 6000),     # 499.9 g, 500 g
                   ("4.5s", "%IX0.0", "FALSE")] +
                  pulse("%IX4.1", 5000, 100) + pulse("%IX4.2", 5500, 50) +  # capped
                  pulse("%IX4.1", 6000, 100) +                         # no torque: reject
                  pulse("cpu1.guard_door_open", 8300, 100) +
                  pulse("%IX4.5", 9500, 1000) +                        # RESET
                  pulse("cpu0.estop_filler", 11_000, 100))
    # START is read by the 1 s task
    assert tr.changes("line_enable") == [(0, "FALSE"), (1 * S, "TRUE"), (8300 * MS, "FALSE")]
    # fill to the target weight (500.0 g net), settle 300 ms, count, release for 250 ms
    assert tr.changes("%QX0.0") == [(0, "FALSE"), (2 * S, "TRUE"), (3500 * MS, "FALSE")]
    assert tr.changes("bottles_filled") == [(0, "0"), (3802 * MS, "1")]
    assert tr.changes("%QX0.1") == [(0, "FALSE"), (3802 * MS, "TRUE"), (4052 * MS, "FALSE")]
    # cap until the torque switch; a cap without torque within 1.5 s is rejected
    assert tr.changes("%QX4.0") == [(0, "FALSE"), (5 * S, "TRUE"), (5500 * MS, "FALSE"),
                                    (6 * S, "TRUE"), (7500 * MS, "FALSE")]
    assert tr.changes("bottles_capped") == [(0, "0"), (5500 * MS, "1")]
    # (the emergency stop ends the reject signal: no bottle is being capped)
    assert tr.changes("%QX4.1") == [(0, "FALSE"), (7500 * MS, "TRUE"), (8300 * MS, "FALSE")]
    # each emergency stop event runs its resource's instance once, at the edge
    assert tr.changes("estop_active") == [(0, "FALSE"), (8300 * MS, "TRUE"), (10 * S, "FALSE"),
                                          (11 * S, "TRUE")]
    assert tr.changes("estop_station") == [(0, "0"), (8300 * MS, "2"), (11 * S, "1")]
    assert tr.changes("cpu1.capper_trips") == [(0, "0"), (8300 * MS, "1")]
    assert tr.changes("cpu0.filler_trips") == [(0, "0"), (11 * S, "1")]


# -------------------------------------------------------------------- hvac
@behaviour("hvac")
def test_hvac_schedule_optimum_start_cooling_pump_overrun_and_override(tmp_path):
    zone_mode = [f"zones[{z}].mode" for z in (1, 2, 3)]
    tr = simulate(tmp_path, "hvac", "2800s",
                  zone_mode + ["%QW20", "%QW21", "%QW22", "%QB0", "%QX1.0", "%QX1.1",
                               "zones[1].override_until"],
                  # Monday 06:30 (the 1 s clock task adds its first second at t = 0);
                  # zones at 20.0, 21.5, 15.0 and 23.0 degC
                  [("0s", "since_midnight", "T#6h30m"), ("0s", "%IW20", 200),
                   ("0s", "%IW21", 215), ("0s", "%IW22", 150), ("0s", "%IW23", 230)] +
                  [("2400s", f"%IW2{z}", 250) for z in range(4)] +     # all at 25.0 degC
                  [("2700s", "since_midnight", "T#19h")] +           # after hours
                  pulse("%IX0.0", 2_710_000, 1000))                  # occupancy button 1
    # optimum start, 20 min per degree below comfort: zone 1 (1 K) preheats from
    # 06:40, zone 3 (6 K, at most 2 h) at once, zone 2 (at comfort) not at all;
    # comfort at 07:00 (clock 06:30:01 + t)
    assert tr.changes(zone_mode[0], 0, 2699 * S) == [(0, "ZM_ECONOMY"), (599 * S, "ZM_PREHEAT"),
                                                    (1799 * S, "ZM_COMFORT")]
    assert tr.changes(zone_mode[1], 0, 2699 * S) == [(0, "ZM_ECONOMY"), (1799 * S, "ZM_COMFORT")]
    assert tr.changes(zone_mode[2], 0, 2699 * S) == [(0, "ZM_PREHEAT"), (1799 * S, "ZM_COMFORT")]
    # proportional valves, 4 K band: zone 1 at 1 K below 21 degC is 25 % (6912 of
    # 27648), zone 3 is fully open, zone 2 is at its setpoint
    assert tr.changes("%QW20", 0, 2699 * S) == [(0, "0"), (599 * S, "6912"), (2400 * S, "0")]
    assert tr.changes("%QW21") == [(0, "0")]
    assert tr.changes("%QW22", 0, 2699 * S) == [(0, "27648"), (2400 * S, "0")]
    # cooling only when occupied: server room (zone 4, above 22) from 07:00, the
    # meeting room (zone 3, above 24) once it is at 25 degC
    assert tr.changes("%QB0") == [(0, "0"), (1799 * S, "8"), (2400 * S, "12"), (2700 * S, "0")]
    # the boiler stops with the last heat demand; the pump runs on for 3 minutes
    assert tr.changes("%QX1.0") == [(0, "TRUE"), (2400 * S, "FALSE")]
    assert tr.changes("%QX1.1") == [(0, "TRUE"), (2580 * S, "FALSE")]
    # after hours the button gives zone 1 two hours of comfort from the press
    assert tr.changes(zone_mode[0], 2700 * S) == [(2700 * S, "ZM_ECONOMY"),
                                                 (2710 * S, "ZM_OVERRIDE")]
    assert tr.changes(zone_mode[1], 2700 * S) == [(2700 * S, "ZM_ECONOMY")]
    assert int(tr.at("zones[1].override_until", 2800 * S)) == (21 * 3600 + 11) * S


# --------------------------------------------------------- packaging_il_st
@behaviour("packaging_il_st")
def test_bagger_seals_cuts_supervises_the_jaw_and_corrects_the_feed(tmp_path):
    marks = []
    for t_ms, position in [(2000, 10000), (2100, 12520), (2200, 14900), (2300, 30000),
                           (2400, 40000), (2500, 50000), (2600, 60000)]:
        marks += [(f"{t_ms}ms", "%ID4", position)] + pulse("%IX0.2", t_ms, 10)
    tr = simulate(tmp_path, "packaging_il_st", "2800ms",
                  ["%QX0.0", "%QD4", "%QX0.1", "%QX0.2", "%QX0.3", "%MD0"],
                  [("0s", "%IX0.0", "TRUE")] +                          # run switch
                  pulse("%IX0.1", 200, 300) +                           # product in the tube
                  pulse("%IX0.3", 300, 400) +                           # jaw closed switch
                  pulse("%IX0.1", 1000, 300) +                          # next product: the
                  pulse("%IX0.4", 1700, 50) + marks +                   # jaw never closes
                  pulse("%IX0.4", 2700, 50))
    # debounced inputs: run after 50 ms, product after 5 ms (the first 2 ms scan at
    # or after 5 ms: 206 ms); the jaw closes on the
    # product and holds 350 ms (seal time) after its closed switch is made
    assert tr.changes("%QX0.1", 0, 999 * MS) == [(0, "FALSE"), (206 * MS, "TRUE"),
                                                 (650 * MS, "FALSE")]
    assert tr.changes("%QX0.0", 0, 999 * MS) == [(0, "FALSE"), (50 * MS, "TRUE"),
                                                 (206 * MS, "FALSE"), (650 * MS, "TRUE")]
    # the knife cuts for 80 ms at the end of each seal; the bag is counted
    assert tr.changes("%QX0.2") == [(0, "FALSE"), (650 * MS, "TRUE"), (730 * MS, "FALSE")]
    assert tr.changes("%MD0") == [(0, "0"), (650 * MS, "1"), (1700 * MS, "0")]
    # the jaw must close within 500 ms, else a fault until RESET stops the feed
    assert tr.changes("%QX0.1", 1 * S, 1999 * MS) == [(1 * S, "FALSE"), (1006 * MS, "TRUE"),
                                                       (1506 * MS, "FALSE")]
    assert tr.changes("%QX0.3", 0, 1999 * MS) == [(0, "FALSE"), (1506 * MS, "TRUE"),
                                                  (1700 * MS, "FALSE")]
    assert tr.changes("%QX0.0", 1 * S, 1999 * MS) == [(1 * S, "TRUE"), (1006 * MS, "FALSE"),
                                                       (1700 * MS, "TRUE")]
    # registration: a mark 2 mm late (err +20) shortens the next bag by half the
    # error, one 12 mm early lengthens it at most 5 mm; a mark more than 20 %
    # off is missed, and more than 3 missed marks light the fault lamp
    assert tr.changes("%QD4") == [(0, "2500"), (2100 * MS, "2490"), (2200 * MS, "2550"),
                                  (2300 * MS, "2500")]
    assert tr.changes("%QX0.3", 2 * S) == [(2 * S, "FALSE"), (2500 * MS, "TRUE"),
                                           (2700 * MS, "FALSE")]
