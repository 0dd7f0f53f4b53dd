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
nearest the UAV's goal that is clear of every obstacle (``radius + clearance`` plus the
navigation budget, so that the true position keeps the clearance), inside the area by
``corner_cut_m + margin_m``, at least ``rally_separation_m`` plus two copters' combined
navigation error (:func:`~ftlbo_mav.gnss.pair_error_m`) from the other UAVs' homes and
rally points and from their return lines to their rally points (the straight lines RTL
flies from each point of their paths that is nearer their rally point than their home),
while its own such lines keep that distance from the other UAVs' homes and rally points
(:func:`~.rally.search_rally_points`). Its altitude is the goal's, in whole metres
(AP_Rally keeps an int16 of metres).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from ..gnss import pair_error_m
from .items import (
    CMD_FENCE_CIRCLE_EXCLUSION,
    CMD_FENCE_POLYGON_VERTEX_INCLUSION,
    CMD_RALLY_POINT,
    FRAME_GLOBAL,
    FRAME_GLOBAL_RELATIVE_ALT,
    MissionItem,
)
from .rally import WORK_PER_UAV, search_rally_points

if TYPE_CHECKING:
    from ..planning.plans import Plan

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


def _predicted_cut(plan: Plan, lo: np.ndarray, hi: np.ndarray,
                   settings: FenceSettings) -> float:
    """How far outside the area the flown path may go: the predicted paths' furthest
    excursion beyond the area's box (0 for a feasible plan), else ``corner_cut_m``."""
    if plan.prediction is None:
        return settings.corner_cut_m
    xy = plan.prediction.positions[..., :2]
    return float(max(0.0, (lo - xy).max(), (xy - hi).max()))


def _flown_clearance(plan: Plan, k: int, kept: float) -> float:
    """The clearance the flown path keeps from obstacle ``k``: the predicted one (at
    most ``kept``; a plan keeps more only by chance), else ``kept``."""
    if plan.prediction is None or k >= len(plan.prediction.obstacle_clearance):
        return kept
    return min(kept, float(plan.prediction.obstacle_clearance[k]))


RALLY_SEARCH_STOPPED = "no rally point, search stopped"
"""How a UAV's fence note begins when its rally search reached its bound
(:data:`~.rally.WORK_PER_UAV`): :func:`rally_search_stopped` finds them."""


def rally_search_stopped(doc: Mapping) -> str | None:
    """One line naming the UAVs of a ``plan.json`` document ``doc`` whose rally search
    reached its bound (their ``fence_notes``), or None: what ``plan`` says on stderr."""
    uavs = doc.get("uavs", [])
    names = [u["name"] for u in uavs
             if any(n.startswith(RALLY_SEARCH_STOPPED) for n in u.get("fence_notes", ()))]
    if not names:
        return None
    shown = ", ".join(names[:12]) + (f" and {len(names) - 12} more" if len(names) > 12 else "")
    return (f"{len(names)} of {len(uavs)} UAVs have no rally point ({shown}): the rally "
            f"search stopped at its bound of {WORK_PER_UAV:,} tests per UAV before finding "
            "a place clear of the others' homes, rally points and return lines; their RTL "
            "goes home (plan.json fence_notes)")


def plan_fences(plan: Plan, *, settings: FenceSettings = FenceSettings()) -> list[UavFence]:
    """Every UAV's fence, rally point and fence parameters for ``plan`` (module notes)."""
    s = plan.scenario
    frame = s.frame
    centres, radii = s.obstacles_enu()
    centres = np.asarray(centres, float).reshape(-1, 2)  # (K, 2), K = 0 included
    centres = np.column_stack([centres, np.zeros(len(centres))])
    radii = np.asarray(radii, float).reshape(-1)
    corners = frame.to_enu(lat_deg=[s.corner_a.lat_deg, s.corner_b.lat_deg],
                           lon_deg=[s.corner_a.lon_deg, s.corner_b.lon_deg]).reshape(-1, 3)
    lo, hi = corners[:, :2].min(axis=0), corners[:, :2].max(axis=0)
    cut = _predicted_cut(plan, lo, hi, settings)
    grow = cut + settings.margin_m
    ring = np.array([[lo[0] - grow, lo[1] - grow], [hi[0] + grow, lo[1] - grow],
                     [hi[0] + grow, hi[1] + grow], [lo[0] - grow, hi[1] + grow]])
    ring_lla = plan.lla(np.column_stack([ring, np.zeros(len(ring))]))
    centre_lla = plan.lla(centres) if len(centres) else np.zeros((0, 3))
    # the planner kept the clearance plus the navigation budget and the corner allowance
    # on the estimated position (which the fence watches): on the predicted flown path
    # when there is one (the circles then need no corner cut)
    kept = s.kept_clearance_m
    flown = replace(settings, corner_cut_m=0.0) if plan.prediction is not None else settings
    excl = tuple(round(exclusion_radius_m(float(r), clearance_m=_flown_clearance(plan, k, kept),
                                          settings=flown), 2) for k, r in enumerate(radii))
    notes: list[str] = []
    if kept < flown.corner_cut_m + settings.margin_m and len(radii):
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
    # where the copters truly are: the obstacles' clearance plus the navigation budget,
    # the others' homes and return lines plus two copters' combined error
    rally_settings = replace(settings, rally_separation_m=settings.rally_separation_m
                             + pair_error_m(s.navigation.horizontal_m))
    search = search_rally_points(paths=paths, centres=centres[:, :2], radii=radii,
                                 clearance_m=s.true_clearance_m, area_min=lo, area_max=hi,
                                 settings=rally_settings)
    rally = search.points
    params = fence_params(s.max_altitude_m, settings)
    sep_m = rally_settings.rally_separation_m
    out = []
    for n, (path, point) in enumerate(zip(paths, rally)):
        own_notes = list(notes)
        items: tuple[MissionItem, ...] = ()
        if point is None and search.stopped[n]:
            own_notes.append(f"{RALLY_SEARCH_STOPPED}: its search reached its bound "
                             f"({WORK_PER_UAV:,} tests) before a place {sep_m:.2f} m from "
                             "the other UAVs' homes, rally points and return lines; RTL "
                             "goes home")
        elif point is None:
            own_notes.append(f"no rally point: no place in the area is clear of the "
                             f"obstacles and {sep_m:.2f} m from the other UAVs' return "
                             "lines; RTL goes home")
        else:
            lat, lon, _ = plan.lla(np.array([[point[0], point[1], 0.0]]))[0]
            alt = float(math.floor(path[-1, 2]))
            items = (MissionItem(seq=0, command=CMD_RALLY_POINT, frame=FRAME_GLOBAL_RELATIVE_ALT,
                                 lat_deg=float(lat), lon_deg=float(lon), alt_m=alt),)
        out.append(UavFence(f"uav{n + 1}", tuple(fence), items, dict(params), excl,
                            tuple(own_notes)))
    return out
