"""Local east-north-up frame of one scenario.

One :class:`LocalFrame` per scenario owns one pyproj transformer: a pipeline from
geodetic WGS84 coordinates to geocentric Cartesian and then to a topocentric (ENU) frame
whose origin is the area's south-west corner on the ellipsoid.

East and north are the topocentric ones. Up is the altitude above home, as an autopilot
measures it along the local vertical (MAVLink ``GLOBAL_RELATIVE_ALT``), not the
topocentric z, which drops with the Earth's curvature by d^2 / 2R (0.8 mm at 100 m from
the origin): a waypoint planned at 4 m is written as 4 m.

pyproj takes (lon, lat); every ftlbo-mav signature takes ``lat_deg``/``lon_deg`` by keyword.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from pyproj import Transformer

_EARTH_RADIUS_M = 6378137.0


def _pipeline(*, lat_deg: float, lon_deg: float) -> str:
    return (
        "+proj=pipeline "
        "+step +proj=cart +ellps=WGS84 "
        f"+step +proj=topocentric +ellps=WGS84 +lat_0={lat_deg!r} +lon_0={lon_deg!r} +h_0=0"
    )


@dataclass(frozen=True)
class LocalFrame:
    """ENU frame with its origin at ``(origin_lat_deg, origin_lon_deg)`` and altitude 0."""

    origin_lat_deg: float
    origin_lon_deg: float
    _transformer: Transformer = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        pipeline = _pipeline(lat_deg=self.origin_lat_deg, lon_deg=self.origin_lon_deg)
        object.__setattr__(self, "_transformer", Transformer.from_pipeline(pipeline))

    def to_enu(self, *, lat_deg, lon_deg, alt_m=0.0) -> np.ndarray:
        """Geodetic degrees and metres above home -> ENU metres, shape ``(..., 3)``."""
        if isinstance(lat_deg, float) and isinstance(lon_deg, float):
            return self._point_enu(lat_deg, lon_deg, float(alt_m))
        if (isinstance(lat_deg, list) and len(lat_deg) <= 16 and isinstance(lon_deg, list)
                and isinstance(alt_m, list) and all(
                    type(x) is float for x in (*lat_deg, *lon_deg))):  # a few reports
            return np.array([(*self._point_en(la, lo), float(al))
                             for la, lo, al in zip(lat_deg, lon_deg, alt_m, strict=True)])
        lat, lon, alt = np.broadcast_arrays(
            np.asarray(lat_deg, float), np.asarray(lon_deg, float), np.asarray(alt_m, float)
        )
        e, n, _ = self._transform(lon, lat, np.zeros_like(lat))
        return np.stack([e, n, alt.ravel()], axis=-1).reshape(*lat.shape, 3)

    def _point_enu(self, lat: float, lon: float, alt: float) -> np.ndarray:
        e, n = self._point_en(lat, lon)
        return np.array([e, n, alt])

    def _point_en(self, lat: float, lon: float) -> tuple[float, float]:
        """One point's east and north, remembered: a flight asks for the same reported
        positions again and again (every vehicle's last report, at each look of the
        watch)."""
        memo = self.__dict__.setdefault("_memo", {})
        en = memo.get((lat, lon))
        if en is None:
            if len(memo) >= 1024:
                memo.clear()
            e, n, _ = self._transformer.transform(lon, lat, 0.0)
            en = memo[(lat, lon)] = (e, n)
        return en

    def to_lla(self, enu) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """ENU metres, shape ``(..., 3)`` -> ``(lat_deg, lon_deg, alt_m)`` arrays."""
        enu = np.asarray(enu, float)
        shape = enu.shape[:-1]
        e, n = enu[..., 0], enu[..., 1]
        # The topocentric z of the ground point under (e, n): the curvature drop.
        ground = -(e * e + n * n) / (2.0 * _EARTH_RADIUS_M)
        lon, lat, _ = self._transform(e, n, ground, direction="INVERSE")
        return lat.reshape(shape), lon.reshape(shape), enu[..., 2].reshape(shape).copy()

    def _transform(self, x, y, z, **kwargs) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """pyproj on flat arrays; a single point goes through its scalar path."""
        x, y, z = (np.ravel(v) for v in (x, y, z))
        if x.size == 1:
            out = self._transformer.transform(float(x[0]), float(y[0]), float(z[0]), **kwargs)
            return tuple(np.array([v], float) for v in out)
        return self._transformer.transform(x, y, z, **kwargs)


def segment_distance(q: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distances from points ``q`` (..., 2) to segments ``a``-``b`` (..., 2), broadcast."""
    ab = b - a
    denom = np.maximum((ab * ab).sum(-1), 1e-12)
    t = np.clip(((q - a) * ab).sum(-1) / denom, 0.0, 1.0)
    return np.linalg.norm(a + t[..., None] * ab - q, axis=-1)
