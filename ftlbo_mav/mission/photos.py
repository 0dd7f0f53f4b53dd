"""Where a survey's missions take their photos, and what the photos cover.

Read from the mission items alone (what goes to the vehicles): the copter's path through
them is predicted as ArduCopter flies it (:mod:`ftlbo_mav.ardupilot.flight_path`); each
DO_SET_CAM_TRIGG_DIST with a distance turns distance triggering on when the waypoint
before it is reached, one with distance 0 turns it off; in between the photos are where
ArduCopter's AP_Camera takes them on that path
(:func:`ftlbo_mav.ardupilot.camera.track_photos`). SITL's photos are within half a metre
of these (``tests/ardupilot/test_camera.py``); on the planned straight lines they were up
to 1.1 m off, most in the corners.
Each photo's footprint is the camera's (:class:`~ftlbo_mav.planning.camera.Camera`) at
the photo's altitude above home, its long side across the lane in landscape. Pure.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..ardupilot.camera import track_photos
from ..ardupilot.flight_path import DEFAULT_NAV, fly_path
from ..ardupilot.navigation import Navigation
from ..geo import LocalFrame
from ..planning.camera import Camera
from ..planning.survey import directions
from .items import CMD_DO_SET_CAM_TRIGG_DIST, CMD_NAV_WAYPOINT, MissionItem, mission_settings


@dataclass(frozen=True)
class UavPhotos:
    """One UAV's photos: ``positions (K, 3)`` metres ENU (altitude above home) and
    ``corners (K, 4, 2)`` metres east/north of each footprint, in its name's order."""

    name: str
    positions: np.ndarray
    corners: np.ndarray

    @property
    def count(self) -> int:
        return len(self.positions)


def camera_switches(items: Sequence[MissionItem], frame: LocalFrame
                    ) -> tuple[np.ndarray, np.ndarray, float | None, list]:
    """What a mission asks of the copter and its camera, as :func:`mission_photos` flies
    it: ``(points (P, 3) metres ENU, holds (P,) seconds, speed, switches)``, the points
    every NAV_WAYPOINT after home (the first where the copter hovers when AUTO starts, as
    ``fly`` starts a plan's legs), the speed of its first DO_CHANGE_SPEED
    (:func:`~.items.mission_settings`), and per DO_SET_CAM_TRIGG_DIST ``(k, distance,
    at_once)``: it runs once point ``k`` is reached (AP_Mission runs DO commands when the
    navigation command before them is done; -1 before the first)."""
    points, holds, switches = [], [], []
    for item in items[1:]:  # item 0 is home
        if item.command == CMD_NAV_WAYPOINT:
            points.append(frame.to_enu(lat_deg=item.lat_deg, lon_deg=item.lon_deg,
                                       alt_m=item.alt_m))
            holds.append(float(item.param1))
        elif item.command == CMD_DO_SET_CAM_TRIGG_DIST:
            switches.append((len(points) - 1, float(item.param1), item.param3 == 1))
    _end, speed = mission_settings(items)
    return np.array(points).reshape(-1, 3), np.array(holds), speed, switches


def mission_photos(name: str, items: Sequence[MissionItem], *, frame: LocalFrame,
                   camera: Camera, heading_deg: float, nav: Navigation = DEFAULT_NAV
                   ) -> UavPhotos:
    """The photos ``items`` take and their footprints: the copter's path through the
    mission's waypoints predicted as ArduCopter flies it (:func:`.fly_path`, with ``nav``:
    the plan's ``[vehicle]``), the trigger switched where each DO_SET_CAM_TRIGG_DIST runs
    (when the waypoint before it is reached), the photos where AP_Camera takes them on that
    path (:func:`.track_photos`): along the lanes behind its straight line by the copter's lag,
    in the rounded corners where the lanes end."""
    points, holds, speed, switches = camera_switches(items, frame)
    if not any(d > 0 for _, d, _ in switches) or not len(points):
        pos = np.zeros((0, 3))
    elif len(points) == 1:
        pos = points[:1] if any(d > 0 and once for _, d, once in switches) else np.zeros((0, 3))
    else:
        flown = fly_path(points, nav=nav, speed_m_s=speed, holds_s=holds)
        at = [(float(flown.reached[max(k, 0)]), d, once) for k, d, once in switches]
        pos = track_photos(flown.times, flown.positions, at)
    along, across = directions(heading_deg)
    width, length = camera.footprint(np.maximum(pos[:, 2], 0.0))
    signs = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], float)  # (across, along) /2
    corners = (pos[:, None, :2]
               + signs[None, :, 0:1] * (width[:, None, None] / 2) * across
               + signs[None, :, 1:2] * (length[:, None, None] / 2) * along)
    return UavPhotos(name=name, positions=pos, corners=corners.reshape(-1, 4, 2))


def coverage(photos: Sequence[UavPhotos], *, lower: np.ndarray, upper: np.ndarray,
             step_m: float = 0.5) -> float:
    """The fraction of the rectangle ``lower..upper`` (metres east/north) inside at least
    one footprint, on a grid ``step_m`` apart."""
    xs = np.arange(lower[0] + step_m / 2, upper[0], step_m)
    ys = np.arange(lower[1] + step_m / 2, upper[1], step_m)
    grid = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)
    covered = np.zeros(len(grid), bool)
    for uav in photos:
        for c in uav.corners:
            u, v = c[1] - c[0], c[3] - c[0]
            rel = grid - c[0]
            a, b = rel @ u / (u @ u), rel @ v / (v @ v)
            covered |= (a >= 0) & (a <= 1) & (b >= 0) & (b <= 1)
    return float(covered.mean()) if len(grid) else 0.0


def plan_photos(plan, missions: Sequence) -> list[UavPhotos]:
    """Each UAV's photos from its mission (``missions``: the plan's
    :class:`~.items.UavMission` list); empty without a ``[camera]``."""
    survey = plan.scenario.survey
    if survey is None or survey.camera is None:
        return []
    return [mission_photos(m.name, m.items, frame=plan.scenario.frame, camera=survey.camera,
                           heading_deg=survey.heading_deg, nav=plan.scenario.vehicle)
            for m in missions]


def camera_document(plan, photos: Sequence[UavPhotos]) -> dict | None:
    """plan.json's ``survey.camera``: the table as read, then per UAV its altitude,
    footprint (across x along the lanes, metres), ground sample distance (cm/px) and the
    photos its mission takes."""
    survey = plan.scenario.survey
    if survey is None or survey.camera is None:
        return None
    cam = survey.camera
    alts = survey.alt_m + plan.scenario.offsets_m[:, 2]
    width, length = cam.footprint(np.maximum(alts, 0.0))
    gsd = cam.gsd(np.maximum(alts, 0.0))
    return {
        "sensor_width_mm": cam.sensor_width_mm, "sensor_height_mm": cam.sensor_height_mm,
        "focal_length_mm": cam.focal_length_mm, "image_width_px": cam.image_width_px,
        "image_height_px": cam.image_height_px, "front_overlap": cam.front_overlap,
        "side_overlap": cam.side_overlap, "landscape": cam.landscape, "gsd_cm": cam.gsd_cm,
        "trigger_distance": round(float(survey.trigger_distance_m), 4),
        "uavs": [{"name": p.name, "alt": round(float(a), 4),
                  "footprint": [round(float(w), 4), round(float(h), 4)],
                  "gsd_cm": round(float(g), 4), "photos": p.count}
                 for p, a, w, h, g in zip(photos, alts, width, length, gsd)],
    }
