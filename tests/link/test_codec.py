"""Items <-> MISSION_ITEM_INT and the comparison behind `verified`."""

from __future__ import annotations

from dataclasses import replace

from hypothesis import given
from hypothesis import strategies as st

from ftlbo_mav.link.codec import (
    decode_item,
    encode_item,
    item_differences,
    mission_differences,
    storage_warnings,
)
from ftlbo_mav.mission.items import MissionItem
from tests.link.support import make_mission

lat = st.floats(-90, 90, allow_nan=False)
lon = st.floats(-180, 180, allow_nan=False)
alt = st.floats(-500, 10_000, allow_nan=False)


@given(lat, lon, alt, st.sampled_from([0, 3, 6, 10]), st.integers(0, 65535))
def test_encode_decode_round_trip_compares_equal(la, lo, al, frame, command):
    item = MissionItem(seq=3, command=command, frame=frame, lat_deg=la, lon_deg=lo, alt_m=al,
                       param1=1.5, param2=-2.0, param3=0.25, param4=float("nan"))
    msg = encode_item(item, target_system=1, target_component=1)
    assert msg.x == round(la * 1e7) and msg.y == round(lo * 1e7)
    back = decode_item(msg)
    assert item_differences(item, back) == []


def test_coordinates_compare_after_the_1e7_integer_encoding():
    item = MissionItem(seq=1, command=16, lat_deg=12.23320990, lon_deg=109.11453270)
    assert item_differences(item, replace(item, lat_deg=12.2332099049)) == []
    (diff,) = item_differences(item, replace(item, lat_deg=12.2332100))
    assert diff.startswith("lat 12.2332100, expected 12.2332099")


@given(st.sampled_from([(6, 3), (3, 6), (5, 0), (0, 2), (11, 10)]))
def test_frames_compare_as_arducopter_keeps_them(pair):
    item = MissionItem(seq=2, command=16, frame=pair[0], lat_deg=12.2, lon_deg=109.1, alt_m=6)
    assert item_differences(item, replace(item, frame=pair[1])) == []


def test_altitude_frames_that_differ_are_named():
    item = MissionItem(seq=2, command=16, frame=3, lat_deg=12.2, lon_deg=109.1, alt_m=6)
    assert item_differences(item, replace(item, frame=0)) == ["frame 0, expected 3"]
    assert item_differences(item, replace(item, frame=10)) == ["frame 10, expected 3"]


def test_altitude_is_compared_to_the_centimetre_and_params_as_float32():
    item = MissionItem(seq=1, command=178, param1=1, param2=0.1, param3=-1)
    assert item_differences(item, replace(item, param2=0.100000001)) == []
    assert item_differences(item, replace(item, param2=0.1001)) == [
        "param2 0.1001, expected 0.1 (as stored)"]
    waypoint = MissionItem(seq=1, command=16, alt_m=20.37)
    assert item_differences(waypoint, replace(waypoint, alt_m=20.37499)) == []
    assert item_differences(waypoint, replace(waypoint, alt_m=20.40)) == [
        "alt 20.40 m, expected 20.37 m"]


def test_an_arducopter_read_back_verifies_what_was_sent():
    """What ArduPilot returns (recorded: NAV_LAND param4 0 -> 1, waypoint hold 2.7 -> 2,
    frame 6 -> 3, altitude truncated to the centimetre) is not a difference."""
    land = MissionItem(seq=14, command=21, frame=6, lat_deg=12.23347400, lon_deg=109.1151763)
    assert item_differences(land, replace(land, frame=3, param4=1.0)) == []
    hold = MissionItem(seq=3, command=16, lat_deg=12.2, lon_deg=109.1, alt_m=6.009, param1=2.7,
                       param4=float("nan"))
    assert item_differences(hold, replace(hold, param1=2.0, param4=0.0, alt_m=6.0)) == []
    assert item_differences(hold, replace(hold, param1=3.0)) == [
        "param1 3, expected 2 (as stored)"]


def test_what_a_copter_would_not_keep_is_named_before_upload():
    items = make_mission()
    assert storage_warnings(items) == []
    held = items[:4] + [replace(items[4], param1=2.5)] + items[5:]
    (line,) = storage_warnings(held)
    assert line.startswith("item 4 (WAYPOINT): param1 (hold time) 2.5 is stored as 2")


def test_item_zero_is_not_compared_but_length_and_every_other_item_are():
    items = make_mission()
    vehicle_home = replace(items[0], lat_deg=-35.0, lon_deg=149.0, alt_m=584.0)
    assert mission_differences(items, [vehicle_home] + items[1:]) == []
    assert mission_differences(items, items[:10]) == ["read back 10 items, sent 16"]
    wrong = items[:4] + [replace(items[4], command=21)] + items[5:]
    assert mission_differences(items, wrong) == ["item 4: command 21, expected 16"]


def test_frame_is_ignored_for_commands_without_a_position():
    """ArduPilot returns DO_CHANGE_SPEED and RETURN_TO_LAUNCH in frame 0 whatever was sent."""
    speed = MissionItem(seq=2, command=178, frame=3, param1=1, param2=5.0, param3=-1)
    rtl = MissionItem(seq=14, command=20, frame=3)
    assert item_differences(speed, replace(speed, frame=0)) == []
    assert item_differences(rtl, replace(rtl, frame=0)) == []
    waypoint = MissionItem(seq=3, command=16, frame=3)
    assert item_differences(waypoint, replace(waypoint, frame=0)) == ["frame 0, expected 3"]
