"""GeoJSON and KML export (standard readers, coordinate round trips) and obstacle import."""

from __future__ import annotations

import itertools
import json
import re
import xml.etree.ElementTree as ET
from functools import lru_cache

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ftlbo_mav.errors import ScenarioError
from ftlbo_mav.mission.export import plan_missions
from ftlbo_mav.mission.gis import geojson_document, render_geojson, render_kml
from ftlbo_mav.mission.waypoints import parse_waypoints, render_waypoints
from ftlbo_mav.obstacles import parse_obstacle_geojson, smallest_enclosing_circle
from ftlbo_mav.planning.planner import plan
from ftlbo_mav.scenario import load_scenario, parse_scenario

from ..conftest import SMALL

KML = "{http://www.opengis.net/kml/2.2}"
DEG = 1e-7  # the round-trip tolerance


@lru_cache(maxsize=1)
def small_plan():
    p = plan(parse_scenario(SMALL), seed=3, students=12, iterations=5)
    return p, plan_missions(p)


def _features(doc, kind):
    return [f for f in doc["features"] if f["properties"]["kind"] == kind]


# --------------------------------------------------------------------------- GeoJSON


def test_geojson_is_rfc7946_lon_lat_and_round_trips_the_paths():
    p, missions = small_plan()
    doc = json.loads(render_geojson(p, missions))
    assert doc["type"] == "FeatureCollection" and "crs" not in doc  # RFC 7946: WGS84 only
    for f in doc["features"]:
        assert f["type"] == "Feature" and set(f) == {"type", "geometry", "properties"}
    [centroid] = _features(doc, "centroid_path")
    assert np.allclose(np.array(centroid["geometry"]["coordinates"])[:, [1, 0, 2]],
                       p.lla(p.centroid), atol=DEG)
    paths = _features(doc, "uav_path")
    assert [f["properties"]["uav"] for f in paths] == ["uav1", "uav2", "uav3"]
    for f, path in zip(paths, p.uav_paths):
        assert f["geometry"]["type"] == "LineString"
        coords = np.array(f["geometry"]["coordinates"])
        assert coords.shape == (len(path), 3)  # with altitude
        # lon first: the area is at 109 E, 12 N
        assert np.all(coords[:, 0] > 100) and np.all(coords[:, 1] < 20)
        assert np.allclose(coords[:, [1, 0]], p.lla(path)[:, :2], atol=DEG)
        assert np.allclose(coords[:, 2], path[:, 2], atol=1e-4)


def test_geojson_points_carry_their_mission_index():
    p, missions = small_plan()
    doc = geojson_document(p, missions)
    for m in missions:
        items = parse_waypoints(render_waypoints(m.items))
        points = [f for f in _features(doc, "mission_item") if f["properties"]["uav"] == m.name]
        assert points, m.name
        for f in points:
            ref = items[f["properties"]["mission_index"]]
            lon, lat, alt = f["geometry"]["coordinates"]
            assert abs(lat - ref.lat_deg) <= DEG and abs(lon - ref.lon_deg) <= DEG
            assert alt == pytest.approx(ref.alt_m, abs=1e-4)
        listed = {f["properties"]["mission_index"] for f in points}
        # every positioned item: home, the waypoints, the landing
        assert listed == {it.seq for it in items if it.command in (16, 21)}


def test_geojson_polygons_are_closed_counter_clockwise_and_obstacles_are_circles():
    p, missions = small_plan()
    doc = geojson_document(p, missions)
    frame = p.scenario.frame
    [area] = _features(doc, "area")
    obstacles = _features(doc, "obstacle")
    assert len(obstacles) == len(p.scenario.obstacles) == 1
    for f in [area, *obstacles]:
        ring = np.array(f["geometry"]["coordinates"][0])
        assert len(ring) >= 4 and np.array_equal(ring[0], ring[-1])
        x, y = ring[:, 0], ring[:, 1]
        assert np.sum(x[:-1] * y[1:] - x[1:] * y[:-1]) > 0  # RFC 7946 3.1.6: exterior CCW
    cyl = p.scenario.obstacles[0]
    ring = np.array(obstacles[0]["geometry"]["coordinates"][0])
    enu = frame.to_enu(lat_deg=ring[:, 1], lon_deg=ring[:, 0])[:, :2]
    centre = frame.to_enu(lat_deg=cyl.lat_deg, lon_deg=cyl.lon_deg)[:2]
    assert np.allclose(np.hypot(*(enu - centre).T), cyl.radius_m, atol=0.01)


