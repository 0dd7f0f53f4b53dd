"""Scenario files: TOML -> a validated, frozen :class:`~.model.Scenario`.

Every mistake a user can make in a scenario ends here as a :class:`ScenarioError` naming
the file, the field and the problem. The key names are fixed (see ``missions/*.toml`` and
the README) so scenarios stay portable between versions; unknown keys are refused, since
a typo that is silently ignored plans a different survey than the one intended.

Here the document as a whole: the area, start and goal, the formation, obstacles and via
points, and the checks of the geometry they make together. The settings tables are read
in :mod:`.settings`, ``[survey]`` and ``[camera]`` (and the lanes) in :mod:`.survey`,
``[vehicle]`` in :mod:`.fleet`.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ScenarioError
from ..formation import PLANES, closest_pair, regular_formation
from ..gnss import NavigationBudget, largest_error_for, true_distance, would_do
from ..inputs import read_user_text
from ..obstacles import Cylinder, read_obstacle_geojson
from .fleet import read_vehicle
from .model import (
    MAX_ALTITUDE_M,
    MAX_AREA_SIDE_M,
    MAX_DISTANCE_M,
    MAX_FORMATION_ERROR_M,
    MAX_OFFSET_M,
    MAX_RADIUS_M,
    MAX_UAVS,
    MIN_SEPARATION_M,
    GeoPoint,
    Scenario,
    ViaPoint,
)
from .settings import read_battery, read_mission, read_navigation, read_planner
from .survey import read_camera, read_survey, with_lanes
from .tables import Table, checked_number


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario file. Raises :class:`ScenarioError` on any problem."""
    path = Path(path)
    source = str(path)
    text = read_user_text(path, error=lambda problem: ScenarioError(source, "", problem))
    return parse_scenario(text, source=source, base_dir=path.parent)


def parse_scenario(
    text: str, *, source: str = "<scenario>", base_dir: Path | None = None
) -> Scenario:
    """Parse scenario TOML text; see :func:`load_scenario`."""
    text = text.removeprefix("\ufeff")  # a byte-order mark, as Windows editors write
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(source, "", f"malformed TOML: {exc}") from None
    root = Table(data, "", source)

    name = root.string("name", "")
    area = root.table("area")
    lat_a, lon_a = area.lat_lon("corner_a")
    lat_b, lon_b = area.lat_lon("corner_b")
    _check_corners_on_the_globe(area, lat_a=lat_a, lon_a=lon_a, lat_b=lat_b, lon_b=lon_b)
    if lat_a == lat_b or lon_a == lon_b:
        raise area.error("corner_b", "must differ from corner_a in both latitude and longitude")
    h_min = area.number("min_altitude", lo=0.0, hi=MAX_ALTITUDE_M, lo_open=True, unit="m")
    h_max = area.number("max_altitude", lo=0.0, hi=MAX_ALTITUDE_M, lo_open=True, unit="m")
    if h_min >= h_max:
        raise area.error("min_altitude", f"must be below max_altitude ({h_min:g} >= {h_max:g})")
    area.done()

    start_t, goal_t = root.table("start"), root.table("goal")
    start, goal = start_t.point(max_alt=MAX_ALTITUDE_M), goal_t.point(max_alt=MAX_ALTITUDE_M)
    start_t.done()
    goal_t.done()

    navigation = read_navigation(root.table("navigation", required=False))
    form = root.table("formation")
    offsets = _read_offsets(form)
    clearance = form.number("clearance", 1.0, lo=0.0, hi=MAX_DISTANCE_M, unit="m")
    separation = form.number("min_separation", MIN_SEPARATION_M, lo=0.0, hi=MAX_DISTANCE_M,
                             unit="m")
    _check_separation(form, offsets, separation, navigation)
    max_error = form.number("max_error", MAX_FORMATION_ERROR_M, lo=0.0, lo_open=True,
                            hi=MAX_DISTANCE_M, unit="m")
    form.done()

    obstacles = _read_obstacles(root.raw("obstacles", []), source)
    obstacles_file = root.string("obstacles_file", "")
    via = _read_via(root.raw("via", []), source)
    survey_t = root.table("survey", required=False)
    camera_t = root.table("camera", required=False)
    camera = read_camera(camera_t) if camera_t else None
    if camera is not None and survey_t is None:
        raise ScenarioError(source, "camera", "needs a [survey]: the photos are taken along "
                            "its lanes")
    survey = (read_survey(survey_t, default_alt=start.alt_m, camera=camera, offsets=offsets)
              if survey_t else None)
    planner = read_planner(root.table("planner", required=False))
    mission = read_mission(root.table("mission", required=False))
    copters = read_vehicle(root.table("vehicle", required=False), count=len(offsets),
                           base_dir=base_dir)
    vehicle = copters[0].nav
    battery = read_battery(root.table("battery", required=False),
                            cruise_speed_m_s=mission.speed_m_s or vehicle.wp_speed)
    root.done()

    scenario = Scenario(
        corner_a=GeoPoint(lat_a, lon_a),
        corner_b=GeoPoint(lat_b, lon_b),
        min_altitude_m=h_min,
        max_altitude_m=h_max,
        start=start,
        goal=goal,
        offsets=tuple(tuple(float(v) for v in row) for row in offsets),
        clearance_m=clearance,
        obstacles=obstacles,
        planner=planner,
        mission=mission,
        name=name,
        source=source,
        via=via,
        min_separation_m=separation,
        max_formation_error_m=max_error,
        vehicle=vehicle,
        copters=copters,
        navigation=navigation,
        battery=battery,
    )
    _check_area_size(scenario)
    if obstacles_file:
        # obstacles_file (optional): a GeoJSON file of obstacles, relative to the scenario
        # file: Points with a `radius` in metres, Polygons -> their smallest enclosing
        # circle (docs/outputs.md). They follow the [[obstacles]] tables, in file order.
        path = (base_dir if base_dir is not None else Path(".")) / obstacles_file
        extra = read_obstacle_geojson(path, frame=scenario.frame)
        scenario = replace(scenario, obstacles=scenario.obstacles + extra)
    scenario = _drop_unreachable_obstacles(scenario)
    if survey is not None:
        scenario = with_lanes(scenario, survey)
    _check_geometry(scenario)
    return scenario


