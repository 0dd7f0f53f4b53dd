"""Obstacles read from GeoJSON, beside the scenario reader (input, not output).

A GeoJSON FeatureCollection of obstacles: a ``Point`` needs a ``radius`` property in
metres; a ``Polygon`` becomes its smallest enclosing circle, computed in the scenario's
local ENU frame. Errors name the file, the feature index and the problem. Writing a plan
as GeoJSON is :mod:`ftlbo_mav.mission.gis`.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .errors import ScenarioError
from .inputs import read_user_text

if TYPE_CHECKING:
    from .geo import LocalFrame


@dataclass(frozen=True)
class Cylinder:
    """A vertical cylinder obstacle (a tree, a pole), unbounded in height.

    ``origin`` says where it was read, for error messages: ``obstacles[2]`` (a table of
    the scenario file) or ``gis/trees.geojson features[3]`` (a feature of an obstacles
    file); empty for one built in code. It takes no part in comparisons."""

    lat_deg: float
    lon_deg: float
    radius_m: float
    name: str = ""
    origin: str = field(default="", compare=False)

    def describe(self, index: int) -> str:
        """How a message names this obstacle, the scenario's ``index``-th:
        ``gis/trees.geojson features[3] ('mango')``, or ``obstacles[index]`` without an
        origin."""
        where = self.origin or f"obstacles[{index}]"
        if self.name and not where.endswith(self.name):  # not the default label again
            return f"{where} ({self.name!r})"
        return where


def smallest_enclosing_circle(
    points, *, rng: np.random.Generator | None = None
) -> tuple[np.ndarray, float]:
    """Smallest circle containing ``points`` ``(n, 2)`` metres: ``(centre (2,), radius)``.

    Welzl's algorithm in its iterative form: expected linear time for points in random
    order, which ``rng`` (default: seeded, so the result is reproducible) provides.
    """
    pts = np.unique(np.asarray(points, float).reshape(-1, 2), axis=0)
    if len(pts) == 0:
        raise ValueError("no points")
    rng = rng if rng is not None else np.random.default_rng(0)
    pts = pts[rng.permutation(len(pts))]
    centre, radius = pts[0], 0.0
    for i in range(1, len(pts)):
        if _inside(pts[i], centre, radius):
            continue
        centre, radius = pts[i], 0.0
        for j in range(i):
            if _inside(pts[j], centre, radius):
                continue
            centre, radius = (pts[i] + pts[j]) / 2, float(np.hypot(*(pts[i] - pts[j]))) / 2
            for k in range(j):
                if not _inside(pts[k], centre, radius):
                    centre, radius = _circumcircle(pts[i], pts[j], pts[k])
    return np.asarray(centre, float), float(radius)


def _inside(p, centre, radius: float) -> bool:
    return float(np.hypot(*(p - centre))) <= radius * (1 + 1e-12) + 1e-9


def _circumcircle(a, b, c) -> tuple[np.ndarray, float]:
    """Circle through three points; for (near-)collinear points, the widest pair's circle."""
    bx, by = b - a
    cx, cy = c - a
    d = 2.0 * (bx * cy - by * cx)
    if abs(d) < 1e-12:
        pairs = ((a, b), (a, c), (b, c))
        p, q = max(pairs, key=lambda pq: float(np.hypot(*(pq[0] - pq[1]))))
        return (p + q) / 2, float(np.hypot(*(p - q))) / 2
    b2, c2 = bx * bx + by * by, cx * cx + cy * cy
    ux = (cy * b2 - by * c2) / d
    uy = (bx * c2 - cx * b2) / d
    centre = a + np.array([ux, uy])
    radius = max(float(np.hypot(*(centre - p))) for p in (a, b, c))
    return centre, radius


_WGS84_CRS = {"urn:ogc:def:crs:OGC:1.3:CRS84", "urn:ogc:def:crs:EPSG::4326", "EPSG:4326"}


