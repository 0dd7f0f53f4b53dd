"""A survey larger than one battery, flown in sorties.

A survey whose missions would land below the ``[battery]`` reserve is cut into sorties,
each a complete flight of every UAV from home and back home (the last one to the
scenario's goal), each flying a run of whole lanes, in lane order: no lane is skipped or
flown twice, so no photo is either (a lane's photos are its own: its camera trigger is
switched on at its entry and off at its exit).

1. The whole survey is planned once (its lanes laid, kept inside the area as its
   copters are predicted to fly them: :func:`.planner.plan`).
2. Its predicted charge along the path (:class:`~ftlbo_mav.energy.MissionCharge`'s
   ``to_end``) says what every lane costs; a sortie of lanes ``a..b`` is estimated as the
   takeoff, the straight way from home to lane ``a``'s entry, the lanes and the ways
   between them as planned, the straight way back home from lane ``b``'s exit and the
   landing, with :data:`DETOUR` on the straight ways (trees) and :data:`ESTIMATE_SHARE`
   of the battery's usable charge kept for the estimate's error. The fewest sorties of
   whole lanes that fit are found exactly over those estimates (:func:`cut`).
3. Each sortie is planned as a scenario of its own (start, its lanes, home), the lanes
   as laid in 1 (not laid again). A sortie whose plan does not fit the battery after all
   gives its last lane to the next one, and is planned again.

Pure computation over scenarios and plans.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from ..energy import BATTERY_VIOLATION
from ..errors import BadInput
from ..scenario import GeoPoint, Scenario
from .plans import Plan

DETOUR = 1.3
"""The way from home to a sortie's first lane (and back from its last) is estimated as
this much longer than the straight line: the trees it goes round."""
ESTIMATE_SHARE = 0.95
"""Sorties are estimated to use at most this share of the battery's usable charge."""
MAX_SHIFTS = 64
"""Lanes moved to the next sortie at most, over all sorties, before giving up."""


class SortieError(BadInput):
    """A survey that cannot be cut into sorties (a lane alone needs more than a battery)."""


@dataclass(frozen=True, eq=False)
class Sorties:
    """The survey as flown: ``plans`` one per sortie (a single plan when it fits one
    battery), ``lanes`` each sortie's ``(first, last)`` lane index (0-based, inclusive) in
    the whole survey's order, and ``whole`` the plan of the whole survey in one flight."""

    plans: tuple[Plan, ...]
    lanes: tuple[tuple[int, int], ...]
    whole: Plan

    @property
    def split(self) -> bool:
        return len(self.plans) > 1


def battery_short(p: Plan) -> bool:
    """Whether some mission of ``p`` would land below its battery's reserve."""
    return any(v.startswith(BATTERY_VIOLATION) for v in p.violations)


def lane_scenario(whole: Scenario, first: int, last: int, *, last_sortie: bool) -> Scenario:
    """The sortie flying lanes ``first..last`` (inclusive) of ``whole``'s survey as laid:
    from the start (through ``whole``'s own ``[[via]]`` points, in the first sortie) to
    home, the start, or to the goal in the last sortie."""
    survey = whole.survey
    lanes = survey.lanes
    own = len(whole.via) - 2 * len(lanes)  # the [[via]] points before the lanes
    via = (whole.via[:own] if first == 0 else ()) + whole.via[own + 2 * first:
                                                              own + 2 * (last + 1)]
    goal = whole.goal if last_sortie else GeoPoint(whole.start.lat_deg, whole.start.lon_deg,
                                                   whole.start.alt_m)
    return replace(whole, via=via, goal=goal,
                   survey=replace(survey, lanes=lanes[first:last + 1]))


def estimates(p: Plan) -> Callable[[int, int], float]:
    """``cost(a, b)``: the estimated charge (mAh, the most any UAV uses) of a sortie of
    lanes ``a..b`` of the whole survey's plan ``p`` (module notes)."""
    battery, nav = p.scenario.battery, p.scenario.vehicle
    ends = np.array(p.lane_points()).reshape(-1, 2)
    speed = p.scenario.mission.speed_m_s or nav.wp_speed
    paths = p.uav_paths

    def way(a: np.ndarray, b: np.ndarray) -> float:
        metres = DETOUR * float(np.hypot(*(b[:2] - a[:2])))
        climb = abs(float(b[2] - a[2]))
        return (battery.mah(metres / speed, speed, 0.0)
                + battery.mah(climb / max(nav.wp_speed_up, 0.1), 0.0, nav.wp_speed_up))

    def cost(a: int, b: int) -> float:
        worst = 0.0
        for n, c in enumerate(p.charges):
            used = c.total_mah - c.to_end_mah  # (P,) used on arriving at each point
            home = paths[n, 0]
            lanes = float(used[ends[b, 1]] - used[ends[a, 0]])
            total = (c.takeoff_mah + way(home, paths[n, ends[a, 0]]) + lanes
                     + way(paths[n, ends[b, 1]], home) + c.end_mah)
            worst = max(worst, total)
        return worst

    return cost