def _check_corners_on_the_globe(area: Table, *, lat_a: float, lon_a: float, lat_b: float,
                                lon_b: float) -> None:
    """The area is the lat/lon box between its corners, from the smaller longitude to the
    larger, with the local ENU frame at its south-west corner: an area across the
    antimeridian or at a pole cannot be one (it would be refused later as "start: outside
    the area", which says nothing of why)."""
    if abs(lon_a - lon_b) > 180.0:
        raise area.error("corner_b", f"longitude {lon_b:g} is {abs(lon_a - lon_b):g} degrees "
                         f"from corner_a's {lon_a:g}: an area across the antimeridian (180 "
                         "degrees longitude) is not supported: the area is the lat/lon box "
                         "from the smaller longitude to the larger, with the local ENU frame "
                         "at its south-west corner, and here that box goes the long way round "
                         "the globe (split the survey at 180 degrees)")
    for key, lat in (("corner_a", lat_a), ("corner_b", lat_b)):
        if abs(lat) >= 90.0:
            raise area.error(f"{key}[0]", f"latitude {lat:g} is a pole: an area at a pole is "
                             "not supported: every longitude meets there, so the lat/lon box "
                             "is no rectangle in the local east/north frame (keep the area "
                             "off the pole)")


def _check_area_size(s: Scenario) -> None:
    lower, upper = s.area_bounds_enu()
    side = float(np.max(upper - lower))
    if not side <= MAX_AREA_SIDE_M:
        raise ScenarioError(s.source, "area.corner_b",
                            f"makes an area {side / 1000:.0f} km across: at most "
                            f"{MAX_AREA_SIDE_M / 1000:g} km a side (the local flat frame is "
                            "made for a field, not a country)")


def _drop_unreachable_obstacles(s: Scenario) -> Scenario:
    """Leave out the obstacles whose disc (radius + clearance) does not reach the area:
    every UAV waypoint is inside the area, so every UAV segment is too (it is convex), and
    such a cylinder can touch none of them. Their count is kept in ``dropped_obstacles``."""
    if not s.obstacles:
        return s
    centres, radii = s.obstacles_enu()
    lower, upper = s.area_bounds_enu()
    outside = np.maximum(np.maximum(lower - centres, centres - upper), 0.0)
    reach = np.hypot(outside[:, 0], outside[:, 1]) <= radii + s.true_clearance_m + 1.0  # spare
    if reach.all():
        return s
    kept = tuple(c for c, r in zip(s.obstacles, reach) if r)
    return replace(s, obstacles=kept, dropped_obstacles=len(s.obstacles) - len(kept))


