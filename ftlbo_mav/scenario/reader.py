"""Scenario files: TOML -> a validated, frozen :class:`~.model.Scenario`.

Every mistake a user can make in a scenario ends here as a :class:`ScenarioError` naming
the file, the field and the problem. The key names are fixed (see ``missions/*.toml`` and
the README) so scenarios stay portable between versions; unknown keys are refused, since
a typo that is silently ignored plans a different survey than the one intended.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from ..energy import Battery
from ..errors import ScenarioError
from ..formation import PLANES, closest_pair, regular_formation
from ..gnss import CLASSES, NavigationBudget, budget, largest_error_for, true_distance, would_do
from ..inputs import read_user_text
from ..obstacles import Cylinder, read_obstacle_geojson
from ..planning.camera import (
    POSITION_ERROR_M,
    Camera,
    formation_gaps,
    trigger_distance,
    widest_spacing,
)
from ..planning.survey import directions, formation_width, lane_spacing, lay_lanes
from .fleet import read_vehicle
from .model import (
    ALGORITHMS,
    AUTO,
    END_ACTIONS,
    MAX_ALTITUDE_M,
    MAX_AREA_SIDE_M,
    MAX_DISTANCE_M,
    MAX_FORMATION_ERROR_M,
    MAX_ITERATIONS,
    MAX_LANES,
    MAX_NAVIGATION_ERROR_M,
    MAX_OFFSET_M,
    MAX_RADIUS_M,
    MAX_SEED,
    MAX_SPEED_M_S,
    MAX_STUDENTS,
    MAX_UAVS,
    MAX_WAYPOINTS,
    MAX_WEIGHT,
    MIN_SEPARATION_M,
    MIN_STUDENTS,
    GeoPoint,
    MissionSettings,
    PlannerSettings,
    Scenario,
    Survey,
    ViaPoint,
    Weights,
)
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

    navigation = _read_navigation(root.table("navigation", required=False))
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
    camera = _read_camera(camera_t) if camera_t else None
    if camera is not None and survey_t is None:
        raise ScenarioError(source, "camera", "needs a [survey]: the photos are taken along "
                            "its lanes")
    survey = (_read_survey(survey_t, default_alt=start.alt_m, camera=camera, offsets=offsets)
              if survey_t else None)
    planner = _read_planner(root.table("planner", required=False))
    mission = _read_mission(root.table("mission", required=False))
    copters = read_vehicle(root.table("vehicle", required=False), count=len(offsets),
                           base_dir=base_dir)
    vehicle = copters[0].nav
    battery = _read_battery(root.table("battery", required=False),
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
        scenario = _with_lanes(scenario, survey)
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


def _read_survey(t: Table, *, default_alt: float, camera: Camera | None,
                 offsets: np.ndarray) -> Survey:
    """``spacing`` may be left out with a camera (it then comes from the side overlap,
    :func:`_camera_spacing`, as does the default margin); ``alt`` may not be given with
    the camera's ``gsd_cm``, which chooses it: the highest UAV flies where a pixel
    covers ``gsd_cm``, the others lower (finer)."""
    spacing = math.nan
    if camera is None or t.has("spacing"):
        spacing = t.number("spacing", lo=0.0, hi=MAX_DISTANCE_M, lo_open=True, unit="m")
    heading = t.number("heading", lo=-360.0, hi=360.0, unit="degrees")
    margin = (t.number("margin", spacing / 2, lo=0.0, hi=MAX_DISTANCE_M, unit="m")
              if t.has("margin") or not math.isnan(spacing) else math.nan)
    t.used.add("margin")
    if camera is not None and camera.gsd_cm is not None:
        if t.has("alt"):
            raise t.error("alt", "give either survey.alt or camera.gsd_cm (which chooses the "
                                 "altitude), not both")
        alt = camera.altitude_for_gsd(camera.gsd_cm) - float(offsets[:, 2].max())
        if not -MAX_ALTITUDE_M <= alt <= MAX_ALTITUDE_M:
            raise ScenarioError(t.source, "camera.gsd_cm", f"asks for a survey at {alt:.0f} m: "
                                f"at most {MAX_ALTITUDE_M:g} m")
    else:
        alt = t.number("alt", default_alt, lo=-MAX_ALTITUDE_M, hi=MAX_ALTITUDE_M, unit="m")
    t.done()
    return Survey(spacing_m=spacing, heading_deg=heading, margin_m=margin, alt_m=alt,
                  camera=camera)


MAX_SENSOR_MM = 100.0
MAX_FOCAL_MM = 2_000.0
MAX_IMAGE_PX = 100_000


def _read_camera(t: Table) -> Camera:
    """A ``[camera]`` table: QGroundControl's camera definition fields."""
    sizes = [t.number(k, lo=0.0, hi=MAX_SENSOR_MM, lo_open=True, unit="mm")
             for k in ("sensor_width_mm", "sensor_height_mm")]
    focal = t.number("focal_length_mm", lo=0.0, hi=MAX_FOCAL_MM, lo_open=True, unit="mm")
    pixels = [t.integer(k, lo=1, hi=MAX_IMAGE_PX) for k in ("image_width_px", "image_height_px")]
    overlaps = []
    for key in ("front_overlap", "side_overlap"):
        value = t.number(key, lo=0.0, hi=1.0)
        if value >= 1.0:
            raise t.error(key, f"must be a fraction within [0, 1), got {value:g} (1 would "
                               "need photos at one place)")
        overlaps.append(value)
    landscape = t.raw("landscape", True)
    if not isinstance(landscape, bool):
        raise t.error("landscape", f"must be true or false, got {landscape!r}")
    gsd = (t.number("gsd_cm", lo=0.0, hi=1e4, lo_open=True, unit="cm")
           if t.has("gsd_cm") else None)
    t.used.add("gsd_cm")
    t.done()
    return Camera(sensor_width_mm=sizes[0], sensor_height_mm=sizes[1], focal_length_mm=focal,
                  image_width_px=pixels[0], image_height_px=pixels[1],
                  front_overlap=overlaps[0], side_overlap=overlaps[1], landscape=landscape,
                  gsd_cm=gsd)


