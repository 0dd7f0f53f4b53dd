"""Wind for the emulator, as ArduPilot's SITL blows it, and how far it pushes a copter
off the target its position controller holds.

SITL (libraries/SITL/SIM_Aircraft.cpp ``Aircraft::update_wind``, parameters SIM_WIND_SPD,
SIM_WIND_DIR, SIM_WIND_TURB; SIM_WIND_T 1 keeps full strength down to the ground,
libraries/AP_HAL_SITL/SITL_State.cpp) blows a steady wind from SIM_WIND_DIR and, on a
copter in the air, adds turbulence at its physics rate (SIM_RATE_HZ, 1200 Hz for a
copter): a horizontal speed and a vertical speed, each an IIR-filtered normal noise
(coefficient 0.98 per step, input ``10 * SIM_WIND_TURB``: a standard deviation of about
SIM_WIND_TURB m/s, correlated over 1 / (1200 * -ln 0.98) = 41 ms), the horizontal one at
an azimuth drawn anew every step. Each SITL instance draws its own noise, so every copter
meets different gusts.

The emulated copter is a point on its position controller's target; in wind it is off
that target by an error :class:`Gusts` carries, per copter:

- the gusts' force is the change of the airframe's drag with the air's velocity
  (libraries/SITL/SIM_Frame.cpp: drag ``areaCd * rho / 2 * v^2`` per body axis, sized so
  that the default frame holds ``refSpd`` 15.08 m/s at ``refAngle`` 45 degrees, that is
  ``g * (v / 15.08)^2`` per unit mass; its slope at the airspeed of the steady wind,
  ``2 g v / 15.08^2`` per second), times the gust's speed;
- AC_PosControl answers it as a PID on velocity around a P on position (the copter's
  PSC_POSXY_P 1, PSC_VELXY_P 2, PSC_VELXY_I 1; PSC_POSZ_P 1, PSC_VELZ_P 5, from its
  :class:`~ftlbo_mav.ardupilot.navigation.Navigation`), reaching the airframe through
  its attitude and thrust with a lag (``response_s``).

The steady wind itself moves no copter off its target for long: the velocity
integrator takes it up, the same for every copter of a formation (their paths are the
same shape). Except where it has not yet: a copter lifts off level (ArduCopter's takeoff
relaxes the horizontal controller on the ground) and is blown downwind, 0.8-0.9 m in
6.6 m/s, coming back over seconds (the emulator's takeoff follows its target with the
airframe's drag, ``ftlbo_mav/sim/modes/guided.py``; tests/conformance/test_takeoff_wind.py).

What turns small gusts into formation error is AC_WPNav's track clock
(:meth:`~ftlbo_mav.sim.physics.WaypointNav.advance` with the copter's own position and
velocity): where a copter falls behind its target by more than a 5% buffer its target's
clock slows, and that time is never made up, so each copter's gusts shift it along its
path on its own (SITL in 5 m/s with 2 m/s turbulence, ``fly --no-keeper``: 0.14 m RMS
along the track, 0.02 m across it and vertically). ``drag_scale`` (0.05: the gusts push a
twentieth as hard as the drag slope above; 0.03-0.1 give much the same, the track
clock's 5% buffer at low speed decides most of it) is held to that recording
(tests/conformance/test_wind.py, tests/data/ardupilot-4.5.6/wind.json).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ..ardupilot.navigation import Navigation

G = 9.80665
SITL_RATE_HZ = 1200.0  # SIM_RATE_HZ, a copter's physics rate
IIR_COEF = 0.98  # SIM_Aircraft.cpp update_wind: iir_coef
REF_SPEED = 15.08  # SIM_Frame.h Model::refSpd (m/s), at refAngle 45 degrees
TURB_TAU_S = -1.0 / (SITL_RATE_HZ * math.log(IIR_COEF))  # 41 ms
NORMALS_AT_ONCE = 300  # a hundred steps' turbulence drawn at a time
TURB_STD = 10.0 * (1 - IIR_COEF) / math.sqrt(1 - IIR_COEF ** 2)  # per SIM_WIND_TURB: 1.005


@dataclass(frozen=True)
class Wind:
    """SITL's wind: ``speed_m_s`` (SIM_WIND_SPD) from ``direction_deg`` (SIM_WIND_DIR,
    where it comes from, degrees from north), turbulence ``turbulence_m_s``
    (SIM_WIND_TURB)."""

    speed_m_s: float = 0.0
    direction_deg: float = 0.0
    turbulence_m_s: float = 0.0

    def __post_init__(self) -> None:
        for name in ("speed_m_s", "direction_deg", "turbulence_m_s"):
            v = getattr(self, name)
            if not math.isfinite(v):
                raise ValueError(f"wind {name} must be finite, got {v!r}")
        if self.speed_m_s < 0 or self.turbulence_m_s < 0:
            raise ValueError("wind speed and turbulence must be >= 0")

    @classmethod
    def parse(cls, value) -> Wind:
        """A :class:`Wind`, or ``(speed, direction, turbulence)``."""
        return value if isinstance(value, Wind) else cls(*(float(v) for v in value))

    @property
    def calm(self) -> bool:
        return self.speed_m_s == 0 and self.turbulence_m_s == 0

    def velocity_enu(self) -> np.ndarray:
        """The steady wind's velocity (where the air goes), ENU m/s."""
        return np.array(self.velocity_xyz)

    @cached_property
    def velocity_xyz(self) -> tuple[float, float, float]:
        """:meth:`velocity_enu` as three floats (read at every step of the emulator)."""
        d = math.radians(self.direction_deg)
        return tuple((-self.speed_m_s * np.array([math.sin(d), math.cos(d), 0.0])).tolist())


