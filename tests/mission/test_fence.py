"""Each UAV's fence and rally point from its plan (ftlbo_mav/mission/fence.py)."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np

from ftlbo_mav.mission.fence import FenceSettings, exclusion_radius_m, plan_fences
from ftlbo_mav.mission.plan_reader import read_plan
from ftlbo_mav.mission.qgc_plan import plan_document

STORED = Path(__file__).resolve().parents[1] / "data" / "orchard-plan"
PLAN = read_plan(STORED)
FENCES = plan_fences(PLAN)


def _en(items):
    f = PLAN.scenario.frame
    return f.to_enu(lat_deg=[i.lat_deg for i in items],
                    lon_deg=[i.lon_deg for i in items]).reshape(-1, 3)[:, :2]


def test_exclusion_radius_leaves_corner_cut_and_margin_of_the_clearance():
    s = FenceSettings()
    assert exclusion_radius_m(4.0, clearance_m=1.0, settings=s) == 4.0 + 1.0 - 0.3 - 0.5
    assert exclusion_radius_m(4.0, clearance_m=0.0, settings=s) == 4.0  # never below the tree
    assert FENCES[0].exclusion_radii_m == (4.2, 4.7, 3.7, 3.2, 3.7, 3.2, 2.7)


def test_every_planned_segment_passes_outside_the_circles_by_more_than_cut_and_margin():
    s = FenceSettings()
    circles = [(c, it.param1) for c, it in zip(_en(FENCES[0].fence[4:]), FENCES[0].fence[4:])]
    for path in PLAN.uav_paths:
        a, b = path[:-1, :2], path[1:, :2]
        for centre, radius in circles:
            ab = b - a
            t = np.clip(((centre - a) * ab).sum(1) / (ab * ab).sum(1), 0, 1)
            d = np.linalg.norm(a + t[:, None] * ab - centre, axis=1).min()
            assert d - radius >= s.corner_cut_m + s.margin_m - 1e-6


def test_the_polygon_is_the_area_grown_and_alt_max_is_above_the_band():
    ring = _en(FENCES[0].fence[:4])
    paths = np.concatenate([p[:, :2] for p in PLAN.uav_paths])
    assert np.all(paths > ring.min(axis=0) + 0.8 - 1e-6)
    assert np.all(paths < ring.max(axis=0) - 0.8 + 1e-6)
    assert [it.param1 for it in FENCES[0].fence[:4]] == [4.0] * 4
    assert FENCES[0].params == {"FENCE_ENABLE": 1.0, "FENCE_TYPE": 5.0, "FENCE_ACTION": 4.0,
                                "FENCE_ALT_MAX": 8.0, "FENCE_MARGIN": 0.5}
    assert PLAN.uav_paths[:, :, 2].max() <= 8.0 - 0.5 - 0.5


def test_rally_points_are_clear_of_obstacles_and_apart():
    centres, radii = PLAN.scenario.obstacles_enu()
    centres = np.asarray(centres).reshape(len(radii), -1)[:, :2]
    points = np.array([_en(f.rally)[0] for f in FENCES])
    for p in points:
        assert np.all(np.linalg.norm(centres - p, axis=1) >= np.asarray(radii) + 1.0)
    gaps = np.linalg.norm(points[:, None] - points[None], axis=2)[np.triu_indices(3, 1)]
    assert gaps.min() >= FenceSettings().rally_separation_m
    assert all(f.rally[0].alt_m == int(f.rally[0].alt_m) for f in FENCES)  # whole metres


def test_rally_points_keep_clearance_and_separation_where_the_copters_truly_are():
    from ftlbo_mav.gnss import budget, pair_error_m

    nav = budget("gps", 1.5)  # 1.5 m at 95 %: 2.12 m between two copters
    rough = replace(PLAN, scenario=replace(PLAN.scenario, navigation=nav))
    fences = plan_fences(rough)
    centres, radii = PLAN.scenario.obstacles_enu()
    centres = np.asarray(centres).reshape(len(radii), -1)[:, :2]
    homes = PLAN.uav_paths[:, 0, :2]
    placed = [(n, _en(f.rally)[0]) for n, f in enumerate(fences) if f.rally]
    assert placed
    for n, p in placed:
        assert np.all(np.linalg.norm(centres - p, axis=1) >= np.asarray(radii) + 1.0 + 1.5)
        others = np.delete(homes, n, axis=0)
        assert np.linalg.norm(others - p, axis=1).min() >= (
            FenceSettings().rally_separation_m + pair_error_m(1.5) - 1e-6)
    plain = [_en(f.rally)[0] for f in FENCES]
    assert any(np.linalg.norm(p - plain[n]) > 0.1 for n, p in placed)  # the budget moved them


def test_no_clearance_makes_the_circles_the_trees_and_says_so():
    bare = replace(PLAN, scenario=replace(PLAN.scenario, clearance_m=0.0))
    fences = plan_fences(bare)
    assert fences[0].exclusion_radii_m == tuple(float(r) for r in bare.scenario.obstacles_enu()[1])
    assert "clearance 0 m is less than" in fences[0].notes[0]


def test_the_qgc_plan_carries_the_fence_and_the_rally_point():
    items = [it for it in FENCES[0].fence]
    from ftlbo_mav.mission.export import plan_missions

    doc = plan_document(plan_missions(PLAN)[0].items, fence=FENCES[0])
    assert len(doc["geoFence"]["polygons"]) == 1
    assert doc["geoFence"]["polygons"][0]["inclusion"] is True
    assert len(doc["geoFence"]["polygons"][0]["polygon"]) == 4
    circles = doc["geoFence"]["circles"]
    assert [c["circle"]["radius"] for c in circles] == [it.param1 for it in items[4:]]
    assert not any(c["inclusion"] for c in circles)
    (point,) = doc["rallyPoints"]["points"]
    assert point == [FENCES[0].rally[0].lat_deg, FENCES[0].rally[0].lon_deg, 6.0]
    json.dumps(doc)


def _rally_reference(*, paths, centres, radii, clearance_m, area_min, area_max, settings):
    """The rally search written plainly (every grid cell, every test, no pruning): the
    fast search must choose the same points."""
    from ftlbo_mav.geo import segment_distance as _segment_distance
    from ftlbo_mav.mission.rally import _densify

    inset = settings.corner_cut_m + settings.margin_m
    sep = settings.rally_separation_m
    xs = np.arange(area_min[0] + inset, area_max[0] - inset + 1e-9, settings.grid_m)
    ys = np.arange(area_min[1] + inset, area_max[1] - inset + 1e-9, settings.grid_m)
    grid = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)
    if len(centres):
        d = np.linalg.norm(grid[:, None, :] - centres[None, :, :2], axis=2)
        grid = grid[np.all(d >= radii[None, :] + clearance_m, axis=1)]
    flat = [_densify(p[:, :2], 1.0) for p in paths]
    homes = paths[:, 0, :2]
    chosen = [None] * len(paths)
    for k in range(len(paths)):
        cand = grid[np.argsort(np.linalg.norm(grid - paths[k, -1, :2], axis=1), kind="stable")]
        own = flat[k]
        own_home = np.linalg.norm(own - homes[k], axis=1)
        ok = np.ones(len(cand), bool)
        to_cand = np.linalg.norm(own[None] - cand[:, None], axis=2) < own_home[None]
        for j in range(len(paths)):
            if j == k:
                continue
            for q in [homes[j]] + ([chosen[j]] if chosen[j] is not None else []):
                ok &= np.linalg.norm(cand - q, axis=1) >= sep
                d = _segment_distance(q, own[None], cand[:, None])
                ok &= np.where(to_cand, d, np.inf).min(axis=1) >= sep
            if chosen[j] is not None:
                pts = flat[j]
                use = (np.linalg.norm(pts - chosen[j], axis=1)
                       < np.linalg.norm(pts - homes[j], axis=1))
                if use.any():
                    d = _segment_distance(cand[:, None], pts[use][None], chosen[j])
                    ok &= d.min(axis=1) >= sep
        if ok.any():
            chosen[k] = cand[int(np.argmax(ok))]
    return chosen


def _same_points(a, b):
    return len(a) == len(b) and all(
        (x is None and y is None) or (x is not None and y is not None and np.array_equal(x, y))
        for x, y in zip(a, b))


def test_the_rally_search_chooses_what_a_plain_search_of_every_cell_chooses():
    from ftlbo_mav.mission.rally import rally_points_enu

    rng = np.random.default_rng(3)
    cases = []
    centres, radii = PLAN.scenario.obstacles_enu()
    lo, hi = PLAN.scenario.area_bounds_enu()
    cases.append(dict(paths=np.asarray(PLAN.uav_paths, float),
                      centres=np.asarray(centres, float).reshape(len(radii), -1)[:, :2],
                      radii=np.asarray(radii, float), clearance_m=1.0, area_min=lo[:2],
                      area_max=hi[:2]))
    for n in (4, 7):  # formations crowding their goals, crossing paths, a tree or two
        home = rng.uniform(2, 8, 2) + 3.0 * np.column_stack([np.arange(n) % 3, np.arange(n) // 3])
        goal = home + rng.uniform(12, 18, 2) + rng.normal(0, 1.0, (n, 2))
        middle = (home + goal) / 2 + rng.normal(0, 2.0, (n, 2))
        paths = np.stack([home, middle, goal], axis=1)
        paths = np.concatenate([paths, np.full((n, 3, 1), 4.0)], axis=2)
        cases.append(dict(paths=paths, centres=rng.uniform(5, 25, (2, 2)),
                          radii=rng.uniform(0.5, 1.5, 2), clearance_m=0.5,
                          area_min=np.zeros(2), area_max=np.array([32.0, 30.0])))
    wide = FenceSettings(rally_separation_m=3.5, grid_m=0.7)
    far = 0
    crowded = FenceSettings(rally_separation_m=9.0, grid_m=1.0)  # no room for some
    for case, settings in [(cases[0], FenceSettings(grid_m=1.5)), (cases[2], crowded)] + [
            (c, s) for c in cases[1:] for s in (FenceSettings(), wide)]:
        fast = rally_points_enu(**case, settings=settings)
        assert _same_points(fast, _rally_reference(**case, settings=settings))
        goals = case["paths"][:, -1, :2]
        far += sum(p is None or np.linalg.norm(p - g) > 2.0 for p, g in zip(fast, goals))
    assert far  # some UAVs' rally points had to move away from their goals, or found none


def test_a_field_without_obstacles_has_a_polygon_and_rally_points_only():
    bare = replace(PLAN, scenario=replace(PLAN.scenario, obstacles=()))
    fences = plan_fences(bare)
    assert [len(f.fence) for f in fences] == [4, 4, 4]
    assert all(f.exclusion_radii_m == () and len(f.rally) == 1 for f in fences)