# --------------------------------------------------------------------------- KML


def test_kml_parses_has_one_folder_per_uav_and_round_trips():
    p, missions = small_plan()
    root = ET.fromstring(render_kml(p, missions))
    assert root.tag == f"{KML}kml"
    folders = {f.findtext(f"{KML}name"): f for f in root.iter(f"{KML}Folder")}
    assert {"uav1", "uav2", "uav3"} <= set(folders)
    for mode in root.iter(f"{KML}altitudeMode"):
        assert mode.text in ("relativeToGround", "clampToGround")
    for m, path in zip(missions, p.uav_paths):
        folder = folders[m.name]
        [line] = folder.iter(f"{KML}LineString")
        assert line.findtext(f"{KML}altitudeMode") == "relativeToGround"
        coords = np.array([c.split(",") for c in line.findtext(f"{KML}coordinates").split()],
                          float)
        assert np.allclose(coords[:, [1, 0]], p.lla(path)[:, :2], atol=DEG)
        assert np.allclose(coords[:, 2], path[:, 2], atol=1e-4)
        points = folder.findall(f".//{KML}Point")
        items = {it.seq: it for it in m.items}
        for placemark in folder.findall(f"{KML}Placemark"):
            point = placemark.find(f"{KML}Point")
            if point is None:
                continue
            seq = int(re.search(r"#(\d+)$", placemark.findtext(f"{KML}name")).group(1))
            lon, lat, alt = map(float, point.findtext(f"{KML}coordinates").split(","))
            assert abs(lat - items[seq].lat_deg) <= DEG and abs(lon - items[seq].lon_deg) <= DEG
            assert alt == pytest.approx(items[seq].alt_m, abs=1e-4)
        assert len(points) >= len(path)


# --------------------------------------------------------------------------- enclosing circle


def _brute_force_circle(pts):
    """Smallest enclosing circle by trying every pair and triple (the reference)."""
    from ftlbo_mav.obstacles import _circumcircle

    best = (None, np.inf)
    candidates = [((a + b) / 2, np.hypot(*(a - b)) / 2) for a, b in itertools.combinations(pts, 2)]
    candidates += [_circumcircle(a, b, c) for a, b, c in itertools.combinations(pts, 3)]
    for centre, r in candidates:
        if r < best[1] and np.all(np.hypot(*(pts - centre).T) <= r + 1e-9):
            best = (centre, r)
    return best


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(-50, 50), st.floats(-50, 50)), min_size=2, max_size=8))
def test_smallest_enclosing_circle_matches_brute_force(points):
    pts = np.unique(np.array(points, float), axis=0)
    centre, r = smallest_enclosing_circle(pts)
    assert np.all(np.hypot(*(pts - centre).T) <= r + 1e-6)
    if len(pts) >= 2:
        assert r == pytest.approx(_brute_force_circle(pts)[1], abs=1e-6)


def test_smallest_enclosing_circle_of_a_square_and_a_big_ring():
    centre, r = smallest_enclosing_circle([[0, 0], [10, 0], [10, 10], [0, 10], [5, 5]])
    assert np.allclose(centre, [5, 5]) and r == pytest.approx(np.sqrt(50))
    angle = np.linspace(0, 2 * np.pi, 5000, endpoint=False)
    ring = np.stack([3 + 7 * np.cos(angle), -2 + 7 * np.sin(angle)], axis=1)
    centre, r = smallest_enclosing_circle(ring)
    assert np.allclose(centre, [3, -2], atol=1e-9) and r == pytest.approx(7)


# --------------------------------------------------------------------------- import


def _collection(*features):
    return json.dumps({"type": "FeatureCollection", "features": list(features)})


def _point(lon, lat, **props):
    return {"type": "Feature", "geometry": {"type": "Point", "coordinates": [lon, lat]},
            "properties": props}


