"""The rally search's bound (issue 51): each UAV's search stops after
:data:`~ftlbo_mav.mission.rally.WORK_PER_UAV` elementary tests, that UAV gets no rally point
and says why (plan.json's fence notes, one line of ``plan`` on stderr); below the bound the
search chooses as before, and the fans' shortcuts (hull, directions) change no answer."""

from __future__ import annotations

import json

import numpy as np
from click.testing import CliRunner

from ftlbo_mav.cli import main
from ftlbo_mav.mission import rally
from ftlbo_mav.mission.export import plan_files
from ftlbo_mav.mission.fence import (
    RALLY_SEARCH_STOPPED,
    FenceSettings,
    plan_fences,
    rally_search_stopped,
)
from ftlbo_mav.mission.rally_fans import Fans

from .test_fence import PLAN
from .test_rally import _crowd


def _counting(monkeypatch):
    """Record the work each call of ``_first_clear`` reports, per UAV (a new list at each
    UAV's first call, told by its ``own`` path)."""
    spent: list[list[int]] = []
    first_clear = rally._first_clear

    def counted(chunk, **kw):
        out = first_clear(chunk, **kw)
        if not spent or spent[-1][0] != id(kw["own"]):
            spent.append([id(kw["own"])])
        spent[-1].append(out[1])
        return out

    monkeypatch.setattr(rally, "_first_clear", counted)
    return spent


def test_a_search_that_would_run_long_stops_at_its_bound_and_says_which_uav(monkeypatch):
    case = _crowd(np.random.default_rng(24), 24)
    settings = FenceSettings(rally_separation_m=6.0, grid_m=0.5)
    monkeypatch.setattr(rally, "COMPILED_UAVS_FROM", 1)
    whole = rally.search_rally_points(**case, settings=settings, work_per_uav=10**12)
    assert not any(whole.stopped)  # unbounded: every search runs to its end
    spent = _counting(monkeypatch)
    bound = 30_000
    cut = rally.search_rally_points(**case, settings=settings, work_per_uav=bound)
    stopped = [k for k, s in enumerate(cut.stopped) if s]
    assert stopped and all(cut.points[k] is None for k in stopped)
    assert any(p is not None for p in cut.points)
    # up to the first UAV stopped, the same points as the search without a bound
    for k in range(stopped[0]):
        assert (whole.points[k] is None) == (cut.points[k] is None)
        if whole.points[k] is not None:
            np.testing.assert_array_equal(whole.points[k], cut.points[k])
    # the exact tests of each UAV stop within a candidate's work of the bound
    one = max(len(case["paths"]) * 2 + 200, 10_000)
    assert all(sum(s[1:]) <= bound + one for s in spent)


def test_a_uav_stopped_at_the_bound_has_no_rally_point_and_plan_json_says_so(monkeypatch):
    monkeypatch.setattr(rally, "WORK_PER_UAV", 1)  # every search stops before a candidate
    fences = plan_fences(PLAN)
    assert all(f.rally == () for f in fences)
    assert all(any(n.startswith(RALLY_SEARCH_STOPPED) for n in f.notes) for f in fences)
    doc = json.loads(plan_files(PLAN)["plan.json"])
    assert all(u["rally"] == [] and u["rally_file"] is None for u in doc["uavs"])
    line = rally_search_stopped(doc)
    assert line.startswith("3 of 3 UAVs have no rally point (uav1, uav2, uav3)")
    assert "RTL" in line and "goes home" in line


def test_without_the_bound_reached_no_uav_is_named():
    doc = json.loads(plan_files(PLAN)["plan.json"])
    assert all(len(u["rally"]) == 1 for u in doc["uavs"])
    assert rally_search_stopped(doc) is None


def test_plan_names_the_uavs_without_a_rally_point_on_stderr(monkeypatch, small_path,
                                                             tmp_path):
    monkeypatch.setattr(rally, "WORK_PER_UAV", 1)
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["plan", str(small_path), "-o", str(out), "-q",
                                       "--seed", "3", "--iterations", "6", "--students", "10"])
    assert result.exit_code == 0, result.output
    said = [ln for ln in result.stderr.splitlines() if "no rally point" in ln]
    assert len(said) == 1 and "(uav1, uav2, uav3)" in said[0]
    assert not list(out.glob("*.rally")) and len(list(out.glob("*.fence"))) == 3


def test_the_fans_shortcuts_change_no_answer():
    """The compiled test with the lines kept as fans (hull, sorted directions, the fans
    listed in the candidate's bucket) answers as numpy measuring every line, the lines in
    every direction from their rally points (the directions' wrap at pi included)."""
    rng = np.random.default_rng(11)
    sep = 2.0
    fans, line_a, line_b, rallies = Fans(), [], [], []
    # the same fans in buckets of 4 m over part of the field (candidates outside it too)
    bucketed = Fans(reach=sep + 1e-6, lo=np.array([0.0, 0.0]), hi=np.array([60.0, 60.0]),
                    bucket_m=4.0)
    for _ in range(6):
        r = rng.uniform(10.0, 50.0, 2)
        # none just above -pi: a candidate there is too near only the lines near +pi
        angle = rng.uniform(-np.pi + 0.8, np.pi, 40)
        angle[:2] = [np.pi, np.pi - 1e-12]
        starts = r + rng.uniform(1.0, 25.0, (40, 1)) * np.column_stack([np.cos(angle),
                                                                         np.sin(angle)])
        order = fans.add(starts, r)
        np.testing.assert_array_equal(bucketed.add(starts, r), order)
        starts = starts[order]
        rallies.append(r)
        line_a.append(starts)
        line_b.append(np.broadcast_to(r, starts.shape))
    line_a, line_b = np.concatenate(line_a), np.concatenate(line_b)
    lines = dict(line_a=line_a, line_b=line_b, line_lo=np.minimum(line_a, line_b) - sep,
                 line_hi=np.maximum(line_a, line_b) + sep)
    own = rally._densify(np.array([[0.0, 0.0], [60.0, 5.0]]), 1.0)
    kw = dict(own=own, own_home=np.linalg.norm(own - own[0], axis=1),
              places=rng.uniform(0.0, 60.0, (5, 2)), sep=sep, **lines)
    # single candidates just either side of the west, where the directions wrap
    west = [r + d * np.array([np.cos(t), np.sin(t)]) for r in rallies
            for d in (3.0, 8.0) for t in (np.pi - 0.3, np.pi - 0.05, -np.pi + 0.05,
                                          -np.pi + 0.3)]
    answers = set()
    for chunk in [w[None] for w in west] + [
            rng.uniform(-5.0, 70.0, (int(rng.integers(1, 30)), 2)) for _ in range(150)]:
        numpy = rally._first_clear(chunk, **kw, hit=np.ones(len(line_a), bool))[0]
        assert rally._first_clear(chunk, **kw, compiled=True, fans=fans)[0] == numpy
        assert rally._first_clear(chunk, **kw, compiled=True, fans=bucketed)[0] == numpy
        answers.add(numpy if numpy is None else min(numpy, 1))
    assert answers == {None, 0, 1}
