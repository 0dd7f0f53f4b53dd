"""A plan folder read back: ``plan.json`` -> :class:`~ftlbo_mav.planning.plans.Plan`.

The inverse of :mod:`.export`: :func:`read_plan` (:func:`read_plan_json` then
:func:`plan_from_document`) rebuilds the scenario and the paths from what ``plan.json``
carries, refusing values no plan could hold; :func:`check_plan_folder` checks that the
folder's mission files are the ones written with it (their SHA-256). Every problem is a
:class:`~ftlbo_mav.errors.MissionFileError` naming the file.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..ardupilot.copters import Copter, copter_of
from ..ardupilot.navigation import VEHICLE_PARAMS, vehicle_navigation
from ..energy import battery_from_document
from ..errors import MissionFileError
from ..gnss import budget_from_document
from ..inputs import read_user_text
from ..planning.cost import CostTerms
from ..planning.plans import Leg, Plan
from ..planning.problem import problem_from_scenario
from ..scenario import (
    AUTO,
    Camera,
    Cylinder,
    GeoPoint,
    MissionSettings,
    PlannerSettings,
    Scenario,
    Survey,
    ViaPoint,
)
from ..scenario.model import (
    MAX_ALTITUDE_M,
    MAX_FORMATION_ERROR_M,
    MAX_OFFSET_M,
    MAX_RADIUS_M,
    MIN_SEPARATION_M,
)
from .files import digest, read_mission_text


def _copters_from_document(doc: dict) -> tuple[Copter, ...]:
    """Each UAV's copter as the plan predicted it (``uavs[].vehicle``); a plan written
    before them: the top-level ``vehicle`` for every UAV, nothing to set."""
    uavs = doc["uavs"]
    if all(isinstance(u.get("vehicle"), dict) for u in uavs):
        return tuple(Copter.from_document(u["vehicle"]) for u in uavs)
    nav = vehicle_navigation({str(k): float(v) for k, v in (doc.get("vehicle") or {}).items()
                              if k in VEHICLE_PARAMS})
    return (copter_of(nav, source="plan.json"),) * len(uavs)


def check_plan_folder(folder: str | Path, doc: dict, *, source: str) -> list[Path]:
    """The mission files ``doc`` (a folder's ``plan.json``) lists, checked to be the ones
    it was written with (their SHA-256) and to be all the folder holds; returns them in
    UAV order. :class:`MissionFileError` naming the file otherwise."""
    folder = Path(folder)
    replan = "; plan again with `ftlbo-mav plan` into an empty folder"
    try:
        uavs = doc["uavs"]
        listed = [(u["mission_file"], u.get("mission_sha256")) for u in uavs]
    except (KeyError, TypeError) as exc:
        raise MissionFileError(f"{source}: not a plan.json written by ftlbo-mav "
                               f"(missing or bad {exc}){replan}") from None
    on_disk = sorted(p.name for p in folder.glob("uav*.waypoints"))
    if any(name is None for name, _ in listed):
        if on_disk:
            raise MissionFileError(f"{source}: its plan has no mission files (infeasible), but "
                                   f"{folder} holds {', '.join(on_disk)} of another plan{replan}")
        raise MissionFileError(f"{source}: the plan is infeasible and has no mission files")
    extra = sorted(set(on_disk) - {name for name, _ in listed})
    if extra:
        raise MissionFileError(f"{folder / extra[0]}: not a mission of the plan in {source} "
                               f"(it has {len(listed)} UAVs){replan}")
    paths = []
    for name, sha in listed:
        path = folder / str(name)
        if Path(str(name)).name != name:
            raise MissionFileError(f"{source}: mission_file {name!r} is not a file name")
        if not isinstance(sha, str):
            raise MissionFileError(f"{source}: no mission_sha256 for {name}: written by an "
                                   f"older ftlbo-mav, so its files cannot be matched{replan}")
        if digest(read_mission_text(path)) != sha:
            raise MissionFileError(f"{path}: not the mission file the plan in {source} was "
                                   f"written with (its SHA-256 differs){replan}")
        paths.append(path)
    return paths


def plan_from_document(doc: dict, *, source: str = "plan.json") -> Plan:
    """Rebuild a :class:`Plan` from ``plan.json`` content (the inverse of
    :func:`~.export.plan_document`).

    The scenario is rebuilt from what ``plan.json`` carries: area, band, obstacles,
    clearance, offsets, via points and survey lanes, and the centroid's first and last
    points as start and goal. Paths come from the file as written (8 decimals: about a
    millimetre). The planner weights are not recorded and read as the defaults; a file
    without ``legs`` (written before surveys) is one leg. Raises :class:`MissionFileError`.
    """
    try:
        area = doc["area"]
        centroid = doc["centroid"]
        uavs = doc["uavs"]
        start, goal = (GeoPoint(p["lat"], p["lon"], p["alt"]) for p in (centroid[0], centroid[-1]))
        via = tuple(ViaPoint(float(v["lat"]), float(v["lon"]), float(v["alt"]), str(v["name"]))
                    for v in doc.get("via", []))
        survey = doc.get("survey")
        lanes_inset = 0.0
        if survey is not None:
            camera = survey.get("camera")
            lane_spacing = survey.get("lane_spacing")
            lanes_inset = float(survey.get("lanes_inset", 0.0))
            survey = Survey(
                spacing_m=float(survey["spacing"]), heading_deg=float(survey["heading"]),
                margin_m=float(survey["margin"]), alt_m=float(survey["alt"]),
                lanes=tuple((GeoPoint(*map(float, a), float(survey["alt"])),
                             GeoPoint(*map(float, b), float(survey["alt"])))
                            for a, b in survey["lanes"]),
                lane_spacing_m=None if lane_spacing is None else float(lane_spacing),
                camera=None if camera is None else _camera_from_document(camera),
                trigger_distance_m=None if camera is None else float(
                    camera["trigger_distance"]),
                first_photo_taken=tuple(bool(v) for v in survey.get("first_photo_taken", ())))
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
            via=via,
            survey=survey,
            navigation=budget_from_document(doc.get("navigation")),
            # what the plan was made with, so that it can be planned again (fly --resume)
            mission=_mission_settings(doc),
            min_separation_m=float(doc.get("min_separation", MIN_SEPARATION_M)),
            max_formation_error_m=float((doc.get("formation_bound") or {}).get(
                "max_error", MAX_FORMATION_ERROR_M)),
            vehicle=vehicle_navigation({str(k): float(v)
                                        for k, v in (doc.get("vehicle") or {}).items()}),
            copters=_copters_from_document(doc),
            battery=battery_from_document(doc.get("battery")),
        )
        waypoints = doc["waypoints"]
        settings = PlannerSettings(
            algorithm=doc["algorithm"], students=int(doc["students"]),
            waypoints=AUTO if waypoints == AUTO else int(waypoints),
            iterations=int(doc["iterations"]), seed=int(doc["seed"]),
        )
        frame = scenario.frame

        def enu(points) -> np.ndarray:
            return frame.to_enu(lat_deg=[p["lat"] for p in points],
                                lon_deg=[p["lon"] for p in points],
                                alt_m=[p["alt"] for p in points]).reshape(-1, 3)

        centroid_enu = enu(centroid)
        uav_paths = np.stack([enu(u["waypoints"]) for u in uavs])
        cost = _cost_terms(doc["cost"])
        history = np.array([_infinite(h) for h in doc["history"]], float)
        violations = tuple(str(v) for v in doc["violations"])
        feasible_flag = bool(doc["feasible"])
        evaluations, seconds = int(doc["evaluations"]), float(doc["seconds"])
        bound = doc.get("lower_bound_length")
        bound = None if bound is None else float(bound)
        leg_docs = doc.get("legs") or [{
            "from": "start", "to": "goal", "first_point": 0,
            "waypoints": len(centroid) - 2, "waypoints_tried": [], "cost": doc["cost"],
            "lower_bound_length": bound, "evaluations": evaluations, "seconds": seconds,
            "feasible": feasible_flag}]
        problem = problem_from_scenario(scenario, waypoints=max(len(centroid_enu) - 2, 1))
        legs = []
        for leg in leg_docs:
            first, m = int(leg["first_point"]), int(leg["waypoints"])
            path = centroid_enu[first : first + m + 2]
            if len(path) != m + 2:
                raise ValueError("legs do not fit the centroid")
            leg_bound = leg["lower_bound_length"]
            legs.append(Leg(
                start_name=str(leg["from"]), goal_name=str(leg["to"]),
                problem=replace(problem, start=path[0], goal=path[-1], waypoints=m),
                centroid=path, cost=_cost_terms(leg["cost"]),
                violations=() if leg["feasible"] else ("infeasible (see plan.json)",),
                history=history if len(leg_docs) == 1 else np.zeros(0),
                evaluations=int(leg["evaluations"]),
                seconds=float(leg["seconds"]),
                lower_bound_length=None if leg_bound is None else float(leg_bound),
                tried=tuple(int(t) for t in leg.get("waypoints_tried", []))))
    except (KeyError, TypeError, ValueError, IndexError, AttributeError) as exc:
        raise MissionFileError(
            f"{source}: not a plan.json this version of ftlbo-mav can read (missing or bad "
            f"{exc}); plan again with `ftlbo-mav plan`"
        ) from None
    _check_plan_values(scenario, settings, legs, doc, source)
    ends = sum(leg.waypoints + 1 for leg in legs) + 1
    if len(centroid_enu) != ends or uav_paths.shape != (len(uavs), len(centroid_enu), 3):
        raise MissionFileError(f"{source}: the paths do not have the legs' waypoints + via "
                               "points + start and goal each")
    if feasible_flag == bool(violations):
        raise MissionFileError(f"{source}: 'feasible' disagrees with 'violations'")
    return Plan(
        scenario=scenario,
        settings=settings,
        problem=problem,
        centroid=centroid_enu,
        uav_paths=uav_paths,
        cost=cost,
        violations=violations,
        history=history,
        evaluations=evaluations,
        seconds=seconds,
        lower_bound_length=bound,
        legs=tuple(legs),
        holds_s=_holds(doc, len(centroid_enu), source),
        lanes_inset_m=lanes_inset,
    )


def _mission_settings(doc: dict) -> MissionSettings:
    """plan.json's ``mission`` and ``corner_allowance`` (a file written before ``mission``
    was recorded reads as the defaults: its mission files say the rest)."""
    mission = doc.get("mission") or {}
    speed = mission.get("speed")
    return MissionSettings(end_action=str(mission.get("end_action", "land")),
                           speed_m_s=None if speed is None else float(speed),
                           corner_allowance_m=float(doc.get("corner_allowance", 0.0)))


def _holds(doc: dict, points: int, source: str) -> np.ndarray | None:
    """``predicted.holds_s`` of a plan.json (None when it has none)."""
    holds = (doc.get("predicted") or {}).get("holds_s") or None
    if holds is None:
        return None
    if len(holds) != points:
        raise MissionFileError(f"{source}: predicted.holds_s has {len(holds)} values for "
                               f"{points} points")
    return np.array(holds, float)


def _check_plan_values(scenario: Scenario, settings: PlannerSettings, legs, doc: dict,
                       source: str) -> None:
    """The values of a plan.json that a scenario file could not have held: every latitude
    and longitude a position, the area with an extent, the band, clearance and radii
    positive, offsets finite, the waypoint count the legs'. :class:`MissionFileError`
    naming the field; a plan folder edited by hand is read as carefully as a scenario."""

    def bad(field: str, problem: str) -> MissionFileError:
        return MissionFileError(f"{source}: {field}: {problem}; plan again with "
                                "`ftlbo-mav plan`")

    def position(field: str, lat, lon, alt=0.0) -> None:
        if not all(math.isfinite(v) for v in (lat, lon, alt)):
            raise bad(field, f"({lat}, {lon}, {alt}) is not a finite position")
        if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0):
            raise bad(field, f"latitude {lat:g}, longitude {lon:g} is not a position on Earth")
        if abs(alt) > MAX_ALTITUDE_M:
            raise bad(field, f"altitude {alt:g} m is beyond {MAX_ALTITUDE_M:g} m")

    a, b = scenario.corner_a, scenario.corner_b
    position("area.corner_a", a.lat_deg, a.lon_deg)
    position("area.corner_b", b.lat_deg, b.lon_deg)
    if a.lat_deg == b.lat_deg or a.lon_deg == b.lon_deg:
        raise bad("area", "the corners must differ in both latitude and longitude (the area "
                          "has no extent)")
    lo, hi = scenario.min_altitude_m, scenario.max_altitude_m
    if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 < lo < hi <= MAX_ALTITUDE_M):
        raise bad("area", f"the altitude band {lo:g}..{hi:g} m is not 0 < min < max")
    if not (math.isfinite(scenario.clearance_m) and scenario.clearance_m >= 0.0):
        raise bad("clearance", f"{scenario.clearance_m:g} m must be >= 0")
    for i, o in enumerate(scenario.obstacles):
        position(f"obstacles[{i}]", o.lat_deg, o.lon_deg)
        if not (math.isfinite(o.radius_m) and 0.0 < o.radius_m <= MAX_RADIUS_M):
            raise bad(f"obstacles[{i}].radius", f"{o.radius_m:g} m must be > 0")
    for i, row in enumerate(scenario.offsets):
        if len(row) != 3 or not all(math.isfinite(v) and abs(v) <= MAX_OFFSET_M for v in row):
            raise bad(f"uavs[{i}].offset", f"{list(row)} is not [east, north, up] in metres "
                                           f"within {MAX_OFFSET_M:g}")
    for i, v in enumerate(scenario.via):
        position(f"via[{i}]", v.lat_deg, v.lon_deg, v.alt_m)
    for i, p in enumerate(doc["centroid"]):
        position(f"centroid[{i}]", float(p["lat"]), float(p["lon"]), float(p["alt"]))
    for n, u in enumerate(doc["uavs"]):
        for i, p in enumerate(u["waypoints"]):
            position(f"uavs[{n}].waypoints[{i}]", float(p["lat"]), float(p["lon"]),
                     float(p["alt"]))
    if settings.waypoints != AUTO:
        for k, leg in enumerate(legs):
            if leg.waypoints != settings.waypoints:
                raise bad(f"legs[{k}].waypoints", f"{leg.waypoints} differs from the plan's "
                                                  f"waypoints = {settings.waypoints}")


def _camera_from_document(doc: dict) -> Camera:
    gsd = doc.get("gsd_cm")
    return Camera(
        sensor_width_mm=float(doc["sensor_width_mm"]),
        sensor_height_mm=float(doc["sensor_height_mm"]),
        focal_length_mm=float(doc["focal_length_mm"]), image_width_px=int(doc["image_width_px"]),
        image_height_px=int(doc["image_height_px"]), front_overlap=float(doc["front_overlap"]),
        side_overlap=float(doc["side_overlap"]), landscape=bool(doc["landscape"]),
        gsd_cm=None if gsd is None else float(gsd))


def _cost_terms(doc: dict) -> CostTerms:
    return CostTerms(*(_infinite(doc[k]) for k in CostTerms._fields))


def _infinite(value) -> float:
    """``null`` in plan.json is an infinite cost."""
    return math.inf if value is None else float(value)


def read_plan_json(folder: str | Path) -> tuple[dict, str]:
    """``folder/plan.json`` as a dict, and its path as text; :class:`MissionFileError`
    when it is missing, unreadable, not JSON, not an object, or holds NaN or infinity."""
    path = Path(folder) / "plan.json"
    if not Path(folder).is_dir():
        raise MissionFileError(f"{folder}: no such folder (run `ftlbo-mav plan` first)")

    def not_finite(name: str):
        raise ValueError(f"{name} is not a finite number")

    if not path.exists():
        raise MissionFileError(f"{path}: no such file (run `ftlbo-mav plan` first)")
    text = read_user_text(path, error=lambda problem: MissionFileError(f"{path}: {problem}"))
    try:
        doc = json.loads(text, parse_constant=not_finite)
    except (ValueError, RecursionError) as exc:
        raise MissionFileError(f"{path}: cannot read: {getattr(exc, 'strerror', None) or exc}"
                               ) from None
    if not isinstance(doc, dict):
        raise MissionFileError(f"{path}: not a plan.json (not a JSON object)")
    return doc, str(path)


def read_plan(folder: str | Path) -> Plan:
    """Read ``folder/plan.json`` back into a :class:`Plan`; see :func:`plan_from_document`."""
    doc, source = read_plan_json(folder)
    return plan_from_document(doc, source=source)
