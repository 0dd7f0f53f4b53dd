"""Each vehicle's battery held to what its mission needs: before the flight and on it.

With or without a ``[battery]`` in the plan. Without one (:class:`OwnBatteries`, the
default), each copter's own battery is what it says of itself, read before arming:
BATT_CAPACITY (its per cent is of that), a floor to land with (its BATT_LOW_MAH, else
BATT_CRT_MAH, else :data:`DEFAULT_RESERVE_PCT` of the capacity) and what its mission
needs: the plan's predicted flight charged at :data:`ASSUMED_HOVER_MIN` minutes of hover
on a full battery before the flight, at the current the copter reports once it flies.
Its own ``Battery N is low`` / ``Battery Failsafe`` with BATT_FS_*_ACT 0 (announced, no
action of its own) is a departure too (:meth:`BatteryWatch.text_kind`).

With a ``[battery]`` (:mod:`ftlbo_mav.energy`), the plan predicts what each mission uses
from each of its points to the end, its landing included (plan.json ``uavs[i].battery``). A
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

from ..ardupilot.battery import LOW_PATTERN
from ..energy import Battery, mission_charges
from ..mission.items import (
    CMD_NAV_LOITER_UNLIM,
    CMD_NAV_RETURN_TO_LAUNCH,
    CMD_NAV_TAKEOFF,
    CMD_NAV_WAYPOINT,
    MissionItem,
)

DEFAULT_RESERVE_PCT = 25.0
"""Without a ``[battery]`` and without a BATT_LOW_MAH / BATT_CRT_MAH of its own, a copter
keeps this much of its BATT_CAPACITY to land with: the reserve a ``[battery]`` keeps by
default (:class:`~ftlbo_mav.energy.Battery`)."""

ASSUMED_HOVER_MIN = 12.0
"""Without a ``[battery]``, before a copter has flown: its full battery assumed to hover
this long (small survey quads hover 7-20 minutes: ArduPilot SITL's quad 7 on its 3300
mAh at 28 A, tests/data/ardupilot-4.5.6/battery.json; a 3DR Solo about 20). In flight
the current it reports replaces it."""

MEASURED_AFTER_S = 3.0  # seconds of reports in the air before the measured current counts


class _Charges:
    """Each vehicle's mission charge (mAh): ``total_mah[i]`` in all, ``to_end[i]`` ``(P,)``
    from each path point to the end."""

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


@dataclass(frozen=True, eq=False)
class MissionBattery(_Charges):
    """The plan's battery and, per vehicle, its mission's charge (mAh) in all and from
    each path point to the end (``to_end[i]``, ``(P,)``)."""

    battery: Battery
    total_mah: tuple[float, ...]
    to_end: tuple[np.ndarray, ...]

    def remaining_mah(self, pct: int, i: int = 0) -> float:
        return self.battery.capacity_mah * pct / 100.0

    def capacity_mah(self, i: int) -> float:
        return self.battery.capacity_mah

    def reserve_mah(self, i: int) -> float:
        return self.battery.reserve_mah

    def reserve_said(self, i: int) -> str:
        return f"{self.battery.reserve_pct:g} % reserve"

    def scale(self, i: int, measured_a: float | None) -> float:
        """The plan's model goes on as it is: what the copter draws changes nothing."""
        return 1.0

    def preflight_problem(self, i: int, pct: int | None) -> str | None:
        return preflight_problem(self, i, pct)


@dataclass(frozen=True)
class CopterBattery:
    """What one copter says of its battery (its BATT_* parameters, ArduPilot's names:
    libraries/AP_BattMonitor/AP_BattMonitor_Params.cpp)."""

    monitor: int = 0
    capacity_mah: float = 0.0
    low_mah: float = 0.0
    crt_mah: float = 0.0
    low_action: int = 0
    crt_action: int = 0

    PARAMS = ("BATT_MONITOR", "BATT_CAPACITY", "BATT_LOW_MAH", "BATT_CRT_MAH",
              "BATT_FS_LOW_ACT", "BATT_FS_CRT_ACT")

    @classmethod
    def from_params(cls, values) -> CopterBattery:
        """From :attr:`PARAMS` as read (a value not answered counts as 0: off)."""
        def get(name: str) -> float:
            v = values.get(name)
            return 0.0 if v is None else float(v)

        return cls(int(get("BATT_MONITOR")), get("BATT_CAPACITY"), get("BATT_LOW_MAH"),
                   get("BATT_CRT_MAH"), int(get("BATT_FS_LOW_ACT")),
                   int(get("BATT_FS_CRT_ACT")))

    @property
    def watched(self) -> bool:
        """It has a monitor and a capacity: its per cent means something."""
        return self.monitor != 0 and self.capacity_mah > 0

    def reserve(self) -> tuple[float, str]:
        """``(mAh, where from)``: what it keeps to land with."""
        if self.low_mah > 0:
            return self.low_mah, f"its BATT_LOW_MAH {self.low_mah:g} mAh"
        if self.crt_mah > 0:
            return self.crt_mah, f"its BATT_CRT_MAH {self.crt_mah:g} mAh"
        return (self.capacity_mah * DEFAULT_RESERVE_PCT / 100.0,
                f"{DEFAULT_RESERVE_PCT:g} % of its BATT_CAPACITY, as no BATT_LOW_MAH is set")


