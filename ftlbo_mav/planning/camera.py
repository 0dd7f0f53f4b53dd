"""A survey camera on the ground: footprint, ground sample distance, lane spacing from the
side overlap, trigger distance from the front overlap, photo positions along a path.

Pure arithmetic on plain numbers and arrays (metres, the ground flat at home's height).
The camera is a pinhole pointing straight down, its image's long side across the track
in landscape, as QGroundControl's survey takes it (its CameraCalc: the footprint is the
sensor size times altitude over focal length; the ground sample distance the footprint
over the image's pixels, across the track).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

POSITION_ERROR_M = 1.0
"""How far a UAV may be off its place across the lane (GPS and track keeping): a
footprint narrower than this across could leave a gap however the lanes are laid."""


@dataclass(frozen=True)
class Camera:
    """A ``[camera]`` table (QGroundControl's camera definition fields): sensor size in
    millimetres, focal length in millimetres, image size in pixels, front and side
    overlap (fractions in [0, 1)), ``landscape`` (the image's long side across the
    track), and ``gsd_cm`` when it chose the survey's altitude."""

    sensor_width_mm: float
    sensor_height_mm: float
    focal_length_mm: float
    image_width_px: int
    image_height_px: int
    front_overlap: float
    side_overlap: float
    landscape: bool = True
    gsd_cm: float | None = None

    def _sides(self) -> tuple[float, float, int]:
        """Sensor across and along the track (mm), pixels across: the sensor's width
        across in landscape, its height in portrait (QGroundControl's CameraCalc)."""
        if self.landscape:
            return self.sensor_width_mm, self.sensor_height_mm, self.image_width_px
        return self.sensor_height_mm, self.sensor_width_mm, self.image_height_px

    def footprint(self, alt_m) -> tuple[np.ndarray, np.ndarray]:
        """Ground footprint at ``alt_m`` (metres above the ground, scalar or array):
        ``(across, along)`` metres."""
        across_mm, along_mm, _ = self._sides()
        alt = np.asarray(alt_m, float)
        return alt * across_mm / self.focal_length_mm, alt * along_mm / self.focal_length_mm

    def gsd(self, alt_m) -> np.ndarray:
        """Ground sample distance at ``alt_m``: centimetres a pixel covers (across)."""
        across_mm, _, px = self._sides()
        return np.asarray(alt_m, float) * across_mm * 100.0 / (self.focal_length_mm * px)

    def altitude_for_gsd(self, gsd_cm: float) -> float:
        """The altitude above the ground at which a pixel covers ``gsd_cm``."""
        across_mm, _, px = self._sides()
        return gsd_cm * self.focal_length_mm * px / (across_mm * 100.0)


def widest_spacing(across: np.ndarray, widths: np.ndarray, overlap: float) -> float:
    """The widest lane spacing at which the strips of neighbouring lanes still overlap by
    ``overlap`` (of the narrower of the two strips).

    ``across (N,)``: each UAV's offset across the lanes; ``widths (N,)``: its footprint
    across. Lane ``k + 1``'s outermost UAV on one side (the smallest ``across``) must
    overlap lane ``k``'s outermost on the other (the largest)."""
    a, b = int(np.argmax(across)), int(np.argmin(across))
    reach = (widths[a] + widths[b]) / 2 - overlap * min(widths[a], widths[b])
    return float(across[a] - across[b] + reach)


def formation_gaps(across: np.ndarray, widths: np.ndarray, overlap: float) -> list[tuple]:
    """Neighbouring UAVs (across the lanes) whose strips overlap less than ``overlap``:
    ``(i, j, gap_m, overlap_fraction)`` each, UAV indices 0-based."""
    order = np.argsort(across, kind="stable")
    out = []
    for i, j in zip(order[:-1], order[1:]):
        gap = float(across[j] - across[i])
        narrow = float(min(widths[i], widths[j]))
        shared = (widths[i] + widths[j]) / 2 - gap
        if shared < overlap * narrow - 1e-9:
            out.append((int(i), int(j), gap, float(shared / narrow)))
    return out


def trigger_distance(along_m: float, overlap: float) -> float:
    """Distance between photos for ``overlap`` of a footprint ``along_m`` long."""
    return float(along_m * (1.0 - overlap))
