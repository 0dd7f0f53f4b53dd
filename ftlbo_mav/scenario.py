"""Scenario files: TOML -> a validated, frozen :class:`Scenario`.

Every mistake a user can make in a scenario ends here as a :class:`ScenarioError` naming
the file, the field and the problem. The key names are fixed (see ``missions/*.toml`` and
the README) so scenarios stay portable between versions; unknown keys are refused, since
a typo that is silently ignored plans a different survey than the one intended.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from .errors import ScenarioError
from .formation import PLANES, regular_formation
from .geo import LocalFrame
from .obstacles import Cylinder, read_obstacle_geojson
from .planning.survey import formation_width, lay_lanes

ALGORITHMS = ("ftlbo-seeded", "ftlbo", "tlbo", "ga", "theta-pso")
"""Every name in planning.optimizers.OPTIMIZERS; the first is the default. ``ftlbo`` is
the paper's FTLBO; ``ftlbo-seeded`` is FTLBO from geometric seed routes (docs/planning.md)."""
END_ACTIONS = ("land", "rtl", "loiter")
AUTO = "auto"
"""``waypoints = "auto"``: per leg, the fewest waypoints whose plan is within
:data:`ftlbo_mav.planning.planner.AUTO_TARGET` of the leg's lower bound."""


@dataclass(frozen=True)
class GeoPoint:
    """A position: degrees WGS84 and metres above home."""

    lat_deg: float
    lon_deg: float
    alt_m: float = 0.0


@dataclass(frozen=True)
class ViaPoint:
    """A point the centroid passes between start and goal: degrees WGS84, metres above
    home, and a label (``"via 1"``, ``"lane 2 start"``... when the file gives none)."""

    lat_deg: float
    lon_deg: float
    alt_m: float
    name: str = ""


@dataclass(frozen=True)
class Survey:
    """A ``[survey]``: lanes ``spacing_m`` apart along ``heading_deg`` (degrees clockwise
    from north), ``margin_m`` inside the area's sides, flown at ``alt_m``. ``lanes``:
    each lane's (entry, exit) in flight order; its ends are the scenario's via points."""

    spacing_m: float
    heading_deg: float
    margin_m: float
    alt_m: float
    lanes: tuple[tuple[GeoPoint, GeoPoint], ...] = ()


@dataclass(frozen=True)
class Weights:
    """The paper's alpha, beta, gamma (eq. 5)."""

    length: float = 1.0
    safety: float = 1.0
    task: float = 1.0


@dataclass(frozen=True)
class PlannerSettings:
    """Optimizer settings; the defaults are the paper's experiment, except the algorithm:
    the seeded FTLBO (near-optimal paths, same budget) rather than the paper's FTLBO."""

    algorithm: str = ALGORITHMS[0]
    students: int = 100
    waypoints: int | str = 10
    """Free waypoints per leg, or :data:`AUTO`."""
    iterations: int = 150
    seed: int = 0
    weights: Weights = field(default_factory=Weights)


@dataclass(frozen=True)
class MissionSettings:
    """How the per-UAV missions end and how fast they fly."""

    end_action: str = "land"
    speed_m_s: float | None = None


