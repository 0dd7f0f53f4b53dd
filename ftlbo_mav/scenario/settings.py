"""The scenario's settings tables, each read on its own: ``[planner]``, ``[mission]``,
``[navigation]`` and ``[battery]``.

Each function takes its :class:`~.tables.Table` (``None`` when the file has none: the
defaults) and returns the frozen value the :class:`~.model.Scenario` holds.
"""

from __future__ import annotations

from ..energy import Battery
from ..gnss import CLASSES, NavigationBudget, budget
from .model import (
    ALGORITHMS,
    AUTO,
    END_ACTIONS,
    MAX_ITERATIONS,
    MAX_NAVIGATION_ERROR_M,
    MAX_SEED,
    MAX_SPEED_M_S,
    MAX_STUDENTS,
    MAX_WAYPOINTS,
    MAX_WEIGHT,
    MIN_STUDENTS,
    MissionSettings,
    PlannerSettings,
    Weights,
)
from .tables import Table


def read_planner(t: Table | None) -> PlannerSettings:
    if t is None:
        return PlannerSettings()
    algorithm = t.string("algorithm", ALGORITHMS[0], choices=ALGORITHMS)
    students = t.integer("students", 100, lo=MIN_STUDENTS, hi=MAX_STUDENTS)
    if t.raw("waypoints", 10) == AUTO:
        waypoints = AUTO
    else:
        value = t.raw("waypoints")
        if (isinstance(value, bool) or not isinstance(value, int)
                or not 1 <= value <= MAX_WAYPOINTS):
            raise t.error("waypoints", f'must be an integer within [1, {MAX_WAYPOINTS}] or '
                                       f'"{AUTO}", got {value!r}')
        waypoints = value
    iterations = t.integer("iterations", 150, lo=1, hi=MAX_ITERATIONS)
    seed = t.integer("seed", 0, lo=0, hi=MAX_SEED)
    weights = Weights()
    w = t.table("weights", required=False)
    if w is not None:
        weights = Weights(
            length=w.number("length", 1.0, lo=0.0, hi=MAX_WEIGHT),
            safety=w.number("safety", 1.0, lo=0.0, hi=MAX_WEIGHT),
            task=w.number("task", 1.0, lo=0.0, hi=MAX_WEIGHT),
        )
        w.done()
    t.done()
    return PlannerSettings(algorithm, students, waypoints, iterations, seed, weights)


def read_mission(t: Table | None) -> MissionSettings:
    if t is None:
        return MissionSettings()
    end = t.string("end_action", "land", choices=END_ACTIONS)
    speed = (t.number("speed", None, lo=0.0, hi=MAX_SPEED_M_S, lo_open=True, unit="m/s")
             if t.has("speed") else None)
    t.used.add("speed")
    allowance = t.number("corner_allowance", 0.0, lo=0.0, hi=10.0, unit="m")
    t.done()
    return MissionSettings(end_action=end, speed_m_s=speed, corner_allowance_m=allowance)


def read_navigation(t: Table | None) -> NavigationBudget:
    """``[navigation]``: how well the copters know where they are. ``class``: one of
    :data:`ftlbo_mav.gnss.CLASSES` (``gps``, the default, ``sbas``, ``rtk-float``,
    ``rtk-fixed``); ``horizontal_error``: the 95 % horizontal bound in metres, in place of
    the class's figure (the class still sets the fix type a copter needs)."""
    if t is None:
        return budget()
    name = t.string("class", None, choices=tuple(CLASSES)) if t.has("class") else None
    t.used.add("class")
    error = (t.number("horizontal_error", lo=0.0, hi=MAX_NAVIGATION_ERROR_M, unit="m")
             if t.has("horizontal_error") else None)
    t.used.add("horizontal_error")
    t.done()
    return budget(name, error)


def read_battery(t: Table | None, *, cruise_speed_m_s: float) -> Battery | None:
    """``[battery]``: each UAV's battery (:mod:`ftlbo_mav.energy`). ``capacity`` (mAh),
    ``reserve`` (per cent of it to land with, default 25), and ``hover_current`` (A) or
    ``endurance`` (minutes of hover on a full battery); optional ``cruise_current`` (A
    at ``cruise_speed`` m/s, default the mission's speed or WPNAV_SPEED's 10 m/s) and
    ``induced_velocity`` (m/s, the rotor's in hover)."""
    if t is None:
        return None
    capacity = t.number("capacity", lo=0.0, hi=1_000_000.0, lo_open=True, unit="mAh")
    reserve = t.number("reserve", 25.0, lo=0.0, hi=100.0, unit="%")
    if reserve >= 100.0:
        raise t.error("reserve", "must be below 100 %: nothing would be left to fly with")
    if t.has("hover_current") == t.has("endurance"):
        raise t.error("hover_current", "give the hover current (A) or the endurance "
                      "(minutes of hover on a full battery), one of them")
    extra = dict(reserve_pct=reserve, source="[battery]", cruise_speed_m_s=cruise_speed_m_s)
    if t.has("cruise_current"):
        extra["cruise_current_a"] = t.number("cruise_current", lo=0.0, hi=1000.0,
                                             lo_open=True, unit="A")
    if t.has("cruise_speed"):
        extra["cruise_speed_m_s"] = t.number("cruise_speed", lo=0.0, hi=50.0, lo_open=True,
                                             unit="m/s")
    if t.has("induced_velocity"):
        extra["induced_velocity_m_s"] = t.number("induced_velocity", lo=0.0, hi=50.0,
                                                 lo_open=True, unit="m/s")
    if t.has("hover_current"):
        hover = t.number("hover_current", lo=0.0, hi=1000.0, lo_open=True, unit="A")
        battery = Battery(capacity_mah=capacity, hover_current_a=hover, **extra)
    else:
        minutes = t.number("endurance", lo=0.0, hi=10_000.0, lo_open=True, unit="min")
        battery = Battery.from_endurance(capacity, minutes, **extra)
    t.done()
    return battery
