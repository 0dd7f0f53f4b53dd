"""The synchronized start, trimmed for each copter's clock (flight/start.py): ArduPilot
opens a start gate by its own clock of the day, which lags GPS time by a different amount
on each copter (ardupilot/rtc.py); the ground measures each clock and holds the others
for the latest one with a relative NAV_DELAY in the gate's place."""

from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace

import pytest

from ftlbo_mav.flight.planned import load_planned_flight
from ftlbo_mav.flight.start import (
    MIN_TRIM_S,
    TimedStart,
    _gate_items,
    choose_start,
    gate_as_onboard,
    start_gate,
    trim_at,
)
from ftlbo_mav.flight.status import Status
from ftlbo_mav.mission.items import CMD_NAV_DELAY, CMD_NAV_WAYPOINT

from ..conftest import EXAMPLE


@pytest.fixture(scope="module")
def planned():
    return load_planned_flight(EXAMPLE.with_suffix(""))


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