@dataclass
class Gusts:
    """One copter's turbulence and its position controller's error in it (ENU metres
    from the target). ``step(dt, airspeed)`` advances both; ``error`` is added to the
    target."""

    wind: Wind
    rng: np.random.Generator
    response_s: float = 0.3
    drag_scale: float = 0.05  # held to SITL: tests/conformance/test_wind.py
    nav: Navigation = field(default_factory=Navigation)  # its PSC_* gains
    gust: np.ndarray = field(default_factory=lambda: np.zeros(3))
    error: np.ndarray = field(default_factory=lambda: np.zeros(3))
    error_vel: np.ndarray = field(default_factory=lambda: np.zeros(3))
    _integral: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    _accel: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    # standard normal draws taken from ``rng`` a block at a time, used in order (the
    # same numbers as drawn one by one: Generator.normal is loc + scale * a standard one)
    _normals: list[float] = field(default_factory=list)

    def _draw(self, dt: float) -> np.ndarray:
        """The turbulence averaged over ``dt`` (:meth:`_draw_xyz`), ENU m/s."""
        self._draw_xyz(dt)
        return self.gust

    def _draw_xyz(self, dt: float) -> tuple[float, float, float]:
        """The turbulence averaged over ``dt``, as SITL's 1200 Hz steps sum up: the
        vertical speed an Ornstein-Uhlenbeck process (41 ms), the horizontal one at a
        new azimuth every SITL step (its mean over ``dt`` per axis: the step's variance
        over the number of steps)."""
        sigma = TURB_STD * self.wind.turbulence_m_s
        if sigma <= 0 or dt <= 0:
            self.gust = np.zeros(3)
            return 0.0, 0.0, 0.0
        a = math.exp(-dt / TURB_TAU_S)
        steps = max(dt * SITL_RATE_HZ, 1.0)
        if len(self._normals) < 3:
            self._normals = self.rng.standard_normal(NORMALS_AT_ONCE).tolist()[::-1]
        z = self._normals
        h = sigma / math.sqrt(2 * steps)
        h0, h1 = 0.0 + h * z.pop(), 0.0 + h * z.pop()
        vertical = a * float(self.gust[2]) + sigma * math.sqrt(1 - a * a) * (0.0 + z.pop())
        self.gust = np.array([h0, h1, vertical])
        return h0, h1, vertical

    def step(self, dt: float, airspeed_m_s: float) -> np.ndarray:
        """Advance ``dt`` seconds with the copter ``airspeed_m_s`` through the air; the
        error (ENU metres from the target)."""
        if dt <= 0:
            return self.error
        gust = self._draw_xyz(dt)
        slope = self.drag_scale * 2 * G * max(airspeed_m_s, 1.0) / REF_SPEED ** 2
        n = self.nav  # PSC_POSXY_P / PSC_POSZ_P, PSC_VELXY_P / PSC_VELZ_P, PSC_VELXY_I
        pos_p = (n.psc_posxy_p, n.psc_posxy_p, n.psc_posz_p)
        vel_p = (n.psc_velxy_p, n.psc_velxy_p, n.psc_velz_p)
        vel_i = (n.psc_velxy_i, n.psc_velxy_i, 0.0)  # the z loop's I is on accel
        # what the controller asks reaches the airframe through attitude and thrust
        lag = min(dt / max(self.response_s, 1e-3), 1.0)
        # per axis in plain floats (numpy's per-call cost on three numbers would be most
        # of a step): the same arithmetic, element by element
        integral, accel_now = self._integral, self._accel
        error, error_vel = self.error.tolist(), self.error_vel.tolist()
        for k in range(3):
            vel_err = -(error_vel[k] + pos_p[k] * error[k])
            integral[k] += vel_err * dt
            wanted = vel_p[k] * vel_err + vel_i[k] * integral[k]
            accel_now[k] += (wanted - accel_now[k]) * lag
            accel = accel_now[k] + slope * gust[k]
            error_vel[k] = error_vel[k] + accel * dt
            error[k] = error[k] + error_vel[k] * dt
        self.error_vel, self.error = np.array(error_vel), np.array(error)
        return self.error
