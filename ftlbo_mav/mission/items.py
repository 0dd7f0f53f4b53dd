"""Mission items as plain values, and the per-UAV mission built from a planned path.

Numbers are MAVLink's (common.xml): frames ``MAV_FRAME_*`` and commands ``MAV_CMD_*``.
Coordinates stay in float degrees here; the 1e-7 integer encoding belongs to the link.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

# MAV_FRAME
FRAME_GLOBAL = 0
FRAME_MISSION = 2
FRAME_GLOBAL_RELATIVE_ALT = 3
FRAME_GLOBAL_RELATIVE_ALT_INT = 6

# MAV_CMD
CMD_NAV_WAYPOINT = 16
CMD_NAV_LOITER_UNLIM = 17
CMD_NAV_RETURN_TO_LAUNCH = 20
CMD_NAV_LAND = 21
CMD_NAV_TAKEOFF = 22
CMD_NAV_DELAY = 93
CMD_DO_CHANGE_SPEED = 178
CMD_DO_SET_CAM_TRIGG_DIST = 206
# fence and rally items (mission_type FENCE / RALLY; their storage: ardupilot/fence.py)
CMD_FENCE_POLYGON_VERTEX_INCLUSION = 5001
CMD_FENCE_CIRCLE_EXCLUSION = 5004
CMD_RALLY_POINT = 5100

COMMAND_NAMES = {
    CMD_NAV_WAYPOINT: "WAYPOINT",
    CMD_NAV_LOITER_UNLIM: "LOITER_UNLIM",
    CMD_NAV_RETURN_TO_LAUNCH: "RETURN_TO_LAUNCH",
    CMD_NAV_LAND: "LAND",
    CMD_NAV_TAKEOFF: "TAKEOFF",
    CMD_NAV_DELAY: "DELAY",
    CMD_DO_CHANGE_SPEED: "DO_CHANGE_SPEED",
    CMD_DO_SET_CAM_TRIGG_DIST: "DO_SET_CAM_TRIGG_DIST",
    CMD_FENCE_POLYGON_VERTEX_INCLUSION: "FENCE_POLYGON_VERTEX_INCLUSION",
    CMD_FENCE_CIRCLE_EXCLUSION: "FENCE_CIRCLE_EXCLUSION",
    CMD_RALLY_POINT: "RALLY_POINT",
}


# What MISSION_ITEM_INT can carry (common.xml): seq and command uint16, frame uint8,
# current and autocontinue 0/1 (uint8 flags), params and z float32; and what means
# something for a copter: an altitude within 100 km of home.
MAX_ITEMS = 65_535
"""MISSION_COUNT's ``count`` is a uint16."""
UINT16_MAX, UINT8_MAX = 65_535, 255
FLOAT32_MAX = 3.4028234663852886e38
MAX_ALT_M = 100_000.0


def item_problem(item: MissionItem) -> str | None:
    """Why ``item`` cannot go to a vehicle as it is (a field that does not fit its
    MAVLink width, a number that is not finite), or ``None``. Pure; the readers of mission
    files call it for every item they read."""
    for name, value, hi in (("seq", item.seq, UINT16_MAX), ("command", item.command, UINT16_MAX),
                            ("frame", item.frame, UINT8_MAX), ("current", item.current, 1),
                            ("autocontinue", item.autocontinue, 1)):
        if not 0 <= value <= hi:
            return f"{name} {value} is outside 0..{hi} (MAVLink's field)"
    for name in ("param1", "param2", "param3", "param4"):
        value = getattr(item, name)
        if not (math.isfinite(value) and abs(value) <= FLOAT32_MAX):
            return f"{name} {value:g} is not a finite 32-bit float"
    if not (math.isfinite(item.lat_deg) and -90 <= item.lat_deg <= 90
            and math.isfinite(item.lon_deg) and -180 <= item.lon_deg <= 180):
        return "latitude/longitude out of range"
    if not (math.isfinite(item.alt_m) and abs(item.alt_m) <= MAX_ALT_M):
        return f"altitude {item.alt_m:g} m is not within +-{MAX_ALT_M:g} m"
    return None


