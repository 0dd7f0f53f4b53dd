"""`[[via]]`, `[survey]` and `waypoints = "auto"` in scenario files and on the command
line: refused inputs in one line, plan.json per leg and in total, figures, the example."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from ftlbo_mav.cli import main
from ftlbo_mav.errors import ScenarioError
from ftlbo_mav.mission.plan_reader import read_plan
from ftlbo_mav.mission.waypoints import read_waypoints
from ftlbo_mav.scenario import AUTO, parse_scenario

from .conftest import ROOT, SMALL
from .test_docs import assert_quotes_hold

SURVEY = ROOT / "missions" / "orchard-survey.toml"
HEAD = SMALL.split("[planner]")[0]
PLANNER = "\n[planner]\nstudents = 12\nwaypoints = 3\niterations = 6\n"


def via(lat: float, lon: float, alt: float = 4.0, name: str | None = None) -> str:
    label = f'name = "{name}"\n' if name else ""
    return f"\n[[via]]\nlat = {lat}\nlon = {lon}\nalt = {alt}\n{label}"


GOAL = "lat = 12.233474\nlon = 109.1151763"
AT_START = "lat = 12.2332099\nlon = 109.1145051"


@pytest.mark.parametrize("text, field, problem", [
    (HEAD + via(12.2340, 109.1146), "via[0].lat", "outside the area"),
    (HEAD + via(12.2333, 109.1148), "via[0]", "from the axis of obstacles[0]"),
    (HEAD + via(12.2334800, 109.1146, alt=6.5), "via[0].alt", "outside the altitude band"),
    (HEAD + via(12.2334, 109.1146) + via(12.2334, 109.1144400), "via[1]",
     "puts UAV 3 outside the area"),  # 1 m inside the west side, UAV 3 is 3 m west
    (HEAD.replace(GOAL, AT_START), "goal", "a loop needs [[via]] points"),
    (HEAD + via(12.2332099, 109.1145051), "via[0]", "same place as start"),
    (HEAD + '\n[survey]\nspacing = 0\nheading = 0\n', "survey.spacing", "must be within (0,"),
    (HEAD + '\n[survey]\nspacing = 10\nheading = 0\nmargin = 40\n', "survey.margin",
     "leaves no room"),
    (HEAD + '\n[survey]\nspacing = 10\nheading = 0\nalt = 9\n', "survey.alt",
     "outside the altitude band"),
    (HEAD + '\n[survey]\nspacing = 10\nheading = 0\nspeed = 3\n', "survey.speed", "unknown key"),
    (HEAD + '\n[planner]\nwaypoints = "many"\n', "planner.waypoints", '"auto"'),
])
def test_bad_via_points_and_surveys_are_refused_like_a_bad_start(text, field, problem):
    with pytest.raises(ScenarioError) as err:
        parse_scenario(text, source="s.toml")
    assert err.value.field == field, str(err.value)
    assert problem in err.value.problem
    assert "\n" not in str(err.value)


def test_the_command_line_says_it_in_one_line_exit_2(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(HEAD + via(12.2333, 109.1148))
    result = CliRunner().invoke(main, ["plan", str(path), "-o", str(tmp_path / "out")])
    assert result.exit_code == 2
    assert result.stderr.strip().count("\n") == 0
    assert "via[0]" in result.stderr and "Traceback" not in result.output
    assert not (tmp_path / "out").exists()


def test_via_names_and_a_survey_after_them(tmp_path):
    text = HEAD + via(12.2334800, 109.1146, name="gate") + (
        "\n[survey]\nspacing = 15\nheading = 90\n") + PLANNER
    s = parse_scenario(text)
    assert s.via[0].name == "gate"
    lanes = s.survey.lanes
    assert len(lanes) >= 2 and len(s.via) == 1 + 2 * len(lanes)
    assert s.route_names()[1:4] == ("gate", "lane 1 start", "lane 1 end")
    assert s.survey.margin_m == 7.5  # half the spacing by default
    assert s.survey.alt_m == s.start.alt_m
    # east-west lanes, the first one the northern (nearest the gate), entered at its west end
    enu = s.route_enu()
    assert enu[2, 1] == pytest.approx(enu[3, 1]) and enu[2, 0] < enu[3, 0]
    assert enu[2, 1] == pytest.approx(enu[2:-1, 1].max())


def test_plan_json_reports_every_leg_and_the_total(tmp_path):
    path = tmp_path / "loop.toml"
    path.write_text(HEAD.replace(GOAL, AT_START) + via(12.2334800, 109.1146, name="north")
                    + via(12.2334700, 109.1151, name="east") + PLANNER)
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["plan", str(path), "-o", str(out), "--waypoints", "auto",
                                       "--plot", "--formats", "all"])
    assert result.exit_code == 0, result.output
    doc = json.loads((out / "plan.json").read_text())
    assert doc["waypoints"] == AUTO
    legs = doc["legs"]
    assert [(g["from"], g["to"]) for g in legs] == [("start", "north"), ("north", "east"),
                                                    ("east", "goal")]
    assert doc["lower_bound_length"] == pytest.approx(
        sum(g["lower_bound_length"] for g in legs), abs=1e-3)
    assert doc["cost"]["length"] == pytest.approx(sum(g["cost"]["length"] for g in legs))
    assert doc["evaluations"] == sum(g["evaluations"] for g in legs)
    assert doc["waypoint_count"] == sum(g["waypoints"] for g in legs) + 2
    assert len(doc["centroid"]) == doc["waypoint_count"] + 2
    for g in legs:
        assert g["waypoints"] in g["waypoints_tried"]
        start = doc["centroid"][g["first_point"]]
        end = doc["centroid"][g["first_point"] + g["waypoints"] + 1]
        assert start != end
    # the count each leg chose is said, one line per leg
    for k, g in enumerate(legs):
        assert f"leg {k + 1}/3 {g['from']} -> {g['to']}: {g['waypoints']} waypoint" in (
            result.stderr)
    assert "3 legs" in result.stdout and "auto waypoints per leg" in result.stdout
    # one continuous mission per UAV: one takeoff, one landing, every point in between
    for uav in doc["uavs"]:
        items = read_waypoints(out / uav["mission_file"])
        names = [i.name for i in items]
        assert names.count("TAKEOFF") == 1 and names.count("LAND") == 1
        # home, takeoff, every point, the start gate, the landing
        assert names[-1] == "LAND" and len(items) == 2 + len(doc["centroid"]) + 1 + 1
    # read back (ftlbo-mav plot): the legs, the via points
    again = read_plan(out)
    assert [g.waypoints for g in again.legs] == [g["waypoints"] for g in legs]
    assert [v.name for v in again.scenario.via] == ["north", "east"]
    assert (out / "plan-ground.png").stat().st_size > 20_000


def test_waypoints_auto_from_the_command_line_and_refused_words(small_path, tmp_path):
    bad = CliRunner().invoke(main, ["plan", str(small_path), "-o", str(tmp_path / "o"),
                                    "--waypoints", "lots"])
    assert bad.exit_code == 2 and "neither an integer within 1..1000 nor auto" in bad.output
    zero = CliRunner().invoke(main, ["plan", str(small_path), "-o", str(tmp_path / "o"),
                                     "--waypoints", "0"])
    assert zero.exit_code == 2


def _timeless(doc):
    """A plan.json document without its ``seconds`` (how long the planning took)."""
    if isinstance(doc, dict):
        return {k: _timeless(v) for k, v in doc.items() if k != "seconds"}
    if isinstance(doc, list):
        return [_timeless(v) for v in doc]
    return doc


def test_the_shipped_survey_missions_are_what_the_planner_writes(tmp_path):
    out = tmp_path / "survey"
    result = CliRunner().invoke(main, ["plan", str(SURVEY), "-o", str(out), "-q"])
    assert result.exit_code == 0, result.output
    # and what the README quotes it as printing (tests/test_docs.py)
    assert_quotes_hold("ftlbo-mav plan missions/orchard-survey.toml -o out", result.output)
    shipped = SURVEY.with_suffix("")
    for n in (1, 2, 3):
        assert (out / f"uav{n}.waypoints").read_text() == (
            shipped / f"uav{n}.waypoints").read_text()
    # every file alike, plan.json but for the planning's seconds: the shipped folder is what
    # tests/integration/test_survey.py flies
    written = sorted(p.name for p in out.iterdir() if p.is_file())
    assert written == sorted(p.name for p in shipped.iterdir() if p.is_file())
    for name in written:
        if name != "plan.json":
            assert (out / name).read_text() == (shipped / name).read_text(), name
    assert _timeless(json.loads((out / "plan.json").read_text())) == _timeless(
        json.loads((shipped / "plan.json").read_text()))
    doc = json.loads((shipped / "plan.json").read_text())
    assert doc["feasible"] and len(doc["legs"]) == 2 * len(doc["survey"]["lanes"]) + 1
    # the plan flies every lane end, in order, at the survey altitude (the lanes as the
    # planner laid them: further in than the margin where the copters would swing out)
    plan = read_plan(shipped)
    firsts = [g.centroid[0] for g in plan.legs] + [plan.centroid[-1]]
    assert np.allclose(firsts, plan.scenario.route_enu(), atol=1e-3)