def _camera_spacing(s: Scenario, survey: Survey) -> Survey:
    """With a camera: every UAV's footprint checked (wider than a UAV's position error,
    neighbouring UAVs' strips overlapping by the side overlap), the spacing chosen (or
    the given one checked) so that neighbouring lanes' outer strips overlap by it, the
    trigger distance from the front overlap. The footprints are each UAV's own, at the
    survey's altitude plus its up offset (above home, the ground taken flat)."""
    cam = survey.camera
    offsets = s.offsets_m
    _, across_dir = directions(survey.heading_deg)
    across = offsets[:, :2] @ across_dir
    alts = np.maximum(survey.alt_m + offsets[:, 2], 0.0)
    widths, lengths = cam.footprint(alts)
    n = int(np.argmin(widths))
    if widths[n] <= POSITION_ERROR_M:
        raise ScenarioError(s.source, "camera", f"gives UAV {n + 1} a footprint "
                            f"{widths[n]:.2f} m across at {alts[n]:g} m, no wider than a "
                            f"UAV's position error ({POSITION_ERROR_M:g} m): fly higher or "
                            "take a wider lens")
    gaps = formation_gaps(across, widths, cam.side_overlap)
    if gaps:
        i, j, gap, shared = gaps[0]
        raise ScenarioError(s.source, "camera.side_overlap",
                            f"{cam.side_overlap:g} cannot be reached: UAVs {i + 1} and {j + 1} "
                            f"fly {gap:.2f} m apart across the lanes and their photos "
                            f"({widths[i]:.2f} m and {widths[j]:.2f} m across) overlap "
                            f"{shared:.2f} (fly higher, or a narrower formation)")
    widest = widest_spacing(across, widths, cam.side_overlap)
    spacing = survey.spacing_m
    if math.isnan(spacing):
        spacing = widest
    elif spacing > widest + 1e-9:
        raise ScenarioError(s.source, "survey.spacing",
                            f"{spacing:g} m cannot reach camera.side_overlap "
                            f"{cam.side_overlap:g}: at most {widest:.2f} m with this "
                            f"formation ({float(np.ptp(across)):.2f} m wide across the lanes) "
                            f"and footprints {float(widths.min()):.2f} m across "
                            "(or leave spacing out: it is then chosen)")
    margin = spacing / 2 if math.isnan(survey.margin_m) else survey.margin_m
    distance = trigger_distance(float(lengths.min()), cam.front_overlap)
    return replace(survey, spacing_m=spacing, margin_m=margin, trigger_distance_m=distance)


def relay_lanes(s: Scenario, *, inset_lower_m, inset_upper_m) -> Scenario:
    """``s`` with its survey's lanes laid again, ``inset_lower_m`` ``(2,)`` and
    ``inset_upper_m`` ``(2,)`` metres (east, north) further inside the area's lower and
    upper sides than its margin asks: the planner's answer to copters predicted to swing
    out of the area where they turn into or out of a lane."""
    if s.survey is None or not s.survey.lanes:
        raise ValueError("the scenario has no survey lanes")
    keep = len(s.via) - 2 * len(s.survey.lanes)  # the lanes' ends are the last via points
    return _with_lanes(replace(s, via=s.via[:keep]), s.survey,
                       inset=(np.asarray(inset_lower_m, float), np.asarray(inset_upper_m, float)))


