"""What a mission costs its battery: the ``[battery]`` table and the charge each UAV uses.

A copter's battery current is modelled from its hover current (the ``[battery]`` table:
given in amperes, or from the copter's hover endurance in minutes on a full battery):

- **forward flight** at the mission's cruise speed draws ``cruise_current`` (default the
  hover current: at survey speeds, 5-10 m/s, a small copter's induced power saved
  roughly offsets the drag added); in between the current goes with the square of the
  speed;
- **climbing and descending** at ``vz`` multiply it by the momentum theory's power ratio
  of axial flight, ``w + sqrt(w^2 + 1)`` with ``w = vz / (2 v_h)``, ``v_h`` the rotor's
  induced velocity in hover (Leishman, *Principles of Helicopter Aerodynamics*, 2nd ed.,
  eqs. 2.55 and 2.70; the descent branch holds for slow descents, ``|vz| < v_h / 2``,
  as ArduCopter's 1.5 m/s is for a 6 m/s rotor; faster ones are counted at that ratio).

A UAV's mission is charged as ArduCopter flies it (:mod:`ftlbo_mav.ardupilot.navigation`'s
parameters): the NAV_TAKEOFF climb at WPNAV_SPEED_UP, the predicted flown path of its legs
(:class:`~ftlbo_mav.planning.predicted.Prediction`), and its end: NAV_LAND's descent
(WPNAV_SPEED_DN, then LAND_SPEED below LAND_ALT_LOW), RTL's climb to RTL_ALT, return at
RTL_SPEED, RTL_LOIT_TIME and descent, or nothing for LOITER (the pilot lands it). The
plan keeps ``reserve`` per cent of the capacity: a UAV that would land with less is
infeasible.

Pure data and arithmetic.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

SOLO = dict(capacity_mah=5200.0, endurance_min=20.0, reserve_pct=25.0)
"""The 3DR Solo's smart battery (5,200 mAh, 14.8 V, 4S) and the flight time 3DR gave for
it with a gimbal and camera, about 20 minutes, taken as hover endurance; 25 % kept to
land with: the documented example of a ``[battery]`` table (README, docs/flight.md)."""

INDUCED_VELOCITY_M_S = 6.0
"""``v_h`` by default: momentum theory's sqrt(T / (2 rho A)) for a 1.8 kg quad with four
10-inch rotors (the Solo with its gimbal: 17.7 N over 0.203 m^2 at 1.225 kg/m^3)."""


@dataclass(frozen=True)
class Battery:
    """A UAV's battery and what its copter draws: ``capacity_mah``; ``reserve_pct`` of
    it kept to land with; ``hover_current_a``; ``cruise_current_a`` at ``cruise_speed_m_s``
    (None: the hover current); ``induced_velocity_m_s`` (``v_h``) for climbs and descents;
    ``source``: where the figures come from."""

    capacity_mah: float
    hover_current_a: float
    reserve_pct: float = 25.0
    cruise_current_a: float | None = None
    cruise_speed_m_s: float = 10.0
    induced_velocity_m_s: float = INDUCED_VELOCITY_M_S
    source: str = ""

    @classmethod
    def from_endurance(cls, capacity_mah: float, endurance_min: float, **kw) -> Battery:
        """The hover current that empties ``capacity_mah`` in ``endurance_min``."""
        return cls(capacity_mah=capacity_mah,
                   hover_current_a=capacity_mah / 1000.0 / (endurance_min / 60.0), **kw)

    @property
    def reserve_mah(self) -> float:
        return self.capacity_mah * self.reserve_pct / 100.0

    @property
    def usable_mah(self) -> float:
        """What a mission may use: the capacity less the reserve."""
        return self.capacity_mah - self.reserve_mah

    def current_a(self, horizontal_m_s, vertical_m_s) -> np.ndarray:
        """The current drawn at these speeds (arrays of one shape; metres per second,
        ``vertical`` positive up)."""
        if isinstance(horizontal_m_s, float) and isinstance(vertical_m_s, float):
            return self._current_a(horizontal_m_s, vertical_m_s)
        v = np.abs(np.asarray(horizontal_m_s, float))
        vz = np.asarray(vertical_m_s, float)
        cruise = self.hover_current_a if self.cruise_current_a is None else self.cruise_current_a
        fraction = np.minimum(v / self.cruise_speed_m_s, 1.0) ** 2
        forward = self.hover_current_a + (cruise - self.hover_current_a) * fraction
        w = np.maximum(vz, -0.5 * self.induced_velocity_m_s) / (2.0 * self.induced_velocity_m_s)
        return forward * (w + np.sqrt(w * w + 1.0))

    def _current_a(self, horizontal_m_s: float, vertical_m_s: float) -> float:
        """:meth:`current_a` of two floats, in plain floats (the emulator asks at every
        step): the same arithmetic."""
        cruise = self.hover_current_a if self.cruise_current_a is None else self.cruise_current_a
        fraction = min(abs(horizontal_m_s) / self.cruise_speed_m_s, 1.0) ** 2
        forward = self.hover_current_a + (cruise - self.hover_current_a) * fraction
        w = max(vertical_m_s, -0.5 * self.induced_velocity_m_s) / (
            2.0 * self.induced_velocity_m_s)
        return forward * (w + math.sqrt(w * w + 1.0))

    def mah(self, seconds: float, horizontal_m_s: float = 0.0, vertical_m_s: float = 0.0
            ) -> float:
        """Charge used flying ``seconds`` at steady speeds."""
        return float(self.current_a(horizontal_m_s, vertical_m_s)) * seconds / 3.6

    def describe(self) -> str:
        return (f"{self.capacity_mah:g} mAh, {self.hover_current_a:.1f} A in hover, "
                f"{self.reserve_pct:g} % reserve")

    def document(self) -> dict:
        return {"capacity_mah": self.capacity_mah, "reserve_pct": self.reserve_pct,
                "hover_current_a": self.hover_current_a,
                "cruise_current_a": self.cruise_current_a,
                "cruise_speed_m_s": self.cruise_speed_m_s,
                "induced_velocity_m_s": self.induced_velocity_m_s, "source": self.source}


def battery_from_document(doc: dict | None) -> Battery | None:
    """plan.json's ``battery`` back as a :class:`Battery` (None: the plan has none)."""
    if not doc:
        return None
    return Battery(capacity_mah=float(doc["capacity_mah"]),
                   hover_current_a=float(doc["hover_current_a"]),
                   reserve_pct=float(doc["reserve_pct"]),
                   cruise_current_a=(None if doc.get("cruise_current_a") is None
                                     else float(doc["cruise_current_a"])),
                   cruise_speed_m_s=float(doc.get("cruise_speed_m_s", 10.0)),
                   induced_velocity_m_s=float(doc.get("induced_velocity_m_s",
                                                      INDUCED_VELOCITY_M_S)),
                   source=str(doc.get("source", "")))


