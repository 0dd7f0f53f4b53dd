"""A plan's outputs: one mission per UAV and the ``plan.json`` summary.

``plan_missions``, ``plan_document`` and ``plan_files`` are pure; ``write_plan`` and
``read_plan`` are the only functions here that touch files (writing all or nothing
through :class:`~ftlbo_mav.mission.files.OutputFolder`). ``plan.json`` records the
SHA-256 of every mission file written with it (``uavs[i].mission_sha256``), so that a
folder whose files come from different plans is refused (:func:`check_plan_folder`).
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
from ..planning.planner import Leg, Plan
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
from .fence import UavFence, plan_fences
from .files import OutputFolder, digest, read_mission_text
from .geodetic import GeodeticPlan, geodetic_view
from .gis import render_geojson, render_kml
from .items import UavMission, build_mission  # UavMission re-exported: it lived here
from .params_file import FENCE_PARAMS_FILE, render_params
from .photos import UavPhotos, camera_document, plan_photos
from .qgc_plan import render_plan
from .waypoints import render_waypoints

# Formats written on request next to the .waypoints files (``plan --formats``).
FORMATS = ("geojson", "kml", "plan")

PLAN_OUTPUTS = (r"uav\d+\.waypoints", r"uav\d+\.plan", r"uav\d+\.fence", r"uav\d+\.rally",
                r"fence\.parm", r"plan\.json", r"plan\.geojson",
                r"plan\.kml", r"plan-3d\.png", r"plan-ground\.png", r"plan-vertical\.png",
                r"convergence\.png")
"""What a plan folder holds of one plan (:func:`write_plan`, ``plan --plot``): a re-plan
removes those of an earlier plan it does not write, so a folder never mixes two plans."""


def plan_missions(plan: Plan, *, geodetic: GeodeticPlan | None = None) -> list[UavMission]:
    """One mission per UAV: home at its own start on the ground, its own path.

    ``geodetic``: the plan's :func:`geodetic_view` (computed here when not given)."""
    missions = []
    settings = plan.scenario.mission
    view = geodetic if geodetic is not None else geodetic_view(plan)
    survey = plan.scenario.survey
    camera = ()
    if survey is not None and survey.trigger_distance_m is not None:
        camera = tuple((a, b, survey.trigger_distance_m) for a, b in lane_points(plan))
    taken = survey.first_photo_taken if survey is not None else ()
    for n, lla in enumerate(view.uav_paths):
        lanes = camera
        if camera and n < len(taken) and taken[n]:  # resumed where its photo was taken
            lanes = ((*camera[0], False), *camera[1:])
        items = build_mission(
            home=(float(lla[0, 0]), float(lla[0, 1])),
            takeoff_alt_m=float(lla[0, 2]),
            path=[tuple(map(float, row)) for row in lla],
            end_action=settings.end_action,
            speed_m_s=settings.speed_m_s,
            holds_s=None if plan.holds_s is None else [float(h) for h in plan.holds_s],
            camera=lanes,
        )
        offset = tuple(float(v) for v in plan.problem.offsets[n])
        missions.append(UavMission(f"uav{n + 1}", offset, tuple(items)))
    return missions


def lane_points(plan: Plan) -> list[tuple[int, int]]:
    """Each survey lane's entry and exit as indices into the plan's paths
    (:meth:`~ftlbo_mav.planning.planner.Plan.lane_points`)."""
    return plan.lane_points()


def _finite(value: float) -> float | None:
    """JSON has no infinity: an infinite cost is written as null."""
    return float(value) if math.isfinite(value) else None


def _points(lla) -> list[dict]:
    return [
        {"lat": round(float(lat), 8), "lon": round(float(lon), 8), "alt": round(float(alt), 6)}
        for lat, lon, alt in lla
    ]


def _cost(terms: CostTerms) -> dict:
    return {k: _finite(getattr(terms, k)) for k in ("total", "length", "safety", "task")}


def _round(value: float | None, digits: int) -> float | None:
    return None if value is None else round(value, digits)


