"""A survey the formation cannot turn in (planning/turns.py): refused before planning,
naming the headland and by how much it is short; accepted when one headland is wide
enough, and never for the shipped examples."""

from __future__ import annotations

import glob
import time

import numpy as np
import pytest

from ftlbo_mav.errors import ScenarioError
from ftlbo_mav.geo import LocalFrame
from ftlbo_mav.planning import turns as T
from ftlbo_mav.planning.planner import plan
from ftlbo_mav.planning.problem import PlanningProblem
from ftlbo_mav.scenario import load_scenario, parse_scenario

COLUMN = np.array([[0.0, 4.0, 0.0], [0.0, 0.0, 0.0], [0.0, -4.0, 0.0]])
LINE = np.array([[-4.0, 0.0, 0.0], [0.0, 0.0, 0.0], [4.0, 0.0, 0.0]])
KEPT = 2.24  # canopy 1.2 m + clearance 1 m + rtk-fixed's 0.04 m


def rows(*, rows: int = 2, per_row: int = 6, south: float = 10.0, north: float = 10.0,
         offsets: np.ndarray = COLUMN, row_m: float = 7.0, tree_m: float = 4.0
         ) -> PlanningProblem:
    """North-south rows ``row_m`` apart of ``per_row`` trees ``tree_m`` apart (1.2 m + the
    kept 1.04 m), ``south`` and ``north`` m of headland; the area one aisle wider than
    the rows on each side."""
    e, n = np.meshgrid((np.arange(rows) + 1) * row_m, south + np.arange(per_row) * tree_m,
                       indexing="ij")
    return PlanningProblem(
        start=np.zeros(3), goal=np.zeros(3), offsets=offsets,
        centres=np.stack([e.ravel(), n.ravel()], axis=1), radii=np.full(e.size, KEPT),
        h_min=2.0, h_max=7.0, area_lower=np.zeros(2),
        area_upper=np.array([(rows + 1) * row_m, south + north + (per_row - 1) * tree_m]),
        waypoints=1, weights=np.ones(3))


def aisles(problem: PlanningProblem, *, y: float) -> np.ndarray:
    """Route points at ``y`` m north in each aisle (centroid, ENU)."""
    xs = np.arange(len(np.unique(problem.centres[:, 0])) + 1) * 7.0 + 3.5
    return np.stack([xs, np.full(len(xs), y), np.full(len(xs), 4.0)], axis=1)


def test_a_headland_too_narrow_at_both_ends_closes_each_row_by_the_shortfall():
    walls = T.walls(rows(south=10.0, north=10.0))
    assert len(walls) == 2 and all(w.axis == 0 for w in walls)  # one per row, north-south
    for w, x in zip(sorted(walls, key=lambda w: w.low), (7.0, 14.0)):
        # 10 m of headland, less the tree's reach (2.24 m), leaves 7.76 m for 8 m
        assert w.short_m == pytest.approx((0.24, 0.24))
        assert w.low == pytest.approx(x - KEPT) and w.high == pytest.approx(x + KEPT)
        assert len(w.trees) == 6


def test_refused_naming_the_leg_the_headlands_and_the_numbers():
    problem = rows(south=10.0, north=9.5)
    points = aisles(problem, y=30.0)
    with pytest.raises(T.SurveyBlocked) as caught:
        T.check_turns(problem, points, ("lane 1 end", "lane 2 start", "lane 3 start"),
                      source="o.toml", kept_clearance_m=1.04)
    text = str(caught.value)
    assert isinstance(caught.value, ScenarioError) and "\n" not in text
    assert text.startswith("o.toml: survey: leg 1/2 (lane 1 end -> lane 2 start)")
    assert "8.00 m deep north-south" in text
    assert "south headland" in text and "7.76 m between" in text and "0.24 m short" in text
    assert "north headland" in text and "7.26 m between" in text and "0.74 m short" in text
    assert "its last tree at 7.0 m east, 10.0 m north" in text


@pytest.mark.parametrize("south, north", [(18.0, 18.0), (10.0, 10.25), (10.25, 10.0),
                                          (10.0, 18.0)])
def test_accepted_when_one_headland_lets_the_formation_round_the_rows(south, north):
    problem = rows(south=south, north=north)
    assert T.walls(problem) == []
    T.check_turns(problem, aisles(problem, y=5.0), ("a", "b", "c"), source="o.toml",
                  kept_clearance_m=1.04)


def test_only_a_leg_across_a_wall_is_refused():
    problem = rows(rows=1, south=10.0, north=10.0)
    west, east = aisles(problem, y=20.0)
    T.check_turns(problem, np.array([west, west + [0.0, 5.0, 0.0]]), ("a", "b"),
                  source="o", kept_clearance_m=1.04)  # along an aisle: fine
    with pytest.raises(T.SurveyBlocked):
        T.check_turns(problem, np.array([west, east]), ("a", "b"), source="o",
                      kept_clearance_m=1.04)