@dataclass(frozen=True)
class Scenario:
    """A survey: area, altitude band, start, via points and goal of the centroid,
    formation, obstacles. ``via``: every point passed between start and goal in flight
    order (the ``[[via]]`` points, then the lane ends of ``survey``)."""

    corner_a: GeoPoint
    corner_b: GeoPoint
    min_altitude_m: float
    max_altitude_m: float
    start: GeoPoint
    goal: GeoPoint
    offsets: tuple[tuple[float, float, float], ...]
    clearance_m: float = 1.0
    obstacles: tuple[Cylinder, ...] = ()
    planner: PlannerSettings = field(default_factory=PlannerSettings)
    mission: MissionSettings = field(default_factory=MissionSettings)
    name: str = ""
    source: str = "<scenario>"
    via: tuple[ViaPoint, ...] = ()
    survey: Survey | None = None

    @cached_property
    def frame(self) -> LocalFrame:
        """ENU frame with its origin at the area's south-west corner."""
        return LocalFrame(
            origin_lat_deg=min(self.corner_a.lat_deg, self.corner_b.lat_deg),
            origin_lon_deg=min(self.corner_a.lon_deg, self.corner_b.lon_deg),
        )

    @property
    def offsets_m(self) -> np.ndarray:
        """Formation offsets, shape ``(N, 3)`` metres ENU."""
        return np.array(self.offsets, dtype=float).reshape(-1, 3)

    @property
    def uav_count(self) -> int:
        return len(self.offsets)

    def area_bounds_enu(self) -> tuple[np.ndarray, np.ndarray]:
        """Horizontal bounds of the area, ``(lower (2,), upper (2,))`` metres east/north.

        The lat/lon rectangle is very nearly an ENU rectangle; the inner box of its four
        corners is used, so a point inside the box is inside the rectangle.
        """
        lat = [self.corner_a.lat_deg, self.corner_b.lat_deg]
        lon = [self.corner_a.lon_deg, self.corner_b.lon_deg]
        lo_lat, hi_lat, lo_lon, hi_lon = min(lat), max(lat), min(lon), max(lon)
        corners = self.frame.to_enu(
            lat_deg=[lo_lat, lo_lat, hi_lat, hi_lat], lon_deg=[lo_lon, hi_lon, lo_lon, hi_lon]
        )
        lower = np.array([max(corners[0, 0], corners[2, 0]), max(corners[0, 1], corners[1, 1])])
        upper = np.array([min(corners[1, 0], corners[3, 0]), min(corners[2, 1], corners[3, 1])])
        return lower, upper

    def start_enu(self) -> np.ndarray:
        return self.frame.to_enu(
            lat_deg=self.start.lat_deg, lon_deg=self.start.lon_deg, alt_m=self.start.alt_m
        )

    def goal_enu(self) -> np.ndarray:
        return self.frame.to_enu(
            lat_deg=self.goal.lat_deg, lon_deg=self.goal.lon_deg, alt_m=self.goal.alt_m
        )

    def route_enu(self) -> np.ndarray:
        """Start, every via point and the goal, ``(V + 2, 3)`` metres ENU: leg ``k`` runs
        from row ``k`` to row ``k + 1``."""
        points = [self.start, *self.via, self.goal]
        return self.frame.to_enu(lat_deg=[p.lat_deg for p in points],
                                 lon_deg=[p.lon_deg for p in points],
                                 alt_m=[p.alt_m for p in points]).reshape(-1, 3)

    def route_names(self) -> tuple[str, ...]:
        """``"start"``, each via point's name, ``"goal"``: the ends of the legs."""
        return ("start", *(v.name for v in self.via), "goal")

    def obstacles_enu(self) -> tuple[np.ndarray, np.ndarray]:
        """Cylinder axes ``(K, 2)`` metres east/north and radii ``(K,)`` metres (no clearance)."""
        if not self.obstacles:
            return np.zeros((0, 2)), np.zeros(0)
        centres = self.frame.to_enu(
            lat_deg=[c.lat_deg for c in self.obstacles],
            lon_deg=[c.lon_deg for c in self.obstacles],
        )[:, :2]
        return centres, np.array([c.radius_m for c in self.obstacles], dtype=float)


# --------------------------------------------------------------------------- reading


