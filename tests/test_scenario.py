"""Scenario reading, and every bad input the issue names: one line, exit 2, nothing written."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from ftlbo_mav.cli import main
from ftlbo_mav.errors import ScenarioError
from ftlbo_mav.scenario import load_scenario, parse_scenario

from .conftest import SMALL


def test_example_loads_with_the_papers_settings(example_path):
    s = load_scenario(example_path)
    assert s.uav_count == 3
    # the paper's class size and iterations; waypoints "auto" and a cruise speed are for
    # ArduCopter's S-curve (docs/flight.md)
    assert s.planner.students == 100 and s.planner.waypoints == "auto"
    assert s.mission.speed_m_s == 5.0
    assert s.planner.iterations == 150
    assert (s.min_altitude_m, s.max_altitude_m) == (2.0, 7.0)
    assert len(s.obstacles) >= 6 and len({c.radius_m for c in s.obstacles}) > 1
    assert s.corner_b.lat_deg == pytest.approx(12.2331044)  # the 112.23 typo corrected


def test_defaults_when_optional_tables_are_missing(small_text):
    text = small_text.split("[planner]")[0]
    s = parse_scenario(text)
    assert s.planner.students == 100 and s.planner.seed == 0
    assert s.mission.end_action == "land" and s.mission.speed_m_s is None


def test_generated_formation(small_text):
    text = small_text.replace(
        "offsets = [[0.0, 0.0, 2.0], [3.0, 0.0, -1.0], [-3.0, 0.0, -1.0]]",
        'count = 5\nradius = 2.0\nplane = "horizontal"',
    )
    s = parse_scenario(text)
    assert s.uav_count == 5
    assert np.allclose(np.linalg.norm(s.offsets_m, axis=1), 2.0)


def _replace(text: str, old: str, new: str) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


BAD = {
    "latitude above 90 (the paper's typo)": (
        ("corner_b = [12.2331044,", "corner_b = [112.2331044,"), "area.corner_b[0]", "latitude"),
    "longitude outside [-180, 180]": (
        ("lon = 109.1145051", "lon = 209.1145051"), "start.lon", "longitude"),
    "min_altitude >= max_altitude": (
        ("min_altitude = 2.0", "min_altitude = 7.0"), "area.min_altitude", "below max_altitude"),
    "start outside the area": (
        ("lat = 12.2332099", "lat = 12.2339"), "start.lat", "outside the area"),
    "goal outside the area": (
        ("lon = 109.1151763", "lon = 109.1153"), "goal.lon", "outside the area"),
    "start puts a UAV inside an obstacle": (
        ("lat = 12.2333\nlon = 109.1148", "lat = 12.2332099\nlon = 109.1145340"),
        "start", "obstacles[0]"),
    "goal puts a UAV outside the band": (
        ("alt = 4.0\n[formation]", "alt = 6.0\n[formation]"), "goal.alt", "altitude band"),
    "non-positive radius": (("radius = 3.0", "radius = 0.0"), "obstacles[0].radius", "within (0,"),
    "unknown key": (("clearance = 1.0", "clearence = 1.0"), "formation.clearence", "unknown key"),
    "wrong type": (("students = 12", 'students = "twelve"'), "planner.students", "integer"),
    "missing field": (("max_altitude = 7.0\n", ""), "area.max_altitude", "missing"),
    "malformed TOML": (("[goal]", "[goal"), "", "malformed TOML"),
    "waypoints < 1": (("waypoints = 4", "waypoints = 0"), "planner.waypoints", "within [1,"),
    "students < 4": (("students = 12", "students = 3"), "planner.students", "within [4,"),
}


@pytest.mark.parametrize("case", list(BAD), ids=list(BAD))
def test_bad_input_is_one_clear_line_exit_2_nothing_written(case, tmp_path):
    (old, new), field, words = BAD[case]
    path = tmp_path / "bad.toml"
    path.write_text(_replace(SMALL, old, new))
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert info.value.field == field
    assert words in str(info.value)

    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["plan", str(path), "-o", str(out)])
    assert result.exit_code == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert str(path) in lines[0] and field in lines[0] and words in lines[0]
    assert "Traceback" not in result.output
    assert not out.exists()


def test_missing_file_is_one_line_exit_2(tmp_path):
    missing = tmp_path / "nope.toml"
    result = CliRunner().invoke(main, ["plan", str(missing), "-o", str(tmp_path / "out")])
    assert result.exit_code == 2
    assert result.stderr.strip().splitlines() == [f"error: {missing}: no such file"]


def test_offsets_and_count_together_are_refused(small_text):
    text = small_text.replace("clearance = 1.0", "clearance = 1.0\ncount = 3")
    with pytest.raises(ScenarioError, match="not both"):
        parse_scenario(text)


def test_the_vehicle_table_takes_arducopters_parameters(small_text):
    from ftlbo_mav.scenario import parse_scenario

    assert parse_scenario(small_text).vehicle.wp_accel == 2.5  # ArduCopter's default
    s = parse_scenario(small_text + "[vehicle]\nWPNAV_ACCEL = 100\nWPNAV_JERK = 2.0\n")
    assert (s.vehicle.wp_accel, s.vehicle.wp_jerk) == (1.0, 2.0)
    for bad, said in (("WPNAV_SPEDE = 5", "vehicle.WPNAV_SPEDE: unknown key"),
                      ("WPNAV_ACCEL = 5000", "vehicle.WPNAV_ACCEL"),
                      ("WPNAV_JERK = 'fast'", "vehicle.WPNAV_JERK")):
        with pytest.raises(ScenarioError, match=said.replace(".", r"\.")):
            parse_scenario(small_text + f"[vehicle]\n{bad}\n")


def _polygon_feature(lat_lon: list[tuple[float, float]], **props) -> dict:
    ring = [[lon, lat] for lat, lon in lat_lon]
    return {"type": "Feature", "properties": props,
            "geometry": {"type": "Polygon", "coordinates": [ring + ring[:1]]}}


@pytest.mark.parametrize("props, named", [
    ({"name": "boundary"}, "gis/layer.geojson features[1] ('boundary') (radius"),
    ({}, "gis/layer.geojson features[1] (radius"),
])
def test_a_polygon_over_the_whole_area_is_refused_naming_its_file_and_feature(
        tmp_path, props, named):
    import json

    # a little beyond the area's corners (12.2331044..12.2335526, 109.1144313..109.1152252)
    outline = [(12.2330, 109.1143), (12.2330, 109.1154), (12.2337, 109.1154),
               (12.2337, 109.1143)]
    far = _polygon_feature([(12.30, 109.20), (12.30, 109.21), (12.31, 109.21)])  # dropped
    (tmp_path / "gis").mkdir()
    (tmp_path / "gis" / "layer.geojson").write_text(json.dumps(
        {"type": "FeatureCollection", "features": [far, _polygon_feature(outline, **props)]}))
    path = tmp_path / "field.toml"
    path.write_text('obstacles_file = "gis/layer.geojson"\n' + SMALL)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    message = str(info.value)
    assert message.startswith(f"{path}: start: puts UAV 1 "), message
    assert f"from the axis of {tmp_path}/{named}" in message, message
    assert "covers the whole area, start and goal included" in message, message


def test_a_table_obstacle_on_the_start_is_named_by_its_table_and_name(small_text):
    text = _replace(small_text, "lat = 12.2333\nlon = 109.1148\nradius = 3.0",
                    'lat = 12.2332099\nlon = 109.1145340\nradius = 3.0\nname = "mango"')
    with pytest.raises(ScenarioError, match=r"start: puts UAV 1 .* axis of obstacles\[0\] "
                                            r"\('mango'\) \(radius 3 m"):
        parse_scenario(text)


def _area(text: str, corner_a, corner_b, start, goal) -> str:
    """SMALL with its area, start and goal moved (and no obstacle)."""
    text = _replace(text, "corner_a = [12.2335526, 109.1144313]", f"corner_a = {list(corner_a)}")
    text = _replace(text, "corner_b = [12.2331044, 109.1152252]", f"corner_b = {list(corner_b)}")
    text = _replace(text, "lat = 12.2332099\nlon = 109.1145051", "lat = {}\nlon = {}".format(
        *start))
    text = _replace(text, "lat = 12.233474\nlon = 109.1151763", "lat = {}\nlon = {}".format(
        *goal))
    return _replace(text, "[[obstacles]]\nlat = 12.2333\nlon = 109.1148\nradius = 3.0\n", "")


@pytest.mark.parametrize("corners, start, goal, field, words", [
    (((12.2335, 179.999), (12.2331, -179.999)), (12.2333, 179.9995), (12.2333, -179.9995),
     "area.corner_b", ("across the antimeridian", "not supported", "lat/lon box")),
    (((12.2335, -179.9995), (12.2331, 179.9995)), (12.2333, 179.9998), (12.2333, -179.9998),
     "area.corner_b", ("across the antimeridian",)),
    (((89.9995, 0.0), (90.0, 10.0)), (89.9997, 1.0), (89.9998, 2.0),
     "area.corner_b[0]", ("latitude 90 is a pole", "not supported", "east/north frame")),
    (((-90.0, 0.0), (-89.9995, 10.0)), (-89.9997, 1.0), (-89.9998, 2.0),
     "area.corner_a[0]", ("latitude -90 is a pole",)),
])
def test_an_area_across_the_antimeridian_or_at_a_pole_is_refused_saying_why(
        tmp_path, corners, start, goal, field, words):
    path = tmp_path / "far.toml"
    path.write_text(_area(SMALL, *corners, start, goal))
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert info.value.field == field, str(info.value)
    for word in words:
        assert word in info.value.problem, str(info.value)
    result = CliRunner().invoke(main, ["plan", str(path), "-o", str(tmp_path / "out")])
    assert result.exit_code == 2 and result.stderr.count("\n") == 1, result.output
    assert not (tmp_path / "out").exists()


def test_an_area_beside_the_antimeridian_is_still_read(small_text):
    s = parse_scenario(_area(small_text, (12.2335, 179.9992), (12.2331, 180.0),
                             (12.2333, 179.99925), (12.2333, 179.99995)))
    assert s.uav_count == 3
