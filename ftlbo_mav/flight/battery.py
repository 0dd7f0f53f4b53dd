"""Each vehicle's battery held to what its mission needs: before the flight and on it.

The plan (``[battery]``, :mod:`ftlbo_mav.energy`) predicts what each mission uses from
each of its points to the end, its landing included (plan.json ``uavs[i].battery``). A
vehicle reports what is left as a percentage (SYS_STATUS ``battery_remaining``, which
ArduPilot computes from BATT_CAPACITY and the charge it has counted:
:mod:`ftlbo_mav.ardupilot.battery`); the plan's capacity turns it into mAh.

- Before arming, a vehicle whose charge does not cover its whole mission *and* the
  reserve is refused (:func:`preflight_problem`).
- In flight, a vehicle whose charge no longer covers the rest of its mission and half
  its reserve is a departure (:meth:`BatteryWatch.check`): it would land on less than
  half the reserve the plan promised, because it draws more than predicted (wind, an
  older battery, a heavier copter) or started with less. This comes before ArduPilot's
  own failsafe, which acts on BATT_LOW_MAH / BATT_LOW_VOLT alone, whatever is left to fly.

Pure: no I/O.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..energy import Battery
from ..mission.items import CMD_NAV_TAKEOFF, CMD_NAV_WAYPOINT, MissionItem


@dataclass(frozen=True, eq=False)
class MissionBattery:
    """The plan's battery and, per vehicle, its mission's charge (mAh) in all and from
    each path point to the end (``to_end[i]``, ``(P,)``)."""

    battery: Battery
    total_mah: tuple[float, ...]
    to_end: tuple[np.ndarray, ...]

    def need_mah(self, i: int, seq: int, waypoints: Sequence[int]) -> float:
        """What vehicle ``i`` still needs when its current mission item is ``seq``
        (``waypoints``: its path points' items, :func:`waypoint_seqs`): all of it up to
        its takeoff; heading for path point k, what is left from point k-1 (from where
        the leg began: an upper bound); past the last point, its landing."""
        if not waypoints or seq <= waypoints[0]:
            return self.total_mah[i]
        k = int(np.searchsorted(waypoints, seq, side="left"))  # heading for point k
        return float(self.to_end[i][min(k - 1, len(self.to_end[i]) - 1)])

    def remaining_mah(self, pct: int) -> float:
        return self.battery.capacity_mah * pct / 100.0


def waypoint_seqs(mission: Sequence[MissionItem]) -> list[int]:
    """The seq of each path point's NAV_WAYPOINT (after NAV_TAKEOFF), in order."""
    after = next((it.seq for it in mission if it.command == CMD_NAV_TAKEOFF), None)
    if after is None:
        return []
    return [it.seq for it in mission if it.command == CMD_NAV_WAYPOINT and it.seq > after]


def preflight_problem(plan: MissionBattery, i: int, pct: int | None) -> str | None:
    """Why vehicle ``i``, reporting ``pct`` per cent, may not take off (None: it may)."""
    if pct is None:
        return ("reports no battery charge (SYS_STATUS battery_remaining): the plan's "
                "[battery] cannot be checked")
    b = plan.battery
    have = plan.remaining_mah(pct)
    need = plan.total_mah[i] + b.reserve_mah
    if have >= need:
        return None
    return (f"battery at {pct} % ({have:.0f} of {b.capacity_mah:g} mAh): its mission needs "
            f"{plan.total_mah[i]:.0f} mAh and the {b.reserve_pct:g} % reserve "
            f"{b.reserve_mah:.0f} mAh, {need:.0f} mAh ({100.0 * need / b.capacity_mah:.0f} %)")


class BatteryWatch:
    """In flight: a vehicle's charge against what the rest of its mission needs plus half
    the reserve (see the module's docstring)."""

    def __init__(self, plan: MissionBattery, missions: Sequence[Sequence[MissionItem]]
                 ) -> None:
        self.plan = plan
        self.waypoints = [waypoint_seqs(m) for m in missions]  # once, not every check

    def check(self, i: int, pct: int | None, seq: int) -> str | None:
        if pct is None or seq < 0:
            return None
        need = self.plan.need_mah(i, seq, self.waypoints[i])
        floor = need + 0.5 * self.plan.battery.reserve_mah
        have = self.plan.remaining_mah(pct)
        if have >= floor:
            return None
        return (f"{pct} % left ({have:.0f} mAh): the rest of its mission needs {need:.0f} mAh "
                f"and it would land below half its {self.plan.battery.reserve_pct:g} % reserve")
