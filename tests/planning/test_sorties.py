"""A survey larger than one battery, planned in sorties (planning/sorties.py, `plan`):
whole lanes in order, none skipped or flown twice, nor its photos; each sortie from home
to home within the battery; the fewest sorties; refusals."""

from __future__ import annotations

import json
from functools import cache

import numpy as np
import pytest
from click.testing import CliRunner

from ftlbo_mav.cli import main
from ftlbo_mav.mission.export import plan_missions
from ftlbo_mav.mission.photos import plan_photos
from ftlbo_mav.planning.planner import plan
from ftlbo_mav.planning.sorties import SortieError, cut, plan_sorties
from ftlbo_mav.scenario import load_scenario

from ..conftest import ROOT

# SITL's quad's battery as recorded (tests/data/ardupilot-4.5.6/battery.json), smaller
BATTERY = """
[battery]
capacity = {capacity}
reserve = 25
hover_current = 28.12
cruise_current = 30.55
cruise_speed = 9.85
"""


def _scenario_file(tmp_path, capacity: float):
    path = tmp_path / "field.toml"
    path.write_text((ROOT / "missions" / "field-survey.toml").read_text()
                    + BATTERY.format(capacity=capacity))
    return path


@cache
def _sorties(capacity: float):
    import tempfile
    from pathlib import Path

    folder = Path(tempfile.mkdtemp())
    return plan_sorties(load_scenario(_scenario_file(folder, capacity)), plan)


def _photos(p) -> int:
    return sum(u.count for u in plan_photos(p, plan_missions(p)))


def test_a_survey_that_fits_one_battery_is_one_plan():
    s = _sorties(3300.0)
    assert not s.split and s.plans == (s.whole,) and s.whole.feasible


def test_lanes_in_order_none_skipped_or_twice_each_sortie_home_to_home_within_the_battery():
    s = _sorties(1200.0)
    whole = s.whole
    assert not whole.feasible  # 1,367 mAh in one flight: below the 25 % reserve
    assert s.split and len(s.plans) == 3
    lanes = whole.scenario.survey.lanes
    flown = [lane for p in s.plans for lane in p.scenario.survey.lanes]
    assert flown == list(lanes)  # every lane once, in order, as laid for the whole
    assert [(a, b) for a, b in s.lanes] == [(0, 1), (2, 3), (4, 5)]
    battery = whole.scenario.battery
    home = whole.uav_paths[:, 0]
    for p in s.plans:
        assert p.feasible, p.violations
        assert max(c.total_mah for c in p.charges) <= battery.usable_mah
        assert np.allclose(p.uav_paths[:, 0], home, atol=1e-6)  # from home
        assert np.allclose(p.uav_paths[:, -1, :2], home[:, :2], atol=1e-6)  # to home
    # and the photos: the whole survey's, no more and no fewer
    assert sum(_photos(p) for p in s.plans) == _photos(whole) > 0


def test_the_fewest_sorties_that_whole_lanes_allow():
    costs = {(0, 0): 5, (0, 1): 9, (0, 2): 14, (1, 1): 5, (1, 2): 9, (2, 2): 5, (2, 3): 9,
             (3, 3): 5, (1, 3): 14, (0, 3): 19}
    assert cut(lambda a, b: costs[a, b], 4, 10.0) == [(0, 1), (2, 3)]
    # taking lanes while they fit would fly 0-1, then 2 and 3 alone (the ways to 2 and 3
    # are long): three sorties where two do
    costs = {(0, 0): 5, (0, 1): 10, (0, 2): 15, (0, 3): 20, (1, 1): 5, (1, 2): 8, (1, 3): 10,
             (2, 2): 5, (2, 3): 11, (3, 3): 5}
    assert cut(lambda a, b: costs[a, b], 4, 10.0) == [(0, 0), (1, 3)]


def test_a_lane_no_battery_can_fly_is_refused_with_its_figure():
    with pytest.raises(SortieError, match="lane 1 alone needs about .* mAh"):
        cut(lambda a, b: 100.0 * (b - a + 1), 3, 50.0)


def test_plan_writes_each_sortie_as_a_plan_folder_and_sorties_json(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "uav1.waypoints").write_text("an earlier plan's\n")  # not this plan's: removed
    result = CliRunner().invoke(main, ["plan", str(_scenario_file(tmp_path, 1200.0)), "-o",
                                       str(out), "-q"])
    assert result.exit_code == 0, result.output
    assert "planning it in sorties, each from home to home" in result.output
    assert "sortie 1: lanes 1-2; at most" in result.output
    doc = json.loads((out / "sorties.json").read_text())
    assert [r["folder"] for r in doc["sorties"]] == ["sortie1", "sortie2", "sortie3"]
    assert [r["lanes"] for r in doc["sorties"]] == [[1, 2], [3, 4], [5, 6]]
    assert doc["lanes"] == 6 and not doc["whole"]["feasible"]
    for k in (1, 2, 3):
        folder = out / f"sortie{k}"
        assert {p.name for p in folder.glob("uav*.waypoints")} == {
            "uav1.waypoints", "uav2.waypoints", "uav3.waypoints"}
        assert json.loads((folder / "plan.json").read_text())["feasible"]
    assert not (out / "uav1.waypoints").exists()
    # planned again with a battery that flies it whole: the sorties are gone
    result = CliRunner().invoke(main, ["plan", str(_scenario_file(tmp_path, 3300.0)), "-o",
                                       str(out), "-q"])
    assert result.exit_code == 0, result.output
    assert (out / "uav1.waypoints").is_file()
    assert not (out / "sorties.json").exists()
    assert not (out / "sortie1").exists()