class _Table:
    """One TOML table being read: tracks which keys were used, to refuse the rest."""

    def __init__(self, data: Any, path: str, source: str) -> None:
        if not isinstance(data, dict):
            raise ScenarioError(source, path, f"must be a table, got {_kind(data)}")
        self.data, self.path, self.source = data, path, source
        self.used: set[str] = set()

    def _field(self, key: str) -> str:
        return f"{self.path}.{key}" if self.path else key

    def error(self, key: str, problem: str) -> ScenarioError:
        return ScenarioError(self.source, self._field(key), problem)

    def has(self, key: str) -> bool:
        return key in self.data

    def raw(self, key: str, default: Any = ..., *, required: bool = True) -> Any:
        self.used.add(key)
        if key in self.data:
            return self.data[key]
        if default is not ... or not required:
            return None if default is ... else default
        raise self.error(key, "missing (required)")

    def number(self, key: str, default: Any = ..., *, lo=None, hi=None, lo_open=False) -> float:
        value = self.raw(key, default)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.error(key, f"must be a number, got {_kind(value)}")
        value = float(value)
        if not math.isfinite(value):
            raise self.error(key, "must be a finite number")
        if lo is not None and (value <= lo if lo_open else value < lo):
            raise self.error(key, f"must be {'>' if lo_open else '>='} {lo:g}, got {value:g}")
        if hi is not None and value > hi:
            raise self.error(key, f"must be <= {hi:g}, got {value:g}")
        return value

    def integer(self, key: str, default: Any = ..., *, lo: int | None = None) -> int:
        value = self.raw(key, default)
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(key, f"must be an integer, got {_kind(value)}")
        if lo is not None and value < lo:
            raise self.error(key, f"must be >= {lo}, got {value}")
        return value

    def string(self, key: str, default: Any = ..., *, choices=None) -> str:
        value = self.raw(key, default)
        if not isinstance(value, str):
            raise self.error(key, f"must be a string, got {_kind(value)}")
        if choices is not None and value not in choices:
            raise self.error(key, f"must be one of {', '.join(choices)}; got {value!r}")
        return value

    def table(self, key: str, *, required: bool = True) -> _Table | None:
        value = self.raw(key, required=required)
        if value is None and not required:
            return None
        return _Table(value, self._field(key), self.source)

    def lat_lon(self, key: str) -> tuple[float, float]:
        value = self.raw(key)
        if (
            not isinstance(value, list)
            or len(value) != 2
            or any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in value)
        ):
            raise self.error(key, f"must be [lat, lon] in degrees, got {value!r}")
        lat, lon = float(value[0]), float(value[1])
        _check_lat_lon(lat, lon, lambda what, problem: self.error(f"{key}[{what}]", problem))
        return lat, lon

    def point(self, *, alt: bool = True) -> GeoPoint:
        lat = self.number("lat")
        lon = self.number("lon")
        _check_lat_lon(lat, lon, lambda what, problem: self.error(("lat", "lon")[what], problem))
        return GeoPoint(lat_deg=lat, lon_deg=lon, alt_m=self.number("alt") if alt else 0.0)

    def done(self) -> None:
        unknown = sorted(set(self.data) - self.used)
        if unknown:
            raise self.error(unknown[0], "unknown key (a typo?)")


def _check_lat_lon(lat: float, lon: float, error) -> None:
    if not -90.0 <= lat <= 90.0:
        raise error(0, f"latitude {lat:g} is outside [-90, 90]")
    if not -180.0 <= lon <= 180.0:
        raise error(1, f"longitude {lon:g} is outside [-180, 180]")


def _kind(value: Any) -> str:
    return {
        bool: "a boolean",
        int: "an integer",
        float: "a number",
        str: "a string",
        list: "an array",
        dict: "a table",
    }.get(type(value), type(value).__name__)


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario file. Raises :class:`ScenarioError` on any problem."""
    path = Path(path)
    source = str(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ScenarioError(source, "", "no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ScenarioError(source, "", f"cannot read: {exc}") from None
    return parse_scenario(text, source=source, base_dir=path.parent)


def parse_scenario(
    text: str, *, source: str = "<scenario>", base_dir: Path | None = None
) -> Scenario:
    """Parse scenario TOML text; see :func:`load_scenario`."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(source, "", f"malformed TOML: {exc}") from None
    root = _Table(data, "", source)

    name = root.string("name", "")
    area = root.table("area")
    lat_a, lon_a = area.lat_lon("corner_a")
    lat_b, lon_b = area.lat_lon("corner_b")
    if lat_a == lat_b or lon_a == lon_b:
        raise area.error("corner_b", "must differ from corner_a in both latitude and longitude")
    h_min = area.number("min_altitude", lo=0.0, lo_open=True)
    h_max = area.number("max_altitude")
    if h_min >= h_max:
        raise area.error("min_altitude", f"must be below max_altitude ({h_min:g} >= {h_max:g})")
    area.done()

    start_t, goal_t = root.table("start"), root.table("goal")
    start, goal = start_t.point(), goal_t.point()
    start_t.done()
    goal_t.done()

    form = root.table("formation")
    offsets = _read_offsets(form)
    clearance = form.number("clearance", 1.0, lo=0.0)
    form.done()

    obstacles = _read_obstacles(root.raw("obstacles", []), source)
    obstacles_file = root.string("obstacles_file", "")
    via = _read_via(root.raw("via", []), source)
    survey_t = root.table("survey", required=False)
    survey = _read_survey(survey_t, default_alt=start.alt_m) if survey_t else None
    planner = _read_planner(root.table("planner", required=False))
    mission = _read_mission(root.table("mission", required=False))
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
    )
    if obstacles_file:
        # obstacles_file (optional): a GeoJSON file of obstacles, relative to the scenario
        # file: Points with a `radius` in metres, Polygons -> their smallest enclosing
        # circle (docs/outputs.md). They follow the [[obstacles]] tables, in file order.
        path = (base_dir if base_dir is not None else Path(".")) / obstacles_file
        extra = read_obstacle_geojson(path, frame=scenario.frame)
        scenario = replace(scenario, obstacles=scenario.obstacles + extra)
    if survey is not None:
        scenario = _with_lanes(scenario, survey)
    _check_geometry(scenario)
    return scenario


