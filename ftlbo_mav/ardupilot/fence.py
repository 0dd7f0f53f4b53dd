"""How ArduCopter 4.5 keeps fence and rally items, its fence parameters, and its breach rules.

Fence and rally points travel through the mission protocol with ``mission_type`` FENCE (1)
and RALLY (2), but ArduPilot stores them apart from the mission, each in its own form:

- **Fence** (libraries/GCS_MAVLink/MissionItemProtocol_Fence.cpp
  ``convert_MISSION_ITEM_INT_to_AC_PolyFenceItem`` and ``get_item_as_mission_item``;
  libraries/AC_Fence/AC_PolyFence_loader.cpp ``write_fence`` / ``get_item``): an item is
  accepted in frames GLOBAL, GLOBAL_RELATIVE_ALT, GLOBAL_TERRAIN_ALT (and their _INT
  spellings), else UNSUPPORTED_FRAME; only the five MAV_CMD_NAV_FENCE_* commands, else
  UNSUPPORTED. What is kept: the type, lat/lon as int32 1e-7 degrees, a polygon vertex's
  count (``vertex_count = param1``, a uint8) and a circle's radius (param1; stored as a
  uint32 when it is within 0.001 of a whole number below it, ``store_as_int``, else as a
  float). Altitude and params 2-4 are not kept: a read-back gives frame GLOBAL (0), z 0,
  params 2-4 0, current 0 and autocontinue 0 (the zero-initialised
  ``mavlink_mission_item_int_t`` of ``MissionItemProtocol::handle_mission_request_int``).
  Items are collected during the upload and written only at its end, after
  ``AC_PolyFence_loader::validate_fence``; a fence it refuses leaves the stored one
  unchanged and the final MISSION_ACK is ERROR, with a STATUSTEXT saying why.
- **Rally** (libraries/GCS_MAVLink/MissionItemProtocol_Rally.cpp
  ``convert_MISSION_ITEM_INT_to_RallyLocation`` / ``get_item_as_mission_item``;
  libraries/AP_Rally/AP_Rally.h ``RallyLocation``): only MAV_CMD_NAV_RALLY_POINT; lat/lon
  int32, the altitude an **int16 of whole metres** (``ret.alt = cmd.z``: truncated toward
  zero; outside int16 -> INVALID_PARAM7) and its frame (GLOBAL, RELATIVE_ALT, TERRAIN_ALT,
  else UNSUPPORTED_FRAME). A read-back gives that frame (non-_INT), z the whole metres,
  params 0, current 0, autocontinue 0. Items are stored one by one as they arrive
  (``append_item`` / ``replace_item``), the list truncated at MISSION_COUNT.

The breach rules (libraries/AC_Fence/AC_Fence.cpp ``check``, ``check_fence_alt_max``,
``check_fence_polygon``; AC_PolyFence_loader.cpp ``breached``) and Copter's response
(ArduCopter/fence.cpp ``Copter::fence_check``, run at 25 Hz by ArduCopter/Copter.cpp's
scheduler) are :func:`breaches` and :func:`breach_modes`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as R

from .modes import CopterMode
from .navigation import INT8, REAL32, ParamDefault
from .storage import WireItem, c_int, check, f32, stored, u8

MISSION_TYPE_MISSION = R.MAV_MISSION_TYPE_MISSION
MISSION_TYPE_FENCE = R.MAV_MISSION_TYPE_FENCE
MISSION_TYPE_RALLY = R.MAV_MISSION_TYPE_RALLY

FENCE_RETURN_POINT = R.MAV_CMD_NAV_FENCE_RETURN_POINT                      # 5000
FENCE_POLYGON_INCLUSION = R.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION     # 5001
FENCE_POLYGON_EXCLUSION = R.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION     # 5002
FENCE_CIRCLE_INCLUSION = R.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION              # 5003
FENCE_CIRCLE_EXCLUSION = R.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION              # 5004
RALLY_POINT = R.MAV_CMD_NAV_RALLY_POINT                                    # 5100

FENCE_COMMANDS = frozenset({FENCE_RETURN_POINT, FENCE_POLYGON_INCLUSION, FENCE_POLYGON_EXCLUSION,
                            FENCE_CIRCLE_INCLUSION, FENCE_CIRCLE_EXCLUSION})
_POLYGONS = (FENCE_POLYGON_INCLUSION, FENCE_POLYGON_EXCLUSION)
_CIRCLES = (FENCE_CIRCLE_INCLUSION, FENCE_CIRCLE_EXCLUSION)

# frames accepted for a fence item (convert_MISSION_ITEM_INT_to_AC_PolyFenceItem) and for
# a rally point, with the frame a rally read-back reports (get_item_as_mission_item)
_FENCE_FRAMES = frozenset({R.MAV_FRAME_GLOBAL, R.MAV_FRAME_GLOBAL_INT,
                           R.MAV_FRAME_GLOBAL_RELATIVE_ALT, R.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                           R.MAV_FRAME_GLOBAL_TERRAIN_ALT, R.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT})
_RALLY_FRAME_KEPT = {
    R.MAV_FRAME_GLOBAL: R.MAV_FRAME_GLOBAL, R.MAV_FRAME_GLOBAL_INT: R.MAV_FRAME_GLOBAL,
    R.MAV_FRAME_GLOBAL_RELATIVE_ALT: R.MAV_FRAME_GLOBAL_RELATIVE_ALT,
    R.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT: R.MAV_FRAME_GLOBAL_RELATIVE_ALT,
    R.MAV_FRAME_GLOBAL_TERRAIN_ALT: R.MAV_FRAME_GLOBAL_TERRAIN_ALT,
    R.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT: R.MAV_FRAME_GLOBAL_TERRAIN_ALT,
}

# AC_PolyFence_loader::max_items: MIN(255, storage size / 8); AP_Rally::get_rally_max:
# storage size / sizeof(RallyLocation), at most 255. The storage sizes are board
# settings (StorageManager); these are the ceilings, not SITL's measured capacity.
FENCE_CAPACITY = 255
RALLY_CAPACITY = 255


def _check_latlon(item: WireItem) -> int:
    if not -900_000_000 <= item.x <= 900_000_000:  # AP_Math check_lat
        return R.MAV_MISSION_INVALID_PARAM5_X
    if not -1_800_000_000 <= item.y <= 1_800_000_000:  # check_lng
        return R.MAV_MISSION_INVALID_PARAM6_Y
    return R.MAV_MISSION_ACCEPTED


def check_fence_item(item: WireItem) -> int:
    """The MAV_MISSION_RESULT of ``replace_item`` for one fence item."""
    if item.frame not in _FENCE_FRAMES:
        return R.MAV_MISSION_UNSUPPORTED_FRAME
    if item.command not in FENCE_COMMANDS:
        return R.MAV_MISSION_UNSUPPORTED
    return R.MAV_MISSION_ACCEPTED


def circle_radius_stored(radius_m: float) -> float:
    """AC_PolyFence_loader::write_fence: ``store_as_int = radius - int(radius) < 0.001``
    keeps a uint32 (the whole metres), else the float32 radius."""
    r = f32(radius_m)
    whole = c_int(r, 32, signed=True)
    if f32(r - whole) < 0.001:
        return float(c_int(r, 32, signed=False))
    return r


def stored_fence_item(item: WireItem) -> WireItem:
    """The fence item as a read-back returns it (``get_item_as_mission_item``)."""
    if check_fence_item(item) != R.MAV_MISSION_ACCEPTED:
        raise ValueError("ArduCopter refuses this fence item")
    p1 = 0.0
    if item.command in _POLYGONS:
        p1 = float(u8(f32(item.param1)))  # AC_PolyFenceItem::vertex_count is a uint8_t
    elif item.command in _CIRCLES:
        p1 = circle_radius_stored(item.param1)
    return WireItem(seq=item.seq, command=item.command, frame=R.MAV_FRAME_GLOBAL, x=item.x,
                    y=item.y, z=0.0, param1=p1, current=0, autocontinue=0)


def validate_fence(items: Sequence[WireItem]) -> str | None:
    """AC_PolyFence_loader::validate_fence on a whole upload: None when ArduCopter writes
    the fence, else the STATUSTEXT it sends (the upload then ends with ACK ERROR)."""
    expecting, left, count = None, 0, 0
    seen_return = False
    for it in items:
        kind = it.command
        if kind in _POLYGONS:
            n = u8(f32(it.param1))
            if n < 3:
                return f"Invalid vertex count ({n})"
            if left == 0:
                expecting, left, count = kind, n, n
            elif kind != expecting:
                return f"Received incorrect vertex type (want={expecting} got={kind})"
            elif n != count:
                return f"Unexpected vertex count want={count} got={n}"
            left -= 1
        elif kind in _CIRCLES:
            if left:
                return f"Received incorrect type (want={expecting} got={kind})"
            if not f32(it.param1) > 1.1920928955078125e-07:  # is_positive
                return "Non-positive circle radius"
        elif kind == FENCE_RETURN_POINT:
            if left:
                return f"Received incorrect type (want={expecting} got={kind})"
            if seen_return:
                return "Multiple return points"
            seen_return = True
        if _check_latlon(it) != R.MAV_MISSION_ACCEPTED:
            return "Bad lat or lon"
    if left:
        return "Incorrect item count"
    return None


def check_rally_item(item: WireItem) -> int:
    """The MAV_MISSION_RESULT of ``convert_MISSION_ITEM_INT_to_RallyLocation``."""
    if item.command != RALLY_POINT:
        return R.MAV_MISSION_UNSUPPORTED
    latlon = _check_latlon(item)
    if latlon != R.MAV_MISSION_ACCEPTED:
        return latlon
    if math.isnan(item.z) or not -32768 <= item.z <= 32767:
        return R.MAV_MISSION_INVALID_PARAM7
    if item.frame not in _RALLY_FRAME_KEPT:
        return R.MAV_MISSION_UNSUPPORTED_FRAME
    return R.MAV_MISSION_ACCEPTED


def rally_alt_stored(z_m: float) -> float:
    """``RallyLocation::alt`` (int16 metres) = ``cmd.z``: truncated toward zero."""
    return float(c_int(f32(z_m), 16, signed=True))


def stored_rally_item(item: WireItem) -> WireItem:
    """The rally point as a read-back returns it."""
    if check_rally_item(item) != R.MAV_MISSION_ACCEPTED:
        raise ValueError("ArduCopter refuses this rally point")
    return WireItem(seq=item.seq, command=RALLY_POINT, frame=_RALLY_FRAME_KEPT[item.frame],
                    x=item.x, y=item.y, z=rally_alt_stored(item.z), current=0, autocontinue=0)


def check_item(item: WireItem, mission_type: int) -> int:
    """Acceptance of one item of any mission type (the mission's is storage.check)."""
    if mission_type == MISSION_TYPE_FENCE:
        return check_fence_item(item)
    if mission_type == MISSION_TYPE_RALLY:
        return check_rally_item(item)
    return check(item)


def stored_item(item: WireItem, mission_type: int) -> WireItem:
    """What a read-back of ``mission_type`` returns for ``item``."""
    if mission_type == MISSION_TYPE_FENCE:
        return stored_fence_item(item)
    if mission_type == MISSION_TYPE_RALLY:
        return stored_rally_item(item)
    return stored(item)


# --- parameters (libraries/AC_Fence/AC_Fence.cpp var_info; AC_FENCE_* defaults there and
# in AC_Fence.h). FENCE_TYPE's default on Copter: ALT_MAX | CIRCLE | POLYGON = 7.
_FENCE = "libraries/AC_Fence/AC_Fence.cpp var_info"
FENCE_PARAM_DEFAULTS: Mapping[str, ParamDefault] = {
    "FENCE_ENABLE": ParamDefault(0.0, INT8, _FENCE + " (0: disabled)"),
    "FENCE_TYPE": ParamDefault(7.0, INT8, _FENCE + " (bits: 1 alt max, 2 circle, 4 polygon, "
                                                   "8 alt min)"),
    "FENCE_ACTION": ParamDefault(1.0, INT8, _FENCE + " (AC_FENCE_ACTION_RTL_AND_LAND)"),
    "FENCE_ALT_MAX": ParamDefault(100.0, REAL32, _FENCE + " (AC_FENCE_ALT_MAX_DEFAULT, m)"),
    "FENCE_ALT_MIN": ParamDefault(-10.0, REAL32, _FENCE + " (AC_FENCE_ALT_MIN_DEFAULT, m)"),
    "FENCE_RADIUS": ParamDefault(300.0, REAL32, _FENCE + " (AC_FENCE_CIRCLE_RADIUS_DEFAULT, m)"),
    "FENCE_MARGIN": ParamDefault(2.0, REAL32, _FENCE + " (AC_FENCE_MARGIN_DEFAULT, m)"),
}
FENCE_PARAMS = ("FENCE_ENABLE", "FENCE_TYPE", "FENCE_ACTION", "FENCE_ALT_MAX", "FENCE_MARGIN")

TYPE_ALT_MAX, TYPE_CIRCLE, TYPE_POLYGON, TYPE_ALT_MIN = 1, 2, 4, 8  # AC_Fence.h
ACTION_REPORT_ONLY, ACTION_RTL_AND_LAND, ACTION_ALWAYS_LAND = 0, 1, 2  # AC_Fence.h
ACTION_SMART_RTL, ACTION_BRAKE, ACTION_SMART_RTL_OR_LAND = 3, 4, 5
GIVE_UP_DISTANCE_M = 100.0  # AC_FENCE_GIVE_UP_DISTANCE: farther out, Copter just lands
FENCE_CHECK_HZ = 25  # ArduCopter/Copter.cpp SCHED_TASK(fence_check, 25, ...)
FENCE_BREACHED = (R.MAV_SEVERITY_NOTICE, "Fence Breached")  # Copter::fence_check

# Copter modes (ArduCopter/mode.h) the breach actions switch to, in the order tried
_RTL, _LAND, _BRAKE, _SMART_RTL = (int(m) for m in (CopterMode.RTL, CopterMode.LAND,
                                                     CopterMode.BRAKE, CopterMode.SMART_RTL))
_ACTION_MODES = {
    ACTION_RTL_AND_LAND: (_RTL, _LAND), ACTION_ALWAYS_LAND: (_LAND,),
    ACTION_SMART_RTL: (_SMART_RTL, _RTL, _LAND), ACTION_BRAKE: (_BRAKE, _LAND),
    ACTION_SMART_RTL_OR_LAND: (_SMART_RTL, _LAND),
}


def param_equal(name: str, sent: float, back: float) -> bool:
    """A parameter read back equals what was set, as AP_Param keeps it: integer types
    are cast, REAL32 is a float32."""
    d = FENCE_PARAM_DEFAULTS.get(name)
    if d is not None and d.type != REAL32:
        return int(sent) == int(back)
    return f32(sent) == f32(back)


def breach_modes(action: int, *, landed: bool, breach_distance_m: float) -> tuple[int, ...]:
    """Copter::fence_check's response to a new breach while armed: the modes it tries in
    order (the first that ArduCopter accepts is taken); ``()`` for none. Landed: it
    disarms instead (returned as ``(-1,)``); more than 100 m outside: LAND."""
    if action == ACTION_REPORT_ONLY:
        return ()
    if landed:
        return (-1,)
    if breach_distance_m > GIVE_UP_DISTANCE_M:
        return (_LAND,)
    return _ACTION_MODES.get(action, (_RTL, _LAND))


@dataclass(frozen=True)
class FenceGeometry:
    """A stored fence in a vehicle's local east/north metres (home-centred).

    ``inclusion``: polygons, each ``(n, 2)``; ``exclusion_circles``: ``(k, 3)`` rows of
    east, north, radius (m)."""

    inclusion: tuple[np.ndarray, ...]
    exclusion_circles: np.ndarray

    @property
    def empty(self) -> bool:
        return not self.inclusion and len(self.exclusion_circles) == 0

    @cached_property
    def plain(self) -> tuple[list[list], list[tuple[float, float, float]]]:
        """The polygons' corners and the circles as plain floats: a copter's fence is
        checked 25 times a second, on a handful of corners and circles, where numpy's
        set-up would cost more than the test."""
        return ([poly.tolist() for poly in self.inclusion],
                [tuple(row) for row in np.asarray(self.exclusion_circles, float).tolist()])


def fence_geometry(items: Sequence[WireItem], to_en) -> FenceGeometry:
    """The stored fence items -> :class:`FenceGeometry`; ``to_en(lat_deg, lon_deg) ->
    (east, north)``. Polygons are read as ArduPilot groups them: ``vertex_count``
    consecutive vertices (AC_PolyFence_loader::load_from_storage)."""
    polygons, circles, i = [], [], 0
    while i < len(items):
        it = items[i]
        if it.command == FENCE_POLYGON_INCLUSION:
            n = int(it.param1)
            polygons.append(np.array([to_en(v.x * 1e-7, v.y * 1e-7) for v in items[i:i + n]]))
            i += n
            continue
        if it.command == FENCE_CIRCLE_EXCLUSION:
            circles.append((*to_en(it.x * 1e-7, it.y * 1e-7), it.param1))
        i += 1  # exclusion polygons, inclusion circles, return points: not emulated
    return FenceGeometry(tuple(polygons), np.array(circles, float).reshape(-1, 3))


def _inside_polygon(point: np.ndarray, polygon) -> bool:
    """Polygon_outside's crossing test (libraries/AP_Math/polygon.cpp), negated;
    ``polygon`` ``(n, 2)``, an array or a list of corners."""
    x, y = float(point[0]), float(point[1])
    corners = polygon.tolist() if isinstance(polygon, np.ndarray) else polygon
    crossings = 0
    for (px, py), (qx, qy) in zip(corners, corners[1:] + corners[:1]):
        if (py > y) != (qy > y) and x < (qx - px) * (y - py) / (qy - py) + px:
            crossings += 1
    return bool(crossings % 2)


def breaches(geometry: FenceGeometry, *, east_north: np.ndarray, alt_m: float,
             fence_type: int, alt_max_m: float) -> int:
    """The fence types breached at a position (bitmask of ``TYPE_*``): above FENCE_ALT_MAX
    (check_fence_alt_max), outside an inclusion polygon or inside an exclusion circle
    (AC_PolyFence_loader::breached: the position itself, no margin; FENCE_MARGIN is for
    avoidance and the pre-arm checks). ``east_north`` (2,) metres."""
    out = 0
    if fence_type & TYPE_ALT_MAX and alt_m > alt_max_m:
        out |= TYPE_ALT_MAX
    if fence_type & TYPE_POLYGON and not geometry.empty:
        x, y = float(east_north[0]), float(east_north[1])
        polygons, circles = geometry.plain
        outside = any(not _inside_polygon((x, y), poly) for poly in polygons)
        inside_circle = any(math.hypot(cx - x, cy - y) < r for cx, cy, r in circles)
        if outside or inside_circle:
            out |= TYPE_POLYGON
    return out


RALLY_LIMIT_M = 300.0  # AP_Rally.cpp RALLY_LIMIT_KM_DEFAULT 0.3 (copter)


def rtl_target(position_en, home_en, rally_en) -> int | None:
    """Where ArduCopter's RTL goes from ``position_en``: the index of the rally point in
    ``rally_en`` ((K, 2) east/north), or None for home (AP_Rally::
    calc_best_rally_or_home_location with RALLY_INCL_HOME 1: the nearest rally point
    within RALLY_LIMIT_KM if it is nearer than home, else home)."""
    rally = np.asarray(rally_en, float).reshape(-1, 2)
    if not len(rally):
        return None
    here = np.asarray(position_en, float)[:2]
    d = np.hypot(*(rally - here).T)
    k = int(np.argmin(d))
    home = float(np.hypot(*(here - np.asarray(home_en, float)[:2])))
    if d[k] > RALLY_LIMIT_M or d[k] >= home:
        return None
    return k
