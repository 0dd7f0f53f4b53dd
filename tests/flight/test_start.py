"""The synchronized start, trimmed for each copter's clock (flight/start.py): ArduPilot
opens a start gate by its own clock of the day, which lags GPS time by a different amount
on each copter (ardupilot/rtc.py); the ground measures each clock and holds the others
for the latest one with a relative NAV_DELAY in the gate's place."""

from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace

import pytest

from ftlbo_mav import clock
from ftlbo_mav.clock import VirtualClock
from ftlbo_mav.flight.start import (
    MIN_TRIM_S,
    TimedStart,
    _gate_items,
    _start_late_ones,
    choose_start,
    gate_as_onboard,
    start_gate,
    trim_at,
)
from ftlbo_mav.flight.status import Status
from ftlbo_mav.mission.items import CMD_NAV_DELAY, CMD_NAV_WAYPOINT


def _vehicle(name: str, utc_behind_s: float, *, delays_s=(0.0, 0.02)) -> SimpleNamespace:
    """Booted at ground time 100 s, a minute of position reports at 10 Hz that came
    ``delays_s`` late in turn, its clock of the day ``utc_behind_s`` behind GPS time
    (SYSTEM_TIME: clock less boot clock)."""
    status = Status(clock_offset_s=100.0, clock_rate=1.0,
                    utc_offset_s=1_765_000_000.0 - utc_behind_s)
    for k in range(600):
        late = delays_s[k % len(delays_s)]
        status._clock_pairs.append((100.0 + k / 10 + late, k / 10))
        status.delays.append(late)
    return SimpleNamespace(name=name, status=status)


def test_each_copter_is_held_for_what_its_clock_is_ahead_of_the_latest():
    """A 4.6.3 copter's clock 0.17 s behind (SITL), a third's 0.03 s."""
    vehicles = [_vehicle("uav1", 0.0), _vehicle("uav2", 0.17), _vehicle("uav3", 0.03)]
    start = choose_start(vehicles, rtt_s=0.1, now=110.0)
    assert isinstance(start, TimedStart)
    # uav2's clock is the latest to read the second: the others wait for it
    assert start.trims_s == pytest.approx((0.17, 0.0, 0.14))
    # on the ground's clock, the legs begin when uav2's clock reads it
    assert start.ground_t == pytest.approx(100.0 + (start.utc_s - 1_765_000_000.0) + 0.17)


def test_clocks_closer_than_a_link_measures_them_get_no_trim():
    """0.07 s apart at most: within what a radio's reports measure clocks by (20-40 ms),
    and copters of one release agree within 5 ms; a trim would add the error."""
    vehicles = [_vehicle("uav1", 0.0), _vehicle("uav2", 0.07), _vehicle("uav3", 0.03)]
    start = choose_start(vehicles, rtt_s=0.1, now=110.0)
    assert isinstance(start, TimedStart) and start.trims_s == ()


def test_a_link_too_jittery_to_measure_the_clocks_by_gets_no_trim():
    """Reports 0-0.3 s late: the least delayed of one copter and another's differ as much
    as their clocks do (SITL's rough-day radio: 38 ms), so the gate is left untrimmed."""
    rough = (0.0, 0.1, 0.3, 0.2, 0.25)
    vehicles = [_vehicle(f"uav{k}", lag, delays_s=rough)
                for k, lag in ((1, 0.0), (2, 0.17), (3, 0.03))]
    start = choose_start(vehicles, rtt_s=0.1, now=110.0)
    assert isinstance(start, TimedStart) and start.trims_s == ()


