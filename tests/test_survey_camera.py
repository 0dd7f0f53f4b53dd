"""`[camera]`: footprint, GSD, spacing from the side overlap, trigger items at every lane's
entry and exit, the photos the written missions take and what they cover; the refused
camera tables; plan.json, GeoJSON, KML and the summary."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from ftlbo_mav.cli import main
from ftlbo_mav.errors import ScenarioError
from ftlbo_mav.mission.items import CMD_DO_SET_CAM_TRIGG_DIST, CMD_NAV_WAYPOINT
from ftlbo_mav.mission.photos import coverage, mission_photos
from ftlbo_mav.mission.plan_reader import read_plan
from ftlbo_mav.mission.waypoints import read_waypoints
from ftlbo_mav.scenario import parse_scenario

from .conftest import ROOT

# 40 m x 30 m, the paper's triangle at 10 m (UAVs at 12, 9, 9 m)
FIELD = """\
name = "camera field"
[navigation]
horizontal_error = 0.0
[area]
corner_a = [12.2340000, 109.1160000]
corner_b = [12.2342713, 109.1163677]
min_altitude = 2.0
max_altitude = 30.0
[start]
lat = 12.2340300
lon = 109.1160460
alt = 10.0
[goal]
lat = 12.2340300
lon = 109.1160460
alt = 10.0
[formation]
offsets = [[0.0, 0.0, 2.0], [3.0, 0.0, -1.0], [-3.0, 0.0, -1.0]]
[survey]
heading = 0.0
margin = 0.0
[planner]
students = 12
waypoints = 1
iterations = 4
"""
CAMERA = """
[camera]
sensor_width_mm = 13.2
sensor_height_mm = 8.8
focal_length_mm = 8.8
image_width_px = 5472
image_height_px = 3648
front_overlap = 0.7
side_overlap = 0.6
"""


def _with(camera: str = CAMERA, survey: str = "", **replace) -> str:
    text = FIELD + camera
    if survey:
        text = text.replace("margin = 0.0\n", "margin = 0.0\n" + survey)
    for old, new in replace.items():
        text = text.replace(old, new)
    return text


def test_the_spacing_comes_from_the_side_overlap_and_the_formation():
    s = parse_scenario(_with())
    sv = s.survey
    # the lowest UAVs (9 m) see 13.5 m x 9 m; 6 m of formation + 13.5 m x (1 - 0.6)
    assert sv.spacing_m == pytest.approx(6.0 + 13.5 * 0.4)
    assert sv.lane_spacing_m <= sv.spacing_m and len(sv.lanes) == 4
    assert sv.trigger_distance_m == pytest.approx(9.0 * 0.3)


def test_gsd_chooses_the_altitude_of_the_highest_uav():
    s = parse_scenario(_with(CAMERA + "gsd_cm = 0.3\n"))
    top = s.survey.alt_m + 2.0
    assert float(s.survey.camera.gsd(top)) == pytest.approx(0.3)


@pytest.mark.parametrize("text, field, problem", [
    (_with(CAMERA.replace("focal_length_mm = 8.8", "focal_length_mm = 0")),
     "camera.focal_length_mm", "must be within (0,"),
    (_with(CAMERA.replace("side_overlap = 0.6", "side_overlap = 1")), "camera.side_overlap",
     "within [0, 1)"),
    (_with(CAMERA.replace("front_overlap = 0.7", "front_overlap = 1.5")),
     "camera.front_overlap", "within [0, 1]"),
    (_with(CAMERA.replace("focal_length_mm = 8.8", "focal_length_mm = 200")), "camera",
     "no wider than a UAV's position error"),
    (_with(CAMERA.replace("focal_length_mm = 8.8", "focal_length_mm = 40")),
     "camera.side_overlap", "UAVs 3 and 1 fly 3.00 m apart"),
    (_with(survey="spacing = 20.0\n"), "survey.spacing",
     "20 m cannot reach camera.side_overlap 0.6: at most 11.40 m"),
    (_with(survey="margin = 30.0\n").replace("margin = 0.0\n", ""), "survey.margin",
     "leaves no room for a lane"),
    (_with(CAMERA + "gsd_cm = 0.3\n", survey="alt = 10.0\n"), "survey.alt",
     "not both"),
    (_with(CAMERA + "lens = 3\n"), "camera.lens", "unknown key"),
    (FIELD.replace("[survey]\nheading = 0.0\nmargin = 0.0\n", "") + CAMERA, "camera",
     "needs a [survey]"),
    (FIELD.replace("heading = 0.0\n", "heading = 0.0\nspacing = -1\n"), "survey.spacing",
     "must be within (0,"),
])
def test_bad_camera_tables_get_one_clear_line(text, field, problem):
    with pytest.raises(ScenarioError) as err:
        parse_scenario(text, source="s.toml")
    assert err.value.field == field, str(err.value)
    assert problem in err.value.problem, err.value.problem
    assert "\n" not in str(err.value)


@pytest.fixture(scope="module")
def planned(tmp_path_factory):
    folder = tmp_path_factory.mktemp("camera")
    path = folder / "field.toml"
    path.write_text(_with())
    out = folder / "out"
    result = CliRunner().invoke(main, ["plan", str(path), "-o", str(out), "-q", "--formats",
                                       "geojson,kml", "--plot"])
    assert result.exit_code == 0, result.output
    return out, result


def test_each_lane_turns_triggering_on_at_its_entry_and_off_at_its_exit(planned):
    out, _ = planned
    doc = json.loads((out / "plan.json").read_text())
    lanes = doc["survey"]["lanes"]
    frame = read_plan(out).scenario.frame
    for uav in doc["uavs"]:
        items = read_waypoints(out / uav["mission_file"])
        triggers = [(k, it) for k, it in enumerate(items)
                    if it.command == CMD_DO_SET_CAM_TRIGG_DIST]
        assert len(triggers) == 2 * len(lanes)
        for j, (k, it) in enumerate(triggers):
            before = items[k - 1]
            assert before.command == CMD_NAV_WAYPOINT
            lane = lanes[j // 2][j % 2]  # the centroid's lane end; the UAV's is offset
            off = np.array(uav["offset"][:2])
            got = frame.to_enu(lat_deg=before.lat_deg, lon_deg=before.lon_deg)[:2]
            want = frame.to_enu(lat_deg=lane[0], lon_deg=lane[1])[:2]
            assert np.allclose(got, want + off, atol=0.01)
            if j % 2 == 0:  # on, a photo at once
                assert it.param1 == pytest.approx(doc["survey"]["camera"]["trigger_distance"])
                assert it.param3 == 1
            else:
                assert it.param1 == 0


def test_the_written_missions_photograph_the_whole_field(planned):
    """From the mission files alone: where each UAV triggers (AP_Camera's distance
    triggering) and that the footprints cover the area, margin 0."""
    out, result = planned
    plan = read_plan(out)
    sv = plan.scenario.survey
    doc = json.loads((out / "plan.json").read_text())
    photos = [mission_photos(u["name"], read_waypoints(out / u["mission_file"]),
                             frame=plan.scenario.frame, camera=sv.camera,
                             heading_deg=sv.heading_deg, nav=plan.scenario.vehicle)
              for u in doc["uavs"]]
    lower, upper = plan.scenario.area_bounds_enu()
    assert coverage(photos, lower=lower, upper=upper) >= 0.98
    for p, u, cam in zip(photos, doc["uavs"], doc["survey"]["camera"]["uavs"]):
        assert p.count == u["photos"] == cam["photos"] > 0
        # on the UAV's lanes as the copter flies them: on the line along the lane, off it
        # only where the copter rounds the corner at a lane's end
        across = p.positions[:, 0] - u["offset"][0]
        lanes_x = np.array([plan.scenario.frame.to_enu(lat_deg=a[0], lon_deg=a[1])[0]
                            for a, _ in doc["survey"]["lanes"]])
        off = np.abs(across[:, None] - lanes_x[None, :]).min(axis=1)
        assert np.median(off) < 0.1 and off.max() < 1.0, off
    # each UAV's line in the summary, and the lanes
    assert "survey: 4 lanes 11.26 m apart (at most 11.40 m)" in result.stdout
    assert "laid 0.30 m further in, where the copters were predicted to swing out" in result.stdout
    assert "camera uav2: at 9.00 m a footprint 13.50 x 9.00 m" in result.stdout
    assert f"{sum(p.count for p in photos)} photos in all" in result.stdout


def test_the_photo_layer_in_geojson_kml_and_a_redrawn_figure(planned, tmp_path):
    out, _ = planned
    doc = json.loads((out / "plan.json").read_text())
    geo = json.loads((out / "plan.geojson").read_text())
    kinds = [f["properties"]["kind"] for f in geo["features"]]
    total = sum(u["photos"] for u in doc["uavs"])
    assert kinds.count("photo") == kinds.count("photo_footprint") == total
    ring = next(f for f in geo["features"] if f["properties"]["kind"] == "photo_footprint")
    assert len(ring["geometry"]["coordinates"][0]) == 5  # a closed rectangle
    kml = (out / "plan.kml").read_text()
    assert kml.count("uav1 photo ") == doc["uavs"][0]["photos"]
    # plan.json carries the camera: read back, the same photos (ftlbo-mav plot)
    again = read_plan(out)
    assert again.scenario.survey.camera == parse_scenario(_with()).survey.camera
    assert (out / "plan-ground.png").stat().st_size > 10_000


def test_the_shipped_field_survey_is_what_the_planner_writes(tmp_path):
    scenario = ROOT / "missions" / "field-survey.toml"
    out = tmp_path / "field"
    result = CliRunner().invoke(main, ["plan", str(scenario), "-o", str(out), "-q"])
    assert result.exit_code == 0, result.output
    for n in (1, 2, 3):
        assert (out / f"uav{n}.waypoints").read_text() == (
            ROOT / "missions" / "field-survey" / f"uav{n}.waypoints").read_text()
