"""Carry on after an early end: the rest of a plan, from the first point not yet flown.

A flight that ended early (a vehicle lost, a battery, an abort) leaves each UAV somewhere
along its path (:mod:`ftlbo_mav.flight.progress`). The formation resumes together, so
it resumes where the UAV that got least far stopped:

- between lanes (or in a plan without a survey, or a lane without a camera) at that
  UAV's point, the resume point;
- in a lane with a camera, where the next photo is due: each UAV's next photo is one
  trigger distance past its last photo on the lane (the entry, when it took none); the
  lane resumes at the earliest of them, so that no UAV leaves a gap. A UAV whose photo
  there is already taken (it got one photo further) turns its trigger on without a
  photo at once (DO_SET_CAM_TRIGG_DIST param3 0): no photo is taken twice. Photos are
  those the camera reported (CAMERA_FEEDBACK) on a lane's line; for a UAV that
  reported none, where
  ArduCopter takes them by distance (:mod:`ftlbo_mav.ardupilot.camera`) up to its point.

A UAV that got more than a photo further than the one the formation resumes from (one
stopped by hand before the others, or the others carrying on without it) takes those
photos again: the formation flies together. The resume point says how many.

The rest is a scenario of its own, as a sortie is (:mod:`.sorties`): from the start,
through the resume point, the via points and lanes not yet flown (the resumed lane from
the resume point to its exit, its lanes as laid), to the goal; planned as every plan
is (the way to the resume point around the obstacles, the flown path predicted and kept
clear). Pure computation over plans.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from ..errors import BadInput
from ..scenario import GeoPoint, Scenario, ViaPoint
from .plans import Plan

ON_LANE_M = 2.5
"""A photo further than this from every lane's line is no lane's (the copter turning
into a lane, GPS error and the tracking error take it a metre or so off the line)."""
SAME_POINT_M = 0.05
"""A resume point this near a route point (a via point, a lane's end) is that point."""


class NothingToResume(BadInput):
    """The plan was flown to its goal: there is nothing left to fly."""


@dataclass(frozen=True)
class ResumePoint:
    """Where the formation resumes: ``point`` ``k + f`` along the plan's paths
    (:mod:`ftlbo_mav.flight.progress`); ``lane`` the survey lane (0-based) it resumes in,
    None between lanes; ``photo_taken`` per UAV, resuming in a lane: its photo at the
    resume point is taken already; ``photos`` per UAV, the photos it took in that lane;
    ``again`` per UAV, photos it took that the rest takes again (it got more than a
    photo further than the UAV the formation resumes from: no formation flies on without
    one of its UAVs)."""

    point: float
    lane: int | None = None
    photo_taken: tuple[bool, ...] = ()
    photos: tuple[int, ...] = ()
    again: tuple[int, ...] = ()

    def describe(self, plan: Plan) -> str:
        where = f"{math.floor(self.point)} + {self.point - math.floor(self.point):.2f}"
        if self.lane is None:
            text = f"path point {where}" + (" (between lanes)" if plan.scenario.survey else "")
        elif not self.photos:
            text = f"lane {self.lane + 1} at path point {where}"
        else:
            text = f"lane {self.lane + 1} at path point {where}, photos taken in it: " + \
                ", ".join(f"uav{n + 1} {c}" for n, c in enumerate(self.photos))
        if any(self.again):
            text += "; taken again (they got further than the formation resumes from): " + \
                ", ".join(f"uav{n + 1} {c}" for n, c in enumerate(self.again) if c)
        return text


def _arcs(line: np.ndarray) -> np.ndarray:
    """Cumulative length along a polyline ``(Q, 2)``, ``(Q,)``."""
    return np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(line, axis=0).T))])


def _project(line: np.ndarray, p: np.ndarray) -> tuple[float, float]:
    """``(arc, distance)``: where along ``line`` the point nearest ``p`` lies, and how far."""
    arcs = _arcs(line)
    best = (0.0, math.inf)
    for a, b, s in zip(line[:-1], line[1:], arcs[:-1]):
        d = b - a
        length2 = float(d @ d)
        t = 0.0 if length2 < 1e-12 else float(np.clip((p - a) @ d / length2, 0.0, 1.0))
        off = float(np.hypot(*(a + t * d - p)))
        if off < best[1]:
            best = (s + t * math.sqrt(length2), off)
    return best


def _at_arc(path: np.ndarray, first: int, arc: float) -> float:
    """The point ``k + f`` of ``path`` that lies ``arc`` metres along it from point
    ``first`` (horizontally)."""
    arcs = _arcs(path[first:, :2])
    j = int(np.clip(np.searchsorted(arcs, arc, side="right") - 1, 0, len(arcs) - 2))
    span = arcs[j + 1] - arcs[j]
    return first + j + (0.0 if span <= 0 else min(1.0, (arc - arcs[j]) / span))