@dataclass(frozen=True, eq=False)
class OwnBatteries(_Charges):
    """No ``[battery]``: each copter's own (``copters``), its mission's charge at
    ``assumed_a`` amperes in all (``total_mah``) and from each path point to the end
    (``to_end``), as :class:`MissionBattery` has them from the plan."""

    copters: tuple[CopterBattery, ...]
    assumed_a: tuple[float, ...]
    total_mah: tuple[float, ...]
    to_end: tuple[np.ndarray, ...]
    seconds: tuple[float, ...]

    def capacity_mah(self, i: int) -> float:
        return self.copters[i].capacity_mah

    def remaining_mah(self, pct: int, i: int = 0) -> float:
        return self.copters[i].capacity_mah * pct / 100.0

    def reserve_mah(self, i: int) -> float:
        return self.copters[i].reserve()[0]

    def reserve_said(self, i: int) -> str:
        return f"reserve ({self.copters[i].reserve()[1]})"

    def scale(self, i: int, measured_a: float | None) -> float:
        """What it draws over what was assumed (1 until measured)."""
        return 1.0 if measured_a is None else measured_a / self.assumed_a[i]

    def preflight_problem(self, i: int, pct: int | None) -> str | None:
        c = self.copters[i]
        if not c.watched or pct is None:
            return None  # said as a note (:meth:`unwatched`), not refused
        have, need = self.remaining_mah(pct, i), self.total_mah[i]
        reserve, where = c.reserve()
        if have >= need + reserve:
            return None
        return (f"battery at {pct} % ({have:.0f} of {c.capacity_mah:g} mAh): its mission "
                f"needs about {need:.0f} mAh ({self.seconds[i]:.0f} s at "
                f"{self.assumed_a[i]:.1f} A, {ASSUMED_HOVER_MIN:g} minutes of hover on a full "
                f"battery, as the plan has no [battery]) and it keeps {reserve:.0f} mAh to land "
                f"with ({where}): {need + reserve:.0f} mAh "
                f"({100.0 * (need + reserve) / c.capacity_mah:.0f} %)")

    def unwatched(self, i: int, pct: int | None) -> str | None:
        """Why copter ``i``'s battery cannot be watched (None: it can)."""
        c = self.copters[i]
        if c.monitor == 0:
            return "has no battery monitor (BATT_MONITOR 0): its battery is not watched"
        if c.capacity_mah <= 0:
            return "has no BATT_CAPACITY: its battery is not watched"
        if pct is None:
            return ("reports no battery charge (SYS_STATUS battery_remaining): its battery "
                    "is not watched")
        return None


def own_batteries_for(missions: Sequence[Sequence[MissionItem]], prediction, navs,
                      copters: Sequence[CopterBattery]) -> OwnBatteries:
    """:class:`OwnBatteries` of a plan's ``missions`` flown as ``prediction`` says (the
    :class:`~ftlbo_mav.planning.predicted.Prediction` with each copter's own values,
    ``navs`` their :class:`~ftlbo_mav.ardupilot.navigation.Navigation`), each charged
    with its copter's assumed battery."""
    homes = prediction.positions[:, 0] * np.array([1.0, 1.0, 0.0])  # each below its start
    charges = [mission_charges(assumed_battery(c), nav, prediction,
                               end_action=end_action(m), homes=homes)[n]
               for n, (m, nav, c) in enumerate(zip(missions, navs, copters))]
    return own_batteries(copters, charges)


def end_action(mission: Sequence[MissionItem]) -> str:
    """How ``mission`` ends, as :func:`~ftlbo_mav.energy.end_charge` names it."""
    last = mission[-1].command if mission else None
    return {CMD_NAV_RETURN_TO_LAUNCH: "rtl", CMD_NAV_LOITER_UNLIM: "loiter"}.get(last, "land")