def _with_lanes(s: Scenario, survey: Survey, *, inset=((0.0, 0.0), (0.0, 0.0))) -> Scenario:
    """Lay the survey's lanes (:func:`~.planning.survey.lay_lanes`) and append their ends
    to the via points.

    The lanes stay ``margin`` inside the area's sides and where the centroid keeps every
    UAV inside the area (and ``inset``, ``(lower (2,), upper (2,))`` metres, further in);
    a lane end on a tree is moved along the lane until every UAV clears it. The survey
    begins from the last ``[[via]]`` point, or the start.
    """
    if survey.camera is not None:
        survey = _camera_spacing(s, survey)
    lower, upper = s.area_bounds_enu()
    offsets = s.offsets_m
    mm = 1e-3  # a millimetre inside: lane ends survive the round trip through lat/lon
    inset_lo, inset_hi = (np.asarray(x, float) for x in inset)
    lo = np.maximum(lower + survey.margin_m, lower - offsets[:, :2].min(axis=0)) + mm + inset_lo
    hi = np.minimum(upper - survey.margin_m, upper - offsets[:, :2].max(axis=0)) - mm - inset_hi
    if np.any(lo >= hi):
        raise ScenarioError(
            s.source, "survey.margin",
            f"leaves no room for a lane: the area is {upper[0] - lower[0]:.1f} m x "
            f"{upper[1] - lower[1]:.1f} m, the margin {survey.margin_m:g} m on every side and "
            "the formation must stay inside (reduce the margin)")
    across = float(np.hypot(*(hi - lo)))  # no lane set is wider than the diagonal
    if across / survey.spacing_m > MAX_LANES:
        raise ScenarioError(
            s.source, "survey.spacing",
            f"{survey.spacing_m:g} m would lay up to {across / survey.spacing_m:.0f} lanes "
            f"across {across:.0f} m: at most {MAX_LANES} (a wider spacing)")
    centres, radii = s.obstacles_enu()
    discs_c = (centres[None, :, :] - offsets[None, :, :2].transpose(1, 0, 2)).reshape(-1, 2)
    discs_r = np.tile(radii + s.true_clearance_m, len(offsets))
    begin = s.frame.to_enu(lat_deg=(s.via[-1] if s.via else s.start).lat_deg,
                           lon_deg=(s.via[-1] if s.via else s.start).lon_deg)
    lanes = lay_lanes(lower=lo, upper=hi, spacing_m=survey.spacing_m,
                      heading_deg=survey.heading_deg, begin=begin[:2], centres=discs_c,
                      radii=discs_r)
    if not lanes:
        raise ScenarioError(s.source, "survey", "no lane fits inside the area with this "
                            "margin, spacing and heading clear of the obstacles")
    across_dir = directions(survey.heading_deg)[1]
    spacing = lane_spacing(np.array([a @ across_dir for a, _ in lanes]))
    ends = np.array([end for lane in lanes for end in lane])
    enu = np.column_stack([ends, np.full(len(ends), survey.alt_m)])
    lat, lon, _ = s.frame.to_lla(enu)
    points = [GeoPoint(float(a), float(o), survey.alt_m) for a, o in zip(lat, lon)]
    lanes_ll = tuple((points[2 * k], points[2 * k + 1]) for k in range(len(lanes)))
    via = tuple(
        ViaPoint(p.lat_deg, p.lon_deg, p.alt_m, f"lane {k // 2 + 1} {('start', 'end')[k % 2]}")
        for k, p in enumerate(points)
    )
    return replace(s, via=s.via + via, survey=replace(survey, lanes=lanes_ll,
                                                      lane_spacing_m=spacing))


def survey_width(s: Scenario) -> float | None:
    """The formation's width across the survey's lanes (metres), ``None`` without one."""
    if s.survey is None:
        return None
    return formation_width(s.offsets_m, s.survey.heading_deg)


