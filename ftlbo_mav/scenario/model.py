"""The scenario as values: a frozen :class:`Scenario` and its parts, and its ENU frame.

Read from TOML by :mod:`.reader`; every name here is also :mod:`ftlbo_mav.scenario`'s
(``Cylinder`` and ``Camera`` with them: they live in :mod:`ftlbo_mav.obstacles` and
:mod:`ftlbo_mav.planning.camera`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ..ardupilot.copters import Copter, copter_of
from ..ardupilot.navigation import Navigation
from ..energy import Battery
from ..geo import LocalFrame
from ..gnss import NavigationBudget, budget
from ..obstacles import Cylinder
from ..planning.camera import Camera

ALGORITHMS = ("ftlbo-seeded", "ftlbo", "tlbo", "ga", "theta-pso")
"""Every name in planning.optimizers.OPTIMIZERS; the first is the default. ``ftlbo`` is
the paper's FTLBO; ``ftlbo-seeded`` is FTLBO from geometric seed routes (docs/planning.md)."""
END_ACTIONS = ("land", "rtl", "loiter")
AUTO = "auto"
"""``waypoints = "auto"``: per leg, the fewest waypoints whose plan is within a target of
the leg's lower bound; planned with :data:`ftlbo_mav.planning.planner.AUTO_LOOSE_TARGET`
and :data:`~ftlbo_mav.planning.planner.AUTO_TARGET`, the plan flown better kept."""

# The ranges a scenario's numbers (and the command line's overrides of them) must be in:
# finite, physically meaningful, and representable where they go (altitudes and speeds
# become float32 mission fields on the vehicle; a UAV needs one MAVLink system id). The
# reader (.reader) and the CLI's option types both take them from here.
MAX_ALTITUDE_M = 10_000.0
"""Altitudes above home (the band, start, goal, via points, survey): 10 km."""
MAX_OFFSET_M = 1_000.0
"""A formation offset's east, north or up component, and a regular formation's radius."""
MAX_DISTANCE_M = 1_000.0
"""Clearance, min_separation, survey spacing and margin."""
MAX_RADIUS_M = 10_000.0
"""An obstacle's radius."""
MAX_AREA_SIDE_M = 100_000.0
"""The area's sides: the local flat (ENU) frame and the planner's grid are built for a
field, not a country."""
MAX_SPEED_M_S = 100.0
"""``[mission] speed``."""
MAX_WEIGHT = 1e6
"""The cost weights alpha, beta, gamma."""
MAX_UAVS = 254
"""One MAVLink system id (1..254) per UAV."""
MAX_NAVIGATION_ERROR_M = 50.0
"""The largest ``[navigation] horizontal_error`` (metres, 95 %) a scenario may give."""
MIN_SEPARATION_M = 2.0
"""``[formation] min_separation``'s default: the closest two UAVs of the formation may be."""
MAX_FORMATION_ERROR_M = 1.0
"""``[formation] max_error``'s default: how far from its slot a UAV may be in flight
before the flight counts it a departure (a plan may state less: ``Plan.formation_bound_m``)."""
MIN_STUDENTS, MAX_STUDENTS = 4, 100_000
MAX_WAYPOINTS = 1_000
"""Free waypoints of one leg (``"auto"`` looks at up to 256)."""
MAX_ITERATIONS = 1_000_000
MAX_SEED = 2**63 - 1
"""Seeds are written to plan.json and read back as 64-bit integers."""
MAX_LANES = 1_000
"""Survey lanes (each one two via points, each one leg)."""


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
    """A ``[survey]``: lanes at most ``spacing_m`` apart along ``heading_deg`` (degrees
    clockwise from north), ``margin_m`` inside the area's sides, flown at ``alt_m``.
    ``lanes``: each lane's (entry, exit) in flight order; its ends are the scenario's via
    points. ``lane_spacing_m``: the spacing they were laid at (the width between the
    outer lanes over their gaps: never wider than ``spacing_m``; 0 for one lane).
    ``camera``: the ``[camera]`` table, when the survey takes photos; ``spacing_m`` then
    comes from its side overlap when the file gives none, and ``trigger_distance_m``
    (metres between photos along a lane) from its front overlap."""

    spacing_m: float
    heading_deg: float
    margin_m: float
    alt_m: float
    lanes: tuple[tuple[GeoPoint, GeoPoint], ...] = ()
    lane_spacing_m: float | None = None
    camera: Camera | None = None
    trigger_distance_m: float | None = None
    first_photo_taken: tuple[bool, ...] = ()
    """Per UAV, for a survey resumed in the middle of its first lane (``fly --resume``):
    the photo at that lane's entry was taken in the flight before, so its trigger is
    turned on there without a photo at once. Empty: every lane begins with a photo."""


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
    # metres the planner keeps beyond the clearance, an optional extra margin: the corners
    # ArduCopter cuts are predicted and kept clear of by the planner itself
    corner_allowance_m: float = 0.0


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
    min_separation_m: float = MIN_SEPARATION_M
    """No two UAVs of the formation are closer than this (metres)."""
    max_formation_error_m: float = MAX_FORMATION_ERROR_M
    """How far from its slot (the group's centroid plus its offset) a UAV may be in
    flight before ``fly`` counts it a departure (``[formation] max_error``)."""
    vehicle: Navigation = field(default_factory=Navigation)
    """How the copters fly (the ``[vehicle]`` table: ArduCopter's parameters, its defaults
    unless set); the planner predicts the flown path with it."""
    copters: tuple[Copter, ...] = ()
    """Each UAV's copter (the ``[vehicle]`` table and its ``[vehicle.uavN]``: release,
    parameters and where they come from); empty: ArduCopter's defaults for every UAV
    (:meth:`fleet`)."""
    navigation: NavigationBudget = field(default_factory=budget)
    """How well the copters know where they are (the ``[navigation]`` table,
    :mod:`ftlbo_mav.gnss`): the clearance and the separation are kept on the true
    position, this much beyond the predicted one."""
    battery: Battery | None = None
    """Each UAV's battery (the ``[battery]`` table, :mod:`ftlbo_mav.energy`): the plan
    predicts what each mission uses of it and keeps its reserve. None: not checked."""
    dropped_obstacles: int = 0
    """Obstacles of the file that cannot touch any UAV's path inside the area (their
    disc, radius + clearance, does not reach it): left out of ``obstacles``."""

    def fleet(self) -> tuple[Copter, ...]:
        """One :class:`~ftlbo_mav.ardupilot.copters.Copter` per UAV."""
        return self._fleet

    @cached_property
    def _fleet(self) -> tuple[Copter, ...]:
        if len(self.copters) == len(self.offsets):
            return self.copters
        return (copter_of(self.vehicle),) * len(self.offsets)

    @property
    def true_clearance_m(self) -> float:
        """The clearance kept on the estimated position so that the true one keeps
        ``clearance_m`` (95 %): the clearance plus the navigation budget."""
        return self.clearance_m + self.navigation.horizontal_m

    @property
    def kept_clearance_m(self) -> float:
        """What the planner keeps from every obstacle's surface on the predicted flown
        path: the clearance, the navigation budget and the ``[mission] corner_allowance``."""
        return self.true_clearance_m + self.mission.corner_allowance_m

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
