"""A plan's outputs: one mission per UAV and the ``plan.json`` summary.

``plan_missions`` and ``plan_document`` are pure; ``write_plan`` is the only function
here that touches files (through :func:`~ftlbo_mav.mission.files.write_atomic`).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

from ..planning.planner import Plan
from .files import write_atomic
from .items import MissionItem, build_mission
from .waypoints import render_waypoints


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


def write_plan(plan: Plan, out_dir: str | Path, *, allow_infeasible: bool = False) -> list[Path]:
    """Write ``plan.json`` and, when feasible (or allowed), ``uavN.waypoints`` per UAV.

    Returns the paths written. An infeasible plan gets its ``plan.json`` (with the
    violations) but no mission files unless ``allow_infeasible``.
    """
    out_dir = Path(out_dir)
    missions = plan_missions(plan)
    write_missions = plan.feasible or allow_infeasible
    written = []
    if write_missions:
        for m in missions:
            written.append(write_atomic(out_dir / f"{m.name}.waypoints", render_waypoints(m.items)))
    doc = plan_document(plan, missions, written=write_missions)
    written.append(write_atomic(out_dir / "plan.json", json.dumps(doc, indent=2) + "\n"))
    return written
