"""How well the copters know where they are: the navigation error budget.

Every figure the planner predicts is a copter's *estimate* of its position: ArduCopter
flies its EKF's position along the mission, and where the copter really is differs by
the position error of its GNSS receiver. The budget is a horizontal error bound that
holds 95 % of the time (:class:`NavigationBudget`), named by a class of receiver
(:data:`CLASSES`) or given in metres (``[navigation] horizontal_error``). The planner
keeps the clearance on the true position: on the predicted (estimated) flown path it
keeps the clearance *plus* the budget (total system error = the flight technical error
the flight model predicts + the navigation error), and between two copters, whose
errors are independent, the combined error ``sqrt(2)`` times the budget
(:func:`pair_error_m`; conservative: receivers side by side share much of their error).

The vertical error is not budgeted: ArduCopter holds altitude on its barometer
(EK3_SRC1_POSZ = 1, libraries/AP_NavEKF3/AP_NavEKF_Source.cpp), and the obstacles are
vertical cylinders, whose clearance is horizontal.

Pure data and arithmetic.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

R95_PER_CEP = math.sqrt(-2.0 * math.log(0.05)) / math.sqrt(2.0 * math.log(2.0))
"""A circular normal error's 95 % radius over its CEP (50 % radius): 2.08."""

# MAVLink GPS_FIX_TYPE (common.xml)
FIX_NAMES = {0: "no GPS", 1: "no fix", 2: "2D fix", 3: "3D fix", 4: "DGPS/SBAS", 5: "RTK float",
             6: "RTK fixed", 7: "static", 8: "PPP"}


@dataclass(frozen=True)
class NavigationBudget:
    """``horizontal_m``: the horizontal position error bound at 95 %; ``name``: its class
    (or ``"custom"``); ``min_fix_type``: the GPS_FIX_TYPE a copter needs to be held to it
    (3: a 3D fix, 4: SBAS, 5: RTK float, 6: RTK fixed); ``source``: where the figure
    comes from."""

    name: str
    horizontal_m: float
    min_fix_type: int = 3
    source: str = ""

    @property
    def pair_m(self) -> float:
        """The combined error of two copters, each within ``horizontal_m``."""
        return pair_error_m(self.horizontal_m)

    def describe(self) -> str:
        what = f"{self.name}, " if self.name != "custom" else ""
        return f"{what}{self.horizontal_m:g} m horizontal at 95 %"

    def document(self) -> dict:
        """The budget as plan.json says it."""
        return {"class": self.name, "horizontal_error_m": self.horizontal_m,
                "min_fix_type": self.min_fix_type, "source": self.source}


def _cep(cep_m: float) -> float:
    return round(cep_m * R95_PER_CEP, 2)


CLASSES: dict[str, NavigationBudget] = {
    "gps": NavigationBudget(
        "gps", _cep(2.5), 3,
        "u-blox NEO-M8 data sheet (UBX-15031086): 2.5 m CEP without corrections; 95 % of a "
        "circular normal is 2.08 CEP"),
    "sbas": NavigationBudget(
        "sbas", _cep(2.0), 4,
        "u-blox NEO-M8 data sheet (UBX-15031086): 2.0 m CEP with SBAS; 95 % = 2.08 CEP"),
    "rtk-float": NavigationBudget(
        "rtk-float", 0.5, 5,
        "ours: an RTK float solution is good to decimetres (no data sheet states a "
        "figure); 0.5 m is conservative"),
    "rtk-fixed": NavigationBudget(
        "rtk-fixed", _cep(0.02), 6,
        "u-blox ZED-F9P data sheet (UBX-17051259): 0.01 m + 1 ppm CEP, 0.02 m CEP at a "
        "10 km baseline; 95 % = 2.08 CEP"),
}
DEFAULT_CLASS = "gps"
"""An uncorrected GPS: the honest default."""


def budget(name: str | None = None, horizontal_m: float | None = None) -> NavigationBudget:
    """The budget of class ``name`` (default :data:`DEFAULT_CLASS`), its error replaced by
    ``horizontal_m`` when given (then ``custom`` without a class)."""
    if name is None and horizontal_m is not None:
        return NavigationBudget("custom", float(horizontal_m), 3, "the scenario")
    base = CLASSES[name or DEFAULT_CLASS]
    if horizontal_m is None:
        return base
    return NavigationBudget(base.name, float(horizontal_m), base.min_fix_type, "the scenario")


def pair_error_m(horizontal_m: float) -> float:
    """The 95 % bound of the difference of two independent errors, each circular normal
    with 95 % bound ``horizontal_m``: ``sqrt(2)`` times it."""
    return math.sqrt(2.0) * horizontal_m


def true_distance(horizontal, vertical, error_m: float):
    """The smallest distance two points ``horizontal`` apart on the ground and
    ``vertical`` apart in height can truly be when their horizontal positions are off by
    up to ``error_m`` between them (arrays broadcast)."""
    h = np.maximum(np.asarray(horizontal, float) - error_m, 0.0)
    return np.hypot(h, vertical)


def largest_error_for(horizontal, vertical, need_m: float) -> float:
    """The largest combined pair error ``e`` with ``true_distance(h, v, e) >= need_m`` for
    every pair (arrays); 0 when one is closer already, inf when the heights alone keep
    them apart."""
    h = np.asarray(horizontal, float).ravel()
    v = np.abs(np.asarray(vertical, float).ravel())
    if not len(h):
        return math.inf
    room = np.where(v >= need_m, np.inf, h - np.sqrt(np.maximum(need_m ** 2 - v ** 2, 0.0)))
    return max(float(room.min()), 0.0)


def classes_within(horizontal_m: float) -> list[NavigationBudget]:
    """The classes whose budget is at most ``horizontal_m``, the loosest first."""
    fits = [c for c in CLASSES.values() if c.horizontal_m <= horizontal_m + 1e-9]
    return sorted(fits, key=lambda c: -c.horizontal_m)


def would_do(horizontal_m: float) -> str:
    """A few words naming the budget that keeps a promise needing at most
    ``horizontal_m`` of navigation error."""
    fits = classes_within(horizontal_m)
    named = (f"[navigation] class = \"{fits[0].name}\" ({fits[0].horizontal_m:g} m) or better"
             if fits else "no class of receiver offers that")
    return f"a budget of at most {max(horizontal_m, 0.0):.2f} m keeps it: {named}"


NO_BUDGET = NavigationBudget("none", 0.0, 3, "a plan written before navigation budgets: "
                             "it promised nothing of the true position")


def budget_from_document(doc: dict | None) -> NavigationBudget:
    """The budget plan.json's ``navigation`` holds (:meth:`NavigationBudget.document`);
    :data:`NO_BUDGET` for a plan written without one. Raises KeyError, TypeError or
    ValueError on a malformed one."""
    if doc is None:
        return NO_BUDGET
    value = float(doc["horizontal_error_m"])
    fix = int(doc.get("min_fix_type", 3))
    if not (math.isfinite(value) and value >= 0.0 and 0 <= fix <= 8):
        raise ValueError(f"navigation: horizontal_error_m {value:g}, min_fix_type {fix}")
    return NavigationBudget(str(doc.get("class", "custom")), value, fix,
                            str(doc.get("source", "")))