def own_batteries(copters, charges) -> OwnBatteries:
    """:class:`OwnBatteries` from each copter's :class:`CopterBattery` and its mission's
    :class:`~ftlbo_mav.energy.MissionCharge` at the assumed current
    (:func:`assumed_battery`)."""
    return OwnBatteries(tuple(copters), tuple(assumed_current_a(c) for c in copters),
                        tuple(ch.total_mah for ch in charges),
                        tuple(np.asarray(ch.to_end_mah, float) for ch in charges),
                        tuple(ch.seconds for ch in charges))


def assumed_current_a(copter: CopterBattery) -> float:
    """The current that empties its capacity in :data:`ASSUMED_HOVER_MIN` (1 A without a
    capacity, never used to judge: such a battery is not watched)."""
    if copter.capacity_mah <= 0:
        return 1.0
    return copter.capacity_mah / 1000.0 / (ASSUMED_HOVER_MIN / 60.0)


def assumed_battery(copter: CopterBattery) -> Battery:
    """Its battery as the plan's energy model charges a mission without a ``[battery]``."""
    return Battery(capacity_mah=max(copter.capacity_mah, 1.0),
                   hover_current_a=assumed_current_a(copter),
                   reserve_pct=DEFAULT_RESERVE_PCT, source="assumed")


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
    the reserve (see the module's docstring). ``plan``: :class:`MissionBattery` (the
    plan's ``[battery]``) or :class:`OwnBatteries` (without one)."""

    def __init__(self, plan: MissionBattery | OwnBatteries,
                 missions: Sequence[Sequence[MissionItem]]) -> None:
        self.plan = plan
        self.waypoints = [waypoint_seqs(m) for m in missions]  # once, not every check
        n = len(missions)
        self._amps = [[0.0, 0.0] for _ in range(n)]  # per vehicle: A s, s in the air
        self._last: list[float | None] = [None] * n
        self._level = [""] * n  # "low" / "critical": the copter's own, announced

    def measured_a(self, i: int) -> float | None:
        """The mean current vehicle ``i`` has reported in the air (None: not yet
        :data:`MEASURED_AFTER_S` of it)."""
        charge, seconds = self._amps[i]
        return charge / seconds if seconds >= MEASURED_AFTER_S else None

    def check(self, i: int, pct: int | None, seq: int, *, current_a: float | None = None,
              now: float | None = None) -> str | None:
        """Why vehicle ``i`` is short (None: it is not); ``current_a`` what it reports it
        draws at ``now`` (seconds, any clock), in the air."""
        if current_a is not None and current_a > 0 and now is not None:
            # (0: a monitor without a current sensor, SYS_STATUS current_battery -1: the
            # assumed current stays)
            last, self._last[i] = self._last[i], now
            if last is not None and 0.0 < now - last < 2.0:
                self._amps[i][0] += current_a * (now - last)
                self._amps[i][1] += now - last
        if pct is None or seq < 0:
            return None
        plan = self.plan
        if isinstance(plan, OwnBatteries) and plan.unwatched(i, pct) is not None:
            return None
        measured = self.measured_a(i)
        need = plan.need_mah(i, seq, self.waypoints[i]) * plan.scale(i, measured)
        floor = need + 0.5 * plan.reserve_mah(i)
        have = plan.remaining_mah(pct, i)
        if have >= floor:
            return None
        drawn = "" if measured is None or isinstance(plan, MissionBattery) else (
            f" at the {measured:.1f} A it draws")
        return (f"{pct} % left ({have:.0f} mAh): the rest of its mission needs {need:.0f} mAh"
                f"{drawn} and it would land below half its {plan.reserve_said(i)}")

    def text_kind(self, i: int, text: str, kind: str | None) -> str | None:
        """The departure vehicle ``i``'s STATUSTEXT ``text`` is, ``kind`` as read without
        the battery (:func:`~ftlbo_mav.ardupilot.failsafes.departure_text`): with
        :class:`OwnBatteries`, its own ``Battery N is low`` (or ``critical``) when its
        BATT_FS_*_ACT for that is 0 is ``"battery"``, and so is the ``Battery Failsafe``
        that follows (Copter::handle_battery_failsafe says it whatever the action, and with
        none the copter flies on in AUTO: not a failsafe it chose)."""
        if not isinstance(self.plan, OwnBatteries):
            return kind
        c = self.plan.copters[i]
        found = LOW_PATTERN.search(text.strip("\x00 "))
        if found:
            self._level[i] = found.group(1)
        level = self._level[i]
        action = c.crt_action if level == "critical" else c.low_action
        if level and action == 0 and (found or text.strip().startswith("Battery Failsafe")):
            return "battery"
        return kind
