"""Where a survey resumes after an early end, and the rest planned from there
(planning/resume.py), on the shipped field survey (six lanes, a photo every 5.7 m)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from ftlbo_mav.mission.export import plan_missions
from ftlbo_mav.mission.items import CMD_DO_SET_CAM_TRIGG_DIST
from ftlbo_mav.mission.photos import plan_photos
from ftlbo_mav.mission.plan_reader import read_plan
from ftlbo_mav.planning.planner import plan as plan_scenario
from ftlbo_mav.planning.resume import (
    NothingToResume,
    ResumePoint,
    plan_resume,
    resume_point,
    resume_scenario,
)
from ftlbo_mav.scenario import MissionSettings

from ..conftest import ROOT

SURVEY = ROOT / "missions" / "field-survey"


@pytest.fixture(scope="module")
def survey():
    p = read_plan(SURVEY)  # (its plan.json predates "mission": the toml's speed)
    return replace(p, scenario=replace(p.scenario, mission=MissionSettings(speed_m_s=5.0)))


def _lane(p, j):
    entry, exit_ = p.lane_points()[j]
    return entry, exit_, p.uav_paths[:, entry:exit_ + 1]


def _photos_along(p, j, n, arcs):
    """UAV n's photos at ``arcs`` metres along lane j (ENU, its altitude)."""
    entry, exit_, lines = _lane(p, j)
    line = lines[n]
    d = line[-1] - line[0]
    return np.array([line[0] + a * d / np.linalg.norm(d[:2]) for a in arcs])


def _arc_of(p, j, point):
    entry, _exit, _ = _lane(p, j)
    c = p.centroid
    k = int(np.floor(point))
    here = c[k] + (point - k) * (c[k + 1] - c[k])
    return float(np.hypot(*(here[:2] - c[entry, :2])))


def test_between_lanes_it_resumes_where_the_last_one_stopped(survey):
    entry, _exit, _ = _lane(survey, 2)
    at = resume_point(survey, [entry - 1.3, entry - 1.5, entry - 1.4], [None] * 3)
    assert at.point == pytest.approx(entry - 1.5) and at.lane is None
    assert at.again == (0, 0, 0)


def test_in_a_lane_without_feedback_at_the_next_photo_by_distance(survey):
    entry, _exit, _ = _lane(survey, 2)
    d = survey.scenario.survey.trigger_distance_m
    # 20 m into lane 3 (a photo at 0, 5.7, 11.4, 17.1): the next is due at 22.8 m
    point = entry + 20.0 / np.hypot(*(survey.centroid[entry + 1, :2]
                                      - survey.centroid[entry, :2]))
    at = resume_point(survey, [point] * 3, [None] * 3)
    assert at.lane == 2 and at.photos == (4, 4, 4) and at.photo_taken == (False,) * 3
    assert _arc_of(survey, 2, at.point) == pytest.approx(4 * d)


def test_a_uav_a_photo_ahead_does_not_take_it_twice(survey):
    d = survey.scenario.survey.trigger_distance_m
    entry, _exit, _ = _lane(survey, 2)
    photos = [_photos_along(survey, 2, 0, [0, d, 2 * d]),
              _photos_along(survey, 2, 1, [0, d, 2 * d, 3 * d]),  # one further
              _photos_along(survey, 2, 2, [0.1, d + 0.1, 2 * d + 0.2])]
    # and one taken on uav3's way home, 6 m off the lane's line: no lane's photo
    photos[2] = np.vstack([photos[2], photos[2][-1] + [6.0, 3.0, 0.0]])
    at = resume_point(survey, [entry + 0.5] * 3, photos)
    assert at.lane == 2 and at.photos == (3, 4, 3)
    assert at.photo_taken == (False, True, False)
    assert _arc_of(survey, 2, at.point) == pytest.approx(3 * d)
    assert at.again == (0, 0, 0)
    rest = resume_scenario(survey, at)
    assert rest.survey.first_photo_taken == (False, True, False)


