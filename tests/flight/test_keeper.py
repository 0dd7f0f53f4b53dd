"""The formation keeper: progress along each UAV's own path, and its speed nudges."""

from __future__ import annotations

import numpy as np
import pytest

from ftlbo_mav.flight.keeper import (
    FormationKeeper,
    KeeperOptions,
    planned_speed,
    progress_along,
)
from ftlbo_mav.mission.items import MissionItem

# an L-shaped centroid path, three UAVs shifted by their offsets (the paper's eq. 4)
CENTROID = np.array([[0.0, 0.0, 4.0], [10.0, 0.0, 4.0], [10.0, 10.0, 4.0]])
OFFSETS = np.array([[0.0, 0.0, 2.0], [3.0, 0.0, -1.0], [-3.0, 0.0, -1.0]])
PATHS = CENTROID[None] + OFFSETS[:, None]
ON = KeeperOptions(enabled=True)  # off by default (docs/flight.md)


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


def test_a_leader_is_slowed_until_the_others_catch_up_then_released():
    keeper = FormationKeeper(PATHS, planned_speed_m_s=10.0, options=ON)
    speeds = np.array([2.0, 2.0, 2.0])
    assert keeper.update(positions_at([5.0, 5.0, 5.0]), speeds, 0.0) == {}
    cmds = keeper.update(positions_at([5.9, 5.0, 5.0]), speeds, 1.0)  # uav1 leads by 0.6 m
    assert list(cmds) == [0] and 1.0 <= cmds[0] < 2.0
    assert keeper.update(positions_at([6.0, 5.1, 5.1]), speeds, 1.1) == {}  # too soon
    assert keeper.update(positions_at([6.45, 6.43, 6.43]), speeds, 2.0) == {0: 10.0}  # back
    assert keeper.log.commands == [2, 0, 0] and keeper.log.slowest_m_s[0] == cmds[0]
    assert keeper.log.max_lead_m[0] == pytest.approx(0.6)


def test_a_slowed_vehicle_is_told_again_and_released_at_the_end():
    keeper = FormationKeeper(PATHS, planned_speed_m_s=3.0, options=ON)
    speeds = np.full(3, 2.0)
    keeper.update(positions_at([10.0, 10.0, 10.0]), speeds, -1.0)  # cruising, in shape
    first = keeper.update(positions_at([12.0, 11.0, 11.0]), speeds, 0.0)
    again = keeper.update(positions_at([12.0, 11.0, 11.0]), speeds, 2.5)
    assert list(first) == [0] and again == first
    assert keeper.release() == {0: 3.0} and keeper.release() == {}


def test_a_disabled_keeper_says_nothing_and_nudges_stay_bounded():
    off = FormationKeeper(PATHS, options=KeeperOptions(enabled=False))
    assert off.update(positions_at([9.0, 1.0, 1.0]), np.full(3, 2.0), 0.0) == {}
    on = FormationKeeper(PATHS, planned_speed_m_s=10.0,
                         options=KeeperOptions(enabled=True, min_fraction=0.5))
    on.update(positions_at([1.0, 1.0, 1.0]), np.full(3, 2.0), -1.0)
    (speed,) = on.update(positions_at([9.0, 1.0, 1.0]), np.full(3, 2.0), 0.0).values()
    assert speed == pytest.approx(1.0)  # half the group's speed, however far it leads


def test_planned_speed_is_the_missions_or_unknown():
    speed = MissionItem(seq=2, command=178, param1=1, param2=3.5, param3=-1)
    assert planned_speed([[speed]]) == 3.5 and planned_speed([[]]) is None


def test_a_keeper_without_a_known_cruise_speed_stays_silent():
    keeper = FormationKeeper(PATHS, planned_speed_m_s=None, options=ON)
    assert not keeper.active
    assert keeper.update(positions_at([9.0, 1.0, 1.0]), np.full(3, 2.0), 0.0) == {}


def test_auto_starts_at_the_first_real_leg_and_keeps_the_cruise_speed():
    from ftlbo_mav.flight.fly import first_leg
    from ftlbo_mav.geo import LocalFrame
    from ftlbo_mav.mission.items import build_mission

    frame = LocalFrame(origin_lat_deg=12.2331044, origin_lon_deg=109.1144313)

    path = [(12.2332099, 109.1145051, 4.0), (12.2332254, 109.1145969, 4.0),
            (12.2332408, 109.1146886, 4.0)]
    plain = build_mission(home=(12.2332099, 109.1145051), takeoff_alt_m=4.0, path=path)
    assert [it.command for it in plain[:4]] == [16, 22, 16, 16]
    assert first_leg(plain, frame) == (3, [])  # item 2 is the start point it hovers at
    fast = build_mission(home=(12.2332099, 109.1145051), takeoff_alt_m=4.0, path=path,
                         speed_m_s=3.0)
    seq, speeds = first_leg(fast, frame)
    assert seq == 4 and [(s.command, s.param2) for s in speeds] == [(178, 3.0)]
    # a first waypoint elsewhere than the start point is a leg of its own: not skipped
    away = build_mission(home=(12.2332099, 109.1145051), takeoff_alt_m=4.0, path=path[1:])
    assert first_leg(away, frame) == (2, [])


def test_hysteresis_small_leads_are_left_alone_and_a_slowed_leader_waits_for_the_group():
    keeper = FormationKeeper(PATHS, planned_speed_m_s=10.0, options=ON)
    speeds = np.full(3, 2.8)
    assert keeper.update(positions_at([5.3, 5.0, 5.0]), speeds, 0.0) == {}  # 0.2 m: no
    assert list(keeper.update(positions_at([5.45, 5.0, 5.0]), speeds, 1.0)) == [0]  # 0.3 m
    assert keeper.update(positions_at([5.2, 5.0, 5.0]), speeds, 2.0) == {}  # 0.13 m: waits
    assert keeper.update(positions_at([5.05, 5.0, 5.0]), speeds, 3.0) == {0: 10.0}


def test_a_leader_below_walking_pace_is_not_nudged_and_caps_stay_near_its_own_speed():
    keeper = FormationKeeper(PATHS, planned_speed_m_s=10.0, options=ON)
    slow = np.array([0.6, 2.0, 2.0])
    keeper.update(positions_at([5.0, 5.0, 5.0]), slow, -1.0)
    assert keeper.update(positions_at([6.0, 5.0, 5.0]), slow, 0.0) == {}
    fast = np.array([3.0, 0.4, 0.4])
    keeper.update(positions_at([8.0, 5.0, 5.0]), fast, 1.0)
    (cap,) = keeper.update(positions_at([9.0, 5.0, 5.0]), fast, 2.0).values()
    assert cap == pytest.approx(0.85 * 3.0)  # not the laggards' 0.4 m/s


def test_no_nudge_while_the_group_accelerates():
    keeper = FormationKeeper(PATHS, planned_speed_m_s=10.0, options=ON)
    keeper.update(positions_at([2.0, 2.0, 2.0]), np.full(3, 1.5), 0.0)
    accelerating = np.array([2.5, 2.2, 2.2])  # 1 m/s in a second
    assert keeper.update(positions_at([4.0, 3.4, 3.4]), accelerating, 1.0) == {}
    steady = np.array([2.6, 2.4, 2.4])
    assert list(keeper.update(positions_at([6.6, 5.8, 5.8]), steady, 2.0)) == [0]
