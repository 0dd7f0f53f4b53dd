"""QGroundControl ``.plan`` files: one mission per file, the same items as the ``.waypoints``.

A ``.plan`` is JSON (QGC developer guide, "Plan File Format"): ``fileType`` "Plan",
``version`` 1, and a ``mission`` object with ``version`` 2, the firmware and vehicle
types, ``plannedHomePosition`` ``[lat, lon, alt]`` and ``items``. Home is not an item
there: item 0 of a ``.waypoints`` file becomes ``plannedHomePosition`` and items 1.. become
``SimpleItem`` objects whose ``doJumpId`` is their ``.waypoints`` index, with the same
frame, command and the seven parameters ``[p1, p2, p3, p4, lat, lon, alt]``.

QGroundControl reads the home altitude as metres above mean sea level. ftlbo-mav knows
altitudes relative to home only, so it writes 0; every item is in a relative-altitude
frame, so the vehicle flies the same heights wherever home is.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import MissionFileError
from .files import read_mission_text, write_atomic
from .items import (
    CMD_FENCE_CIRCLE_EXCLUSION,
    CMD_FENCE_POLYGON_VERTEX_INCLUSION,
    CMD_NAV_LAND,
    CMD_NAV_LOITER_UNLIM,
    CMD_NAV_TAKEOFF,
    CMD_NAV_WAYPOINT,
    FRAME_GLOBAL,
    MissionItem,
)

if TYPE_CHECKING:
    from .fence import UavFence

FIRMWARE_ARDUPILOT = 3  # MAV_AUTOPILOT_ARDUPILOTMEGA
VEHICLE_QUADROTOR = 2  # MAV_TYPE_QUADROTOR
ALTITUDE_MODE_RELATIVE = 1  # QGC: altitudes relative to home
DEFAULT_HOVER_SPEED_M_S = 5.0

# Commands with a position: QGC writes their altitude and altitude mode next to params.
_NAV_COMMANDS = {CMD_NAV_WAYPOINT, CMD_NAV_TAKEOFF, CMD_NAV_LAND, CMD_NAV_LOITER_UNLIM}


def geofence_document(fence: UavFence | None) -> dict:
    """QGC's ``geoFence`` (version 2): ``polygons`` ``{inclusion, polygon [[lat, lon]..],
    version 1}`` and ``circles`` ``{inclusion, circle {center [lat, lon], radius},
    version 1}``, from the fence items (consecutive polygon vertices make one polygon)."""
    polygons, circles = [], []
    items = list(fence.fence) if fence is not None else []
    i = 0
    while i < len(items):
        it = items[i]
        if it.command == CMD_FENCE_POLYGON_VERTEX_INCLUSION:
            n = int(it.param1)
            polygons.append({"inclusion": True, "version": 1,
                             "polygon": [[v.lat_deg, v.lon_deg] for v in items[i:i + n]]})
            i += n
            continue
        if it.command == CMD_FENCE_CIRCLE_EXCLUSION:
            circles.append({"inclusion": False, "version": 1,
                            "circle": {"center": [it.lat_deg, it.lon_deg], "radius": it.param1}})
        i += 1
    return {"version": 2, "circles": circles, "polygons": polygons}


def rally_document(fence: UavFence | None) -> dict:
    """QGC's ``rallyPoints`` (version 2): ``points`` ``[lat, lon, alt]``, alt above home."""
    points = [[r.lat_deg, r.lon_deg, r.alt_m] for r in (fence.rally if fence else ())]
    return {"version": 2, "points": points}


def plan_document(
    items: Sequence[MissionItem], *, hover_speed_m_s: float | None = None,
    fence: UavFence | None = None,
) -> dict:
    """Items (item 0 home, as in a ``.waypoints`` file) -> the ``.plan`` JSON object;
    ``fence``: the UAV's fence and rally point for ``geoFence`` and ``rallyPoints``."""
    if not items:
        raise ValueError("a mission needs at least its home item")
    home, rest = items[0], items[1:]
    speed = hover_speed_m_s if hover_speed_m_s is not None else DEFAULT_HOVER_SPEED_M_S
    return {
        "fileType": "Plan",
        "version": 1,
        "groundStation": "ftlbo-mav",
        "mission": {
            "version": 2,
            "firmwareType": FIRMWARE_ARDUPILOT,
            "vehicleType": VEHICLE_QUADROTOR,
            "globalPlanAltitudeMode": ALTITUDE_MODE_RELATIVE,
            "cruiseSpeed": speed,
            "hoverSpeed": speed,
            "plannedHomePosition": [home.lat_deg, home.lon_deg, home.alt_m],
            "items": [_simple_item(it) for it in rest],
        },
        "geoFence": geofence_document(fence),
        "rallyPoints": rally_document(fence),
    }