@dataclass(frozen=True)
class MissionItem:
    """One mission item; ``seq`` is its index, item 0 being home."""

    seq: int
    command: int
    frame: int = FRAME_GLOBAL_RELATIVE_ALT
    lat_deg: float = 0.0
    lon_deg: float = 0.0
    alt_m: float = 0.0
    param1: float = 0.0
    param2: float = 0.0
    param3: float = 0.0
    param4: float = 0.0
    current: int = 0
    autocontinue: int = 1

    @property
    def name(self) -> str:
        return COMMAND_NAMES.get(self.command, str(self.command))


def build_mission(
    *,
    home: tuple[float, float],
    takeoff_alt_m: float,
    path: Sequence[tuple[float, float, float]],
    end_action: str = "land",
    speed_m_s: float | None = None,
    holds_s: Sequence[float] | None = None,
    camera: Sequence[tuple] = (),
) -> list[MissionItem]:
    """The mission of one UAV.

    ``home``: ``(lat_deg, lon_deg)`` of the UAV's start on the ground.
    ``path``: ``(lat_deg, lon_deg, alt_m)`` rows from the start point to the goal, altitudes
    relative to home.

    Items, in order: 0 home (frame 0, current=1, as Mission Planner writes it),
    NAV_TAKEOFF to ``takeoff_alt_m``, one NAV_WAYPOINT per path point (after the first,
    the start point, the start gate :func:`start_gate` and, when ``speed_m_s`` is given,
    a DO_CHANGE_SPEED), then
    NAV_LAND at the goal, RTL, or NAV_LOITER_UNLIM at the goal for ``end_action`` "land",
    "rtl" or "loiter". ``holds_s``: per path point the whole seconds the copter holds
    there (NAV_WAYPOINT param1: ArduCopter stops at such a waypoint instead of rounding
    its corner; the planner's corner stops); default none. ``camera``: per survey lane
    ``(entry, exit, distance[, at_once])`` path point indices and the trigger distance:
    DO_SET_CAM_TRIGG_DIST on after the entry (a photo at once unless ``at_once`` is
    False: a lane resumed where its photo was taken), off after the exit.
    """
    if len(path) < 2:
        raise ValueError("a path needs at least a start and a goal")
    lat0, lon0 = home
    items: list[tuple] = [
        dict(command=CMD_NAV_WAYPOINT, frame=FRAME_GLOBAL, lat_deg=lat0, lon_deg=lon0, current=1),
        # Copter ignores a takeoff's lat/lon and climbs where it stands; Mission Planner
        # writes them as 0 (ArduPilot wiki, "Mission Commands": NAV_TAKEOFF).
        dict(command=CMD_NAV_TAKEOFF, alt_m=takeoff_alt_m),
    ]
    holds = [0.0] * len(path) if holds_s is None else [float(h) for h in holds_s]
    if len(holds) != len(path):
        raise ValueError(f"holds_s has {len(holds)} values for {len(path)} path points")
    after: dict[int, list[dict]] = {}
    for entry, exit_, distance, *at_once in camera:
        if not 0 < entry < exit_ < len(path):
            raise ValueError(f"a lane from path point {entry} to {exit_} is not in the path")
        first = not at_once or bool(at_once[0])
        after.setdefault(entry, []).append(dict(
            command=CMD_DO_SET_CAM_TRIGG_DIST, param1=float(distance),
            param3=1.0 if first else 0.0))
        after.setdefault(exit_, []).append(dict(command=CMD_DO_SET_CAM_TRIGG_DIST))
    for k, ((lat, lon, alt), hold) in enumerate(zip(path, holds)):
        items.append(dict(command=CMD_NAV_WAYPOINT, lat_deg=lat, lon_deg=lon, alt_m=alt,
                          param1=hold))
        items += after.get(k, [])
    if speed_m_s is not None:
        # After the start gate, before the first leg: it runs as the legs begin, and
        # ModeAuto::init would forget a speed given before AUTO. param1 = 1: ground
        # speed; param3 = -1: throttle unchanged.
        items.insert(3, dict(command=CMD_DO_CHANGE_SPEED, param1=1.0, param2=speed_m_s,
                             param3=-1.0))
    items.insert(3, start_gate())
    lat_f, lon_f, alt_f = path[-1]
    if end_action == "land":
        items.append(dict(command=CMD_NAV_LAND, lat_deg=lat_f, lon_deg=lon_f, alt_m=0.0))
    elif end_action == "rtl":
        items.append(dict(command=CMD_NAV_RETURN_TO_LAUNCH))
    elif end_action == "loiter":
        items.append(dict(command=CMD_NAV_LOITER_UNLIM, lat_deg=lat_f, lon_deg=lon_f, alt_m=alt_f))
    else:
        raise ValueError(f"unknown end action {end_action!r}")
    return [MissionItem(seq=i, **fields) for i, fields in enumerate(items)]


