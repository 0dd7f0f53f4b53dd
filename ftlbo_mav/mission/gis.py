"""GIS formats: a plan as GeoJSON (RFC 7946) and KML, and obstacles read from GeoJSON.

Export: the area, the obstacle cylinders (as circle polygons), the centroid's and every
UAV's path (LineStrings with altitude) and every positioned mission item (Points with
their mission index, the ``seq`` of the ``.waypoints`` line). Positions are
``[lon, lat, alt]`` as RFC 7946 orders them. Altitudes are metres above home, as in the
missions (RFC 7946 speaks of ellipsoidal height; every feature says so in its
``altitude_reference`` property). KML uses ``relativeToGround``, which Google Earth draws
above the terrain under each point: the same thing over flat ground.

Import: a GeoJSON FeatureCollection of obstacles. A ``Point`` needs a ``radius``
property in metres; a ``Polygon`` becomes its smallest enclosing circle, computed in the
scenario's local ENU frame. Errors name the file, the feature index and the problem.
"""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import ScenarioError
from .items import CMD_NAV_LAND, CMD_NAV_LOITER_UNLIM, CMD_NAV_WAYPOINT

if TYPE_CHECKING:  # imported for annotations only: scenario.py imports this module
    from ..geo import LocalFrame
    from ..planning.planner import Plan
    from ..scenario import Cylinder
    from .export import UavMission

ALTITUDE_REFERENCE = "metres above home (MAVLink GLOBAL_RELATIVE_ALT)"
CIRCLE_VERTICES = 72
KML_NS = "http://www.opengis.net/kml/2.2"

# Mission items that carry a position (home is item 0, a NAV_WAYPOINT).
_POSITIONED = {CMD_NAV_WAYPOINT, CMD_NAV_LAND, CMD_NAV_LOITER_UNLIM}
# One colour per UAV, shared with the figures: matplotlib's tab10 without its red.
UAV_COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#17becf",
               "#bcbd22", "#7f7f7f")
OBSTACLE_COLOUR = "#8b5a2b"


def uav_colour(n: int) -> str:
    """Colour of UAV ``n`` (0-based), as ``#rrggbb``."""
    return UAV_COLOURS[n % len(UAV_COLOURS)]


# --------------------------------------------------------------------------- geometry


def circle_ring_enu(centre, radius_m: float, *, vertices: int = CIRCLE_VERTICES) -> np.ndarray:
    """A closed counter-clockwise ring around ``centre`` (2,), shape ``(vertices+1, 2)`` metres."""
    angle = np.linspace(0.0, 2.0 * np.pi, vertices + 1)
    ring = np.asarray(centre, float)[None, :2] + radius_m * np.stack(
        [np.cos(angle), np.sin(angle)], axis=1
    )
    ring[-1] = ring[0]
    return ring


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


# --------------------------------------------------------------------------- export


def _position(lat: float, lon: float, alt: float | None = None) -> list[float]:
    """RFC 7946 position: ``[lon, lat]`` or ``[lon, lat, alt]`` (9 decimals: 0.1 mm)."""
    pos = [round(float(lon), 9), round(float(lat), 9)]
    if alt is not None:
        pos.append(round(float(alt), 4))
    return pos


def _ring_lla(plan: Plan, ring_enu: np.ndarray) -> np.ndarray:
    """ENU ring ``(n, 2)`` on the ground -> ``(n, 3)`` lat, lon, alt rows, closed exactly."""
    enu = np.column_stack([ring_enu, np.zeros(len(ring_enu))])
    lla = plan.lla(enu)
    lla[-1] = lla[0]
    return lla


def _area_ring(plan: Plan) -> list[tuple[float, float]]:
    """The area's lat/lon rectangle, counter-clockwise from the south-west corner."""
    s = plan.scenario
    lat = sorted([s.corner_a.lat_deg, s.corner_b.lat_deg])
    lon = sorted([s.corner_a.lon_deg, s.corner_b.lon_deg])
    corners = [(lat[0], lon[0]), (lat[0], lon[1]), (lat[1], lon[1]), (lat[1], lon[0])]
    return corners + corners[:1]


def _obstacle_rings(plan: Plan) -> list[np.ndarray]:
    centres, radii = plan.scenario.obstacles_enu()
    return [_ring_lla(plan, circle_ring_enu(c, r)) for c, r in zip(centres, radii)]


def _positioned_items(mission: UavMission):
    return [it for it in mission.items if it.command in _POSITIONED]


def _feature(geometry: dict, **properties: Any) -> dict:
    return {"type": "Feature", "geometry": geometry, "properties": properties}