def test_a_trimmed_gate_goes_in_the_start_points_place_and_its_trim_in_its_own(planned):
    mission = planned.missions[0]
    gate = start_gate(mission, planned.frame)
    assert trim_at(mission, gate) == gate - 1 and trim_at(mission, None) is None
    assert next(it for it in mission if it.seq == gate - 1).command == CMD_NAV_WAYPOINT
    start = TimedStart(utc_s=1_765_000_037, ground_t=0.0, trims_s=(0.04, 0.0, 0.0))
    moved, trim = _gate_items(planned, 0, gate, start, trimmed=True)
    assert (moved.seq, moved.command, moved.param4) == (gate - 1, CMD_NAV_DELAY,
                                                        1_765_000_037 % 60)
    assert (trim.seq, trim.command, trim.param1) == (gate, CMD_NAV_DELAY, 0.04)
    # one that is the latest is held the least a relative NAV_DELAY can say
    _moved, trim = _gate_items(planned, 1, gate, start, trimmed=True)
    assert trim.param1 == MIN_TRIM_S
    # back as planned after the flight: the start point and the gate's placeholder
    back = _gate_items(planned, 0, gate, None, trimmed=True)
    assert back == [it for it in mission if it.seq in (gate - 1, gate)]


def test_a_trimmed_start_left_on_board_is_no_difference(planned):
    mission = planned.missions[0]
    gate = start_gate(mission, planned.frame)
    start = TimedStart(utc_s=1_765_000_037, ground_t=0.0, trims_s=(0.04, 0.0, 0.0))
    onboard = [it for it in mission if it.seq not in (gate - 1, gate)] + _gate_items(
        planned, 0, gate, start, trimmed=True)
    onboard.sort(key=lambda it: it.seq)
    assert gate_as_onboard(mission, onboard, planned.frame) == onboard
    # a waypoint that is not the plan's is still one
    wrong = [replace(it, lat_deg=it.lat_deg + 1e-4) if it.command == CMD_NAV_WAYPOINT
             and it.seq > gate else it for it in onboard]
    assert gate_as_onboard(mission, wrong, planned.frame) != wrong


class _AtGate:
    """A copter at its gate (seq 4) whose reports come through a link of our making:
    ``reports(now)`` is ``(its clock of the latest report that arrived, seq, speed)``."""

    def __init__(self, name, reports):
        self.name, self.sysid, self.aborted_to = name, int(name[-1]), None
        self.status = Status(clock_offset_s=0.0, clock_rate=1.0)
        self._reports = reports
        self.started = []
        self._update()

    def _update(self):
        st = self.status
        st.position_boot_s, st.seq, st.ground_speed_m_s = self._reports(clock.monotonic())

    def wait_for(self, _predicate, timeout_s):
        clock.sleep(timeout_s)
        for v in _AtGate.all:
            v._update()
        return False

    def set_current(self, seq):
        self.started.append((round(clock.monotonic(), 2), seq))


def test_only_a_copter_seen_at_its_gate_after_the_start_is_started_again():
    """At 10 s the legs begin. uav1 leaves its gate; uav2 is seen still at it at 11.6 s
    (its AUTO came late): started; uav3's reports stop at 9.8 s (an outage): no report
    is evidence, so it is left to its gate, which it left on time (a start sent to a
    copter on its leg restarts the leg)."""
    def flying(now):
        return (now - 0.1, 4 if now < 10.2 else 5, 0.0 if now < 10.2 else 1.0)

    def late(now):
        return (now - 0.1, 4, 0.0)

    def silent(now):
        return (min(now, 9.8) - 0.1, 4, 0.0)

    said = []
    with VirtualClock(start_s=9.0):
        _AtGate.all = [_AtGate("uav1", flying), _AtGate("uav2", late),
                       _AtGate("uav3", silent)]
        _start_late_ones(_AtGate.all, [4, 4, 4], TimedStart(1_765_000_010, 10.0),
                         say=said.append, poll=lambda: None)
        uav1, uav2, uav3 = _AtGate.all
    assert uav1.started == [] and uav3.started == []
    assert [seq for _t, seq in uav2.started] == [5]
    # started once seen at its gate 1.5 s after the start by its clock, not when uav3 is
    assert uav2.started[0][0] == pytest.approx(11.65, abs=0.06)
    assert said[0].startswith("uav2 (sysid 2): its legs had not begun 1.5 s after")
    assert said[1].startswith("uav3 (sysid 3): no report of its legs 3.5 s after the start")
