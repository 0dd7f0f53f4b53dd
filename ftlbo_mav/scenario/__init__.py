"""Scenario files: TOML -> a validated, frozen :class:`Scenario`.

The values are :mod:`.model` (a :class:`Scenario` and its parts, its ENU frame); reading
and validating TOML is :mod:`.reader` (every mistake a user can make ends there as a
:class:`~ftlbo_mav.errors.ScenarioError` naming the file, the field and the problem),
with its tables: :mod:`.tables` (one TOML table), :mod:`.settings` (``[planner]``,
``[mission]``, ``[navigation]``, ``[battery]``), :mod:`.survey` (``[survey]``,
``[camera]``, the lanes), :mod:`.fleet` (``[vehicle]``); obstacles read from GeoJSON are
:mod:`ftlbo_mav.obstacles`. Every public name is importable from here, as it was when the
scenario was one module.
"""

from .model import (
    ALGORITHMS,
    AUTO,
    END_ACTIONS,
    Camera,
    Cylinder,
    GeoPoint,
    MissionSettings,
    PlannerSettings,
    Scenario,
    Survey,
    ViaPoint,
    Weights,
)
from .reader import load_scenario, parse_scenario
from .survey import relay_lanes, survey_width

__all__ = [
    "relay_lanes",
    "ALGORITHMS", "AUTO", "END_ACTIONS", "Camera", "Cylinder", "GeoPoint", "MissionSettings",
    "PlannerSettings", "Scenario", "Survey", "ViaPoint", "Weights", "load_scenario",
    "parse_scenario", "survey_width",
]