def test_import_points_and_polygons():
    p, _ = small_plan()
    frame = p.scenario.frame
    # A 6 m x 8 m rectangle centred 40 m east, 20 m north: enclosing circle radius 5 m.
    corners = np.array([[37, 16, 0], [43, 16, 0], [43, 24, 0], [37, 24, 0], [37, 16, 0]], float)
    lat, lon, _ = frame.to_lla(corners)
    polygon = {"type": "Feature", "properties": {"name": "mango"},
               "geometry": {"type": "Polygon", "coordinates": [list(map(list, zip(lon, lat)))]}}
    cylinders = parse_obstacle_geojson(
        _collection(_point(109.1148, 12.2333, radius=2.5), polygon), frame=frame, source="t.json")
    assert cylinders[0].lat_deg == 12.2333 and cylinders[0].radius_m == 2.5
    assert cylinders[1].name == "mango" and cylinders[1].radius_m == pytest.approx(5.0, abs=1e-6)
    centre = frame.to_enu(lat_deg=cylinders[1].lat_deg, lon_deg=cylinders[1].lon_deg)
    assert np.allclose(centre[:2], [40, 20], atol=1e-6)


def test_exported_obstacles_import_back_to_the_same_cylinders():
    p, missions = small_plan()
    doc = geojson_document(p, missions)
    obstacles = {"type": "FeatureCollection", "features": _features(doc, "obstacle")}
    back = parse_obstacle_geojson(json.dumps(obstacles), frame=p.scenario.frame, source="x")
    for got, ref in zip(back, p.scenario.obstacles, strict=True):
        assert abs(got.lat_deg - ref.lat_deg) <= DEG and abs(got.lon_deg - ref.lon_deg) <= DEG
        assert got.radius_m == pytest.approx(ref.radius_m, abs=1e-3)


SQUARE = [[109.1148, 12.2333], [109.1149, 12.2333], [109.1149, 12.2334], [109.1148, 12.2333]]


@pytest.mark.parametrize("feature, problem", [
    (_point(109.1148, 12.2333), "a Point needs a 'radius' property in metres > 0, got None"),
    (_point(109.1148, 12.2333, radius=-1), "'radius' property in metres > 0, got -1"),
    (_point(109.1148, 12.2333, radius="3"), "radius"),
    (_point(1234567.0, 1380000.0, radius=3), "is not [lon, lat] in degrees"),
    ({"type": "Feature", "properties": {}, "geometry": None}, "has no geometry"),
    ({"type": "Feature", "properties": {},
      "geometry": {"type": "LineString", "coordinates": [[109.1, 12.2], [109.2, 12.3]]}},
     "geometry type 'LineString' is not supported"),
    ({"type": "Feature", "properties": {},
      "geometry": {"type": "Polygon", "coordinates": [SQUARE[:3]]}}, "at least 4 positions"),
    ({"type": "Feature", "properties": {"radius": 3},
      "geometry": {"type": "Polygon", "coordinates": [SQUARE]}}, "'radius' is for Points"),
    ({"type": "Feature", "properties": {},
      "geometry": {"type": "Polygon", "coordinates": [[[109.1, 12.2]] * 4]}}, "has no area"),
    ({"type": "Polygon", "coordinates": [SQUARE]}, "must be a Feature"),
])
def test_import_errors_name_the_feature_index(feature, problem):
    p, _ = small_plan()
    text = _collection(_point(109.1148, 12.2333, radius=2.0), feature)
    with pytest.raises(ScenarioError) as err:
        parse_obstacle_geojson(text, frame=p.scenario.frame, source="trees.geojson")
    message = str(err.value)
    assert message.startswith("trees.geojson: features[1]: "), message
    assert problem in message


@pytest.mark.parametrize("text, problem", [
    ("{", "not JSON"),
    ('{"type": "GeometryCollection", "geometries": []}', "type: must be FeatureCollection"),
    ('{"type": "FeatureCollection", "crs": {"type": "name", "properties": {"name": '
     '"urn:ogc:def:crs:EPSG::3405"}}, "features": []}', "crs: must be WGS84"),
])
def test_import_errors_for_the_whole_file(text, problem):
    p, _ = small_plan()
    with pytest.raises(ScenarioError, match=re.escape(problem)):
        parse_obstacle_geojson(text, frame=p.scenario.frame, source="trees.geojson")


