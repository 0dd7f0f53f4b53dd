"""Local east-north-up frame of one scenario.

One :class:`LocalFrame` per scenario owns one pyproj transformer: a pipeline from
geodetic WGS84 coordinates to geocentric Cartesian and then to a topocentric (ENU) frame
whose origin is the area's south-west corner at home altitude. Altitudes in ftlbo-mav are
metres above home (MAVLink ``GLOBAL_RELATIVE_ALT``), used as the ellipsoidal height of a
home placed on the ellipsoid; over a survey area of a few hundred metres this is exact to
well below a millimetre for the round trip and a few millimetres for the curvature drop.

pyproj takes (lon, lat); every ftlbo-mav signature takes ``lat_deg``/``lon_deg`` by keyword.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from pyproj import Transformer


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
        lat, lon, alt = np.broadcast_arrays(
            np.asarray(lat_deg, float), np.asarray(lon_deg, float), np.asarray(alt_m, float)
        )
        e, n, u = self._transformer.transform(lon, lat, alt)
        return np.stack([np.asarray(e, float), np.asarray(n, float), np.asarray(u, float)], -1)

    def to_lla(self, enu) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """ENU metres, shape ``(..., 3)`` -> ``(lat_deg, lon_deg, alt_m)`` arrays."""
        enu = np.asarray(enu, float)
        lon, lat, alt = self._transformer.transform(
            enu[..., 0], enu[..., 1], enu[..., 2], direction="INVERSE"
        )
        return np.asarray(lat, float), np.asarray(lon, float), np.asarray(alt, float)