def geojson_document(plan: Plan, missions: Sequence[UavMission]) -> dict:
    """The plan as an RFC 7946 FeatureCollection (a plain ``dict``, ready for ``json``).

    Every feature has a ``kind`` property: ``area``, ``obstacle``, ``centroid_path``,
    ``uav_path`` or ``mission_item``.
    """
    s = plan.scenario
    features = [
        _feature(
            {"type": "Polygon",
             "coordinates": [[_position(lat, lon) for lat, lon in _area_ring(plan)]]},
            kind="area",
            name=s.name,
            min_altitude_m=s.min_altitude_m,
            max_altitude_m=s.max_altitude_m,
        )
    ]
    for k, (cyl, ring) in enumerate(zip(s.obstacles, _obstacle_rings(plan))):
        features.append(
            _feature(
                {"type": "Polygon", "coordinates": [[_position(lat, lon) for lat, lon, _ in ring]]},
                kind="obstacle",
                index=k,
                name=cyl.name,
                center=_position(cyl.lat_deg, cyl.lon_deg),
                radius_m=cyl.radius_m,
                clearance_m=s.clearance_m,
            )
        )
    features.append(
        _feature(
            {"type": "LineString", "coordinates": [_position(*p) for p in plan.lla(plan.centroid)]},
            kind="centroid_path",
            feasible=plan.feasible,
            altitude_reference=ALTITUDE_REFERENCE,
        )
    )
    for n, (mission, path) in enumerate(zip(missions, plan.uav_paths)):
        features.append(
            _feature(
                {"type": "LineString", "coordinates": [_position(*p) for p in plan.lla(path)]},
                kind="uav_path",
                uav=mission.name,
                offset_m=list(mission.offset),
                colour=uav_colour(n),
                feasible=plan.feasible,
                altitude_reference=ALTITUDE_REFERENCE,
            )
        )
        for it in _positioned_items(mission):
            features.append(
                _feature(
                    {"type": "Point", "coordinates": _position(it.lat_deg, it.lon_deg, it.alt_m)},
                    kind="mission_item",
                    uav=mission.name,
                    mission_index=it.seq,
                    command="HOME" if it.seq == 0 else it.name,
                    altitude_reference=ALTITUDE_REFERENCE,
                )
            )
    return {"type": "FeatureCollection", "name": s.name or "ftlbo-mav plan", "features": features}


def render_geojson(plan: Plan, missions: Sequence[UavMission]) -> str:
    return json.dumps(geojson_document(plan, missions), indent=1) + "\n"


def _kml_colour(hex_rgb: str, alpha: int = 0xFF) -> str:
    """``#rrggbb`` -> KML's ``aabbggrr``."""
    r, g, b = hex_rgb[1:3], hex_rgb[3:5], hex_rgb[5:7]
    return f"{alpha:02x}{b}{g}{r}"


def _kml_coords(rows) -> str:
    return " ".join(f"{lon:.9f},{lat:.9f},{alt:.4f}" for lat, lon, alt in rows)


def _sub(parent: ET.Element, tag: str, text: str | None = None, **attrib: str) -> ET.Element:
    el = ET.SubElement(parent, f"{{{KML_NS}}}{tag}", attrib)
    if text is not None:
        el.text = text
    return el


def _kml_style(doc: ET.Element, style_id: str, *, line: str, width: float, poly: str | None = None):
    style = _sub(doc, "Style", id=style_id)  # children in the KML 2.2 schema's order
    icon = _sub(style, "IconStyle")
    _sub(icon, "color", line)
    _sub(icon, "scale", "0.6")
    line_style = _sub(style, "LineStyle")
    _sub(line_style, "color", line)
    _sub(line_style, "width", f"{width:g}")
    if poly is not None:
        poly_style = _sub(style, "PolyStyle")
        _sub(poly_style, "color", poly)


def _kml_line(folder: ET.Element, name: str, style: str, rows) -> None:
    pm = _sub(folder, "Placemark")
    _sub(pm, "name", name)
    _sub(pm, "styleUrl", f"#{style}")
    line = _sub(pm, "LineString")
    _sub(line, "altitudeMode", "relativeToGround")
    _sub(line, "coordinates", _kml_coords(rows))


def _kml_polygon(
    folder: ET.Element, name: str, style: str, rows, *, height_m: float | None
) -> None:
    """A ground polygon, or with ``height_m`` a prism extruded down to the ground."""
    pm = _sub(folder, "Placemark")
    _sub(pm, "name", name)
    _sub(pm, "styleUrl", f"#{style}")
    poly = _sub(pm, "Polygon")
    if height_m is None:
        _sub(poly, "tessellate", "1")
        _sub(poly, "altitudeMode", "clampToGround")
    else:
        _sub(poly, "extrude", "1")
        _sub(poly, "altitudeMode", "relativeToGround")
        rows = [(lat, lon, height_m) for lat, lon, _ in rows]
    ring = _sub(_sub(poly, "outerBoundaryIs"), "LinearRing")
    _sub(ring, "coordinates", _kml_coords(rows))