def start_gate(hms: tuple[int, int, int] | None = None) -> dict:
    """The NAV_DELAY after the start point, where ``fly`` starts AUTO: the legs begin
    when the vehicle's clock (GPS time) reads ``hms`` (hour, minute, second UTC; -1: not
    given), the same instant for every copter however late its AUTO came through the
    radio (:func:`ftlbo_mav.ardupilot.commands.nav_delay_ms`). As planned (``hms`` None)
    every field is -1: the copter holds until the next whole second of GPS time (less
    than a second; without GPS time not at all), so the mission flies as before in any
    ground station; ``fly`` writes its start second before the start and the placeholder
    back after the flight."""
    hour, minute, second = (-1, -1, -1) if hms is None else hms
    return dict(command=CMD_NAV_DELAY, param1=-1.0, param2=float(hour),
                param3=float(minute), param4=float(second))


def mission_settings(items: Sequence[MissionItem]) -> tuple[str, float | None]:
    """``(end_action, speed_m_s)`` of a mission :func:`build_mission` wrote: "land", "rtl"
    or "loiter" from its last item, the speed of its first DO_CHANGE_SPEED (None: none)."""
    ends = {CMD_NAV_LAND: "land", CMD_NAV_RETURN_TO_LAUNCH: "rtl",
            CMD_NAV_LOITER_UNLIM: "loiter"}
    speed = next((float(it.param2) for it in items if it.command == CMD_DO_CHANGE_SPEED), None)
    return ends.get(items[-1].command, "land") if items else "land", speed


def build_return(*, home: tuple[float, float], path: Sequence[tuple[float, float, float]],
                 holds_s: Sequence[float], land: tuple[float, float],
                 speed_m_s: float | None = None, camera_off: bool = False
                 ) -> list[MissionItem]:
    """The mission home of a vehicle in the air (:mod:`ftlbo_mav.flight.homeward`): 0 home,
    1 a NAV_WAYPOINT where it hovers (``path[0]``, where AUTO is started, as ``fly``
    starts a plan's legs), with ``camera_off`` DO_SET_CAM_TRIGG_DIST 0 (a copter stopped
    in a survey lane takes no photos on its way home: they would be nobody's, and a
    resumed survey counts the photos taken), DO_CHANGE_SPEED to ``speed_m_s`` (when given), one
    NAV_WAYPOINT per further path point (param1: ``holds_s``, whole seconds), then NAV_LAND
    at ``land`` ``(lat_deg, lon_deg)``."""
    if len(path) < 2 or len(holds_s) != len(path):
        raise ValueError("a way home needs a start, a point after it and a hold for each")
    items: list[dict] = [
        dict(command=CMD_NAV_WAYPOINT, frame=FRAME_GLOBAL, lat_deg=home[0], lon_deg=home[1],
             current=1)]
    for k, ((lat, lon, alt), hold) in enumerate(zip(path, holds_s)):
        items.append(dict(command=CMD_NAV_WAYPOINT, lat_deg=lat, lon_deg=lon, alt_m=alt,
                          param1=float(hold)))
        if k == 0 and camera_off:
            items.append(dict(command=CMD_DO_SET_CAM_TRIGG_DIST))
        if k == 0 and speed_m_s is not None:
            items.append(dict(command=CMD_DO_CHANGE_SPEED, param1=1.0, param2=speed_m_s,
                              param3=-1.0))
    items.append(dict(command=CMD_NAV_LAND, lat_deg=land[0], lon_deg=land[1], alt_m=0.0))
    return [MissionItem(seq=i, **fields) for i, fields in enumerate(items)]


@dataclass(frozen=True)
class UavMission:
    """One UAV's mission: its name (``uav1``...), offset and items."""

    name: str
    offset: tuple[float, float, float]
    items: tuple[MissionItem, ...]
