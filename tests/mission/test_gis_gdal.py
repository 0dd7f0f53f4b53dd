"""The GeoJSON and KML open with GDAL/OGR (pyogrio, the reader under GeoPandas and the
library under QGIS): the expected layers, geometry types and lon/lat coordinates."""

from __future__ import annotations

import struct
from collections import Counter
from pathlib import Path

import numpy as np
import pyogrio
import pytest
from pyogrio import raw

from ftlbo_mav.mission.export import write_plan
from ftlbo_mav.mission.fence_files import read_fence_set
from ftlbo_mav.mission.plan_reader import read_plan

STORED = Path(__file__).resolve().parents[1] / "data" / "orchard-plan"
TYPES = {1: "Point", 2: "LineString", 3: "Polygon"}


def wkb(blob: bytes) -> tuple[str, np.ndarray]:
    """A Point / LineString / Polygon (outer ring) from ISO or extended WKB: its type and
    ``(n, 2 or 3)`` coordinates in the order the file holds them (x = lon, y = lat)."""
    order = "<" if blob[0] == 1 else ">"
    (code,) = struct.unpack(order + "I", blob[1:5])
    dims = 3 if code & 0x80000000 or 1000 <= code % 0x80000000 < 2000 else 2
    kind = TYPES[(code & 0x0FFFFFFF) % 1000]
    at = 5

    def points(n):
        nonlocal at
        values = struct.unpack(order + "d" * (n * dims), blob[at:at + 8 * n * dims])
        at += 8 * n * dims
        return np.array(values).reshape(n, dims)

    if kind == "Point":
        return kind, points(1)
    (n,) = struct.unpack(order + "I", blob[at:at + 4])
    at += 4
    if kind == "Polygon":
        (n,) = struct.unpack(order + "I", blob[at:at + 4])
        at += 4
    return kind, points(n)


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("gis")
    write_plan(read_plan(STORED), out, formats=("geojson", "kml"))
    return out


def _features(path, layer=None):
    meta, _fids, geometry, fields = raw.read(path, layer=layer)
    names = list(meta["fields"])
    return meta, [(wkb(g), {n: f[i] for n, f in zip(names, fields)})
                  for i, g in enumerate(geometry)]


def test_geojson_is_one_wgs84_layer_with_every_kind(folder):
    path = folder / "plan.geojson"
    layers = pyogrio.list_layers(path)
    assert len(layers) == 1
    meta, features = _features(path)
    assert meta["crs"] == "EPSG:4326"
    kinds = Counter((props["kind"], shape[0]) for shape, props in features)
    assert kinds[("area", "Polygon")] == 1
    assert kinds[("obstacle", "Polygon")] == 7
    assert kinds[("centroid_path", "LineString")] == 1
    assert kinds[("uav_path", "LineString")] == 3
    assert kinds[("mission_item", "Point")] == 3 * 14
    assert kinds[("fence_inclusion", "Polygon")] == 3
    assert kinds[("fence_exclusion", "Polygon")] == 3 * 7
    assert kinds[("rally_point", "Point")] == 3


def test_coordinates_are_lon_lat_where_the_plan_is(folder):
    plan = read_plan(STORED)
    s = plan.scenario
    lat = sorted([s.corner_a.lat_deg, s.corner_b.lat_deg])
    lon = sorted([s.corner_a.lon_deg, s.corner_b.lon_deg])
    _meta, features = _features(folder / "plan.geojson")
    for (_kind, xy), props in features:
        assert np.all((xy[:, 0] > lon[0] - 1e-4) & (xy[:, 0] < lon[1] + 1e-4)), props["kind"]
        assert np.all((xy[:, 1] > lat[0] - 1e-4) & (xy[:, 1] < lat[1] + 1e-4)), props["kind"]
    rally = [xy for (kind, xy), p in features if p["kind"] == "rally_point" and p["uav"] == "uav1"]
    want = read_fence_set(folder, "uav1").rally[0]
    assert rally[0][0, 0] == pytest.approx(want.lon_deg, abs=1e-8)
    assert rally[0][0, 1] == pytest.approx(want.lat_deg, abs=1e-8)
    assert rally[0][0, 2] == pytest.approx(want.alt_m)


def test_kml_has_the_folders_as_layers_with_their_geometries(folder):
    path = folder / "plan.kml"
    names = [name for name, _ in pyogrio.list_layers(path)]
    assert names == ["Area and obstacles", "Centroid", "uav1", "uav2", "uav3",
                     "uav1 fence", "uav2 fence", "uav3 fence"]
    _meta, area = _features(path, "Area and obstacles")
    assert Counter(shape[0] for shape, _ in area) == {"Polygon": 8}
    _meta, uav = _features(path, "uav2")
    assert Counter(shape[0] for shape, _ in uav) == {"LineString": 1, "Point": 14}
    _meta, fence = _features(path, "uav2 fence")
    assert Counter(shape[0] for shape, _ in fence) == {"Polygon": 8, "Point": 1}
    ring = next(xy for (kind, xy), _ in area if kind == "Polygon")
    assert 109.11 < ring[0, 0] < 109.12 and 12.23 < ring[0, 1] < 12.24  # lon, lat