def _read_planner(t: Table | None) -> PlannerSettings:
    if t is None:
        return PlannerSettings()
    algorithm = t.string("algorithm", ALGORITHMS[0], choices=ALGORITHMS)
    students = t.integer("students", 100, lo=MIN_STUDENTS, hi=MAX_STUDENTS)
    if t.raw("waypoints", 10) == AUTO:
        waypoints = AUTO
    else:
        value = t.raw("waypoints")
        if (isinstance(value, bool) or not isinstance(value, int)
                or not 1 <= value <= MAX_WAYPOINTS):
            raise t.error("waypoints", f'must be an integer within [1, {MAX_WAYPOINTS}] or '
                                       f'"{AUTO}", got {value!r}')
        waypoints = value
    iterations = t.integer("iterations", 150, lo=1, hi=MAX_ITERATIONS)
    seed = t.integer("seed", 0, lo=0, hi=MAX_SEED)
    weights = Weights()
    w = t.table("weights", required=False)
    if w is not None:
        weights = Weights(
            length=w.number("length", 1.0, lo=0.0, hi=MAX_WEIGHT),
            safety=w.number("safety", 1.0, lo=0.0, hi=MAX_WEIGHT),
            task=w.number("task", 1.0, lo=0.0, hi=MAX_WEIGHT),
        )
        w.done()
    t.done()
    return PlannerSettings(algorithm, students, waypoints, iterations, seed, weights)


def _read_mission(t: Table | None) -> MissionSettings:
    if t is None:
        return MissionSettings()
    end = t.string("end_action", "land", choices=END_ACTIONS)
    speed = (t.number("speed", None, lo=0.0, hi=MAX_SPEED_M_S, lo_open=True, unit="m/s")
             if t.has("speed") else None)
    t.used.add("speed")
    allowance = t.number("corner_allowance", 0.0, lo=0.0, hi=10.0, unit="m")
    t.done()
    return MissionSettings(end_action=end, speed_m_s=speed, corner_allowance_m=allowance)


def _read_navigation(t: Table | None) -> NavigationBudget:
    """``[navigation]``: how well the copters know where they are. ``class``: one of
    :data:`ftlbo_mav.gnss.CLASSES` (``gps``, the default, ``sbas``, ``rtk-float``,
    ``rtk-fixed``); ``horizontal_error``: the 95 % horizontal bound in metres, in place of
    the class's figure (the class still sets the fix type a copter needs)."""
    if t is None:
        return budget()
    name = t.string("class", None, choices=tuple(CLASSES)) if t.has("class") else None
    t.used.add("class")
    error = (t.number("horizontal_error", lo=0.0, hi=MAX_NAVIGATION_ERROR_M, unit="m")
             if t.has("horizontal_error") else None)
    t.used.add("horizontal_error")
    t.done()
    return budget(name, error)


def _read_battery(t: Table | None, *, cruise_speed_m_s: float) -> Battery | None:
    """``[battery]``: each UAV's battery (:mod:`ftlbo_mav.energy`). ``capacity`` (mAh),
    ``reserve`` (per cent of it to land with, default 25), and ``hover_current`` (A) or
    ``endurance`` (minutes of hover on a full battery); optional ``cruise_current`` (A
    at ``cruise_speed`` m/s, default the mission's speed or WPNAV_SPEED's 10 m/s) and
    ``induced_velocity`` (m/s, the rotor's in hover)."""
    if t is None:
        return None
    capacity = t.number("capacity", lo=0.0, hi=1_000_000.0, lo_open=True, unit="mAh")
    reserve = t.number("reserve", 25.0, lo=0.0, hi=100.0, unit="%")
    if reserve >= 100.0:
        raise t.error("reserve", "must be below 100 %: nothing would be left to fly with")
    if t.has("hover_current") == t.has("endurance"):
        raise t.error("hover_current", "give the hover current (A) or the endurance "
                      "(minutes of hover on a full battery), one of them")
    extra = dict(reserve_pct=reserve, source="[battery]", cruise_speed_m_s=cruise_speed_m_s)
    if t.has("cruise_current"):
        extra["cruise_current_a"] = t.number("cruise_current", lo=0.0, hi=1000.0,
                                             lo_open=True, unit="A")
    if t.has("cruise_speed"):
        extra["cruise_speed_m_s"] = t.number("cruise_speed", lo=0.0, hi=50.0, lo_open=True,
                                             unit="m/s")
    if t.has("induced_velocity"):
        extra["induced_velocity_m_s"] = t.number("induced_velocity", lo=0.0, hi=50.0,
                                                 lo_open=True, unit="m/s")
    if t.has("hover_current"):
        hover = t.number("hover_current", lo=0.0, hi=1000.0, lo_open=True, unit="A")
        battery = Battery(capacity_mah=capacity, hover_current_a=hover, **extra)
    else:
        minutes = t.number("endurance", lo=0.0, hi=10_000.0, lo_open=True, unit="min")
        battery = Battery.from_endurance(capacity, minutes, **extra)
    t.done()
    return battery


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
