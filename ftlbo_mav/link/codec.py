"""Mission items <-> MAVLink messages, and the item-by-item comparison behind ``verified``.

The only place where degrees become MAVLink's 1e-7 integers. MISSION_ITEM_INT carries
latitude and longitude as ``int32`` 1e-7 degrees, altitude and params as ``float32``:
a mission read back is compared in that encoding, never in the file's float text.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from ..ardupilot import fence as ap_fence
from ..ardupilot import storage
from ..ardupilot.storage import WireItem
from ..mission.items import MissionItem

MISSION_TYPE_MISSION = 0
MISSION_TYPE_FENCE = 1
MISSION_TYPE_RALLY = 2
MISSION_TYPE_NAMES = {MISSION_TYPE_MISSION: "mission", MISSION_TYPE_FENCE: "fence",
                      MISSION_TYPE_RALLY: "rally"}

# Altitudes: ArduPilot truncates ``z * 100.0f`` (float32) to whole centimetres, so 0.53 m
# is kept as 52 cm (0.53f * 100.0f = 52.999996); a read-back stored once more can lose
# another centimetre, and a vehicle that keeps items as sent has not truncated at all:
# altitudes compare within 1 cm.
ALT_TOLERANCE_CM = 1


def degrees_to_e7(deg: float) -> int:
    return round(deg * 1e7)


def to_wire(item: MissionItem) -> WireItem:
    """``item`` exactly as MISSION_ITEM_INT will carry it (1e-7 integers, float32)."""
    f = storage.f32
    return WireItem(seq=item.seq, command=item.command, frame=item.frame,
                    x=degrees_to_e7(item.lat_deg), y=degrees_to_e7(item.lon_deg),
                    z=f(item.alt_m), param1=f(item.param1), param2=f(item.param2),
                    param3=f(item.param3), param4=f(item.param4), current=item.current,
                    autocontinue=item.autocontinue)


def from_wire(w: WireItem) -> MissionItem:
    return MissionItem(seq=w.seq, command=w.command, frame=w.frame, lat_deg=w.x * 1e-7,
                       lon_deg=w.y * 1e-7, alt_m=w.z, param1=w.param1, param2=w.param2,
                       param3=w.param3, param4=w.param4, current=w.current,
                       autocontinue=w.autocontinue)


def encode_item(item: MissionItem, *, target_system: int, target_component: int,
                mission_type: int = MISSION_TYPE_MISSION):
    """One item as a MISSION_ITEM_INT message (frames as in the file)."""
    w = to_wire(item)
    return mavlink2.MAVLink_mission_item_int_message(
        target_system, target_component, w.seq, w.frame, w.command, w.current,
        w.autocontinue, w.param1, w.param2, w.param3, w.param4, w.x, w.y, w.z,
        mission_type,
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


def kept(item: MissionItem, mission_type: int = MISSION_TYPE_MISSION) -> WireItem:
    """What an ArduCopter keeps of ``item`` (:func:`ftlbo_mav.ardupilot.storage.stored`;
    fence and rally items: :func:`ftlbo_mav.ardupilot.fence.stored_item`); an item it
    would refuse stays as sent (the upload itself reports the refusal)."""
    w = to_wire(item)
    if ap_fence.check_item(w, mission_type) != mavlink2.MAV_MISSION_ACCEPTED:
        return w
    return ap_fence.stored_item(w, mission_type)


def _same(a: float, b: float) -> bool:
    return (math.isnan(a) and math.isnan(b)) or a == b


def item_differences(expected: MissionItem, actual: MissionItem,
                     mission_type: int = MISSION_TYPE_MISSION) -> list[str]:
    """What differs between two items once both are in the form an ArduCopter keeps
    (:mod:`ftlbo_mav.ardupilot.storage`, :mod:`ftlbo_mav.ardupilot.fence`): a read-back
    from ArduPilot and one from a vehicle that stores items as sent compare alike."""
    want, got = kept(expected, mission_type), kept(actual, mission_type)
    out = []
    if got.command != want.command:
        return [f"command {got.command}, expected {want.command}"]
    if got.frame != want.frame:
        out.append(f"frame {got.frame}, expected {want.frame}")
    for name, a, b in (("lat", got.x, want.x), ("lon", got.y, want.y)):
        if a != b:
            out.append(f"{name} {a * 1e-7:.7f}, expected {b * 1e-7:.7f}")
    if abs(storage.altitude_cm(got.z) - storage.altitude_cm(want.z)) > ALT_TOLERANCE_CM:
        out.append(f"alt {actual.alt_m:.2f} m, expected {expected.alt_m:.2f} m")
    for k, (a, b) in enumerate(zip(got.params, want.params), start=1):
        if not _same(a, b):
            out.append(f"param{k} {a:.7g}, expected {b:.7g} (as stored)")
    return out


def mission_differences(expected: Sequence[MissionItem], actual: Sequence[MissionItem], *,
                        mission_type: int = MISSION_TYPE_MISSION) -> list[str]:
    """Why ``actual`` (read back) is not ``expected``; empty when they match.

    In a mission, item 0 is not compared: ArduPilot answers a read-back with its own
    home as item 0 (MissionItemProtocol_Waypoints::get_item reads slot 0 =
    AP::ahrs().get_home()); fence and rally items are all compared. A list that came
    back shorter or longer never matches.
    """
    problems = []
    if len(actual) != len(expected):
        problems.append(f"read back {len(actual)} items, sent {len(expected)}")
    first = 1 if mission_type == MISSION_TYPE_MISSION else 0
    for want, got in zip(expected[first:], actual[first:]):
        diff = item_differences(want, got, mission_type)
        if diff:
            problems.append(f"item {want.seq}: " + "; ".join(diff))
    return problems


def storage_warnings(items: Sequence[MissionItem]) -> list[str]:
    """One line per item whose stored form loses something that matters to the flight
    (:func:`ftlbo_mav.ardupilot.storage.storage_notes`), item 0 (home) excepted."""
    out = []
    for item in items[1:]:
        notes = storage.storage_notes(to_wire(item))
        if notes:
            out.append(f"item {item.seq} ({item.name}): " + "; ".join(notes))
    return out