def test_qgis_crs84_header_is_accepted():
    p, _ = small_plan()
    doc = {"type": "FeatureCollection",
           "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:OGC:1.3:CRS84"}},
           "features": [_point(109.1148, 12.2333, radius=2.0)]}
    assert len(parse_obstacle_geojson(json.dumps(doc), frame=p.scenario.frame, source="q")) == 1


@pytest.mark.parametrize("crs", ["EPSG:4326", "urn:ogc:def:crs:OGC:1.3:CRS84",
                                 "urn:ogc:def:crs:EPSG::4326"])
def test_a_plain_string_crs_naming_wgs84_is_accepted(crs):
    p, _ = small_plan()
    doc = {"type": "FeatureCollection", "crs": crs,
           "features": [_point(109.1148, 12.2333, radius=2.0)]}
    assert len(parse_obstacle_geojson(json.dumps(doc), frame=p.scenario.frame, source="q")) == 1


@pytest.mark.parametrize("crs", ["EPSG:3405", "WGS84", "", "urn:ogc:def:crs:EPSG::3857"])
def test_a_plain_string_crs_naming_anything_else_is_refused_naming_the_file(crs):
    p, _ = small_plan()
    doc = {"type": "FeatureCollection", "crs": crs,
           "features": [_point(109.1148, 12.2333, radius=2.0)]}
    with pytest.raises(ScenarioError) as err:
        parse_obstacle_geojson(json.dumps(doc), frame=p.scenario.frame, source="trees.geojson")
    assert str(err.value).startswith(f"trees.geojson: crs: is the string {crs!r}: must be WGS84")


# --------------------------------------------------------------------------- scenario key


def test_scenario_obstacles_file_adds_to_the_obstacle_tables(tmp_path):
    (tmp_path / "gis").mkdir()
    (tmp_path / "gis" / "trees.geojson").write_text(
        _collection(_point(109.1150, 12.2334, radius=2.0, name="lychee")))
    path = tmp_path / "field.toml"
    path.write_text('obstacles_file = "gis/trees.geojson"\n' + SMALL)
    scenario = load_scenario(path)
    assert len(scenario.obstacles) == 2
    assert scenario.obstacles[0] == parse_scenario(SMALL).obstacles[0]  # [[obstacles]] first
    assert scenario.obstacles[1].name == "lychee" and scenario.obstacles[1].radius_m == 2.0


def test_scenario_obstacles_file_errors(tmp_path):
    path = tmp_path / "field.toml"
    path.write_text('obstacles_file = "missing.geojson"\n' + SMALL)
    with pytest.raises(ScenarioError, match="missing.geojson: no such file"):
        load_scenario(path)
    (tmp_path / "bad.geojson").write_text(_collection(_point(109.1150, 12.2334)))
    path.write_text('obstacles_file = "bad.geojson"\n' + SMALL)
    with pytest.raises(ScenarioError, match=re.escape("bad.geojson: features[0]: a Point needs")):
        load_scenario(path)
    path.write_text("obstacles_file = 3\n" + SMALL)
    with pytest.raises(ScenarioError, match="obstacles_file: must be a string"):
        load_scenario(path)


def test_obstacle_from_file_is_checked_against_start(tmp_path):
    """An imported obstacle is a real obstacle: one on top of the start is refused."""
    (tmp_path / "t.geojson").write_text(_collection(_point(109.1145051, 12.2332099, radius=1.0)))
    path = tmp_path / "field.toml"
    path.write_text('obstacles_file = "t.geojson"\n' + SMALL)
    with pytest.raises(ScenarioError,
                       match=r"start: puts UAV 1 .* axis of \S*t\.geojson features\[0\] "):
        load_scenario(path)


def test_shipped_gis_example_has_the_same_trees_as_the_toml_example(example_path):
    toml = load_scenario(example_path)
    gis = load_scenario(example_path.with_name("nha-trang-orchard-gis.toml"))
    assert gis.obstacles_enu()[0].shape == toml.obstacles_enu()[0].shape == (7, 2)
    for got, ref in zip(gis.obstacles, toml.obstacles, strict=True):
        assert abs(got.lat_deg - ref.lat_deg) <= DEG and abs(got.lon_deg - ref.lon_deg) <= DEG
        assert got.radius_m == pytest.approx(ref.radius_m, abs=1e-3)