def _check_separation(form: Table, offsets: np.ndarray, separation: float,
                      navigation: NavigationBudget) -> None:
    """No two UAVs of the formation closer than ``min_separation`` (3D), the pair named,
    where they truly are: their horizontal distance less the navigation budget's
    combined error of two copters (:func:`~ftlbo_mav.gnss.true_distance`)."""
    pair = closest_pair(offsets)
    if pair is None:
        return
    key = "offsets" if form.has("offsets") else "radius"
    i, j, dist = pair
    if dist < separation:
        raise form.error(key, f"puts UAV {i + 1} and UAV {j + 1} {dist:.2f} m apart, closer "
                              f"than min_separation = {separation:g} m")
    a, b = np.triu_indices(len(offsets), 1)
    d = offsets[a] - offsets[b]
    horizontal, vertical = np.hypot(d[:, 0], d[:, 1]), d[:, 2]
    true = true_distance(horizontal, vertical, navigation.pair_m)
    k = int(np.argmin(true))
    if true[k] < separation - 1e-9:
        room = largest_error_for(horizontal, vertical, separation) / math.sqrt(2.0)
        raise form.error(key, f"puts UAV {a[k] + 1} and UAV {b[k] + 1} {horizontal[k]:.2f} m "
                              f"apart horizontally ({np.hypot(horizontal[k], vertical[k]):.2f} m"
                              f" in 3D): with [navigation] {navigation.describe()} each, they "
                              f"can truly be {true[k]:.2f} m apart, closer than min_separation "
                              f"= {separation:g} m ({would_do(room)})")


def _read_offsets(form: Table) -> np.ndarray:
    if form.has("offsets"):
        for key in ("count", "radius", "plane"):
            if form.has(key):
                raise form.error(key, "give either offsets or count/radius/plane, not both")
        rows = form.raw("offsets")
        if not isinstance(rows, list) or not rows:
            raise form.error("offsets", "must be a non-empty array of [east, north, up] rows")
        if len(rows) > MAX_UAVS:
            raise form.error("offsets", f"has {len(rows)} UAVs: at most {MAX_UAVS} (one "
                                        "MAVLink system id each)")
        for i, row in enumerate(rows):
            if (
                not isinstance(row, list)
                or len(row) != 3
                or any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in row)
            ):
                raise form.error(f"offsets[{i}]",
                                 f"must be [east, north, up] in metres, got {row!r}")
            for axis, v in zip(("east", "north", "up"), row):
                checked_number(v, lambda problem, i=i, axis=axis: form.error(
                    f"offsets[{i}]", f"{axis} {problem}"), lo=-MAX_OFFSET_M, hi=MAX_OFFSET_M,
                    unit="m")
        return np.array(rows, dtype=float)
    if not form.has("count"):
        raise form.error("offsets", "missing: give offsets, or count and radius")
    count = form.integer("count", lo=1, hi=MAX_UAVS)
    radius = form.number("radius", lo=0.0, hi=MAX_OFFSET_M, unit="m")
    plane = form.string("plane", "horizontal", choices=PLANES)
    return regular_formation(count=count, radius_m=radius, plane=plane)


def _read_obstacles(rows: Any, source: str) -> tuple[Cylinder, ...]:
    if not isinstance(rows, list):
        raise ScenarioError(source, "obstacles", "must be an array of tables ([[obstacles]])")
    cylinders = []
    for i, row in enumerate(rows):
        t = Table(row, f"obstacles[{i}]", source)
        point = t.point(alt=False)
        radius = t.number("radius", lo=0.0, hi=MAX_RADIUS_M, lo_open=True, unit="m")
        label = t.string("name", "")
        t.done()
        cylinders.append(Cylinder(point.lat_deg, point.lon_deg, radius, label,
                                  f"obstacles[{i}]"))
    return tuple(cylinders)


def _read_via(rows: Any, source: str) -> tuple[ViaPoint, ...]:
    if not isinstance(rows, list):
        raise ScenarioError(source, "via", "must be an array of tables ([[via]])")
    points = []
    for i, row in enumerate(rows):
        t = Table(row, f"via[{i}]", source)
        point = t.point(max_alt=MAX_ALTITUDE_M)
        label = t.string("name", f"via {i + 1}")
        t.done()
        points.append(ViaPoint(point.lat_deg, point.lon_deg, point.alt_m, label))
    return tuple(points)