def cut(cost: Callable[[int, int], float], lanes: int, usable_mah: float
        ) -> list[tuple[int, int]]:
    """Whole lanes in order, in the fewest sorties whose ``cost`` each stays within
    ``usable_mah`` (a shortest path over the lane boundaries; of equal counts, the one
    whose last sortie begins earliest); :class:`SortieError` for a lane that alone does
    not fit."""
    for a in range(lanes):
        if cost(a, a) > usable_mah:
            raise SortieError(f"lane {a + 1} alone needs about {cost(a, a):.0f} mAh with the "
                              f"ways to it and back, more than the {usable_mah:.0f} mAh a "
                              "battery has above its reserve: the survey cannot be flown in "
                              "sorties (a larger battery, or shorter lanes)")
    # fewest[b]: sorties for lanes 0..b-1; since[b]: where its last sortie begins
    fewest = [0] + [math.inf] * lanes
    since = [0] * (lanes + 1)
    for b in range(1, lanes + 1):
        for a in range(b - 1, -1, -1):  # the last sortie: lanes a..b-1
            # (no early stop: a sortie that begins later can cost more, its way longer)
            if fewest[a] + 1 <= fewest[b] and cost(a, b - 1) <= usable_mah:
                fewest[b], since[b] = fewest[a] + 1, a
    out, b = [], lanes
    while b > 0:
        out.append((since[b], b - 1))
        b = since[b]
    return out[::-1]


def plan_sorties(scenario: Scenario, planner: Callable[..., Plan], *,
                 whole: Plan | None = None, **kw) -> Sorties:
    """``scenario``'s survey planned with ``planner`` (:func:`.planner.plan`, keyword
    arguments ``kw``), in sorties when one battery does not fly it (module notes);
    ``whole``: its plan in one flight, when made already."""
    whole = planner(scenario, **kw) if whole is None else whole
    s = whole.scenario  # its lanes as laid, kept inside the area
    if (s.battery is None or s.survey is None or not s.survey.lanes
            or whole.charges is None or not battery_short(whole)):
        return Sorties((whole,), (), whole)
    count = len(s.survey.lanes)
    cuts = cut(estimates(whole), count, ESTIMATE_SHARE * s.battery.usable_mah)
    plans: list[Plan] = []
    shifts = 0
    k = 0
    while k < len(cuts):
        a, b = cuts[k]
        last = b == count - 1
        p = planner(lane_scenario(s, a, b, last_sortie=last), relay=False, **kw)
        if battery_short(p) and b > a and shifts < MAX_SHIFTS:
            shifts += 1
            cuts[k] = (a, b - 1)  # its last lane to the next sortie
            if last:
                cuts.append((b, b))
            else:
                cuts[k + 1] = (b, cuts[k + 1][1])
            continue
        plans.append(p)
        k += 1
    return Sorties(tuple(plans), tuple(cuts), whole)


def sortie_note(sorties: Sorties) -> list[str]:
    """A line per sortie: its lanes, charge and time (for the CLI)."""
    lines = []
    battery = sorties.whole.scenario.battery
    for k, (p, (a, b)) in enumerate(zip(sorties.plans, sorties.lanes)):
        worst = max(p.charges, key=lambda c: c.total_mah) if p.charges else None
        charge = (f"; at most {worst.total_mah:.0f} mAh in {worst.seconds / 60.0:.1f} min, "
                  f"landing with {100.0 * (1 - worst.total_mah / battery.capacity_mah):.0f} %"
                  if worst is not None else "")
        lines.append(f"sortie {k + 1}: lanes {a + 1}-{b + 1}{charge}"
                     + ("" if p.feasible else " (infeasible: see its plan.json)"))
    return lines


def sorties_document(sorties: Sorties, folders: list[str]) -> dict:
    """``sorties.json``: the battery, the whole survey in one flight, and per sortie its
    folder, lanes (1-based), feasibility, each UAV's charge (mAh) and the longest time."""
    battery = sorties.whole.scenario.battery
    rows = []
    for folder, p, (a, b) in zip(folders, sorties.plans, sorties.lanes):
        rows.append({"folder": folder, "lanes": [a + 1, b + 1], "feasible": p.feasible,
                     "charge_mah": [round(c.total_mah, 1) for c in p.charges or ()],
                     "seconds": round(max((c.seconds for c in p.charges or ()),
                                          default=0.0), 1)})
    whole = sorties.whole
    return {"battery": battery.document() if battery is not None else None,
            "lanes": len(whole.scenario.survey.lanes),
            "whole": {"feasible": whole.feasible,
                      "charge_mah": [round(c.total_mah, 1) for c in whole.charges or ()]},
            "sorties": rows}


__all__ = ["Sorties", "SortieError", "battery_short", "cut", "estimates", "lane_scenario",
           "plan_sorties", "sortie_note", "sorties_document"]
