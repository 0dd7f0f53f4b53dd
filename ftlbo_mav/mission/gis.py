"""GIS formats: a plan written as GeoJSON (RFC 7946) and KML.

Export: the area, the obstacle cylinders (as circle polygons), the centroid's and every
UAV's path (LineStrings with altitude) and every positioned mission item (Points with
their mission index, the ``seq`` of the ``.waypoints`` line). Positions are
``[lon, lat, alt]`` as RFC 7946 orders them. Altitudes are metres above home, as in the
missions (RFC 7946 speaks of ellipsoidal height; every feature says so in its
``altitude_reference`` property). KML uses ``relativeToGround``, which Google Earth draws
above the terrain under each point: the same thing over flat ground.

Positions come from the plan's one geodetic view (:mod:`.geodetic`). Obstacles read from
GeoJSON (input) are :mod:`ftlbo_mav.obstacles`.
"""

from __future__ import annotations

import json
import math
import re
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from .geodetic import CIRCLE_VERTICES, GeodeticPlan, geodetic_view
from .items import (
    CMD_FENCE_CIRCLE_EXCLUSION,
    CMD_FENCE_POLYGON_VERTEX_INCLUSION,
    CMD_NAV_LAND,
    CMD_NAV_LOITER_UNLIM,
    CMD_NAV_WAYPOINT,
)
from .photos import UavPhotos

if TYPE_CHECKING:  # for annotations only
    from ..planning.plans import Plan
    from .fence import UavFence
    from .items import UavMission

ALTITUDE_REFERENCE = "metres above home (MAVLink GLOBAL_RELATIVE_ALT)"
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


# --------------------------------------------------------------------------- export


def _position(lat: float, lon: float, alt: float | None = None) -> list[float]:
    """RFC 7946 position: ``[lon, lat]`` or ``[lon, lat, alt]`` (9 decimals: 0.1 mm)."""
    pos = [round(float(lon), 9), round(float(lat), 9)]
    if alt is not None:
        pos.append(round(float(alt), 4))
    return pos


def _positioned_items(mission: UavMission):
    return [it for it in mission.items if it.command in _POSITIONED]


def _feature(geometry: dict, **properties: Any) -> dict:
    return {"type": "Feature", "geometry": geometry, "properties": properties}


def _circle_lonlat(lat: float, lon: float, radius_m: float) -> list[tuple[float, float]]:
    """A closed counter-clockwise ring ``(lat, lon)`` of ``radius_m`` around a point, on a
    local sphere tangent (metres to degrees at the centre; exact to millimetres here)."""
    angle = np.linspace(0.0, 2.0 * np.pi, CIRCLE_VERTICES + 1)
    m_lat = 111_132.954 - 559.822 * math.cos(2 * math.radians(lat))
    m_lon = 111_412.84 * math.cos(math.radians(lat))
    ring = [(lat + radius_m * math.sin(a) / m_lat, lon + radius_m * math.cos(a) / m_lon)
            for a in angle]
    ring[-1] = ring[0]
    return ring


def fence_shapes(fence: UavFence):
    """The fence as drawable shapes: ``(kind, ring (lat, lon) closed, properties)`` for the
    inclusion polygon(s) and exclusion circles, ``(kind, (lat, lon, alt), properties)``
    for the rally point(s)."""
    items = list(fence.fence)
    i = 0
    while i < len(items):
        it = items[i]
        if it.command == CMD_FENCE_POLYGON_VERTEX_INCLUSION:
            n = int(it.param1)
            ring = [(v.lat_deg, v.lon_deg) for v in items[i:i + n]]
            yield "fence_inclusion", ring + ring[:1], {}
            i += n
            continue
        if it.command == CMD_FENCE_CIRCLE_EXCLUSION:
            yield ("fence_exclusion", _circle_lonlat(it.lat_deg, it.lon_deg, it.param1),
                   {"radius_m": it.param1, "center": _position(it.lat_deg, it.lon_deg)})
        i += 1
    for r in fence.rally:
        yield "rally_point", (r.lat_deg, r.lon_deg, r.alt_m), {}