def _leg_document(leg: Leg, first: int) -> dict:
    return {
        "from": leg.start_name,
        "to": leg.goal_name,
        "first_point": first,
        "waypoints": leg.waypoints,
        "waypoints_tried": list(leg.tried),
        "feasible": leg.feasible,
        "cost": _cost(leg.cost),
        "lower_bound_length": _round(leg.lower_bound_length, 4),
        "length_ratio": _round(leg.length_ratio, 6),
        "evaluations": leg.evaluations,
        "seconds": round(leg.seconds, 4),
    }


def plan_document(
    plan: Plan, missions: list[UavMission], *, written: bool, geodetic: GeodeticPlan | None = None,
    digests: dict[str, str] | None = None, fences: list[UavFence] | None = None,
    photos: list[UavPhotos] | None = None,
) -> dict:
    """The ``plan.json`` content. ``written``: whether the mission files were written;
    ``digests``: their SHA-256 by UAV name (:func:`~.files.digest` of the text written).

    Totals at the top (cost, bound, evaluations, seconds: sums over the legs), one entry
    per leg in ``legs`` (``first_point``: index of the leg's start in ``centroid``).
    ``photos``: the survey's (:func:`~.photos.plan_photos`, computed here when not given)."""
    s, sc = plan.settings, plan.scenario
    view = geodetic if geodetic is not None else geodetic_view(plan)
    firsts = np.cumsum([0] + [leg.waypoints + 1 for leg in plan.legs[:-1]])
    survey = sc.survey
    fleet = [c.document() for c in sc.fleet()]
    if photos is None:
        photos = plan_photos(plan, missions)
    return {
        "scenario": plan.scenario.name or plan.scenario.source,
        "algorithm": s.algorithm,
        "seed": s.seed,
        "students": s.students,
        "waypoints": s.waypoints,
        "waypoint_count": plan.waypoint_count,
        "iterations": s.iterations,
        "feasible": plan.feasible,
        "violations": list(plan.violations),
        "cost": _cost(plan.cost),
        "seconds": round(plan.seconds, 4),
        "evaluations": plan.evaluations,
        "lower_bound_length": _round(plan.lower_bound_length, 4),
        "length_ratio": _round(plan.length_ratio, 6),
        "history": [_finite(h) for h in plan.history],
        "clearance": plan.scenario.clearance_m,
        "navigation": _navigation_document(plan),
        "corner_allowance": plan.scenario.mission.corner_allowance_m,
        "mission": {"end_action": sc.mission.end_action, "speed": sc.mission.speed_m_s},
        # the first copter's values (every UAV's own, with what upload sets: uavs[].vehicle)
        "vehicle": dict(fleet[0]["params"]),
        "predicted": _predicted_document(plan),
        **({} if sc.battery is None else {"battery": sc.battery.document()}),
        "min_separation": plan.scenario.min_separation_m,
        # in flight: a UAV farther from its slot is a departure (flight/departures.py)
        "formation_bound": {"max_error": sc.max_formation_error_m,
                            "error_m": _round(_finite(plan.formation_bound_m), 4)},
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
        "via": [{"name": v.name, "lat": v.lat_deg, "lon": v.lon_deg, "alt": v.alt_m}
                for v in sc.via],
        "survey": None if survey is None else {
            "spacing": survey.spacing_m,
            "heading": survey.heading_deg,
            "margin": survey.margin_m,
            "alt": survey.alt_m,
            "lane_count": len(survey.lanes),
            "lane_spacing": _round(survey.lane_spacing_m, 4),
            "lanes": [[[a.lat_deg, a.lon_deg], [b.lat_deg, b.lon_deg]] for a, b in survey.lanes],
            # further inside than the margin, for the copters' predicted swings (planner)
            "lanes_inset": round(plan.lanes_inset_m, 3),
            "camera": camera_document(plan, photos),
            **({"first_photo_taken": list(survey.first_photo_taken)}
               if survey.first_photo_taken else {}),
        },
        "legs": [_leg_document(leg, int(f)) for leg, f in zip(plan.legs, firsts)],
        "centroid": _points(view.centroid),
        "uavs": [
            {
                "name": m.name,
                "offset": list(m.offset),
                "waypoints": _points(path),
                "mission_file": f"{m.name}.waypoints" if written else None,
                "mission_sha256": (digests or {}).get(m.name) if written else None,
                "vehicle": fleet[n],
                **_uav_predicted(plan, n),
                **_uav_battery(plan, n),
                **_fence_document(m.name, fences, n, written),
                **({"photos": photos[n].count} if photos else {}),
            }
            for n, (m, path) in enumerate(zip(missions, view.uav_paths))
        ],
    } | ({} if not fences else {"fence": {
        "params": dict(fences[0].params),
        "params_file": FENCE_PARAMS_FILE if written else None,
        "exclusion_radii_m": list(fences[0].exclusion_radii_m),
    }})