def _check_geometry(s: Scenario) -> None:
    """Start, via points and goal inside the area, every UAV clear of every obstacle and
    in the band; no two consecutive points at one place; a loop needs via points."""
    points = [("start", s.start), *((_via_field(s, i), v) for i, v in enumerate(s.via)),
              ("goal", s.goal)]
    enus = s.route_enu()
    for (key, point), enu in zip(points, enus):
        _check_point(s, key, point, enu)
    for k in range(1, len(points)):
        if np.hypot(*(enus[k, :2] - enus[k - 1, :2])) < 0.01:
            key, before = points[k][0], points[k - 1][0]
            if not s.via:
                raise ScenarioError(s.source, "goal", "is the start: a loop needs [[via]] "
                                    "points (or a [survey]) to pass between them")
            raise ScenarioError(s.source, key, f"is at the same place as {before} (within "
                                "1 cm): every leg needs two different places")


def _via_field(s: Scenario, i: int) -> str:
    """How errors name via point ``i``: ``via[i]``, or ``survey (lane 2 start)``."""
    v = s.via[i]
    lane_points = 2 * len(s.survey.lanes) if s.survey is not None else 0
    if i >= len(s.via) - lane_points:
        return f"survey ({v.name})"
    return f"via[{i}]"


def _check_point(s: Scenario, key: str, point, enu: np.ndarray) -> None:
    lower, upper = s.area_bounds_enu()
    centres, radii = s.obstacles_enu()
    offsets = s.offsets_m
    alt_key = "survey.alt" if key.startswith("survey") else f"{key}.alt"
    lat_ok = min(s.corner_a.lat_deg, s.corner_b.lat_deg) <= point.lat_deg <= max(
        s.corner_a.lat_deg, s.corner_b.lat_deg
    )
    lon_ok = min(s.corner_a.lon_deg, s.corner_b.lon_deg) <= point.lon_deg <= max(
        s.corner_a.lon_deg, s.corner_b.lon_deg
    )
    if not (lat_ok and lon_ok):
        field_name = f"{key}.lat" if not lat_ok else f"{key}.lon"
        raise ScenarioError(s.source, field_name, "is outside the area")
    uavs = enu + offsets
    for n, uav in enumerate(uavs, start=1):
        alt = uav[2]
        if not s.min_altitude_m - 1e-6 <= alt <= s.max_altitude_m + 1e-6:
            raise ScenarioError(
                s.source,
                alt_key,
                f"puts UAV {n} at {alt:.2f} m, outside the altitude band "
                f"[{s.min_altitude_m:g}, {s.max_altitude_m:g}] m",
            )
        if np.any(uav[:2] < lower - 1e-6) or np.any(uav[:2] > upper + 1e-6):
            raise ScenarioError(s.source, key, f"puts UAV {n} outside the area")
        if len(radii):
            dist = np.hypot(*(centres - uav[:2]).T)
            k = int(np.argmin(dist - radii))
            if dist[k] <= radii[k] + s.true_clearance_m:
                corners = np.array([lower, [lower[0], upper[1]], upper, [upper[0], lower[1]]])
                covers = np.all(np.hypot(*(corners - centres[k]).T)
                                <= radii[k] + s.true_clearance_m)
                nav = s.navigation
                budgeted = (f" + navigation {nav.horizontal_m:g} m ([navigation] "
                            f"{nav.describe()}; "
                            f"{would_do(dist[k] - radii[k] - s.clearance_m)})"
                            if nav.horizontal_m and dist[k] > radii[k] + s.clearance_m else "")
                raise ScenarioError(
                    s.source,
                    key,
                    f"puts UAV {n} {dist[k]:.2f} m from the axis of "
                    f"{s.obstacles[k].describe(k)} (radius {radii[k]:g} m + clearance "
                    f"{s.clearance_m:g} m{budgeted})"
                    + ("; it covers the whole area, start and goal included" if covers else ""),
                )


def scenario_inputs(path: str | Path) -> list[Path]:
    """The files a scenario is read from: itself and its ``obstacles_file``, if any (for
    a command that must not write over its inputs). Call after :func:`load_scenario`."""
    path = Path(path)
    data = tomllib.loads(read_user_text(path, error=lambda p: ScenarioError(str(path), "", p)
                                        ).removeprefix("\ufeff"))
    extra = data.get("obstacles_file")
    return [path] + ([path.parent / extra] if isinstance(extra, str) and extra else [])
