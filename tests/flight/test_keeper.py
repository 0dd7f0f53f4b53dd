"""The formation keeper: progress along each UAV's own path, and its speed nudges."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from ftlbo_mav.flight.keeper import (
    FormationKeeper,
    KeeperOptions,
    planned_speed,
    progress_along,
    still_to_lose_s,
)
from ftlbo_mav.mission.items import MissionItem

# an L-shaped centroid path, three UAVs shifted by their offsets (the paper's eq. 4)
CENTROID = np.array([[0.0, 0.0, 4.0], [10.0, 0.0, 4.0], [10.0, 10.0, 4.0]])
OFFSETS = np.array([[0.0, 0.0, 2.0], [3.0, 0.0, -1.0], [-3.0, 0.0, -1.0]])
PATHS = CENTROID[None] + OFFSETS[:, None]
ON = KeeperOptions()  # on by default
CRUISE = 5.0


def test_progress_is_the_distance_along_the_path_of_the_nearest_point():
    path = PATHS[0]
    assert progress_along(path, path[0])[0] == pytest.approx(0.0)
    assert progress_along(path, path[0] + [4.0, 0.3, 0.1])[0] == pytest.approx(4.0)
    s, seg = progress_along(path, path[1] + [0.2, 5.0, 0.0])
    assert s == pytest.approx(15.0) and seg == 1


def test_progress_does_not_jump_back_to_an_earlier_leg():
    path = np.array([[0.0, 0, 0], [10, 0, 0], [10, 1, 0], [0, 1, 0]])  # a hairpin
    s, seg = progress_along(path, np.array([2.0, 0.9, 0]), start_segment=2)
    assert seg == 2 and s == pytest.approx(19.0)


def positions_at(progress):
    out = []
    for path, s in zip(PATHS, progress):
        a, b = (path[0], path[1]) if s <= 10 else (path[1], path[2])
        t = s / 10 if s <= 10 else (s - 10) / 10
        out.append(a + t * (b - a))
    return np.array(out)


def test_a_leader_waits_just_long_enough_to_lose_its_lead_then_continues():
    keeper = FormationKeeper(PATHS, CRUISE, options=ON)
    speeds = np.full(3, 5.0)
    assert keeper.update(positions_at([5.0, 5.0, 5.0]), speeds, 0.0) == {}
    # uav1 0.6 m ahead of the others (0.4 m ahead of the group's mean): a pause a copter
    # can take back all of, since the others cannot be made to catch up
    assert keeper.update(positions_at([5.6, 5.0, 5.0]), speeds, 1.0) == {0: True}
    pause = ON.pause_for(0.6, 5.0, CRUISE)
    lost = 5.0 * ON.navigation.pause_cost_s(pause, CRUISE)
    assert 0.6 <= lost < 0.6 + 0.1 and 0.0 < pause < ON.max_pause_s

    def flown(t):  # uav1 losing its lead as the pause model has it; the others at 5 m/s
        others = 5.0 + 5.0 * (t - 1.0)
        owed = still_to_lose_s(ON.navigation, pause, CRUISE, t - 1.0)
        return positions_at([others + 0.6 - lost + 5.0 * owed, others, others])

    assert keeper.update(flown(1.0 + pause - 0.06), speeds, 1.0 + pause - 0.06) == {}
    assert keeper.update(flown(1.0 + pause), speeds, 1.0 + pause) == {0: False}
    # the continue is said again 0.05, 0.1, 0.4, 1.2 and 2.2 s after (a lost one would
    # leave the copter stopped; a radio loses frames in bursts and for a second at a
    # time), and nothing else: what the pause has still to take counts as taken, so
    # nobody is paused for it
    said = [keeper.update(flown(1.0 + pause + 0.1 * k), speeds, 1.0 + pause + 0.1 * k)
            for k in range(1, 24)]
    assert [k + 1 for k, out in enumerate(said) if out] == [1, 4, 12, 22]
    assert all(out in ({}, {0: False}) for out in said)
    assert keeper.log.pauses == [1, 0, 0] and keeper.log.paused_s[0] == pytest.approx(pause)
    assert keeper.log.max_lead_m[0] == pytest.approx(0.4)  # the formation's view: the mean


def test_a_lead_that_keeps_growing_is_answered_again():
    """A copter paused for a lead that then grows further (the laggard's track clock still
    slowing) is paused again once the growth shows, beyond what its pause still owes."""
    keeper = FormationKeeper(PATHS, CRUISE, options=ON)
    speeds = np.full(3, 5.0)
    assert keeper.update(positions_at([5.3, 5.0, 5.0]), speeds, 0.0) == {0: True}
    pause = ON.pause_for(0.3, 5.0, CRUISE)
    assert keeper.update(positions_at([6.0, 5.5, 5.5]), speeds, pause) == {0: False}
    keeper.update(positions_at([6.5, 6.0, 6.0]), speeds, pause + 0.1)
    keeper.update(positions_at([7.0, 6.5, 6.5]), speeds, pause + 0.2)
    # ON.rest_s after the continue uav1 is 0.6 m ahead, far more than it still owes
    again = keeper.update(positions_at([8.6, 8.0, 8.0]), speeds, pause + ON.rest_s)
    assert again == {0: True}


def test_a_waited_leader_rests_before_it_is_paused_again():
    keeper = FormationKeeper(PATHS, CRUISE, options=ON)
    speeds = np.full(3, 5.0)
    assert keeper.update(positions_at([5.6, 5.0, 5.0]), speeds, 0.0) == {0: True}
    t = ON.pause_for(0.6, 5.0, CRUISE)
    assert keeper.update(positions_at([6.6, 6.0, 6.0]), speeds, t) == {0: False}
    for k in range(1, 3):
        keeper.update(positions_at([6.6, 6.0, 6.0]), speeds, t + 0.1 * k)
    # still ahead (its pace not back yet): no second pause within rest_s (the continue
    # said again 0.4 s after it)
    assert keeper.update(positions_at([7.6, 7.0, 7.0]), speeds, t + ON.rest_s - 0.1) == {
        0: False}
    assert keeper.update(positions_at([7.6, 7.0, 7.0]), speeds, t + ON.rest_s) == {0: True}


def test_while_the_group_speeds_up_a_lead_in_seconds_is_enough():
    keeper = FormationKeeper(PATHS, CRUISE, options=ON)
    slow = np.full(3, 0.4)  # 0.05 m ahead at 0.4 m/s: 0.125 s ahead (a late start)
    assert keeper.update(positions_at([1.05, 1.0, 1.0]), slow, 0.0) == {0: True}
    tiny = FormationKeeper(PATHS, CRUISE, options=ON)  # below the 1.1 cm quantization x3
    assert tiny.update(positions_at([1.025, 1.0, 1.0]), np.full(3, 0.2), 0.0) == {}


def test_a_lead_seen_while_the_group_speeds_up_is_paused_as_metres_at_cruise():
    """A lead seen at 1 m/s may be one in space (a copter's estimate put ahead by its GPS)
    as well as one in time: sized as 0.5 m over 1 m/s (0.5 s of track) the pause would
    cost a copter 2.5 m at cruise, and the others would be paused for that in turn (SITL
    and the emulator with GPS wander: leads of 3 m). Sized at the cruise speed it never
    costs more than the lead; a lead in time shows again as the group speeds up, and is
    answered again then."""
    keeper = FormationKeeper(PATHS, CRUISE, options=ON)
    slow = np.full(3, 1.0)
    assert keeper.update(positions_at([1.5, 1.0, 1.0]), slow, 0.0) == {0: True}
    pause = ON.pause_for(0.5, CRUISE, CRUISE)
    assert pause < ON.pause_for(0.5, 1.0, CRUISE)
    assert CRUISE * ON.navigation.pause_cost_s(pause, CRUISE) < 0.5 + 0.1
    assert keeper.update(positions_at([1.6, 1.2, 1.2]), slow, pause - 0.06) == {}
    assert keeper.update(positions_at([1.6, 1.2, 1.2]), slow, pause) == {0: False}


def test_longer_leads_get_longer_pauses_up_to_the_limit():
    pauses = [ON.pause_for(lead, 5.0, CRUISE) for lead in (0.12, 0.3, 0.8, 1.5, 50.0)]
    assert pauses == sorted(pauses) and len(set(pauses)) == 5
    assert pauses[-1] == ON.max_pause_s
    # at a fifth of the speed the same lead in metres is five times the time: longer
    assert ON.pause_for(0.3, 1.0, CRUISE) > ON.pause_for(0.3, 5.0, CRUISE)


def test_small_leads_slow_groups_and_unknown_cruise_speeds_are_left_alone():
    keeper = FormationKeeper(PATHS, CRUISE, options=ON)
    assert keeper.update(positions_at([5.07, 5.0, 5.0]), np.full(3, 5.0), 0.0) == {}
    assert keeper.update(positions_at([6.0, 5.0, 5.0]), np.full(3, 0.1), 1.0) == {}  # starting
    off = FormationKeeper(PATHS, CRUISE, options=KeeperOptions(enabled=False))
    assert off.update(positions_at([9.0, 1.0, 1.0]), np.full(3, 5.0), 0.0) == {}
    unknown = FormationKeeper(PATHS, None, options=ON)
    assert not unknown.active
    assert unknown.update(positions_at([9.0, 1.0, 1.0]), np.full(3, 5.0), 0.0) == {}


def test_a_link_gap_continues_every_paused_vehicle_and_stands_aside():
    keeper = FormationKeeper(PATHS, CRUISE, options=ON)
    speeds = np.full(3, 5.0)
    assert keeper.update(positions_at([5.6, 5.0, 5.0]), speeds, 0.0) == {0: True}
    stale = np.array([0.0, 2.0, 0.0])  # uav2 silent for 2 s
    assert keeper.update(positions_at([5.6, 5.0, 5.0]), speeds, 0.1, ages_s=stale) == {0: False}
    # while the gap lasts: continue again (it may have been lost), and no new pause
    assert keeper.update(positions_at([9.6, 5.0, 5.0]), speeds, 0.2, ages_s=stale) == {0: False}
    assert keeper.log.link_gaps == 1


def test_release_continues_a_paused_vehicle_at_the_end_of_the_legs():
    keeper = FormationKeeper(PATHS, CRUISE, options=ON)
    keeper.update(positions_at([5.6, 5.0, 5.0]), np.full(3, 5.0), 0.0)
    assert keeper.release(0.1) == {0: False} and keeper.release(0.2) == {}


def test_the_pause_model_matches_arducopter_sitl():
    """ArduCopter 4.5.6 SITL (copter.parm, the example's first leg at 5 m/s): uav3 paused
    for 0.6 s and continued fell 1.79 m behind the other two (0.66 and 0.53 m ahead of
    the mean against its 1.19 m behind: docs/flight.md), its speed dipping to 3.4 m/s."""
    lost = 4.9 * KeeperOptions().navigation.pause_cost_s(0.6, 5.0)
    assert lost == pytest.approx(1.79, rel=0.1)


def test_planned_speed_is_the_missions_or_unknown():
    speed = MissionItem(seq=2, command=178, param1=1, param2=3.5, param3=-1)
    assert planned_speed([[speed]]) == 3.5 and planned_speed([[]]) is None


def test_auto_starts_at_the_first_real_leg_and_keeps_the_cruise_speed():
    from ftlbo_mav.flight.fly import first_leg
    from ftlbo_mav.flight.start import start_gate
    from ftlbo_mav.geo import LocalFrame
    from ftlbo_mav.mission.items import build_mission

    frame = LocalFrame(origin_lat_deg=12.2331044, origin_lon_deg=109.1144313)

    path = [(12.2332099, 109.1145051, 4.0), (12.2332254, 109.1145969, 4.0),
            (12.2332408, 109.1146886, 4.0)]
    plain = build_mission(home=(12.2332099, 109.1145051), takeoff_alt_m=4.0, path=path)
    assert [it.command for it in plain[:5]] == [16, 22, 16, 93, 16]
    assert first_leg(plain, frame) == (3, [])  # item 2 is the start point, 3 its gate
    assert start_gate(plain, frame) == 3
    fast = build_mission(home=(12.2332099, 109.1145051), takeoff_alt_m=4.0, path=path,
                         speed_m_s=3.0)
    assert [it.command for it in fast[:6]] == [16, 22, 16, 93, 178, 16]
    # AUTO starts at the gate; the DO_CHANGE_SPEED after it runs as the legs begin
    assert first_leg(fast, frame) == (3, [])
    # without the gate (a mission of an earlier plan): at the DO_CHANGE_SPEED
    ungated = [replace(it, seq=k) for k, it in enumerate(fast[:3] + fast[4:])]
    assert first_leg(ungated, frame) == (3, []) and start_gate(ungated, frame) is None
    # another tool's mission, the speed before the start point: skipped, sent after AUTO
    other = [ungated[0], ungated[1], ungated[3], ungated[2], *ungated[4:]]
    other = [replace(it, seq=k) for k, it in enumerate(other)]
    seq, speeds = first_leg(other, frame)
    assert seq == 4 and [(s.command, s.param2) for s in speeds] == [(178, 3.0)]
    # a first waypoint elsewhere than the start point is a leg of its own: not skipped
    away = build_mission(home=(12.2332099, 109.1145051), takeoff_alt_m=4.0, path=path[1:])
    assert first_leg(away, frame) == (2, [])


def test_a_late_report_is_not_measured_on_but_a_pause_still_ends_on_time():
    """A report 0.3 s late or more (positions come at 10 Hz): no new pause on it; one under
    way still gets its continue when due. From 1 s the keeper stands aside."""
    keeper = FormationKeeper(PATHS, CRUISE, options=ON)
    speeds = np.full(3, 5.0)
    late = np.array([0.05, 0.6, 0.05])
    assert keeper.update(positions_at([5.6, 5.0, 5.0]), speeds, 0.0, ages_s=late) == {}
    assert keeper.update(positions_at([5.6, 5.0, 5.0]), speeds, 0.1) == {0: True}
    pause = ON.pause_for(0.6, 5.0, CRUISE)
    assert keeper.update(positions_at([6.0, 6.0, 5.0]), speeds, 0.1 + pause,
                         ages_s=late) == {0: False}
    assert keeper.log.link_gaps == 0


def test_progress_does_not_jump_to_the_way_back_of_a_spur():
    """Out to a lane's end and back the same way (SITL, a survey at 10 m/s: a copter near
    the spur was measured 20 m on, on its way back, and the keeper paused the others for
    it): progress goes on from where it was."""
    spur = np.array([[0.0, 0, 4], [10, 0, 4], [20, 0.4, 4], [10, 0.8, 4], [0, 0.8, 4]])
    keeper = FormationKeeper(spur[None], CRUISE, options=ON)
    seen = [float(keeper.progress(np.array([[x, 0.45, 4.0]]))[0]) for x in range(13)]
    assert np.all(np.diff(seen) > 0) and seen[-1] < 13.0, seen


def test_no_pause_while_the_links_delays_vary_too_much_to_time_one():
    """A pause and its continue cross the same link: where their delays vary by more than
    ``max_jitter_s`` a pause takes back what the difference makes of it (SITL behind the
    rough-day radio: the formation came apart with the keeper, held without it)."""
    keeper = FormationKeeper(PATHS, CRUISE, options=ON)
    speeds = np.full(3, 5.0)
    keeper.update(positions_at([5.0, 5.0, 5.0]), speeds, 0.0, jitter_s=0.3)
    assert keeper.update(positions_at([5.6, 5.0, 5.0]), speeds, 1.0, jitter_s=0.3) == {}
    assert keeper.log.rough_s == pytest.approx(1.0) and keeper.log.worst_jitter_s == 0.3
    # the link settles: the lead is answered
    assert keeper.update(positions_at([6.1, 5.5, 5.5]), speeds, 1.1, jitter_s=0.08) == {0: True}


def test_no_pause_while_the_link_has_lately_gone_silent():
    """A link that went silent for more than ``max_gap_s`` lately can hold a paused copter
    paused that long, its continues lost (SITL, rough-day radio: 2.1 m, a departure)."""
    keeper = FormationKeeper(PATHS, CRUISE, options=ON)
    speeds = np.full(3, 5.0)
    keeper.update(positions_at([5.0, 5.0, 5.0]), speeds, 0.0, gap_s=1.0)
    assert keeper.update(positions_at([5.6, 5.0, 5.0]), speeds, 1.0, gap_s=1.0) == {}
    assert keeper.log.rough_s == pytest.approx(1.0) and keeper.log.worst_gap_s == 1.0
    # short silences only (a frame or two lost): the lead is answered
    assert keeper.update(positions_at([6.1, 5.5, 5.5]), speeds, 1.1, gap_s=0.3) == {0: True}


def _speeding_up(lead_of, options):
    """The group speeding up from 0.4 to 1.4 m/s over 1 s, uav1 ``lead_of(speed)`` metres
    ahead; the pause uav1 gets, in seconds (None: none)."""
    keeper = FormationKeeper(PATHS, CRUISE, options=options)
    for k in range(21):
        t = 0.05 * k
        v = 0.4 + t
        s = 1.0 + 0.4 * t + 0.5 * t * t  # where the others are along their paths
        if keeper.update(positions_at([s + lead_of(v), s, s]), np.full(3, v), t):
            return keeper._pause[0][1]
    return None


def test_a_lead_that_grows_with_the_groups_speed_is_paused_for_as_one_in_time():
    """0.25 s behind the others (a track clock stalled at the start): its lead grows with
    the group's speed, and once past 0.3 m (at 1.2 m/s) the leader is paused for 0.25 s
    of track, where sized in metres at cruise it got a pause for 0.06 s of it."""
    late = replace(ON, engage_m=0.3, engage_s=1.0)
    pause = _speeding_up(lambda v: 0.25 * v, late)
    assert pause == ON.pause_for(0.25 * CRUISE, CRUISE, CRUISE)
    assert ON.navigation.pause_cost_s(pause, CRUISE) >= 0.25 - 0.01
    assert pause > ON.pause_for(0.31, CRUISE, CRUISE) + 0.1


def test_a_lead_that_does_not_grow_with_the_speed_is_still_paused_for_in_metres_at_cruise():
    """0.31 m ahead in space (its estimate moved by its GPS) while the group speeds up:
    no growth with speed, so sized at cruise as before; never more than the lead."""
    late = replace(ON, engage_m=0.3, engage_s=1.0)
    pause = _speeding_up(lambda _v: 0.31, late)
    assert pause == ON.pause_for(0.31, CRUISE, CRUISE)


def test_once_the_group_has_cruised_a_lead_growing_with_speed_is_sized_at_cruise():
    """After a corner the group speeds up again, and leads measured along paths that cut
    it differently grow with the speed too: only the legs' first speed-up, from a hover,
    judges a lead as time."""
    late = replace(ON, engage_m=0.3, engage_s=1.0)
    keeper = FormationKeeper(PATHS, CRUISE, options=late)
    keeper.update(positions_at([1.0, 1.0, 1.0]), np.full(3, 0.95 * CRUISE), 0.0)  # cruising
    pause = None
    for k in range(1, 22):
        t = 0.05 * k
        v = 0.4 + t
        s = 1.0 + 0.4 * t + 0.5 * t * t
        if keeper.update(positions_at([s + 0.25 * v, s, s]), np.full(3, v), t):
            pause = keeper._pause[0][1]
            break
    assert pause is not None and pause < ON.pause_for(0.25 * CRUISE, CRUISE, CRUISE)