def _copters_from_document(doc: dict) -> tuple[Copter, ...]:
    """Each UAV's copter as the plan predicted it (``uavs[].vehicle``); a plan written
    before them: the top-level ``vehicle`` for every UAV, nothing to set."""
    uavs = doc["uavs"]
    if all(isinstance(u.get("vehicle"), dict) for u in uavs):
        return tuple(Copter.from_document(u["vehicle"]) for u in uavs)
    nav = vehicle_navigation({str(k): float(v) for k, v in (doc.get("vehicle") or {}).items()
                              if k in VEHICLE_PARAMS})
    return (copter_of(nav, source="plan.json"),) * len(uavs)


def _navigation_document(plan: Plan) -> dict:
    """The navigation budget and what the plan keeps, at 95 %, where the copters truly
    are: the predicted flown path's clearance less the budget, and its separation less
    two copters' combined error (:mod:`ftlbo_mav.gnss`)."""
    nav = plan.scenario.navigation
    doc = nav.document()
    p = plan.prediction
    if p is not None:
        true_sep = p.separation if p.true_separation is None else p.true_separation
        doc["kept_at_95"] = {
            "clearance_m": _round(_finite(float(p.clearance.min()) - nav.horizontal_m), 4),
            "separation_m": _round(_finite(float(true_sep.min())), 4),
        }
    return doc


def _predicted_document(plan: Plan) -> dict | None:
    """What the planner did for the flown path: its corner moves, stops and re-plans,
    and how long predicting took."""
    if plan.prediction is None:
        return None
    return {
        "model": "ArduCopter " + " and ".join(sorted({c.release for c in plan.scenario.fleet()}))
                 + " AC_WPNav/SCurve (ftlbo_mav.ardupilot.flight_path)",
        "corners_moved": plan.corners_moved,
        "corner_stops": plan.corner_stops,
        "holds_s": [] if plan.holds_s is None else [int(h) for h in plan.holds_s],
        "replans": plan.replans,
        "seconds": round(plan.predict_seconds, 4),
        "min_clearance_m": _round(_finite(float(plan.prediction.clearance.min())), 4),
        "min_separation_m": _round(_finite(float(plan.prediction.separation.min())), 4),
        "obstacle_clearance_m": [round(float(c), 4) for c in plan.prediction.obstacle_clearance],
    }


def _uav_predicted(plan: Plan, n: int) -> dict:
    """Per UAV: its predicted flown path's smallest clearance and separation, seconds
    per leg (point to point) and in all."""
    p = plan.prediction
    if p is None:
        return {}
    return {
        "predicted_clearance_m": _round(_finite(float(p.clearance[n])), 4),
        "predicted_separation_m": _round(_finite(float(p.separation[n])), 4),
        "predicted_leg_seconds": [round(float(t), 2) for t in p.leg_seconds[n]],
        "predicted_seconds": round(float(p.seconds[n]), 2),
    }


def _uav_battery(plan: Plan, n: int) -> dict:
    """Per UAV, when the scenario has a ``[battery]``: its mission's predicted charge
    (mAh: takeoff, legs, landing, all), what it would land with, and from each path
    point reached what is left to use to the end (``fly`` holds the vehicle to it)."""
    if plan.charges is None:
        return {}
    c, b = plan.charges[n], plan.scenario.battery
    left = b.capacity_mah - c.total_mah
    return {"battery": {
        "mah": round(c.total_mah, 1), "takeoff_mah": round(c.takeoff_mah, 1),
        "legs_mah": round(c.legs_mah, 1), "landing_mah": round(c.end_mah, 1),
        "seconds": round(c.seconds, 1), "lands_with_mah": round(left, 1),
        "lands_with_pct": round(100.0 * left / b.capacity_mah, 1),
        "to_end_mah": [round(float(v), 1) for v in c.to_end_mah]}}


