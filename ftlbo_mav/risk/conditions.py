"""The conditions one risk flight is flown in, drawn from its seed.

Every distribution is the user's to set (:class:`Ranges`, ``ftlbo-mav risk`` options); a
flight's :class:`Conditions` follow from ``(ranges, seed)`` alone, so ``risk --replay
SEED`` flies the same one again. Pure.

- steady wind: speed uniform on ``0..wind_max_m_s``, from a direction uniform on 0-360
  degrees (SITL's SIM_WIND_SPD / SIM_WIND_DIR: where it comes from);
- turbulence (gusts): uniform on ``0..turbulence_max_m_s`` (SIM_WIND_TURB; each copter
  meets its own gusts, :mod:`ftlbo_mav.sim.wind`);
- each copter's GPS error: a slowly varying offset (:mod:`ftlbo_mav.sim.gps`: per axis a
  Gauss-Markov wander of ``gps_wander_m`` standard deviation and ``gps_correlation_s``
  correlation time), its own seed per copter; by default from the plan's navigation
  budget (its 95 % horizontal error is 2.45 standard deviations of a circular error);
- fleet variation (``vary``): each copter differs as a real fleet does
  (:func:`ftlbo_mav.sim.physics.varied`: start latency, jerk);
- a vehicle lost (``lost_rate``): with that probability one copter, chosen uniformly, is
  killed at a time uniform on ``lost_window_s`` seconds after its missions start;
- a mode taken over (``takeover_rate``): with that probability one copter, chosen
  uniformly, is switched to BRAKE from its second port (a pilot's or another station's
  MAV_CMD_DO_SET_MODE) at a time uniform on the same window; drawn after everything
  above, so a seed's other conditions do not depend on it.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ..errors import BadInput

R95_PER_SIGMA = math.sqrt(-2.0 * math.log(0.05))  # 2.45: 95 % radius of a circular error


@dataclass(frozen=True)
class Ranges:
    """Where each condition is drawn from (module notes). ``gps_wander_m`` None: from the
    plan's navigation budget."""

    wind_max_m_s: float = 8.0
    turbulence_max_m_s: float = 2.0
    gps_wander_m: float | None = None
    gps_correlation_s: float = 30.0
    vary: bool = True
    lost_rate: float = 0.0
    lost_window_s: tuple[float, float] = (5.0, 20.0)
    takeover_rate: float = 0.0

    def __post_init__(self) -> None:
        for name in ("wind_max_m_s", "turbulence_max_m_s"):
            value = getattr(self, name)
            if not (math.isfinite(value) and 0 <= value <= 30):
                raise BadInput(f"{name.replace('_', '-')}: 0..30 m/s, got {value!r}")
        if self.gps_wander_m is not None and not (0 <= self.gps_wander_m <= 10):
            raise BadInput(f"gps wander: 0..10 m, got {self.gps_wander_m!r}")
        if not self.gps_correlation_s > 0:
            raise BadInput(f"gps correlation time must be > 0 s, got {self.gps_correlation_s!r}")
        for name in ("lost_rate", "takeover_rate"):
            if not 0 <= getattr(self, name) <= 1:
                raise BadInput(f"{name.replace('_', ' ')}: a probability 0..1, got "
                               f"{getattr(self, name)!r}")
        lo, hi = self.lost_window_s
        if not 0 <= lo <= hi:
            raise BadInput(f"lost window: 0 <= from <= to, got {self.lost_window_s!r}")

    def with_budget(self, horizontal_95_m: float) -> Ranges:
        """These ranges with the GPS wander from a navigation budget (95 % horizontal)
        when none was given."""
        if self.gps_wander_m is not None:
            return self
        wander = horizontal_95_m / R95_PER_SIGMA if math.isfinite(horizontal_95_m) else 0.0
        return Ranges(**{**asdict(self), "gps_wander_m": round(wander, 4)})

    def describe(self) -> str:
        window = f"{self.lost_window_s[0]:g}-{self.lost_window_s[1]:g} s into its missions"
        lost = (f"; a vehicle lost in {self.lost_rate:.0%} of flights, {window}"
                if self.lost_rate else "")
        if self.takeover_rate:
            lost += (f"; a vehicle's mode taken over (BRAKE) in {self.takeover_rate:.0%} of "
                     f"flights, {window}")
        return (f"wind 0-{self.wind_max_m_s:g} m/s from any direction, turbulence "
                f"0-{self.turbulence_max_m_s:g} m/s; GPS wander {self.gps_wander_m or 0:g} m "
                f"per axis (1 sigma, {self.gps_correlation_s:g} s correlation); fleet "
                f"variation {'on' if self.vary else 'off'}{lost}")


@dataclass(frozen=True)
class Conditions:
    """One flight's conditions: wind ``(speed, from_deg, turbulence)``, each copter's GPS
    seed, fleet variation, and the copter lost and the one whose mode is taken over
    (index, seconds after the missions start), or None."""

    seed: int
    wind: tuple[float, float, float]
    gps_wander_m: float
    gps_correlation_s: float
    gps_seeds: tuple[int, ...]
    vary: bool
    lost: tuple[int, float] | None
    takeover: tuple[int, float] | None = None

    def describe(self) -> str:
        spd, frm, turb = self.wind
        lost = f"; uav{self.lost[0] + 1} lost at +{self.lost[1]:.1f} s" if self.lost else ""
        if self.takeover:
            lost += f"; uav{self.takeover[0] + 1} taken over at +{self.takeover[1]:.1f} s"
        return (f"seed {self.seed}: wind {spd:.1f} m/s from {frm:.0f} deg, turbulence "
                f"{turb:.1f} m/s; GPS wander {self.gps_wander_m:g} m{lost}")


def draw(ranges: Ranges, seed: int, copters: int) -> Conditions:
    """The conditions of flight ``seed`` (module notes)."""
    if copters < 1:
        raise BadInput("a flight needs at least one copter")
    rng = np.random.default_rng([seed, 31])
    spd = float(rng.uniform(0.0, ranges.wind_max_m_s))
    frm = float(rng.uniform(0.0, 360.0))
    turb = float(rng.uniform(0.0, ranges.turbulence_max_m_s))
    gps_seeds = tuple(int(s) for s in rng.integers(0, 2**31 - 1, copters))
    lost = _fault(rng, ranges.lost_rate, copters, ranges.lost_window_s)
    takeover = _fault(rng, ranges.takeover_rate, copters, ranges.lost_window_s)
    return Conditions(seed=seed, wind=(round(spd, 3), round(frm, 1), round(turb, 3)),
                      gps_wander_m=float(ranges.gps_wander_m or 0.0),
                      gps_correlation_s=ranges.gps_correlation_s, gps_seeds=gps_seeds,
                      vary=ranges.vary, lost=lost, takeover=takeover)


def _fault(rng, rate: float, copters: int, window: tuple[float, float]
           ) -> tuple[int, float] | None:
    """One fault's draw: (copter, seconds into its missions) with probability ``rate``.
    Three numbers are drawn whatever the rate, so the draws after it stay the seed's."""
    happens, who, when = rng.random(), int(rng.integers(copters)), float(rng.uniform(*window))
    return (who, when) if happens < rate else None
