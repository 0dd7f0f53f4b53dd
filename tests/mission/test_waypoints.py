from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pymavlink import mavwp

from ftlbo_mav.errors import MissionFileError
from ftlbo_mav.mission.items import (
    CMD_DO_CHANGE_SPEED,
    CMD_NAV_DELAY,
    CMD_NAV_LAND,
    CMD_NAV_LOITER_UNLIM,
    CMD_NAV_RETURN_TO_LAUNCH,
    CMD_NAV_TAKEOFF,
    CMD_NAV_WAYPOINT,
    FRAME_GLOBAL,
    FRAME_GLOBAL_RELATIVE_ALT,
    build_mission,
)
from ftlbo_mav.mission.waypoints import (
    parse_waypoints,
    read_waypoints,
    render_waypoints,
    write_waypoints,
)

coord = st.tuples(
    st.floats(-89.9, 89.9).map(lambda v: round(v, 8)),
    st.floats(-179.9, 179.9).map(lambda v: round(v, 8)),
    st.floats(0.5, 120).map(lambda v: round(v, 6)),
)


@settings(max_examples=100, deadline=None)
@given(path=st.lists(coord, min_size=2, max_size=20),
       end=st.sampled_from(["land", "rtl", "loiter"]),
       speed=st.none() | st.floats(0.5, 15).map(lambda v: round(v, 3)))
def test_render_parse_round_trip(path, end, speed):
    items = build_mission(home=path[0][:2], takeoff_alt_m=path[0][2], path=path,
                          end_action=end, speed_m_s=speed)
    text = render_waypoints(items)
    assert parse_waypoints(text) == items
    assert render_waypoints(parse_waypoints(text)) == text


def test_mission_layout_and_file_format(tmp_path):
    path = [(12.23, 109.11, 4.0), (12.2301, 109.1101, 5.0), (12.2302, 109.1102, 4.0)]
    items = build_mission(home=(12.23, 109.11), takeoff_alt_m=4.0, path=path)
    assert [it.command for it in items] == [
        CMD_NAV_WAYPOINT, CMD_NAV_TAKEOFF, CMD_NAV_WAYPOINT, CMD_NAV_DELAY, CMD_NAV_WAYPOINT,
        CMD_NAV_WAYPOINT, CMD_NAV_LAND,
    ]
    # the start gate as planned: no time given (fly writes one before its start)
    assert (items[3].param1, items[3].param2, items[3].param3, items[3].param4) == (-1,) * 4
    assert items[0].frame == FRAME_GLOBAL and items[0].current == 1
    assert all(it.frame == FRAME_GLOBAL_RELATIVE_ALT for it in items[1:])
    assert all(it.autocontinue == 1 for it in items)
    assert (items[-1].lat_deg, items[-1].lon_deg) == path[-1][:2]

    file = write_waypoints(tmp_path / "m.waypoints", items)
    lines = file.read_text().splitlines()
    assert lines[0] == "QGC WPL 110"
    fields = lines[1].split("\t")
    assert len(fields) == 12 and fields[1] == "1" and fields[2] == "0"
    assert fields[8] == "12.23000000" and fields[9] == "109.11000000"  # 8 decimals
    assert list(tmp_path.iterdir()) == [file]  # no temp file left behind


def test_end_actions_and_speed():
    path = [(1.0, 2.0, 4.0), (1.0001, 2.0001, 4.0)]
    rtl = build_mission(home=(1, 2), takeoff_alt_m=4, path=path, end_action="rtl")
    assert rtl[-1].command == CMD_NAV_RETURN_TO_LAUNCH
    loiter = build_mission(home=(1, 2), takeoff_alt_m=4, path=path, end_action="loiter")
    assert loiter[-1].command == CMD_NAV_LOITER_UNLIM and loiter[-1].alt_m == 4.0
    fast = build_mission(home=(1, 2), takeoff_alt_m=4, path=path, speed_m_s=3.0)
    # after the start point and its gate, where fly's synchronized AUTO start begins
    # (first_leg): it runs as the legs begin
    assert [it.command for it in fast[1:6]] == [22, 16, CMD_NAV_DELAY, CMD_DO_CHANGE_SPEED, 16]
    assert fast[4].param2 == 3.0 and [it.seq for it in fast] == list(range(len(fast)))
    with pytest.raises(ValueError):
        build_mission(home=(1, 2), takeoff_alt_m=4, path=path, end_action="crash")


def test_pymavlink_loads_our_file_unchanged(tmp_path):
    path = [(12.2332099, 109.1145051, 4.0), (12.2333, 109.1147, 5.5), (12.233474, 109.1151763, 4.0)]
    items = build_mission(home=(12.2332099, 109.1145051), takeoff_alt_m=4.0, path=path)
    file = write_waypoints(tmp_path / "uav1.waypoints", items)
    loader = mavwp.MAVWPLoader()
    assert loader.load(str(file)) == len(items)
    for ours, theirs in zip(items, (loader.wp(i) for i in range(loader.count()))):
        assert (theirs.seq, theirs.frame, theirs.command) == (ours.seq, ours.frame, ours.command)
        assert theirs.current == ours.current and theirs.autocontinue == ours.autocontinue
        assert theirs.x == pytest.approx(ours.lat_deg, abs=1e-8)
        assert theirs.y == pytest.approx(ours.lon_deg, abs=1e-8)
        assert theirs.z == pytest.approx(ours.alt_m, abs=1e-6)
    # and pymavlink's writer (6 decimals) produces a file our parser reads back
    loader.save(str(tmp_path / "saved.waypoints"))
    again = read_waypoints(tmp_path / "saved.waypoints")
    assert [(i.command, i.frame) for i in again] == [(i.command, i.frame) for i in items]
    assert all(abs(a.lat_deg - b.lat_deg) <= 5e-7 for a, b in zip(again, items))


@pytest.mark.parametrize(
    "text, words",
    [
        ("", "empty"),
        ("hello\n", "header"),
        ("QGC WPL 120\n0\t1\t0\t16\t0\t0\t0\t0\t1\t2\t0\t1\n", "version 110"),
        ("QGC WPL 110\n0\t1\t0\t16\t0\t0\t0\t1\t2\t0\t1\n", "12 fields"),
        ("QGC WPL 110\n0\t1\t0\t16\t0\t0\t0\t0\tx\t2\t0\t1\n", "not a number"),
        ("QGC WPL 110\n1\t1\t0\t16\t0\t0\t0\t0\t1\t2\t0\t1\n", "expected 0"),
        ("QGC WPL 110\n0\t1\t0\t16\t0\t0\t0\t0\t91\t2\t0\t1\n", "out of range"),
        ("QGC WPL 110\n", "no mission items"),
    ],
)
def test_parse_errors_name_the_line(text, words):
    with pytest.raises(MissionFileError, match=words):
        parse_waypoints(text, source="x.waypoints")


def test_unreadable_file(tmp_path):
    with pytest.raises(MissionFileError, match="no such file"):
        read_waypoints(tmp_path / "missing.waypoints")


def test_written_files_are_readable_by_others(tmp_path):
    import os
    import stat

    file = write_waypoints(tmp_path / "m.waypoints",
                           build_mission(home=(1, 2), takeoff_alt_m=4,
                                         path=[(1.0, 2.0, 4.0), (1.0001, 2.0, 4.0)]))
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(file.stat().st_mode) == 0o666 & ~umask