def _fence_document(name: str, fences: list[UavFence] | None, n: int, written: bool) -> dict:
    if not fences:
        return {}
    f = fences[n]
    return {
        "fence_file": f"{name}.fence" if written else None,
        "rally_file": f"{name}.rally" if written and f.rally else None,
        "rally": [{"lat": round(r.lat_deg, 8), "lon": round(r.lon_deg, 8), "alt": r.alt_m}
                  for r in f.rally],
        "fence_notes": list(f.notes),
    }


def plan_files(
    plan: Plan, *, allow_infeasible: bool = False, formats: tuple[str, ...] = (),
    fence: bool = True,
) -> dict[str, str]:
    """Every output file of ``plan`` by name, ``plan.json`` last (pure; see :func:`write_plan`)."""
    unknown = sorted(set(formats) - set(FORMATS))
    if unknown:
        raise ValueError(f"unknown format {unknown[0]!r}; known: {', '.join(FORMATS)}")
    view = geodetic_view(plan)  # the one conversion to degrees every writer takes
    missions = plan_missions(plan, geodetic=view)
    write_missions = plan.feasible or allow_infeasible
    fences = plan_fences(plan) if fence else []
    photos = plan_photos(plan, missions)
    files: dict[str, str] = {}
    if write_missions:
        for n, m in enumerate(missions):
            uav_fence = fences[n] if fences else None
            files[f"{m.name}.waypoints"] = render_waypoints(m.items)
            if uav_fence is not None:
                files[f"{m.name}.fence"] = render_waypoints(uav_fence.fence)
                if uav_fence.rally:
                    files[f"{m.name}.rally"] = render_waypoints(uav_fence.rally)
            if "plan" in formats:
                files[f"{m.name}.plan"] = render_plan(
                    m.items, hover_speed_m_s=plan.scenario.mission.speed_m_s, fence=uav_fence)
        if fences:
            files[FENCE_PARAMS_FILE] = render_params(fences[0].params)
    if "geojson" in formats:
        files["plan.geojson"] = render_geojson(plan, missions, geodetic=view, fences=fences,
                                               photos=photos)
    if "kml" in formats:
        files["plan.kml"] = render_kml(plan, missions, geodetic=view, fences=fences,
                                       photos=photos)
    digests = {m.name: digest(files[f"{m.name}.waypoints"])
               for m in missions if write_missions}
    doc = plan_document(plan, missions, written=write_missions, geodetic=view, digests=digests,
                        fences=fences, photos=photos)
    files["plan.json"] = json.dumps(doc, indent=2) + "\n"
    return files


def write_plan(
    plan: Plan,
    out_dir: str | Path,
    *,
    allow_infeasible: bool = False,
    formats: tuple[str, ...] = (),
    fence: bool = True,
) -> list[Path]:
    """Write ``plan.json`` and, when feasible (or allowed), ``uavN.waypoints`` per UAV.

    ``formats`` (from :data:`FORMATS`) adds ``plan.geojson``, ``plan.kml`` and a
    QGroundControl ``uavN.plan`` next to each ``uavN.waypoints``. Returns the paths
    written. An infeasible plan gets its ``plan.json`` (with the violations), GeoJSON and
    KML, to be looked at, but no mission files (``.waypoints``, ``.plan``) unless
    ``allow_infeasible``. With ``fence`` (the default) each UAV also gets ``uavN.fence``
    and ``uavN.rally`` (``QGC WPL 110``, :mod:`.fence`), the folder ``fence.parm`` (the
    fence parameters), and the ``.plan`` its ``geoFence`` and ``rallyPoints``.
    All or nothing: the outputs of an earlier plan in ``out_dir``
    (:data:`PLAN_OUTPUTS`) that this one does not write are removed; a failure raises
    :class:`~ftlbo_mav.errors.OutputError` with ``out_dir`` untouched.
    """
    files = plan_files(plan, allow_infeasible=allow_infeasible, formats=formats, fence=fence)
    with OutputFolder(out_dir, replaces=PLAN_OUTPUTS, last="plan.json") as out:
        return out.write_all(files)


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
    """Rebuild a :class:`Plan` from ``plan.json`` content (the inverse of :func:`plan_document`).

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