def _simple_item(it: MissionItem) -> dict:
    item = {
        "type": "SimpleItem",
        "doJumpId": it.seq,
        "autoContinue": bool(it.autocontinue),
        "frame": it.frame,
        "command": it.command,
        "params": [it.param1, it.param2, it.param3, it.param4, it.lat_deg, it.lon_deg, it.alt_m],
    }
    if it.command in _NAV_COMMANDS:
        item.update(
            Altitude=it.alt_m, AltitudeMode=ALTITUDE_MODE_RELATIVE, AMSLAltAboveTerrain=None
        )
    return item


def render_plan(items: Sequence[MissionItem], *, hover_speed_m_s: float | None = None,
                fence: UavFence | None = None) -> str:
    """Items -> ``.plan`` text (JSON, trailing newline)."""
    doc = plan_document(items, hover_speed_m_s=hover_speed_m_s, fence=fence)
    return json.dumps(doc, indent=2) + "\n"


def parse_plan(text: str, *, source: str = "<plan>") -> list[MissionItem]:
    """``.plan`` text -> items with home as item 0, as :func:`parse_waypoints` returns them.

    Only ``SimpleItem`` mission items are read (ftlbo-mav writes no complex items).
    Raises :class:`MissionFileError` naming the file and the item.
    """
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise MissionFileError(f"{source}: not JSON: {exc}") from None
    if not isinstance(doc, dict) or doc.get("fileType") != "Plan":
        raise MissionFileError(f"{source}: fileType must be \"Plan\"")
    mission = doc.get("mission")
    if not isinstance(mission, dict):
        raise MissionFileError(f"{source}: mission: missing")
    home = mission.get("plannedHomePosition")
    if not (isinstance(home, list) and len(home) == 3 and all(_is_number(v) for v in home)):
        raise MissionFileError(f"{source}: mission.plannedHomePosition: expected [lat, lon, alt]")
    items = [
        MissionItem(
            seq=0, command=CMD_NAV_WAYPOINT, frame=FRAME_GLOBAL,
            lat_deg=float(home[0]), lon_deg=float(home[1]), alt_m=float(home[2]), current=1,
        )
    ]
    raw_items = mission.get("items")
    if not isinstance(raw_items, list):
        raise MissionFileError(f"{source}: mission.items: expected an array")
    for i, raw in enumerate(raw_items):
        where = f"{source}: mission.items[{i}]"
        if not isinstance(raw, dict) or raw.get("type") != "SimpleItem":
            raise MissionFileError(f"{where}: only SimpleItem items are supported")
        params = raw.get("params")
        if not (isinstance(params, list) and len(params) == 7):
            raise MissionFileError(f"{where}: params: expected 7 numbers")
        # QGC writes NaN parameters as null.
        values = [math.nan if p is None else p for p in params]
        if not all(_is_number(v) for v in values) or not all(
            _is_int(raw.get(k)) for k in ("frame", "command")
        ):
            raise MissionFileError(f"{where}: frame, command and params must be numbers")
        p1, p2, p3, p4, lat, lon, alt = (float(v) for v in values)
        items.append(
            MissionItem(
                seq=len(items), command=int(raw["command"]), frame=int(raw["frame"]),
                lat_deg=lat, lon_deg=lon, alt_m=alt,
                param1=p1, param2=p2, param3=p3, param4=p4,
                autocontinue=int(bool(raw.get("autoContinue", True))),
            )
        )
    return items


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _is_int(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def read_plan_file(path: str | Path) -> list[MissionItem]:
    return parse_plan(read_mission_text(path), source=str(path))


def write_plan_file(
    path: str | Path, items: Iterable[MissionItem], *, hover_speed_m_s: float | None = None
) -> Path:
    return write_atomic(path, render_plan(list(items), hover_speed_m_s=hover_speed_m_s))
