"""``fly --resume``: the rest of a plan after a flight that ended early, as a plan folder.

The flight before wrote ``progress.json`` (:mod:`.progress`) beside its log; from it and
the plan folder the rest is planned (:mod:`ftlbo_mav.planning.resume`) and written as
``PLAN/resume/``, a plan folder like any other: ``fly --resume`` uploads it, verified,
and flies it; ``fly PLAN/resume --resume`` carries on after that one.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, replace
from pathlib import Path

from ..errors import BadInput, MissionFileError
from ..mission.export import plan_from_document, read_plan_json, write_plan
from ..mission.items import mission_settings
from ..planning.planner import Plan
from ..planning.planner import plan as plan_scenario
from ..planning.resume import ResumePoint, plan_resume, resume_point
from .planned import PlannedFlight
from .progress import progress_from_document

RESUME_FOLDER = "resume"
PROGRESS_FILE = "progress.json"


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
    write_plan(rest, folder, fence=any(f is not None for f in planned.fences))
    return Resumed(folder, at, rest, tuple(p.point for p in progress))


__all__ = ["PROGRESS_FILE", "RESUME_FOLDER", "ResumeError", "Resumed", "plan_rest"]