@dataclass(frozen=True)
class MissionCharge:
    """One UAV's predicted charge (mAh): ``takeoff``, ``legs`` and ``end``; ``to_end``:
    ``(P,)`` what is left to use from each path point reached to the mission's end
    (its landing included); ``seconds``: the mission's predicted time, takeoff to
    landing."""

    takeoff_mah: float
    legs_mah: float
    end_mah: float
    to_end_mah: np.ndarray
    seconds: float

    @property
    def total_mah(self) -> float:
        return self.takeoff_mah + self.legs_mah + self.end_mah


def _leg_charge(battery: Battery, times: np.ndarray, positions: np.ndarray) -> np.ndarray:
    """``(T,)`` cumulative mAh along one predicted flown path (``times`` ``(T,)``,
    ``positions`` ``(T, 3)``), its speeds by differences of the positions."""
    if len(times) < 2:
        return np.zeros(len(times))
    dt = np.diff(times)
    step = np.diff(positions, axis=0)
    safe = np.where(dt > 0, dt, 1.0)
    horizontal = np.hypot(step[:, 0], step[:, 1]) / safe
    vertical = step[:, 2] / safe
    amps = battery.current_a(horizontal, vertical)
    return np.concatenate([[0.0], np.cumsum(amps * dt) / 3.6])