def _photo_rings(plan: Plan, photos: Sequence[UavPhotos]):
    """Per UAV: its photos ``(lat, lon, alt)`` and footprint rings ``[(lat, lon), ...]``
    (closed), from the ENU positions and corners of :mod:`.photos`."""
    frame = plan.scenario.frame
    for uav in photos:
        if not uav.count:
            yield uav, [], []
            continue
        lat, lon, _ = frame.to_lla(uav.positions)
        corners = uav.corners.reshape(-1, 2)
        clat, clon, _ = frame.to_lla(np.column_stack([corners, np.zeros(len(corners))]))
        clat, clon = clat.reshape(-1, 4), clon.reshape(-1, 4)
        points = list(zip(np.atleast_1d(lat), np.atleast_1d(lon), uav.positions[:, 2]))
        rings = [[*zip(a, o), (a[0], o[0])] for a, o in zip(clat, clon)]
        yield uav, points, rings


def geojson_document(
    plan: Plan, missions: Sequence[UavMission], *, geodetic: GeodeticPlan | None = None,
    fences: Sequence[UavFence] = (), photos: Sequence[UavPhotos] = (),
) -> dict:
    """The plan as an RFC 7946 FeatureCollection (a plain ``dict``, ready for ``json``).

    Every feature has a ``kind`` property: ``area``, ``obstacle``, ``centroid_path``,
    ``uav_path``, ``mission_item``, the fence's kinds, and for a survey with a camera
    ``photo`` (where a photo is taken, its number per UAV) and ``photo_footprint`` (the
    ground it covers). ``geodetic``: the plan's :func:`geodetic_view` (computed here when
    not given).
    """
    s = plan.scenario
    view = geodetic if geodetic is not None else geodetic_view(plan)
    features = [
        _feature(
            {"type": "Polygon",
             "coordinates": [[_position(lat, lon) for lat, lon in view.area_ring]]},
            kind="area",
            name=s.name,
            min_altitude_m=s.min_altitude_m,
            max_altitude_m=s.max_altitude_m,
        )
    ]
    for k, (cyl, ring) in enumerate(zip(s.obstacles, view.obstacle_rings)):
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
            {"type": "LineString", "coordinates": [_position(*p) for p in view.centroid]},
            kind="centroid_path",
            feasible=plan.feasible,
            altitude_reference=ALTITUDE_REFERENCE,
        )
    )
    for n, (mission, path) in enumerate(zip(missions, view.uav_paths)):
        features.append(
            _feature(
                {"type": "LineString", "coordinates": [_position(*p) for p in path]},
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
    for fence in fences:
        for kind, shape, props in fence_shapes(fence):
            if kind == "rally_point":
                geometry = {"type": "Point", "coordinates": _position(*shape)}
                props = {**props, "altitude_reference": ALTITUDE_REFERENCE}
            else:
                geometry = {"type": "Polygon",
                            "coordinates": [[_position(lat, lon) for lat, lon in shape]]}
            features.append(_feature(geometry, kind=kind, uav=fence.name, **props))
    for uav, points, rings in _photo_rings(plan, photos):
        for k, (point, ring) in enumerate(zip(points, rings), start=1):
            features.append(_feature({"type": "Point", "coordinates": _position(*point)},
                                     kind="photo", uav=uav.name, photo=k,
                                     altitude_reference=ALTITUDE_REFERENCE))
            features.append(_feature(
                {"type": "Polygon", "coordinates": [[_position(a, o) for a, o in ring]]},
                kind="photo_footprint", uav=uav.name, photo=k))
    return {"type": "FeatureCollection", "name": s.name or "ftlbo-mav plan", "features": features}


def render_geojson(
    plan: Plan, missions: Sequence[UavMission], *, geodetic: GeodeticPlan | None = None,
    fences: Sequence[UavFence] = (), photos: Sequence[UavPhotos] = (),
) -> str:
    doc = geojson_document(plan, missions, geodetic=geodetic, fences=fences, photos=photos)
    return json.dumps(doc, indent=1) + "\n"


def _kml_colour(hex_rgb: str, alpha: int = 0xFF) -> str:
    """``#rrggbb`` -> KML's ``aabbggrr``."""
    r, g, b = hex_rgb[1:3], hex_rgb[3:5], hex_rgb[5:7]
    return f"{alpha:02x}{b}{g}{r}"


def _kml_coords(rows) -> str:
    return " ".join(f"{lon:.9f},{lat:.9f},{alt:.4f}" for lat, lon, alt in rows)


# What XML 1.0 cannot hold at all, escaped or not (its Char production): C0 controls
# but tab, newline and return; surrogates; U+FFFE and U+FFFF
_NOT_XML = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ud800-\udfff\ufffe\uffff]")


def _sub(parent: ET.Element, tag: str, text: str | None = None, **attrib: str) -> ET.Element:
    el = ET.SubElement(parent, f"{{{KML_NS}}}{tag}", attrib)
    if text is not None:
        el.text = _NOT_XML.sub("\ufffd", text)  # a name's control character: well-formed
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


def render_kml(
    plan: Plan, missions: Sequence[UavMission], *, geodetic: GeodeticPlan | None = None,
    fences: Sequence[UavFence] = (), photos: Sequence[UavPhotos] = (),
) -> str:
    """The plan as KML 2.2: area and obstacles, the centroid, then one folder per UAV.

    Altitudes are ``relativeToGround``. Obstacles are drawn as prisms up to the top of
    the altitude band, so Google Earth shows the cylinders the paths avoid. ``geodetic``:
    the plan's :func:`geodetic_view` (computed here when not given). A survey's photos
    (``photos``) are a folder per UAV of footprints on the ground.
    """
    ET.register_namespace("", KML_NS)
    s = plan.scenario
    view = geodetic if geodetic is not None else geodetic_view(plan)
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
    for n, uav in enumerate(photos):
        _kml_style(doc, f"{uav.name}-photo", line=_kml_colour(uav_colour(n)), width=1,
                   poly=_kml_colour(uav_colour(n), 0x30))

    area = _sub(doc, "Folder")
    _sub(area, "name", "Area and obstacles")
    _kml_polygon(area, "area", "area", [(lat, lon, 0.0) for lat, lon in view.area_ring],
                 height_m=None)
    for k, (cyl, ring) in enumerate(zip(s.obstacles, view.obstacle_rings)):
        _kml_polygon(area, cyl.name or f"obstacle {k + 1} (r {cyl.radius_m:g} m)", "obstacle",
                     ring, height_m=s.max_altitude_m)

    centroid = _sub(doc, "Folder")
    _sub(centroid, "name", "Centroid")
    _kml_line(centroid, "centroid path", "centroid", view.centroid)

    for mission, path in zip(missions, view.uav_paths):
        folder = _sub(doc, "Folder")
        _sub(folder, "name", mission.name)
        _kml_line(folder, f"{mission.name} path", mission.name, path)
        for it in _positioned_items(mission):
            pm = _sub(folder, "Placemark")
            _sub(pm, "name", f"{mission.name} #{it.seq}")
            _sub(pm, "description", "HOME" if it.seq == 0 else it.name)
            _sub(pm, "styleUrl", f"#{mission.name}")
            point = _sub(pm, "Point")
            _sub(point, "altitudeMode", "relativeToGround")
            _sub(point, "coordinates", _kml_coords([(it.lat_deg, it.lon_deg, it.alt_m)]))
    for fence in fences:
        folder = _sub(doc, "Folder")
        _sub(folder, "name", f"{fence.name} fence")
        for kind, shape, props in fence_shapes(fence):
            if kind == "rally_point":
                pm = _sub(folder, "Placemark")
                _sub(pm, "name", f"{fence.name} rally point")
                _sub(pm, "styleUrl", f"#{fence.name}")
                point = _sub(pm, "Point")
                _sub(point, "altitudeMode", "relativeToGround")
                _sub(point, "coordinates", _kml_coords([shape]))
            else:
                label = ("inclusion" if kind == "fence_inclusion"
                         else f"exclusion r {props['radius_m']:g} m")
                _kml_polygon(folder, f"{fence.name} fence {label}", "area",
                             [(lat, lon, 0.0) for lat, lon in shape], height_m=None)
    for uav, _points, rings in _photo_rings(plan, photos):
        folder = _sub(doc, "Folder")
        _sub(folder, "name", f"{uav.name} photos ({uav.count})")
        for k, ring in enumerate(rings, start=1):
            _kml_polygon(folder, f"{uav.name} photo {k}", f"{uav.name}-photo",
                         [(a, o, 0.0) for a, o in ring], height_m=None)
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"
