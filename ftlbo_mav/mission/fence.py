"""Each UAV's geofence and rally point, derived from its plan (pure).

The fence ArduCopter enforces on board (its storage and breach rules:
:mod:`ftlbo_mav.ardupilot.fence`), one per UAV:

- an **inclusion polygon**: the survey area, grown outward by ``corner_cut_m +
  margin_m`` so that a UAV flying the area's edge stays that far inside the polygon;
- an **exclusion circle** around every obstacle, of radius
  ``radius + max(0, clearance - corner_cut_m - margin_m)`` (:func:`exclusion_radius_m`).
  Every planned segment keeps ``radius + clearance`` from the obstacle's axis (a
  feasible plan); ArduCopter's S-curve cuts a corner by at most ``corner_cut_m`` (0.28 m
  measured on ArduCopter 4.5.6 SITL flying the example's uav1 mission,
  ``tests/data/ardupilot-4.5.6/flight.json``; re-measured for all three UAVs on SITL, see
  docs/outputs.md); so the flown path stays at least ``margin_m`` (FENCE_MARGIN) outside
  the circle. With a clearance smaller than ``corner_cut_m + margin_m`` the circle is the
  obstacle itself and the plan says the margin is not met;
- a **maximum altitude** FENCE_ALT_MAX = ``max_altitude + alt_overshoot_m + margin_m``:
  every planned waypoint is inside the band, the flown altitude overshoots it by less
  than ``alt_overshoot_m``;
- the fence parameters: FENCE_ENABLE 1, FENCE_TYPE 5 (alt max + polygon),
  FENCE_ACTION 4 (brake, else land: a copter that strays stops where it is, instead of
  RTL's straight line home through the orchard), FENCE_ALT_MAX, FENCE_MARGIN.

And one **rally point** per UAV (where RTL goes when it is nearer than home): the point
nearest the UAV's goal that is clear of every obstacle (``radius + clearance``), inside
the area by ``corner_cut_m + margin_m``, at least ``rally_separation_m`` from the other
UAVs' homes and rally points and from their return lines to their rally points (the
straight lines RTL flies from each point of their paths that is nearer their rally point
than their home), while its own such lines keep that distance from the other UAVs'
homes and rally points (:func:`rally_points_enu`). Its altitude is the goal's, in whole
metres (AP_Rally keeps an int16 of metres).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from .items import (
    CMD_FENCE_CIRCLE_EXCLUSION,
    CMD_FENCE_POLYGON_VERTEX_INCLUSION,
    CMD_RALLY_POINT,
    FRAME_GLOBAL,
    FRAME_GLOBAL_RELATIVE_ALT,
    MissionItem,
)

if TYPE_CHECKING:
    from ..planning.planner import Plan

ACTION_BRAKE = 4      # FENCE_ACTION: brake, or land if brake fails (AC_Fence.h)
TYPE_ALT_MAX_POLYGON = 1 | 4  # FENCE_TYPE bits: alt max, polygon (incl. circles)


@dataclass(frozen=True)
class FenceSettings:
    """How the fence is sized. ``margin_m``: FENCE_MARGIN (ArduPilot accepts any value
    >= 0; its documentation suggests 1-10 m, its default is 2 m, too wide for 1 m of
    clearance between trees); ``corner_cut_m``: how far the flown path may come inside
    the planned polyline (S-curve corners; 0.28 m measured on SITL); ``alt_overshoot_m``:
    how far above its planned altitude a copter may fly (0.05 m measured);
    ``rally_separation_m``: rally points from other UAVs' return lines; ``grid_m``:
    the rally search's grid step."""

    margin_m: float = 0.5
    corner_cut_m: float = 0.3
    alt_overshoot_m: float = 0.5
    action: int = ACTION_BRAKE
    rally_separation_m: float = 2.0
    grid_m: float = 0.5


@dataclass(frozen=True)
class UavFence:
    """One UAV's fence items (seq from 0), rally items and fence parameters."""

    name: str
    fence: tuple[MissionItem, ...]
    rally: tuple[MissionItem, ...]
    params: Mapping[str, float]
    exclusion_radii_m: tuple[float, ...]
    notes: tuple[str, ...] = field(default=())


