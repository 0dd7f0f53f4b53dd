"""The scenario's ``[survey]`` and ``[camera]`` tables, and the survey's lanes laid on it.

:func:`read_survey` and :func:`read_camera` read the two tables; :func:`with_lanes` lays
the lanes inside the area (the geometry is :mod:`ftlbo_mav.planning.survey`'s), clear of
the obstacles, with the spacing the camera's side overlap asks for, and appends their
ends to the via points; :func:`relay_lanes` lays them again further inside when the
planner asks. Mistakes end as a :class:`~ftlbo_mav.errors.ScenarioError` naming the field.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..errors import ScenarioError
from ..planning.camera import (
    POSITION_ERROR_M,
    Camera,
    formation_gaps,
    trigger_distance,
    widest_spacing,
)
from ..planning.survey import directions, formation_width, lane_spacing, lay_lanes
from .model import (
    MAX_ALTITUDE_M,
    MAX_DISTANCE_M,
    MAX_LANES,
    GeoPoint,
    Scenario,
    Survey,
    ViaPoint,
)
from .tables import Table


def read_survey(t: Table, *, default_alt: float, camera: Camera | None,
                offsets: np.ndarray) -> Survey:
    """``spacing`` may be left out with a camera (it then comes from the side overlap,
    :func:`camera_spacing`, as does the default margin); ``alt`` may not be given with
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


def read_camera(t: Table) -> Camera:
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


def camera_spacing(s: Scenario, survey: Survey) -> Survey:
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
    return with_lanes(replace(s, via=s.via[:keep]), s.survey,
                       inset=(np.asarray(inset_lower_m, float), np.asarray(inset_upper_m, float)))


def with_lanes(s: Scenario, survey: Survey, *, inset=((0.0, 0.0), (0.0, 0.0))) -> Scenario:
    """Lay the survey's lanes (:func:`~.planning.survey.lay_lanes`) and append their ends
    to the via points.

    The lanes stay ``margin`` inside the area's sides and where the centroid keeps every
    UAV inside the area (and ``inset``, ``(lower (2,), upper (2,))`` metres, further in);
    a lane end on a tree is moved along the lane until every UAV clears it. The survey
    begins from the last ``[[via]]`` point, or the start.
    """
    if survey.camera is not None:
        survey = camera_spacing(s, survey)
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
