"""A plan's outputs: one mission per UAV and the ``plan.json`` summary.

``plan_missions`` and ``plan_document`` are pure; ``write_plan`` and ``read_plan`` are
the only functions here that touch files (writing through
:func:`~ftlbo_mav.mission.files.write_atomic`).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import MissionFileError
from ..planning.cost import CostTerms
from ..planning.planner import Plan
from ..planning.problem import problem_from_scenario
from ..scenario import Cylinder, GeoPoint, PlannerSettings, Scenario
from .files import write_atomic
from .gis import render_geojson, render_kml
from .items import MissionItem, build_mission
from .qgc_plan import render_plan
from .waypoints import render_waypoints

# Formats written on request next to the .waypoints files (``plan --formats``).
FORMATS = ("geojson", "kml", "plan")


@dataclass(frozen=True)
class UavMission:
    """One UAV's mission: its name (``uav1``...), offset and items."""

    name: str
    offset: tuple[float, float, float]
    items: tuple[MissionItem, ...]


def plan_missions(plan: Plan) -> list[UavMission]:
    """One mission per UAV: home at its own start on the ground, its own path."""
    missions = []
    settings = plan.scenario.mission
    for n, path in enumerate(plan.uav_paths):
        lla = plan.lla(path)
        items = build_mission(
            home=(float(lla[0, 0]), float(lla[0, 1])),
            takeoff_alt_m=float(lla[0, 2]),
            path=[tuple(map(float, row)) for row in lla],
            end_action=settings.end_action,
            speed_m_s=settings.speed_m_s,
        )
        offset = tuple(float(v) for v in plan.problem.offsets[n])
        missions.append(UavMission(f"uav{n + 1}", offset, tuple(items)))
    return missions


def _finite(value: float) -> float | None:
    """JSON has no infinity: an infinite cost is written as null."""
    return float(value) if math.isfinite(value) else None


def _points(lla) -> list[dict]:
    return [
        {"lat": round(float(lat), 8), "lon": round(float(lon), 8), "alt": round(float(alt), 6)}
        for lat, lon, alt in lla
    ]


def plan_document(plan: Plan, missions: list[UavMission], *, written: bool) -> dict:
    """The ``plan.json`` content. ``written``: whether the mission files were written."""
    s, sc = plan.settings, plan.scenario
    return {
        "scenario": plan.scenario.name or plan.scenario.source,
        "algorithm": s.algorithm,
        "seed": s.seed,
        "students": s.students,
        "waypoints": s.waypoints,
        "iterations": s.iterations,
        "feasible": plan.feasible,
        "violations": list(plan.violations),
        "cost": {
            "total": _finite(plan.cost.total),
            "length": _finite(plan.cost.length),
            "safety": _finite(plan.cost.safety),
            "task": _finite(plan.cost.task),
        },
        "seconds": round(plan.seconds, 4),
        "evaluations": plan.evaluations,
        "lower_bound_length": (
            None if plan.lower_bound_length is None else round(plan.lower_bound_length, 4)
        ),
        "length_ratio": None if plan.length_ratio is None else round(plan.length_ratio, 6),
        "history": [_finite(h) for h in plan.history],
        "clearance": plan.scenario.clearance_m,
        "area": {
            "corner_a": [sc.corner_a.lat_deg, sc.corner_a.lon_deg],
            "corner_b": [sc.corner_b.lat_deg, sc.corner_b.lon_deg],
            "min_altitude": sc.min_altitude_m,
            "max_altitude": sc.max_altitude_m,
        },
        "obstacles": [
            {"lat": c.lat_deg, "lon": c.lon_deg, "radius": c.radius_m, "name": c.name}
            for c in sc.obstacles
        ],
        "centroid": _points(plan.lla(plan.centroid)),
        "uavs": [
            {
                "name": m.name,
                "offset": list(m.offset),
                "waypoints": _points(plan.lla(path)),
                "mission_file": f"{m.name}.waypoints" if written else None,
            }
            for m, path in zip(missions, plan.uav_paths)
        ],
    }


def write_plan(
    plan: Plan,
    out_dir: str | Path,
    *,
    allow_infeasible: bool = False,
    formats: tuple[str, ...] = (),
) -> list[Path]:
    """Write ``plan.json`` and, when feasible (or allowed), ``uavN.waypoints`` per UAV.

    ``formats`` (from :data:`FORMATS`) adds ``plan.geojson``, ``plan.kml`` and a
    QGroundControl ``uavN.plan`` next to each ``uavN.waypoints``. Returns the paths
    written. An infeasible plan gets its ``plan.json`` (with the violations), GeoJSON and
    KML, to be looked at, but no mission files (``.waypoints``, ``.plan``) unless
    ``allow_infeasible``.
    """
    unknown = sorted(set(formats) - set(FORMATS))
    if unknown:
        raise ValueError(f"unknown format {unknown[0]!r}; known: {', '.join(FORMATS)}")
    out_dir = Path(out_dir)
    missions = plan_missions(plan)
    write_missions = plan.feasible or allow_infeasible
    written = []
    if write_missions:
        for m in missions:
            written.append(write_atomic(out_dir / f"{m.name}.waypoints", render_waypoints(m.items)))
            if "plan" in formats:
                text = render_plan(m.items, hover_speed_m_s=plan.scenario.mission.speed_m_s)
                written.append(write_atomic(out_dir / f"{m.name}.plan", text))
    if "geojson" in formats:
        written.append(write_atomic(out_dir / "plan.geojson", render_geojson(plan, missions)))
    if "kml" in formats:
        written.append(write_atomic(out_dir / "plan.kml", render_kml(plan, missions)))
    doc = plan_document(plan, missions, written=write_missions)
    written.append(write_atomic(out_dir / "plan.json", json.dumps(doc, indent=2) + "\n"))
    return written