def _read_offsets(form: _Table) -> np.ndarray:
    if form.has("offsets"):
        for key in ("count", "radius", "plane"):
            if form.has(key):
                raise form.error(key, "give either offsets or count/radius/plane, not both")
        rows = form.raw("offsets")
        if not isinstance(rows, list) or not rows:
            raise form.error("offsets", "must be a non-empty array of [east, north, up] rows")
        for i, row in enumerate(rows):
            if (
                not isinstance(row, list)
                or len(row) != 3
                or any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in row)
            ):
                raise form.error(f"offsets[{i}]",
                                 f"must be [east, north, up] in metres, got {row!r}")
        return np.array(rows, dtype=float)
    if not form.has("count"):
        raise form.error("offsets", "missing: give offsets, or count and radius")
    count = form.integer("count", lo=1)
    radius = form.number("radius", lo=0.0)
    plane = form.string("plane", "horizontal", choices=PLANES)
    return regular_formation(count=count, radius_m=radius, plane=plane)


def _read_obstacles(rows: Any, source: str) -> tuple[Cylinder, ...]:
    if not isinstance(rows, list):
        raise ScenarioError(source, "obstacles", "must be an array of tables ([[obstacles]])")
    cylinders = []
    for i, row in enumerate(rows):
        t = _Table(row, f"obstacles[{i}]", source)
        point = t.point(alt=False)
        radius = t.number("radius", lo=0.0, lo_open=True)
        label = t.string("name", "")
        t.done()
        cylinders.append(Cylinder(point.lat_deg, point.lon_deg, radius, label))
    return tuple(cylinders)


def _read_via(rows: Any, source: str) -> tuple[ViaPoint, ...]:
    if not isinstance(rows, list):
        raise ScenarioError(source, "via", "must be an array of tables ([[via]])")
    points = []
    for i, row in enumerate(rows):
        t = _Table(row, f"via[{i}]", source)
        point = t.point()
        label = t.string("name", f"via {i + 1}")
        t.done()
        points.append(ViaPoint(point.lat_deg, point.lon_deg, point.alt_m, label))
    return tuple(points)


def _read_survey(t: _Table, *, default_alt: float) -> Survey:
    spacing = t.number("spacing", lo=0.0, lo_open=True)
    heading = t.number("heading")
    margin = t.number("margin", spacing / 2, lo=0.0)
    alt = t.number("alt", default_alt)
    t.done()
    return Survey(spacing_m=spacing, heading_deg=heading, margin_m=margin, alt_m=alt)


