"""``fly --resume``: the rest of a plan after a flight that ended early, as a plan folder.

The flight before wrote ``progress.json`` (:mod:`.progress`) beside its log; from it and
the plan folder the rest is planned (:mod:`ftlbo_mav.planning.resume`) and written as
``PLAN/resume/``, a plan folder like any other (with ``resumed.json``: what it carries
on from): ``fly --resume`` uploads it, verified, and flies it; ``fly PLAN/resume
--resume`` carries on after that one.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, replace
from pathlib import Path

from ..errors import BadInput, MissionFileError
from ..mission.export import PLAN_OUTPUTS, plan_files
from ..mission.files import OutputFolder
from ..mission.items import mission_settings
from ..mission.plan_reader import plan_from_document, read_plan_json
from ..planning.planner import plan as plan_scenario
from ..planning.plans import Plan
from ..planning.resume import ResumePoint, plan_resume, resume_point
from .planned import PlannedFlight
from .progress import progress_from_document

RESUME_FOLDER = "resume"
PROGRESS_FILE = "progress.json"
RESUMED_FILE = "resumed.json"


class ResumeError(BadInput):
    """Nothing to resume from, or the rest cannot be planned."""


@dataclass(frozen=True)
class Resumed:
    """The rest of a plan: ``folder`` (written), where it resumes and its plan."""

    folder: Path
    at: ResumePoint
    plan: Plan
    progress: tuple[float, ...]


def plan_rest(planned: PlannedFlight, progress_file: Path) -> Resumed:
    """Plan the rest of ``planned`` after the flight whose ``progress_file`` is given and
    write it to ``planned.folder / "resume"``. :class:`ResumeError` (or
    :class:`~ftlbo_mav.planning.resume.NothingToResume`) when it cannot."""
    if not progress_file.is_file():
        raise ResumeError(f"{progress_file}: no such file: `fly` writes it at the end of "
                          "every flight of a plan; there is no flight of this plan to resume")
    try:
        progress = progress_from_document(planned, json.loads(progress_file.read_text()))
    except (ValueError, KeyError, TypeError) as exc:
        raise ResumeError(f"{progress_file}: not the progress of a flight of "
                          f"{planned.folder} ({exc})") from None
    doc, source = read_plan_json(planned.folder)
    try:
        plan = plan_from_document(doc, source=source)
    except MissionFileError as exc:
        raise ResumeError(str(exc)) from None
    if "mission" not in doc:  # a plan.json of before it was recorded: its missions say
        end, speed = mission_settings(planned.missions[0])
        plan = replace(plan, scenario=replace(plan.scenario, mission=replace(
            plan.scenario.mission, end_action=end, speed_m_s=speed)))
    at = resume_point(plan, [p.point for p in progress], [p.photos for p in progress])
    rest = plan_resume(plan, at, plan_scenario)
    if not rest.feasible:
        raise ResumeError("the rest of the plan from " + at.describe(plan) + " is infeasible: "
                          + "; ".join(rest.violations))
    folder = planned.folder / RESUME_FOLDER
    files = plan_files(rest, fence=any(f is not None for f in planned.fences))
    files[RESUMED_FILE] = json.dumps(resumed_document(progress_file, progress, at),
                                     indent=1) + "\n"
    with OutputFolder(folder, replaces=(*PLAN_OUTPUTS, re.escape(RESUMED_FILE)),
                      last="plan.json") as out:
        out.write_all(files)
    return Resumed(folder, at, rest, tuple(p.point for p in progress))


def resumed_document(progress_file: Path, progress, at: ResumePoint) -> dict:
    """``resumed.json`` in the rest's folder: the flight it carries on from (its
    progress.json and each UAV's point), where it resumes, the photos each UAV took in
    the resumed lane, whether its photo at the resume point was taken, and how many of
    its photos the rest takes again."""
    return {"progress": str(progress_file),
            "flown_to": {p.name: round(p.point, 4) for p in progress},
            "point": round(float(at.point), 4),
            "lane": None if at.lane is None else at.lane + 1,
            "photos_in_lane": list(at.photos), "photo_taken": list(at.photo_taken),
            "again": list(at.again) or [0] * len(progress)}


__all__ = ["PROGRESS_FILE", "RESUMED_FILE", "RESUME_FOLDER", "ResumeError", "Resumed",
           "plan_rest", "resumed_document"]