def plan_from_document(doc: dict, *, source: str = "plan.json") -> Plan:
    """Rebuild a :class:`Plan` from ``plan.json`` content (the inverse of :func:`plan_document`).

    The scenario is rebuilt from what ``plan.json`` carries: area, band, obstacles,
    clearance, offsets, and the centroid's first and last points as start and goal. Paths
    come from the file as written (8 decimals: about a millimetre). The planner weights
    are not recorded and read as the defaults. Raises :class:`MissionFileError`.
    """
    try:
        area = doc["area"]
        centroid = doc["centroid"]
        uavs = doc["uavs"]
        start, goal = (GeoPoint(p["lat"], p["lon"], p["alt"]) for p in (centroid[0], centroid[-1]))
        scenario = Scenario(
            corner_a=GeoPoint(*map(float, area["corner_a"])),
            corner_b=GeoPoint(*map(float, area["corner_b"])),
            min_altitude_m=float(area["min_altitude"]),
            max_altitude_m=float(area["max_altitude"]),
            start=start,
            goal=goal,
            offsets=tuple(tuple(float(v) for v in u["offset"]) for u in uavs),
            clearance_m=float(doc["clearance"]),
            obstacles=tuple(
                Cylinder(float(o["lat"]), float(o["lon"]), float(o["radius"]), o.get("name", ""))
                for o in doc["obstacles"]
            ),
            name=str(doc.get("scenario", "")),
            source=source,
        )
        settings = PlannerSettings(
            algorithm=doc["algorithm"], students=int(doc["students"]),
            waypoints=int(doc["waypoints"]), iterations=int(doc["iterations"]),
            seed=int(doc["seed"]),
        )
        frame = scenario.frame

        def enu(points) -> np.ndarray:
            return frame.to_enu(lat_deg=[p["lat"] for p in points],
                                lon_deg=[p["lon"] for p in points],
                                alt_m=[p["alt"] for p in points])

        centroid_enu = enu(centroid)
        uav_paths = np.stack([enu(u["waypoints"]) for u in uavs])
        cost = CostTerms(*(_infinite(doc["cost"][k]) for k in CostTerms._fields))
        history = np.array([_infinite(h) for h in doc["history"]], float)
        violations = tuple(str(v) for v in doc["violations"])
        feasible_flag = bool(doc["feasible"])
        evaluations, seconds = int(doc["evaluations"]), float(doc["seconds"])
        bound = doc.get("lower_bound_length")
        bound = None if bound is None else float(bound)
    except (KeyError, TypeError, ValueError, IndexError) as exc:
        raise MissionFileError(
            f"{source}: not a plan.json this version of ftlbo-mav can read (missing or bad "
            f"{exc}); plan again with `ftlbo-mav plan`"
        ) from None
    if len(centroid_enu) != settings.waypoints + 2 or uav_paths.shape != (
        len(uavs), len(centroid_enu), 3
    ):
        raise MissionFileError(f"{source}: the paths do not have waypoints + 2 points each")
    if feasible_flag == bool(violations):
        raise MissionFileError(f"{source}: 'feasible' disagrees with 'violations'")
    return Plan(
        scenario=scenario,
        settings=settings,
        problem=problem_from_scenario(scenario, waypoints=settings.waypoints),
        centroid=centroid_enu,
        uav_paths=uav_paths,
        cost=cost,
        violations=violations,
        history=history,
        evaluations=evaluations,
        seconds=seconds,
        lower_bound_length=bound,
    )


def _infinite(value) -> float:
    """``null`` in plan.json is an infinite cost."""
    return math.inf if value is None else float(value)


def read_plan(folder: str | Path) -> Plan:
    """Read ``folder/plan.json`` back into a :class:`Plan`; see :func:`plan_from_document`."""
    path = Path(folder) / "plan.json"
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise MissionFileError(f"{path}: no such file (run `ftlbo-mav plan` first)") from None
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise MissionFileError(f"{path}: cannot read: {exc}") from None
    if not isinstance(doc, dict):
        raise MissionFileError(f"{path}: not a plan.json")
    return plan_from_document(doc, source=str(path))
