"""A plan's outputs: one mission per UAV and the ``plan.json`` summary.

``plan_missions``, ``plan_document`` and ``plan_files`` are pure; ``write_plan`` is the
only function here that touches files (writing all or nothing through
:class:`~ftlbo_mav.mission.files.OutputFolder`). ``plan.json`` records the SHA-256 of
every mission file written with it (``uavs[i].mission_sha256``), so that a folder whose
files come from different plans is refused when it is read back (:mod:`.plan_reader`).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from ..planning.cost import CostTerms
from ..planning.plans import Leg, Plan
from .fence import UavFence, plan_fences
from .files import OutputFolder, digest
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
    (:meth:`~ftlbo_mav.planning.plans.Plan.lane_points`)."""
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