def end_charge(battery: Battery, nav, *, end_action: str, goal: np.ndarray,
               home: np.ndarray) -> tuple[float, float]:
    """(mAh, seconds) of a mission's end from its goal ``(3,)`` (metres ENU, altitude above
    home) to the ground: NAV_LAND, RTL to ``home`` or LOITER (nothing: a pilot lands it).
    ``nav``: the copter's :class:`~ftlbo_mav.ardupilot.navigation.Navigation`."""
    alt = max(float(goal[2]), 0.0)
    mah = seconds = 0.0
    if end_action == "loiter":
        return 0.0, 0.0
    if end_action == "rtl":
        climb = max(nav.rtl_alt - alt, 0.0)  # ModeRTL climbs to RTL_ALT first
        up = nav.wp_speed_up
        distance = float(np.hypot(*(np.asarray(goal[:2]) - np.asarray(home[:2]))))
        speed = nav.rtl_speed if nav.rtl_speed > 0 else nav.wp_speed
        for s, v, vz in ((climb / up, 0.0, up), (distance / speed, speed, 0.0),
                         (nav.rtl_loit_time, 0.0, 0.0)):
            mah += battery.mah(s, v, vz)
            seconds += s
        alt = max(alt, nav.rtl_alt)
    low = min(alt, nav.land_alt_low)  # Mode::land_run_vertical_control: slow below
    fast = nav.land_descent_speed()
    for s, vz in ((nav.land_descent_delay_s, 0.0), ((alt - low) / fast, -fast),
                  (low / abs(nav.land_speed), -abs(nav.land_speed))):
        mah += battery.mah(s, 0.0, vz)
        seconds += s
    return mah, seconds


def mission_charges(battery: Battery, nav, prediction, *, end_action: str,
                    homes: np.ndarray) -> list[MissionCharge]:
    """Each UAV's :class:`MissionCharge` from the plan's ``prediction`` (its legs'
    flown path on a common clock, altitudes above each UAV's home) and ``homes``
    ``(N, 3)`` (each UAV's start on the ground, ENU)."""
    out = []
    times = prediction.times
    for n in range(prediction.positions.shape[0]):
        positions = prediction.positions[n]
        reached = prediction.reached[n]
        last = min(int(np.searchsorted(times, reached[-1], side="right")), len(times))
        cumulative = _leg_charge(battery, times[:last], positions[:last])
        at_points = np.interp(reached, times[:last], cumulative) if last else np.zeros(
            len(reached))
        takeoff_alt = max(float(positions[0, 2]), 0.0)
        up = nav.wp_speed_up
        takeoff = battery.mah(takeoff_alt / up, 0.0, up)
        end, end_s = end_charge(battery, nav, end_action=end_action, goal=positions[last - 1],
                                home=homes[n])
        legs = float(cumulative[-1]) if len(cumulative) else 0.0
        out.append(MissionCharge(takeoff, legs, end, legs - at_points + end,
                                 takeoff_alt / up + float(reached[-1]) + end_s))
    return out


BATTERY_VIOLATION = "battery: "
"""How a plan's battery violations begin (the only kind a tighter navigation class cannot
mend)."""


def charge_problem(name: str, charge: MissionCharge, battery: Battery) -> str | None:
    """Why ``name`` cannot fly its mission on ``battery`` with the reserve, or None."""
    if charge.total_mah <= battery.usable_mah:
        return None
    left = battery.capacity_mah - charge.total_mah
    return (f"{BATTERY_VIOLATION}{name}'s mission uses {charge.total_mah:.0f} mAh of "
            f"{battery.capacity_mah:g} (takeoff {charge.takeoff_mah:.0f}, legs "
            f"{charge.legs_mah:.0f}, landing {charge.end_mah:.0f}); it would land with "
            f"{max(left, 0.0):.0f} mAh "
            f"({100.0 * left / battery.capacity_mah:.0f} %), below the "
            f"{battery.reserve_pct:g} % reserve")