def parse_obstacle_geojson(text: str, *, frame: LocalFrame, source: str) -> tuple[Cylinder, ...]:
    """GeoJSON text -> obstacle cylinders; ``frame`` is the scenario's ENU frame.

    Raises :class:`ScenarioError` with ``source`` and ``features[i]`` on any problem.
    """
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ScenarioError(source, "", f"not JSON: {exc}") from None
    if not isinstance(doc, dict):
        raise ScenarioError(source, "", "must be a GeoJSON FeatureCollection")
    crs = doc.get("crs")
    if crs is not None:
        _check_crs(crs, source)
    if doc.get("type") == "FeatureCollection":
        features = doc.get("features")
        if not isinstance(features, list):
            raise ScenarioError(source, "features", "must be an array")
        prefix = "features"
    elif doc.get("type") == "Feature":
        features, prefix = [doc], "feature"
    else:
        raise ScenarioError(source, "type", "must be FeatureCollection or Feature")

    cylinders = []
    for i, feature in enumerate(features):
        where = f"{prefix}[{i}]" if prefix == "features" else prefix

        def error(problem: str, where=where) -> ScenarioError:
            return ScenarioError(source, where, problem)

        if not isinstance(feature, dict) or feature.get("type") != "Feature":
            raise error("must be a Feature")
        props = feature.get("properties") or {}
        if not isinstance(props, dict):
            raise error("properties must be an object or null")
        name = props.get("name")
        label = name if isinstance(name, str) else f"{Path(source).name} {where}"
        geometry = feature.get("geometry")
        if not isinstance(geometry, dict):
            raise error("has no geometry (give a Point with a radius, or a Polygon)")
        kind = geometry.get("type")
        radius = props.get("radius")
        if kind == "Point":
            lon, lat = _read_position(geometry.get("coordinates"), error, "coordinates")
            if isinstance(radius, bool) or not isinstance(radius, (int, float)) or not (
                math.isfinite(radius) and radius > 0
            ):
                raise error(f"a Point needs a 'radius' property in metres > 0, got {radius!r}")
            cylinders.append(Cylinder(lat, lon, float(radius), label, f"{source} {where}"))
        elif kind == "Polygon":
            if radius is not None:
                raise error("'radius' is for Points; a Polygon becomes its smallest enclosing "
                            "circle (remove the radius, or make the feature a Point)")
            rings = geometry.get("coordinates")
            if not isinstance(rings, list) or not rings or not isinstance(rings[0], list):
                raise error("Polygon coordinates must be an array of rings")
            ring = rings[0]
            if len(ring) < 4:
                raise error(f"the Polygon's outer ring needs at least 4 positions, has {len(ring)}")
            lonlat = np.array([
                _read_position(p, error, f"coordinates[0][{j}]") for j, p in enumerate(ring)
            ])
            enu = frame.to_enu(lat_deg=lonlat[:, 1], lon_deg=lonlat[:, 0])[:, :2]
            centre, r = smallest_enclosing_circle(enu)
            if r <= 0:
                raise error("the Polygon has no area (all its positions coincide)")
            lat_c, lon_c, _ = frame.to_lla(np.append(centre, 0.0))
            cylinders.append(Cylinder(float(lat_c), float(lon_c), r, label,
                                      f"{source} {where}"))
        else:
            raise error(f"geometry type {kind!r} is not supported: use Point (with a radius "
                        "property in metres) or Polygon")
    return tuple(cylinders)


def _check_crs(crs, source: str) -> None:
    """A GeoJSON 2008 ``crs`` member: ``{"type": "name", "properties": {"name": ...}}``
    naming WGS84 longitude/latitude; anything else names what it got."""
    want = "WGS84 longitude/latitude, as {\"type\": \"name\", \"properties\": {\"name\": " \
           "\"urn:ogc:def:crs:OGC:1.3:CRS84\"}} (or leave crs out: RFC 7946 GeoJSON is WGS84)"
    if isinstance(crs, str):
        if crs in _WGS84_CRS:
            return
        raise ScenarioError(source, "crs", f"is the string {crs!r}: must be {want}")
    if not isinstance(crs, dict):
        raise ScenarioError(source, "crs", f"must be an object naming {want}, got {crs!r}")
    props = crs.get("properties")
    if not isinstance(props, dict):
        raise ScenarioError(source, "crs.properties",
                            f"must be an object with a name, got {props!r}: crs must be {want}")
    name = props.get("name")
    if name not in _WGS84_CRS:
        raise ScenarioError(source, "crs", f"must be {want}, got the name {name!r} (reproject "
                                           "the layer to EPSG:4326)")


def _read_position(value, error, what: str) -> tuple[float, float]:
    if (
        not isinstance(value, list)
        or len(value) < 2
        or any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in value)
    ):
        raise error(f"{what} must be [lon, lat] in degrees, got {value!r}")
    lon, lat = float(value[0]), float(value[1])
    if not (-180 <= lon <= 180 and -90 <= lat <= 90):
        raise error(f"{what} [{lon:g}, {lat:g}] is not [lon, lat] in degrees (WGS84)")
    return lon, lat


def read_obstacle_geojson(path: str | Path, *, frame: LocalFrame) -> tuple[Cylinder, ...]:
    """Read a GeoJSON obstacle file; see :func:`parse_obstacle_geojson`."""
    path = Path(path)
    text = read_user_text(path, error=lambda problem: ScenarioError(str(path), "", problem))
    return parse_obstacle_geojson(text, frame=frame, source=str(path))