def _with_lanes(s: Scenario, survey: Survey) -> Scenario:
    """Lay the survey's lanes (:func:`~.planning.survey.lay_lanes`) and append their ends
    to the via points.

    The lanes stay ``margin`` inside the area's sides and where the centroid keeps every
    UAV inside the area; a lane end on a tree is moved along the lane until every UAV
    clears it. The survey begins from the last ``[[via]]`` point, or the start.
    """
    lower, upper = s.area_bounds_enu()
    offsets = s.offsets_m
    inset = 1e-3  # a millimetre inside: lane ends survive the round trip through lat/lon
    lo = np.maximum(lower + survey.margin_m, lower - offsets[:, :2].min(axis=0)) + inset
    hi = np.minimum(upper - survey.margin_m, upper - offsets[:, :2].max(axis=0)) - inset
    if np.any(lo >= hi):
        raise ScenarioError(
            s.source, "survey.margin",
            f"leaves no room for a lane: the area is {upper[0] - lower[0]:.1f} m x "
            f"{upper[1] - lower[1]:.1f} m, the margin {survey.margin_m:g} m on every side and "
            "the formation must stay inside (reduce the margin)")
    centres, radii = s.obstacles_enu()
    discs_c = (centres[None, :, :] - offsets[None, :, :2].transpose(1, 0, 2)).reshape(-1, 2)
    discs_r = np.tile(radii + s.clearance_m, len(offsets))
    begin = s.frame.to_enu(lat_deg=(s.via[-1] if s.via else s.start).lat_deg,
                           lon_deg=(s.via[-1] if s.via else s.start).lon_deg)
    lanes = lay_lanes(lower=lo, upper=hi, spacing_m=survey.spacing_m,
                      heading_deg=survey.heading_deg, begin=begin[:2], centres=discs_c,
                      radii=discs_r)
    if not lanes:
        raise ScenarioError(s.source, "survey", "no lane fits inside the area with this "
                            "margin, spacing and heading clear of the obstacles")
    ends = np.array([end for lane in lanes for end in lane])
    enu = np.column_stack([ends, np.full(len(ends), survey.alt_m)])
    lat, lon, _ = s.frame.to_lla(enu)
    points = [GeoPoint(float(a), float(o), survey.alt_m) for a, o in zip(lat, lon)]
    lanes_ll = tuple((points[2 * k], points[2 * k + 1]) for k in range(len(lanes)))
    via = tuple(
        ViaPoint(p.lat_deg, p.lon_deg, p.alt_m, f"lane {k // 2 + 1} {('start', 'end')[k % 2]}")
        for k, p in enumerate(points)
    )
    return replace(s, via=s.via + via, survey=replace(survey, lanes=lanes_ll))


def survey_width(s: Scenario) -> float | None:
    """The formation's width across the survey's lanes (metres), ``None`` without one."""
    if s.survey is None:
        return None
    return formation_width(s.offsets_m, s.survey.heading_deg)


def _read_planner(t: _Table | None) -> PlannerSettings:
    if t is None:
        return PlannerSettings()
    algorithm = t.string("algorithm", ALGORITHMS[0], choices=ALGORITHMS)
    students = t.integer("students", 100, lo=4)
    if t.raw("waypoints", 10) == AUTO:
        waypoints = AUTO
    else:
        value = t.raw("waypoints")
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise t.error("waypoints", f'must be an integer >= 1 or "{AUTO}", got {value!r}')
        waypoints = value
    iterations = t.integer("iterations", 150, lo=1)
    seed = t.integer("seed", 0, lo=0)
    weights = Weights()
    w = t.table("weights", required=False)
    if w is not None:
        weights = Weights(
            length=w.number("length", 1.0, lo=0.0),
            safety=w.number("safety", 1.0, lo=0.0),
            task=w.number("task", 1.0, lo=0.0),
        )
        w.done()
    t.done()
    return PlannerSettings(algorithm, students, waypoints, iterations, seed, weights)


def _read_mission(t: _Table | None) -> MissionSettings:
    if t is None:
        return MissionSettings()
    end = t.string("end_action", "land", choices=END_ACTIONS)
    speed = t.number("speed", None, lo=0.0, lo_open=True) if t.has("speed") else None
    t.used.add("speed")
    t.done()
    return MissionSettings(end_action=end, speed_m_s=speed)


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
            if dist[k] <= radii[k] + s.clearance_m:
                raise ScenarioError(
                    s.source,
                    key,
                    f"puts UAV {n} {dist[k]:.2f} m from the axis of obstacles[{k}] "
                    f"(radius {radii[k]:g} m + clearance {s.clearance_m:g} m)",
                )
