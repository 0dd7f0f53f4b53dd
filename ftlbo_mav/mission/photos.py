"""Where a survey's missions take their photos, and what the photos cover.

Read from the mission items alone (what goes to the vehicles): each
DO_SET_CAM_TRIGG_DIST with a distance turns distance triggering on where the waypoint
before it was reached, one with distance 0 turns it off; in between the photos are where
ArduCopter's AP_Camera takes them (:func:`ftlbo_mav.ardupilot.camera.photo_positions`).
Each photo's footprint is the camera's (:class:`~ftlbo_mav.planning.camera.Camera`) at
the photo's altitude above home, its long side across the lane in landscape. Pure.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..ardupilot.camera import photo_positions
from ..geo import LocalFrame
from ..planning.camera import Camera
from ..planning.survey import directions
from .items import CMD_DO_SET_CAM_TRIGG_DIST, CMD_NAV_TAKEOFF, CMD_NAV_WAYPOINT, MissionItem


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


def trigger_runs(items: Sequence[MissionItem], frame: LocalFrame) -> list[tuple[np.ndarray,
                                                                                 float, bool]]:
    """Each stretch flown with distance triggering on: ``(path (P, 3) metres ENU,
    distance, at_once)``, from the waypoint after which it was turned on to the one
    after which it was turned off (or the last waypoint)."""
    runs, here, current = [], None, None
    for item in items[1:]:  # item 0 is home
        if item.command == CMD_NAV_TAKEOFF and here is None:
            home = items[0]
            here = frame.to_enu(lat_deg=home.lat_deg, lon_deg=home.lon_deg, alt_m=item.alt_m)
        elif item.command == CMD_NAV_WAYPOINT:
            here = frame.to_enu(lat_deg=item.lat_deg, lon_deg=item.lon_deg, alt_m=item.alt_m)
            if current is not None:
                current[0].append(here)
        elif item.command == CMD_DO_SET_CAM_TRIGG_DIST:
            if current is not None:
                runs.append((np.array(current[0]), current[1], current[2]))
                current = None
            if item.param1 > 0 and here is not None:
                current = ([here], float(item.param1), item.param3 == 1)
    if current is not None:
        runs.append((np.array(current[0]), current[1], current[2]))
    return runs


def mission_photos(name: str, items: Sequence[MissionItem], *, frame: LocalFrame,
                   camera: Camera, heading_deg: float) -> UavPhotos:
    """The photos ``items`` take (see the module) and their footprints."""
    along, across = directions(heading_deg)
    positions = []
    for path, distance, at_once in trigger_runs(items, frame):
        flat = photo_positions(path[:, :2], distance)
        if not at_once:
            flat = flat[1:]
        if not len(flat):
            continue
        positions.append(np.column_stack([flat, _altitude_on(path, flat)]))
    pos = np.concatenate(positions) if positions else np.zeros((0, 3))
    width, length = camera.footprint(np.maximum(pos[:, 2], 0.0))
    signs = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], float)  # (across, along) /2
    corners = (pos[:, None, :2]
               + signs[None, :, 0:1] * (width[:, None, None] / 2) * across
               + signs[None, :, 1:2] * (length[:, None, None] / 2) * along)
    return UavPhotos(name=name, positions=pos, corners=corners.reshape(-1, 4, 2))


def _altitude_on(path: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The altitude of ``path (P, 3)`` at each of ``points (K, 2)`` (which lie on it):
    that of the nearest point of its segments."""
    if len(path) == 1:
        return np.full(len(points), path[0, 2])
    a, b = path[:-1], path[1:]
    d = b[:, :2] - a[:, :2]
    rel = points[:, None, :] - a[None, :, :2]
    t = np.clip((rel * d).sum(-1) / np.maximum((d * d).sum(-1), 1e-18), 0.0, 1.0)
    gap = np.hypot(*(rel - t[..., None] * d).transpose(2, 0, 1))
    k = np.argmin(gap, axis=1)
    tk = t[np.arange(len(points)), k]
    return a[k, 2] + tk * (b[k, 2] - a[k, 2])


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
                           heading_deg=survey.heading_deg) for m in missions]


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
