"""Mission items <-> MAVLink messages, and the item-by-item comparison behind ``verified``.

The only place where degrees become MAVLink's 1e-7 integers. MISSION_ITEM_INT carries
latitude and longitude as ``int32`` 1e-7 degrees, altitude and params as ``float32``:
a mission read back is compared in that encoding, never in the file's float text.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Sequence

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from ..mission.items import MissionItem

MISSION_TYPE_MISSION = 0

# The *_INT frames say "x, y are 1e-7 integers", which MISSION_ITEM_INT says anyway:
# ArduPilot stores GLOBAL_RELATIVE_ALT_INT (6) as GLOBAL_RELATIVE_ALT (3) and returns 3 on
# read-back (AP_Mission::mavlink_int_to_mission_cmd / mission_cmd_to_mavlink_int keep only
# the altitude frame), likewise 5 -> 0 and 11 -> 10.
_FRAME_TWIN = {5: 0, 6: 3, 11: 10}

# Commands whose item carries a position (AP_Mission::stored_in_location, libraries/
# AP_Mission/AP_Mission.cpp). For any other command (DO_CHANGE_SPEED, RETURN_TO_LAUNCH...)
# the frame means nothing: ArduPilot returns frame 0 (GLOBAL) whatever was sent.
POSITION_COMMANDS = frozenset(getattr(mavlink2, f"MAV_CMD_{name}") for name in (
    "NAV_WAYPOINT", "NAV_LOITER_UNLIM", "NAV_LOITER_TURNS", "NAV_LOITER_TIME", "NAV_LAND",
    "NAV_TAKEOFF", "NAV_CONTINUE_AND_CHANGE_ALT", "NAV_LOITER_TO_ALT", "NAV_SPLINE_WAYPOINT",
    "NAV_GUIDED_ENABLE", "DO_SET_HOME", "DO_LAND_START", "DO_GO_AROUND", "DO_SET_ROI",
    "NAV_VTOL_TAKEOFF", "NAV_VTOL_LAND", "NAV_PAYLOAD_PLACE",
))

# ArduPilot keeps altitudes as int32 centimetres (Location::alt, libraries/AP_Common/Location.h):
# an altitude comes back rounded to the centimetre.
ALT_TOLERANCE_M = 0.01
PARAM_TOLERANCE = 1e-4


def degrees_to_e7(deg: float) -> int:
    return round(deg * 1e7)


def encode_item(item: MissionItem, *, target_system: int, target_component: int):
    """One item as a MISSION_ITEM_INT message (frames as in the file)."""
    return mavlink2.MAVLink_mission_item_int_message(
        target_system, target_component, item.seq, item.frame, item.command,
        item.current, item.autocontinue,
        item.param1, item.param2, item.param3, item.param4,
        degrees_to_e7(item.lat_deg), degrees_to_e7(item.lon_deg), item.alt_m,
        MISSION_TYPE_MISSION,
    )


def decode_item(msg) -> MissionItem:
    """A MISSION_ITEM_INT (or a float MISSION_ITEM) -> :class:`MissionItem`."""
    scale = 1e-7 if msg.get_type() == "MISSION_ITEM_INT" else 1.0
    return MissionItem(
        seq=msg.seq, command=msg.command, frame=msg.frame,
        lat_deg=msg.x * scale, lon_deg=msg.y * scale, alt_m=float(msg.z),
        param1=float(msg.param1), param2=float(msg.param2),
        param3=float(msg.param3), param4=float(msg.param4),
        current=msg.current, autocontinue=msg.autocontinue,
    )


def _f32(x: float) -> float:
    return struct.unpack("<f", struct.pack("<f", x))[0]


def _same_param(a: float, b: float) -> bool:
    a, b = _f32(a), _f32(b)
    if math.isnan(a) or math.isnan(b):
        return math.isnan(a) and math.isnan(b)
    return abs(a - b) <= PARAM_TOLERANCE * max(1.0, abs(a))


def same_frame(a: int, b: int) -> bool:
    return _FRAME_TWIN.get(a, a) == _FRAME_TWIN.get(b, b)


def item_differences(expected: MissionItem, actual: MissionItem) -> list[str]:
    """What differs between two items, compared as MISSION_ITEM_INT carries them."""
    out = []
    if actual.command != expected.command:
        out.append(f"command {actual.command}, expected {expected.command}")
    if expected.command in POSITION_COMMANDS and not same_frame(actual.frame, expected.frame):
        out.append(f"frame {actual.frame}, expected {expected.frame}")
    for name in ("lat_deg", "lon_deg"):
        got, want = degrees_to_e7(getattr(actual, name)), degrees_to_e7(getattr(expected, name))
        if got != want:
            out.append(f"{name[:3]} {got * 1e-7:.7f}, expected {want * 1e-7:.7f}")
    if abs(_f32(actual.alt_m) - _f32(expected.alt_m)) > ALT_TOLERANCE_M:
        out.append(f"alt {actual.alt_m:.2f} m, expected {expected.alt_m:.2f} m")
    for k in (1, 2, 3, 4):
        got, want = getattr(actual, f"param{k}"), getattr(expected, f"param{k}")
        if not _same_param(got, want):
            out.append(f"param{k} {got:g}, expected {want:g}")
    return out


def mission_differences(expected: Sequence[MissionItem],
                        actual: Sequence[MissionItem]) -> list[str]:
    """Why ``actual`` (read back) is not ``expected``; empty when they match.

    Item 0 is not compared: ArduPilot answers a read-back with its own home as item 0
    (MissionItemProtocol_Waypoints::get_item reads slot 0 = AP::ahrs().get_home()).
    A mission that came back shorter or longer never matches.
    """
    problems = []
    if len(actual) != len(expected):
        problems.append(f"read back {len(actual)} items, sent {len(expected)}")
    for want, got in zip(expected[1:], actual[1:]):
        diff = item_differences(want, got)
        if diff:
            problems.append(f"item {want.seq}: " + "; ".join(diff))
    return problems
