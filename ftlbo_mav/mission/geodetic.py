"""One geodetic view of a plan: what every writer needs in degrees, converted once.

The planner works in the scenario's local ENU frame; the files a user opens (``.waypoints``,
``.plan``, ``plan.json``, GeoJSON, KML) speak latitude and longitude. :func:`geodetic_view`
converts a :class:`~ftlbo_mav.planning.plans.Plan` once, and the writers take the view.
Altitudes are metres above home (MAVLink GLOBAL_RELATIVE_ALT), as in the missions.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from ..planning.plans import Plan

CIRCLE_VERTICES = 72


@dataclass(frozen=True)
class GeodeticPlan:
    """A plan in degrees. Rows are ``(lat_deg, lon_deg, alt_m above home)``.

    ``centroid``: ``(n, 3)``; ``uav_paths``: one ``(n, 3)`` per UAV, whose first row is
    the UAV's home (:attr:`homes`); ``obstacle_rings``: per obstacle a closed ground ring
    ``(CIRCLE_VERTICES + 1, 3)`` (last row == first); ``area_ring``: the area's lat/lon
    rectangle ``(lat_deg, lon_deg)``, counter-clockwise from the south-west corner, closed.
    """

    centroid: np.ndarray
    uav_paths: tuple[np.ndarray, ...]
    obstacle_rings: tuple[np.ndarray, ...]
    area_ring: tuple[tuple[float, float], ...]

    @property
    def homes(self) -> tuple[tuple[float, float, float], ...]:
        """Each UAV's start ``(lat_deg, lon_deg, alt_m)``: where its mission's home is."""
        return tuple(tuple(float(v) for v in path[0]) for path in self.uav_paths)


def circle_ring_enu(centre, radius_m: float, *, vertices: int = CIRCLE_VERTICES) -> np.ndarray:
    """A closed counter-clockwise ring around ``centre`` (2,), shape ``(vertices+1, 2)`` metres."""
    angle = np.linspace(0.0, 2.0 * np.pi, vertices + 1)
    ring = np.asarray(centre, float)[None, :2] + radius_m * np.stack(
        [np.cos(angle), np.sin(angle)], axis=1
    )
    ring[-1] = ring[0]
    return ring


def _ring_lla(plan: Plan, ring_enu: np.ndarray) -> np.ndarray:
    """ENU ring ``(n, 2)`` on the ground -> ``(n, 3)`` lat, lon, alt rows, closed exactly."""
    enu = np.column_stack([ring_enu, np.zeros(len(ring_enu))])
    lla = plan.lla(enu)
    lla[-1] = lla[0]
    return lla


def _area_ring(plan: Plan) -> tuple[tuple[float, float], ...]:
    s = plan.scenario
    lat = sorted([s.corner_a.lat_deg, s.corner_b.lat_deg])
    lon = sorted([s.corner_a.lon_deg, s.corner_b.lon_deg])
    corners = [(lat[0], lon[0]), (lat[0], lon[1]), (lat[1], lon[1]), (lat[1], lon[0])]
    return tuple(corners + corners[:1])


def geodetic_view(plan: Plan) -> GeodeticPlan:
    """Convert ``plan`` to degrees once (the only place the writers reach ``Plan.lla``)."""
    centres, radii = plan.scenario.obstacles_enu()
    return GeodeticPlan(
        centroid=plan.lla(plan.centroid),
        uav_paths=tuple(plan.lla(path) for path in plan.uav_paths),
        obstacle_rings=tuple(
            _ring_lla(plan, circle_ring_enu(c, r)) for c, r in zip(centres, radii)
        ),
        area_ring=_area_ring(plan),
    )