def resume_point(plan: Plan, points: Sequence[float],
                 photos: Sequence[np.ndarray | None]) -> ResumePoint:
    """Where ``plan`` resumes (module notes), from each UAV's ``points`` (``k + f``) and
    ``photos`` (``(K, 3)`` metres ENU, the ones it took on the plan; None: its camera
    reported none). :class:`NothingToResume` when every UAV reached the goal."""
    last = plan.centroid.shape[0] - 1
    least = float(min(points))
    if least >= last - 1e-9:
        raise NothingToResume("every UAV reached the goal: the plan was flown to its end, "
                              "nothing to resume")
    lanes = plan.lane_points()
    distance = plan.scenario.survey.trigger_distance_m if lanes else None
    # each photo as (lane, metres along it) per UAV (None: its camera reported none)
    placed = [None if p is None else [x for x in (_place(plan, n, lanes, q[:2]) for q in p)
                                      if x is not None]
              for n, p in enumerate(photos)]
    k = int(math.floor(least))
    lane = next((j for j, (a, b) in enumerate(lanes) if a <= k < b), None)
    if lane is None or not distance:  # between lanes, or lanes without a camera
        later = next((j for j, (a, _b) in enumerate(lanes) if a >= least - 1e-9), len(lanes))
        return ResumePoint(least, lane, again=_again(placed, later, -1.0))
    entry, exit_ = lanes[lane]
    nxt, counts = [], []
    for n, path in enumerate(plan.uav_paths):
        if placed[n] is None:  # no feedback: photos at the entry and each distance after
            flown = _project(path[entry:exit_ + 1, :2], _position(path, points[n])[:2])[0]
            counts.append(int(flown // distance) + 1)
            nxt.append(counts[-1] * distance)
            continue
        mine = [arc for j, arc in placed[n] if j == lane]
        counts.append(len(mine))
        nxt.append(max(mine) + distance if mine else 0.0)
    at = min(nxt)
    length = float(_arcs(plan.centroid[entry:exit_ + 1, :2])[-1])
    if at >= length - SAME_POINT_M:  # every photo of the lane taken: on from its exit
        return ResumePoint(float(exit_), again=_again(placed, lane + 1, -1.0))
    taken = tuple(bool(x > at + distance / 2) for x in nxt)
    return ResumePoint(_at_arc(plan.centroid[:exit_ + 1], entry, at), lane, taken,
                       tuple(counts), _again(placed, lane, at + distance / 2))


def _place(plan: Plan, n: int, lanes, p: np.ndarray) -> tuple[int, float] | None:
    """``(lane, metres along it)`` of UAV ``n``'s photo at ``p``: the lane whose line
    passes nearest; None when that is further than :data:`ON_LANE_M` (not a lane's
    photo: one taken on the way home with the trigger still on)."""
    found = [_project(plan.uav_paths[n, a:b + 1, :2], p) for a, b in lanes]
    j = int(np.argmin([off for _arc, off in found]))
    return (j, found[j][0]) if found[j][1] <= ON_LANE_M else None


def _again(placed, lane: int, beyond_m: float) -> tuple[int, ...]:
    """Per UAV, its photos the rest takes again: in lanes after ``lane``, and in ``lane``
    more than ``beyond_m`` along it (a UAV that got further than the one the formation
    resumes from)."""
    return tuple(0 if p is None else sum(1 for j, arc in p if j > lane or (
        j == lane and arc > beyond_m)) for p in placed)


def _position(path: np.ndarray, point: float) -> np.ndarray:
    """The position ``k + f`` along ``path (P, 3)``."""
    k = min(int(math.floor(point)), len(path) - 2)
    f = point - k
    return path[k] + f * (path[k + 1] - path[k])


def resume_scenario(plan: Plan, at: ResumePoint) -> Scenario:
    """The rest of ``plan``'s scenario from ``at`` (module notes): the start, the resume
    point, the via points and lanes after it, the goal; the survey's lanes as laid."""
    s = plan.scenario
    survey = s.survey
    lanes = survey.lanes if survey is not None else ()
    own = len(s.via) - 2 * len(lanes)  # [[via]] points before the lanes
    firsts = np.cumsum([0] + [leg.waypoints + 1 for leg in plan.legs])  # route point -> index
    k = min(int(math.floor(at.point)), len(plan.centroid) - 2)
    r = int(np.searchsorted(firsts, k, side="right") - 1)  # the leg it is in
    here = _position(plan.centroid, at.point)
    lat, lon, alt = (float(v) for v in s.frame.to_lla(here))
    if r == 0 and np.hypot(*(here[:2] - plan.centroid[0, :2])) <= SAME_POINT_M:
        return s  # it never left the start: the whole plan
    resumed: tuple = ()
    if np.hypot(*(here[:2] - plan.centroid[firsts[r], :2])) <= SAME_POINT_M:
        via = s.via[r - 1:]  # at route point r itself (via point r - 1)
        rest = max(0, math.ceil((r - 1 - own) / 2))
    elif at.lane is not None:  # in a lane: it runs from here to its exit
        via = (ViaPoint(lat, lon, alt, f"lane {at.lane + 1} resumed"),
               *s.via[own + 2 * at.lane + 1:])
        resumed = ((GeoPoint(lat, lon, survey.alt_m), lanes[at.lane][1]),)
        rest = at.lane + 1
    else:
        via = (ViaPoint(lat, lon, alt, "resume point"), *s.via[r:])
        rest = max(0, math.ceil((r - own) / 2))
    if survey is None:
        return replace(s, via=via)
    taken = at.photo_taken if at.lane is not None and any(at.photo_taken) else ()
    return replace(s, via=via, survey=replace(
        survey, lanes=(*resumed, *lanes[rest:]), first_photo_taken=taken))


def plan_resume(plan: Plan, at: ResumePoint, planner, **kw) -> Plan:
    """The rest of ``plan`` from ``at``, planned with ``planner`` (:func:`.planner.plan`,
    keyword arguments ``kw``) as ``plan`` was (its settings), its lanes as laid."""
    return planner(replace(resume_scenario(plan, at), planner=plan.settings), relay=False, **kw)


__all__ = ["NothingToResume", "ResumePoint", "plan_resume", "resume_point", "resume_scenario"]
