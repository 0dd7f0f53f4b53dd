"""Issue 12: every number of a scenario is checked where it enters (finite, in a range
that means something, representable where it goes); formation separation; start equal to
goal; obstacles that cannot matter dropped; sizes too large refused before allocating.

Each case ends with one line naming the file and the field, exit 2, nothing written."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from click.testing import CliRunner

from ftlbo_mav.cli import main
from ftlbo_mav.errors import BadInput, ScenarioError
from ftlbo_mav.flight.planned import load_planned_flight
from ftlbo_mav.mission.export import write_plan
from ftlbo_mav.planning.planner import PlanTooLarge, plan
from ftlbo_mav.scenario import load_scenario, parse_scenario

from .conftest import ROOT, SMALL

# field -> (the line as SMALL has it, the line with {} for the value)
FIELDS = {
    "area.min_altitude": ("min_altitude = 2.0", "min_altitude = {}"),
    "area.max_altitude": ("max_altitude = 7.0", "max_altitude = {}"),
    "start.lat": ("lat = 12.2332099", "lat = {}"),
    "start.alt": ("alt = 4.0\n[goal]", "alt = {}\n[goal]"),
    "goal.lon": ("lon = 109.1151763", "lon = {}"),
    "goal.alt": ("alt = 4.0\n[formation]", "alt = {}\n[formation]"),
    "formation.offsets[1]": ("[3.0, 0.0, -1.0]", "[{}, 0.0, -1.0]"),
    "formation.clearance": ("clearance = 1.0", "clearance = {}"),
    "formation.min_separation": ("clearance = 1.0", "clearance = 1.0\nmin_separation = {}"),
    "formation.max_error": ("clearance = 1.0", "clearance = 1.0\nmax_error = {}"),
    "obstacles[0].lat": ("lat = 12.2333\n", "lat = {}\n"),
    "obstacles[0].radius": ("radius = 3.0", "radius = {}"),
    "planner.students": ("students = 12", "students = {}"),
    "planner.waypoints": ("waypoints = 4", "waypoints = {}"),
    "planner.iterations": ("iterations = 8", "iterations = {}"),
    "planner.seed": ("seed = 0", "seed = {}"),
    "planner.weights.length": ("seed = 0", "seed = 0\nweights = {{ length = {} }}"),
    "mission.speed": ("seed = 0", "seed = 0\n[mission]\nspeed = {}"),
    "survey.spacing": ("seed = 0", "seed = 0\n[survey]\nspacing = {}\nheading = 0.0"),
    "survey.heading": ("seed = 0", "seed = 0\n[survey]\nspacing = 2.5\nheading = {}"),
    "survey.alt": ("seed = 0", "seed = 0\n[survey]\nspacing = 2.5\nheading = 0.0\nalt = {}"),
    "navigation.horizontal_error": ("horizontal_error = 0.0", "horizontal_error = {}"),
}
# Values no field takes: not finite, far beyond anything physical, the wrong type.
BAD_VALUES = ["nan", "inf", "-inf", "1e300", "-1e300", '"12"', "true", "[1.0]"]
# Integers beyond what is sane for the integer fields (memory and time bombs).
HUGE_INTEGERS = {"planner.students": "1000000000", "planner.waypoints": "1000000",
                 "planner.iterations": "1000000000000", "planner.seed": "99999999999999999999"}


def _text(field: str, value: str) -> str:
    old, new = FIELDS[field]
    assert old in SMALL, old
    return SMALL.replace(old, new.format(value), 1)


def _refused(text: str, field: str, tmp_path: Path) -> str:
    """The scenario is refused by load_scenario naming ``field``, and by `plan` in one
    line with exit 2 and nothing written; returns the message."""
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert info.value.field.startswith(field.split("[")[0]), info.value
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["plan", str(path), "-o", str(out), "-q"])
    assert result.exit_code == 2, result.output
    assert result.stderr.strip().splitlines() == [f"error: {info.value}"]
    assert not out.exists() and [p.name for p in tmp_path.iterdir()] == ["bad.toml"]
    return str(info.value)


@pytest.mark.parametrize("value", BAD_VALUES)
@pytest.mark.parametrize("field", list(FIELDS))
def test_every_number_is_finite_in_range_and_a_number(field, value, tmp_path):
    if value in ("1e300", "-1e300") and field.endswith("seed"):
        value = "-1"  # TOML integers cannot be 1e300: the out-of-range integer here
    message = _refused(_text(field, value), field, tmp_path)
    assert str(Path(tmp_path / "bad.toml")) in message


@pytest.mark.parametrize("field", list(HUGE_INTEGERS))
def test_integer_bombs_are_refused_with_the_range(field, tmp_path):
    message = _refused(_text(field, HUGE_INTEGERS[field]), field, tmp_path)
    assert re.search(r"within \[\d+, \d+\]", message)


@pytest.mark.parametrize("field", ["area.max_altitude", "start.alt", "survey.alt",
                                   "obstacles[0].radius", "formation.offsets[1]",
                                   "mission.speed", "planner.weights.length"])
def test_the_range_is_said(field, tmp_path):
    message = _refused(_text(field, "1e30"), field, tmp_path)
    assert re.search(r"within [\[(]-?[\d.e+]+, [\d.e+]+\]", message), message


def test_values_in_range_still_plan_with_finite_outputs(tmp_path):
    text = _text("mission.speed", "12.5").replace("max_altitude = 7.0", "max_altitude = 9000")
    path = tmp_path / "ok.toml"
    path.write_text(text)
    result = CliRunner().invoke(main, ["plan", str(path), "-o", str(tmp_path / "out"), "-q"])
    assert result.exit_code == 0, result.output
    for file in (tmp_path / "out").iterdir():
        assert not re.search(r"\b(nan|inf)\b", file.read_text(), re.I), file


@pytest.mark.parametrize("formation, pair", [
    ("offsets = [[0.0, 0.0, 2.0], [0.0, 0.0, 2.0], [3.0, 0.0, -1.0]]", (1, 2)),
    ("offsets = [[3.0, 0.0, -1.0], [0.0, 0.0, 2.0], [0.1, 0.0, 2.0]]", (2, 3)),
    ("offsets = [[0.0, 0.0, 0.0], [1.5, 0.0, 0.0], [-3.0, 0.0, 0.0]]", (1, 2)),
    ("count = 3\nradius = 0.0", (1, 2)),
    ("count = 40\nradius = 5.0", None),  # 0.79 m between neighbours on the circle
])
def test_formations_closer_than_min_separation_are_refused_naming_the_pair(
        formation, pair, tmp_path):
    text = SMALL.replace(
        "offsets = [[0.0, 0.0, 2.0], [3.0, 0.0, -1.0], [-3.0, 0.0, -1.0]]", formation)
    field = "formation.offsets" if "offsets" in formation else "formation.radius"
    message = _refused(text, field, tmp_path)
    assert "closer than min_separation = 2 m" in message
    if pair:
        assert f"UAV {pair[0]} and UAV {pair[1]}" in message


def test_min_separation_is_a_setting_and_can_be_relaxed():
    close = SMALL.replace("[3.0, 0.0, -1.0], [-3.0, 0.0, -1.0]",
                          "[1.0, 0.0, 2.0], [-3.0, 0.0, -1.0]")
    with pytest.raises(ScenarioError, match="UAV 1 and UAV 2 1.00 m apart"):
        parse_scenario(close)
    relaxed = parse_scenario(close.replace("clearance = 1.0",
                                           "clearance = 1.0\nmin_separation = 0.5"))
    assert relaxed.min_separation_m == 0.5


def test_the_formation_bound_is_a_setting_within_what_the_separation_allows(tmp_path):
    with pytest.raises(ScenarioError, match=r"max_error: must be within \(0, 1000\] m, got 0"):
        parse_scenario(SMALL.replace("clearance = 1.0", "clearance = 1.0\nmax_error = 0"))
    tight = plan(parse_scenario(SMALL.replace(
        "clearance = 1.0", "clearance = 1.0\nmax_error = 0.25")))
    assert tight.scenario.max_formation_error_m == 0.25 and tight.formation_bound_m == 0.25
    # the default 1 m, but no more than half the predicted flight's room beyond
    # min_separation and two copters' navigation error
    loose = plan(parse_scenario(SMALL))
    room = (float(loose.prediction.separation.min()) - 2.0
            - 2 ** 0.5 * loose.scenario.navigation.horizontal_m) / 2
    assert loose.formation_bound_m == pytest.approx(min(1.0, room))
    write_plan(loose, tmp_path)
    doc = json.loads((tmp_path / "plan.json").read_text())
    assert doc["formation_bound"] == {"max_error": 1.0,
                                      "error_m": round(loose.formation_bound_m, 4)}
    assert load_planned_flight(tmp_path).formation_bound_m == round(loose.formation_bound_m, 4)


@pytest.mark.parametrize("path", sorted((ROOT / "missions").glob("*.toml")), ids=lambda p: p.name)
def test_the_shipped_examples_keep_their_uavs_2_m_apart(path):
    s = load_scenario(path)
    assert s.min_separation_m == 2.0  # the default: every example passes it as it is


def test_start_equal_to_goal_is_refused_without_via_and_planned_with_one(tmp_path):
    loop = SMALL.replace("lat = 12.233474\nlon = 109.1151763",
                         "lat = 12.2332099\nlon = 109.1145051")
    _refused(loop, "goal", tmp_path)
    with_via = loop + "[[via]]\nlat = 12.2334\nlon = 109.1150\nalt = 4.0\n"
    path = tmp_path / "loop.toml"
    path.write_text(with_via)
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["plan", str(path), "-o", str(out), "-q"])
    assert result.exit_code in (0, 1), result.output  # planned: feasible or not, no crash
    assert "Traceback" not in result.output and "error" not in result.output


def test_obstacles_that_cannot_reach_the_area_are_dropped_and_counted(tmp_path):
    far = "".join(f"[[obstacles]]\nlat = {10.0 + i * 1e-4:.4f}\nlon = 100.0\nradius = 1.0\n"
                  for i in range(2000))
    # 3 m north of the area, radius 3 m + clearance 1 m: it reaches in, and is kept
    edge = "[[obstacles]]\nlat = 12.23358\nlon = 109.1148\nradius = 3.0\n"
    s = parse_scenario(SMALL.replace("[planner]", far + edge + "[planner]"))
    assert len(s.obstacles) == 2 and s.dropped_obstacles == 2000
    path = tmp_path / "far.toml"
    path.write_text(SMALL.replace("[planner]", far + "[planner]"))
    result = CliRunner().invoke(main, ["plan", str(path), "-o", str(tmp_path / "out"), "-q"])
    assert result.exit_code == 0, result.output
    assert "note: 2000 obstacles left out" in result.stderr


@pytest.mark.parametrize("overrides", [
    {"students": 10**9}, {"waypoints": 10**6}, {"iterations": 10**12},
    {"students": 100_000, "waypoints": 1000},
    {"students": 100_000, "iterations": 1_000_000},
])
def test_sizes_beyond_memory_or_time_are_refused_before_allocating(overrides):
    scenario = parse_scenario(SMALL)
    with pytest.raises(PlanTooLarge) as info:
        plan(scenario, **overrides)  # would be a MemoryError or hours without the check
    assert isinstance(info.value, BadInput) and "fewer" in str(info.value)


@pytest.mark.parametrize("option, value", [
    ("--students", "1000000000"), ("--waypoints", "1000000"), ("--iterations", "10000000000"),
    ("--seed", "99999999999999999999"), ("--seed", "-1"), ("--students", "3"),
])
def test_command_line_overrides_have_the_scenario_ranges(option, value, small_path, tmp_path):
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["plan", str(small_path), "-o", str(out), option, value])
    assert result.exit_code == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error:") and option in lines[0]
    assert not out.exists()


def test_a_survey_too_fine_to_fly_is_refused_before_laying_lanes(tmp_path):
    text = SMALL.replace("[planner]", "[survey]\nspacing = 1e-6\nheading = 0.0\n[planner]")
    message = _refused(text, "survey.spacing", tmp_path)
    assert "lanes" in message


def test_an_area_the_size_of_a_country_is_refused(tmp_path):
    text = SMALL.replace("corner_b = [12.2331044, 109.1152252]", "corner_b = [2.0, 119.0]")
    message = _refused(text, "area.corner_b", tmp_path)
    assert "km" in message