def test_a_line_across_the_aisles_cannot_pass_between_the_rows():
    # 8 m wide in 7 m aisles: every row's discs merge into one blob from west to east
    problem = rows(rows=4, south=18.0, north=18.0, offsets=LINE)
    walls = T.walls(problem)
    assert [w.axis for w in walls] == [1]
    with pytest.raises(T.SurveyBlocked, match="8.00 m deep east-west"):
        T.check_turns(problem, np.array([[17.5, 5.0, 4.0], [17.5, 50.0, 4.0]]), ("a", "b"),
                      source="o", kept_clearance_m=1.04)


def test_a_gap_the_formation_fits_through_makes_no_wall():
    one = np.zeros((1, 3))
    assert T.walls(rows(south=1.0, north=1.0, tree_m=5.0, offsets=one)) == []  # 0.52 m gaps
    # the column's three discs of consecutive trees overlap: no y puts all three in gaps
    assert len(T.walls(rows(south=10.0, north=10.0, tree_m=5.0))) == 2


def test_components_are_the_graphs():
    rng = np.random.default_rng(3)
    i, j = rng.integers(0, 200, 150), rng.integers(0, 200, 150)
    label = T._components(200, i, j)
    reference = np.arange(200)  # plain relabelling until nothing changes
    changed = True
    while changed:
        changed = False
        for a, b in zip(i, j):
            low = min(reference[a], reference[b])
            for x in (a, b):
                if reference[x] != low:
                    reference[reference == reference[x]] = low
                    changed = True
    assert np.array_equal(label, reference)


def orchard_text(*, headland: float) -> str:
    """A scenario of 3 rows of 8 trees (7 m x 4 m, radius 1.2 m), ``headland`` m at each
    end, a column of three UAVs 4 m apart flying the aisles, rtk-fixed."""
    frame = LocalFrame(12.2331044, 109.1144313)
    width, length = 28.0, 2 * headland + 7 * 4.0

    def ll(e, n):
        lat, lon, _ = frame.to_lla([e, n, 0.0])
        return float(lat), float(lon)

    trees = "\n".join("[[obstacles]]\nlat = {:.8f}\nlon = {:.8f}\nradius = 1.2".format(
        *ll(7.0 * (r + 1), headland + 4.0 * t)) for r in range(3) for t in range(8))
    return "\n".join([
        'name = "small orchard"', "[area]", "corner_a = [12.2331044, 109.1144313]",
        "corner_b = [{:.8f}, {:.8f}]".format(*ll(width, length)),
        "min_altitude = 2.0", "max_altitude = 7.0",
        "[start]", "lat = {:.8f}\nlon = {:.8f}\nalt = 4.0".format(*ll(3.5, 5.0)),
        "[goal]", "lat = {:.8f}\nlon = {:.8f}\nalt = 4.0".format(*ll(24.5, length - 5.0)),
        "[formation]", "offsets = [[0.0, 4.0, 0.0], [0.0, 0.0, 0.0], [0.0, -4.0, 0.0]]",
        "clearance = 1.0", "[navigation]", 'class = "rtk-fixed"',
        "[survey]", "spacing = 7.0", "heading = 0.0", "margin = 3.5",
        "[planner]", 'waypoints = "auto"', "seed = 0", trees, ""])


def test_plan_refuses_the_narrow_orchard_before_planning():
    scenario = parse_scenario(orchard_text(headland=10.0), source="narrow.toml")
    t0 = time.perf_counter()
    with pytest.raises(T.SurveyBlocked, match=r"narrow.toml: survey: leg 3/\d+ .*0\.24 m short"):
        plan(scenario)
    assert time.perf_counter() - t0 < 5.0  # refused, not planned


def test_the_command_refuses_it_in_one_line_with_exit_code_2(tmp_path):
    from click.testing import CliRunner

    from ftlbo_mav.cli import main

    path = tmp_path / "narrow.toml"
    path.write_text(orchard_text(headland=10.0))
    result = CliRunner().invoke(main, ["plan", str(path), "-o", str(tmp_path / "out"), "-q"])
    assert result.exit_code == 2
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and "south headland" in lines[0] and "north headland" in lines[0]
    assert "Traceback" not in result.output and not (tmp_path / "out").exists()


def test_the_wide_orchard_and_the_shipped_scenarios_are_not_refused():
    T.check_survey_turns(parse_scenario(orchard_text(headland=18.0)))
    for path in sorted(glob.glob("missions/*.toml") + glob.glob("benchmarks/scenarios/*.toml")):
        T.check_survey_turns(load_scenario(path))
