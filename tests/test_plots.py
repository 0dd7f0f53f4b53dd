"""Figures: written, non-empty, and showing the obstacles where they are."""

from __future__ import annotations

from dataclasses import replace
from functools import lru_cache

import matplotlib.colors as mcolors
import matplotlib.image as mimage
import numpy as np
import pytest

from ftlbo_mav.mission.gis import OBSTACLE_COLOUR
from ftlbo_mav.planning.planner import plan
from ftlbo_mav.plots import (
    AREA_COLOUR,
    FIGURES,
    figure_convergence,
    figure_ground,
    figure_vertical,
    render_png,
    write_figures,
)
from ftlbo_mav.scenario import parse_scenario

from .conftest import SMALL

# A second, off-path obstacle in the north-west corner, so the check sees two.
TWO_TREES = SMALL.replace("[planner]", "[[obstacles]]\nlat = 12.23350\nlon = 109.11450\n"
                          "radius = 2.0\n\n[planner]")


@lru_cache(maxsize=1)
def small_plan():
    return plan(parse_scenario(TWO_TREES), seed=3, students=12, iterations=5)


def _blend(fg: str, alpha: float, bg) -> np.ndarray:
    return alpha * np.array(mcolors.to_rgb(fg)) + (1 - alpha) * np.asarray(bg, float)


def _pixel(png: np.ndarray, fig, ax, x: float, y: float) -> np.ndarray:
    """RGB of the saved PNG at data point (x, y) of ``ax``."""
    px, py = ax.transData.transform((x, y))
    height = png.shape[0]
    assert png.shape[1] == round(fig.get_figwidth() * fig.dpi)
    return png[int(round(height - py)), int(round(px)), :3]


def _png(fig, tmp_path, name):
    path = tmp_path / name
    path.write_bytes(render_png(fig))
    return mimage.imread(path)


def test_write_figures_writes_every_png_non_empty(tmp_path):
    paths = write_figures(small_plan(), tmp_path)
    assert [p.name for p in paths] == list(FIGURES)
    for path in paths:
        data = path.read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20_000, path
        img = mimage.imread(path)
        assert img.shape[0] >= 400 and img.shape[1] >= 700
        assert img[..., :3].std() > 0.05  # not a blank canvas


def test_ground_view_shows_each_obstacle_at_its_centre(tmp_path):
    p = small_plan()
    fig = figure_ground(p)
    png = _png(fig, tmp_path, "ground.png")
    [ax] = fig.axes
    expected = _blend(OBSTACLE_COLOUR, 0.55, mcolors.to_rgb(AREA_COLOUR))
    centres, radii = p.scenario.obstacles_enu()
    assert len(centres) == 2
    for c, r in zip(centres, radii):
        assert np.abs(_pixel(png, fig, ax, *c) - expected).max() < 0.03
        # and the area, not the obstacle, just outside its clearance ring
        outside = _pixel(png, fig, ax, c[0], c[1] - r - p.scenario.clearance_m - 0.6)
        assert np.abs(outside - mcolors.to_rgb(AREA_COLOUR)).max() < 0.03


def test_vertical_views_show_each_obstacle_below_the_band(tmp_path):
    p = small_plan()
    fig = figure_vertical(p)
    png = _png(fig, tmp_path, "vertical.png")
    east_up, north_up = fig.axes[:2]
    below_band = _blend("#c00000", 0.06, (1, 1, 1))
    expected = _blend(OBSTACLE_COLOUR, 0.35, below_band)
    for c in p.scenario.obstacles_enu()[0]:
        for ax, coordinate in ((east_up, c[0]), (north_up, c[1])):
            # 0.5 m up: under every path (the band starts at 2 m), so only the obstacle is there
            assert np.abs(_pixel(png, fig, ax, coordinate, 0.5) - expected).max() < 0.05


def test_convergence_leaves_out_infeasible_iterations_and_says_so():
    p = small_plan()
    history = np.array([np.inf, np.inf, 230.0, 180.0, 150.0])
    fig = figure_convergence(replace(p, history=history))
    [ax] = fig.axes
    [line] = [ln for ln in ax.get_lines() if ln.get_label() == "best cost"]
    assert list(line.get_xdata()) == [3, 4, 5]
    assert any("2 iterations without a feasible path" in t.get_text() for t in ax.texts)


def test_infeasible_plan_is_drawn_with_a_red_title(tmp_path):
    p = replace(small_plan(), violations=("uav1 waypoint 2 inside obstacle 1",),
                history=np.full(5, np.inf))
    fig = figure_ground(p)
    [ax] = fig.axes
    assert "INFEASIBLE" in ax.get_title()
    assert mcolors.to_hex(ax.title.get_color()) == "#c00000"
    write_figures(p, tmp_path)  # every figure copes, the convergence one with no finite cost


@pytest.mark.parametrize("offsets", ["[[0.0, 0.0, 0.0]]", "[[0.0, 2.0, 0.0], [0.0, -2.0, 0.0]]"])
def test_one_and_two_uav_formations_draw(tmp_path, offsets):
    text = TWO_TREES.replace(
        "offsets = [[0.0, 0.0, 2.0], [3.0, 0.0, -1.0], [-3.0, 0.0, -1.0]]", f"offsets = {offsets}")
    p = plan(parse_scenario(text), seed=1, students=8, iterations=2)
    assert len(write_figures(p, tmp_path)) == len(FIGURES)