def render_kml(plan: Plan, missions: Sequence[UavMission]) -> str:
    """The plan as KML 2.2: area and obstacles, the centroid, then one folder per UAV.

    Altitudes are ``relativeToGround``. Obstacles are drawn as prisms up to the top of
    the altitude band, so Google Earth shows the cylinders the paths avoid.
    """
    ET.register_namespace("", KML_NS)
    s = plan.scenario
    root = ET.Element(f"{{{KML_NS}}}kml")
    doc = _sub(root, "Document")
    _sub(doc, "name", s.name or "ftlbo-mav plan")
    _sub(doc, "description", f"{plan.settings.algorithm} seed {plan.settings.seed}; "
         f"{'feasible' if plan.feasible else 'INFEASIBLE'}; altitudes {ALTITUDE_REFERENCE}")
    _kml_style(doc, "area", line=_kml_colour("#ffffff"), width=2, poly=_kml_colour("#ffffff", 0x20))
    _kml_style(doc, "obstacle", line=_kml_colour(OBSTACLE_COLOUR),
               width=1, poly=_kml_colour(OBSTACLE_COLOUR, 0x90))
    _kml_style(doc, "centroid", line=_kml_colour("#000000"), width=2)
    for n in range(len(missions)):
        _kml_style(doc, f"uav{n + 1}", line=_kml_colour(uav_colour(n)), width=3)

    area = _sub(doc, "Folder")
    _sub(area, "name", "Area and obstacles")
    _kml_polygon(area, "area", "area", [(lat, lon, 0.0) for lat, lon in _area_ring(plan)],
                 height_m=None)
    for k, (cyl, ring) in enumerate(zip(s.obstacles, _obstacle_rings(plan))):
        _kml_polygon(area, cyl.name or f"obstacle {k + 1} (r {cyl.radius_m:g} m)", "obstacle",
                     ring, height_m=s.max_altitude_m)

    centroid = _sub(doc, "Folder")
    _sub(centroid, "name", "Centroid")
    _kml_line(centroid, "centroid path", "centroid", plan.lla(plan.centroid))

    for mission, path in zip(missions, plan.uav_paths):
        folder = _sub(doc, "Folder")
        _sub(folder, "name", mission.name)
        _kml_line(folder, f"{mission.name} path", mission.name, plan.lla(path))
        for it in _positioned_items(mission):
            pm = _sub(folder, "Placemark")
            _sub(pm, "name", f"{mission.name} #{it.seq}")
            _sub(pm, "description", "HOME" if it.seq == 0 else it.name)
            _sub(pm, "styleUrl", f"#{mission.name}")
            point = _sub(pm, "Point")
            _sub(point, "altitudeMode", "relativeToGround")
            _sub(point, "coordinates", _kml_coords([(it.lat_deg, it.lon_deg, it.alt_m)]))
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


# --------------------------------------------------------------------------- import

_WGS84_CRS = {"urn:ogc:def:crs:OGC:1.3:CRS84", "urn:ogc:def:crs:EPSG::4326", "EPSG:4326"}


def parse_obstacle_geojson(text: str, *, frame: LocalFrame, source: str) -> tuple[Cylinder, ...]:
    """GeoJSON text -> obstacle cylinders; ``frame`` is the scenario's ENU frame.

    Raises :class:`ScenarioError` with ``source`` and ``features[i]`` on any problem.
    """
    from ..scenario import Cylinder  # scenario.py imports this module lazily

    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ScenarioError(source, "", f"not JSON: {exc}") from None
    if not isinstance(doc, dict):
        raise ScenarioError(source, "", "must be a GeoJSON FeatureCollection")
    crs = doc.get("crs")
    if crs is not None:
        name = crs.get("properties", {}).get("name") if isinstance(crs, dict) else None
        if name not in _WGS84_CRS:
            raise ScenarioError(
                source, "crs", f"must be WGS84 longitude/latitude (CRS84), got {name!r}")
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
            cylinders.append(Cylinder(lat, lon, float(radius), label))
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
            cylinders.append(Cylinder(float(lat_c), float(lon_c), r, label))
        else:
            raise error(f"geometry type {kind!r} is not supported: use Point (with a radius "
                        "property in metres) or Polygon")
    return tuple(cylinders)


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
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ScenarioError(str(path), "", "no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ScenarioError(str(path), "", f"cannot read: {exc}") from None
    return parse_obstacle_geojson(text, frame=frame, source=str(path))
