"""Scenario files: TOML -> a validated, frozen :class:`Scenario`.

The values are :mod:`.model` (a :class:`Scenario` and its parts, its ENU frame); reading
and validating TOML is :mod:`.reader` (every mistake a user can make ends there as a
:class:`~ftlbo_mav.errors.ScenarioError` naming the file, the field and the problem);
obstacles read from GeoJSON are :mod:`ftlbo_mav.obstacles`. Every public name of the two
modules is importable from here, as it was when the scenario was one module.
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
from .reader import load_scenario, parse_scenario, relay_lanes, survey_width

__all__ = [
    "relay_lanes",
    "ALGORITHMS", "AUTO", "END_ACTIONS", "Camera", "Cylinder", "GeoPoint", "MissionSettings",
    "PlannerSettings", "Scenario", "Survey", "ViaPoint", "Weights", "load_scenario",
    "parse_scenario", "survey_width",
]