def test_photos_further_than_the_formation_resumes_are_counted_as_taken_again(survey):
    d = survey.scenario.survey.trigger_distance_m
    entry, _exit, _ = _lane(survey, 2)
    photos = [_photos_along(survey, 2, 0, [0, d]),
              _photos_along(survey, 2, 1, [0, d, 2 * d, 3 * d, 4 * d]),
              _photos_along(survey, 2, 2, [0, d])]
    at = resume_point(survey, [entry + 0.3] * 3, photos)
    assert _arc_of(survey, 2, at.point) == pytest.approx(2 * d)
    assert at.again == (0, 2, 0)  # its photos at 3d and 4d; the one at 2d is not retaken
    assert "taken again" in at.describe(survey) and "uav2 2" in at.describe(survey)


def test_a_lane_whose_photos_are_all_taken_resumes_at_its_exit(survey):
    d = survey.scenario.survey.trigger_distance_m
    entry, exit_, lines = _lane(survey, 2)
    length = float(np.hypot(*(lines[0, -1, :2] - lines[0, 0, :2])))
    arcs = np.arange(0, length, d)
    photos = [_photos_along(survey, 2, n, arcs) for n in range(3)]
    at = resume_point(survey, [exit_ - 0.01] * 3, photos)
    assert at.point == exit_ and at.lane is None


def test_a_plan_flown_to_its_goal_has_nothing_to_resume(survey):
    last = len(survey.centroid) - 1
    with pytest.raises(NothingToResume, match="flown to its end"):
        resume_point(survey, [last] * 3, [None] * 3)


def test_the_rest_keeps_the_lanes_not_flown_as_laid(survey):
    entry, exit_, _ = _lane(survey, 2)
    at = ResumePoint(entry + 0.4, 2, (False, False, False), (3, 3, 3))
    rest = resume_scenario(survey, at)
    lanes = survey.scenario.survey.lanes
    assert rest.survey.lanes[1:] == lanes[3:]
    assert rest.survey.lanes[0][1] == lanes[2][1]  # the resumed lane's own exit
    assert rest.via[0].name == "lane 3 resumed" and len(rest.via) == 2 * len(rest.survey.lanes)
    assert (rest.start, rest.goal) == (survey.scenario.start, survey.scenario.goal)
    # at a lane's entry itself: no second point there
    at_entry = resume_scenario(survey, ResumePoint(float(entry), 2, (False,) * 3, (0,) * 3))
    assert at_entry.survey.lanes == lanes[2:] and at_entry.via[0].name == "lane 3 start"
    # between lanes: a resume point, then the next lane
    between = resume_scenario(survey, ResumePoint(entry - 1.5))
    assert between.via[0].name == "resume point" and between.survey.lanes == lanes[2:]
    # never left the start: the whole survey
    assert resume_scenario(survey, ResumePoint(0.0)) is survey.scenario


def test_the_rest_takes_every_photo_not_yet_taken_once(survey):
    d = survey.scenario.survey.trigger_distance_m
    entry, _exit, _ = _lane(survey, 2)
    photos = [_photos_along(survey, 2, 0, [0, d, 2 * d]),
              _photos_along(survey, 2, 1, [0, d, 2 * d, 3 * d]),
              _photos_along(survey, 2, 2, [0, d, 2 * d])]
    at = resume_point(survey, [entry + 0.6] * 3, photos)
    rest = plan_resume(survey, at, plan_scenario)
    assert rest.feasible, rest.violations
    missions = plan_missions(rest)
    first_on = [next(it for it in m.items if it.command == CMD_DO_SET_CAM_TRIGG_DIST)
                for m in missions]
    assert [it.param3 for it in first_on] == [1.0, 0.0, 1.0]
    planned = plan_photos(survey, plan_missions(survey))
    resumed = plan_photos(rest, missions)
    before = [22 + 3, 22 + 4, 22 + 3]  # two lanes of 11, and those in lane 3
    for n in range(3):
        # what the first flight took and what the rest takes: the whole survey's photos
        assert before[n] + resumed[n].count == planned[n].count
        # in the same places, within the difference in the copter's lag behind its track:
        # the rest starts from rest (its first photo, at once, where the copter stopped),
        # the whole survey flew into the lane at speed (SITL: 0.4-0.7 m behind the line)
        want = planned[n].positions[before[n]:, :2]
        got = resumed[n].positions[:, :2]
        far = np.hypot(*(want[:, None, :] - got[None, :, :]).transpose(2, 0, 1)).min(axis=1)
        assert far[0] < 1.2 and far[1:].max() < 0.5, far