def exclusion_radius_m(radius_m: float, *, clearance_m: float,
                       settings: FenceSettings) -> float:
    """The exclusion circle around an obstacle of ``radius_m`` (see the module notes)."""
    return radius_m + max(0.0, clearance_m - settings.corner_cut_m - settings.margin_m)


def fence_params(max_altitude_m: float, settings: FenceSettings) -> dict[str, float]:
    """FENCE_ENABLE, FENCE_TYPE, FENCE_ACTION, FENCE_ALT_MAX, FENCE_MARGIN."""
    alt_max = max_altitude_m + settings.alt_overshoot_m + settings.margin_m
    return {"FENCE_ENABLE": 1.0, "FENCE_TYPE": float(TYPE_ALT_MAX_POLYGON),
            "FENCE_ACTION": float(settings.action), "FENCE_ALT_MAX": round(alt_max, 2),
            "FENCE_MARGIN": settings.margin_m}


def _segment_distance(q: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distances from points ``q`` (..., 2) to segments ``a``-``b`` (..., 2), broadcast."""
    ab = b - a
    denom = np.maximum((ab * ab).sum(-1), 1e-12)
    t = np.clip(((q - a) * ab).sum(-1) / denom, 0.0, 1.0)
    return np.linalg.norm(a + t[..., None] * ab - q, axis=-1)


def _densify(path: np.ndarray, step_m: float) -> np.ndarray:
    """Points along a polyline ``(n, 2)`` at most ``step_m`` apart, ends included."""
    out = [path[:1]]
    for a, b in zip(path[:-1], path[1:]):
        k = max(1, math.ceil(float(np.linalg.norm(b - a)) / step_m))
        out.append(a + (b - a) * (np.arange(1, k + 1) / k)[:, None])
    return np.concatenate(out)


def rally_points_enu(*, paths: np.ndarray, centres: np.ndarray, radii: np.ndarray,
                     clearance_m: float, area_min: np.ndarray, area_max: np.ndarray,
                     settings: FenceSettings) -> list[np.ndarray | None]:
    """One rally point (east, north) per UAV, or None where none fits (module notes).

    Chosen in UAV order, each the candidate nearest its goal that is clear of the
    obstacles, inside the area, ``rally_separation_m`` from the homes and rally points
    of the others, from the others' return lines to their rally points, and whose own
    return lines keep that distance from the others' homes and rally points. A return
    line to a rally point: from each point of the UAV's path nearer to its rally point
    than to its home (RTL flies to the nearer, RALLY_INCL_HOME 1), straight to it.
    ``paths`` (N, n, 3) ENU metres, row 0 each UAV's home; ``centres`` (K, 2), ``radii``
    (K,); ``area_min``/``area_max`` (2,) the area's ENU bounding box."""
    inset = settings.corner_cut_m + settings.margin_m
    sep = settings.rally_separation_m
    xs = np.arange(area_min[0] + inset, area_max[0] - inset + 1e-9, settings.grid_m)
    ys = np.arange(area_min[1] + inset, area_max[1] - inset + 1e-9, settings.grid_m)
    grid = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)
    if len(centres):
        d = np.linalg.norm(grid[:, None, :] - centres[None, :, :2], axis=2)
        grid = grid[np.all(d >= radii[None, :] + clearance_m, axis=1)]
    flat = [_densify(p[:, :2], 1.0) for p in paths]
    homes = paths[:, 0, :2]
    chosen: list[np.ndarray | None] = [None] * len(paths)
    for k in range(len(paths)):
        goal = paths[k, -1, :2]
        cand = grid[np.argsort(np.linalg.norm(grid - goal, axis=1), kind="stable")]
        own = flat[k]
        own_home = np.linalg.norm(own - homes[k], axis=1)  # (P,)
        for chunk in np.array_split(cand, max(1, len(cand) // 512)):
            ok = np.ones(len(chunk), bool)
            # this UAV's lines to the candidate: from the path points nearer to it
            to_cand = np.linalg.norm(own[None] - chunk[:, None], axis=2) < own_home[None]
            for j in range(len(paths)):
                if j == k:
                    continue
                places = [homes[j]] + ([chosen[j]] if chosen[j] is not None else [])
                for q in places:
                    ok &= np.linalg.norm(chunk - q, axis=1) >= sep
                    d = _segment_distance(q, own[None], chunk[:, None])  # (C, P)
                    ok &= np.where(to_cand, d, np.inf).min(axis=1) >= sep
                if chosen[j] is not None:  # the other's lines to its rally point
                    pts = flat[j]
                    use = (np.linalg.norm(pts - chosen[j], axis=1)
                           < np.linalg.norm(pts - homes[j], axis=1))
                    if use.any():
                        d = _segment_distance(chunk[:, None], pts[use][None], chosen[j])
                        ok &= d.min(axis=1) >= sep
            if ok.any():
                chosen[k] = chunk[int(np.argmax(ok))]
                break
    return chosen


def plan_fences(plan: Plan, *, settings: FenceSettings = FenceSettings()) -> list[UavFence]:
    """Every UAV's fence, rally point and fence parameters for ``plan`` (module notes)."""
    s = plan.scenario
    frame = s.frame
    centres, radii = s.obstacles_enu()
    centres = np.asarray(centres, float).reshape(-1, 2)  # (K, 2), also for K = 0
    centres = np.column_stack([centres, np.zeros(len(centres))])
    radii = np.asarray(radii, float).reshape(-1)
    corners = frame.to_enu(lat_deg=[s.corner_a.lat_deg, s.corner_b.lat_deg],
                           lon_deg=[s.corner_a.lon_deg, s.corner_b.lon_deg]).reshape(-1, 3)
    lo, hi = corners[:, :2].min(axis=0), corners[:, :2].max(axis=0)
    grow = settings.corner_cut_m + settings.margin_m
    ring = np.array([[lo[0] - grow, lo[1] - grow], [hi[0] + grow, lo[1] - grow],
                     [hi[0] + grow, hi[1] + grow], [lo[0] - grow, hi[1] + grow]])
    ring_lla = plan.lla(np.column_stack([ring, np.zeros(len(ring))]))
    centre_lla = plan.lla(centres) if len(centres) else np.zeros((0, 3))
    # the planner kept the clearance plus the scenario's corner allowance
    kept = s.clearance_m + s.mission.corner_allowance_m
    excl = tuple(round(exclusion_radius_m(float(r), clearance_m=kept,
                                          settings=settings), 2) for r in radii)
    notes: list[str] = []
    if kept < settings.corner_cut_m + settings.margin_m and len(radii):
        notes.append(f"clearance {kept:g} m is less than the corner cut "
                     f"{settings.corner_cut_m:g} m + FENCE_MARGIN {settings.margin_m:g} m: "
                     "the exclusion circles are the obstacles themselves and a flown path "
                     "may come within FENCE_MARGIN of them")
    fence: list[MissionItem] = [
        MissionItem(seq=i, command=CMD_FENCE_POLYGON_VERTEX_INCLUSION, frame=FRAME_GLOBAL,
                    lat_deg=float(lat), lon_deg=float(lon), param1=float(len(ring)))
        for i, (lat, lon, _alt) in enumerate(ring_lla)]
    fence += [MissionItem(seq=len(ring) + i, command=CMD_FENCE_CIRCLE_EXCLUSION,
                          frame=FRAME_GLOBAL, lat_deg=float(lat), lon_deg=float(lon),
                          param1=r)
              for i, ((lat, lon, _alt), r) in enumerate(zip(centre_lla, excl))]
    paths = np.asarray(plan.uav_paths, float)
    rally = rally_points_enu(paths=paths, centres=centres[:, :2], radii=radii,
                             clearance_m=s.clearance_m, area_min=lo, area_max=hi,
                             settings=settings)
    params = fence_params(s.max_altitude_m, settings)
    out = []
    for n, (path, point) in enumerate(zip(paths, rally)):
        own_notes = list(notes)
        items: tuple[MissionItem, ...] = ()
        if point is None:
            own_notes.append(f"no rally point: no place in the area is clear of the "
                             f"obstacles and {settings.rally_separation_m:g} m from the other "
                             "UAVs' return lines; RTL goes home")
        else:
            lat, lon, _ = plan.lla(np.array([[point[0], point[1], 0.0]]))[0]
            alt = float(math.floor(path[-1, 2]))
            items = (MissionItem(seq=0, command=CMD_RALLY_POINT, frame=FRAME_GLOBAL_RELATIVE_ALT,
                                 lat_deg=float(lat), lon_deg=float(lon), alt_m=alt),)
        out.append(UavFence(f"uav{n + 1}", tuple(fence), items, dict(params), excl,
                            tuple(own_notes)))
    return out
