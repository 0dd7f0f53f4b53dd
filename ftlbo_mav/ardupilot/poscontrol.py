"""How an ArduCopter follows its position target: AC_PosControl's horizontal loops and
the airframe they drive.

AC_WPNav (:mod:`.wpnav`) moves a target along the S-curves; the copter is not on it. Each
400 Hz step of AC_PosControl::update_xy_controller
(libraries/AC_AttitudeControl/AC_PosControl.cpp):

- position: ``vel_target = sqrt_controller(pos_target - pos, PSC_POSXY_P) + vel_desired``
  (AC_P_2D::update_all);
- velocity: ``accel_target = PID(vel_target - vel) + accel_desired`` (AC_PID_2D::update_all:
  the error low-passed at PSC_VELXY_FLTE, its derivative at PSC_VELXY_FLTD, gains
  PSC_VELXY_P / _I / _D, the integrator at most PSC_VELXY_IMAX);
- the acceleration is limited to what the lean angle allows (limit_accel_xy,
  ``g tan(ANGLE_MAX)``) and becomes a lean angle (accel_to_lean_angles), which the attitude
  controller reaches with its input time constant ATC_INPUT_TC
  (AC_AttitudeControl::input_euler_angle_roll_pitch_euler_rate_yaw).

The airframe holds its height, so a lean gives ``g tan(lean)`` of horizontal acceleration,
less the drag of the air going past it. SITL's copter (libraries/SITL/SIM_Frame.cpp,
Frame::init and Frame::calculate_forces) has a quadratic drag per body axis
``areaCd rho / 2 v^2`` and the rotors' momentum drag, linear in airspeed; SITL prints the
two as ballistic and momentum coefficients at start ("Suggested EK3_DRAG_BCOEF_* = 16.288,
EK3_DRAG_MCOEF = 0.209" for the default frame), in the units of ArduPilot's own drag
model (libraries/AP_NavEKF3/AP_NavEKF3_core.cpp, drag fusion):
``accel = rho / (2 BCOEF) v^2 + MCOEF sqrt(rho / 1.225) v``. :class:`Airframe` holds them.

The drag is what makes the copter fall behind: nothing in the feedforward knows of it, so
the velocity loop's P and I terms must supply it, and they only do from an error. On
ArduCopter 4.5.6 SITL at 6.8 m/s the copter ran 0.3-0.4 m/s slower than its target and
0.2 m behind; through a 110 degree turn it swung 0.69 m outside its target's path. Run
on the position targets SITL logged (PSCN/PSCE), this model put the copter within
0.03 m (median) and 0.12 m (worst) of where SITL's was, over 24 s of that flight
(``tests/conformance/test_tracking.py``, ``tests/data/ardupilot-4.5.6/tracking.json``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .navigation import GRAVITY_M_S2, Navigation, sqrt_controller

STEP_S = 0.0025  # AC_PosControl runs at the main loop's 400 Hz (SCHED_LOOP_RATE)
SEA_LEVEL_DENSITY = 1.225  # kg/m^3, ArduPilot's reference for EK3_DRAG_MCOEF


@dataclass(frozen=True)
class Airframe:
    """The drag of the airframe, as ArduPilot's EKF describes it: ``drag_bcoef`` the
    ballistic coefficient (kg/m^2, EK3_DRAG_BCOEF_X/Y; mass over drag area), ``drag_mcoef``
    the momentum drag coefficient (1/s, EK3_DRAG_MCOEF), ``air_density`` (kg/m^3). The
    defaults are SITL's default copter frame (SIM_Frame.cpp prints them at start) in air
    of 1.184 kg/m^3 (its 25 C at sea level, Frame::get_air_density). 0 for a coefficient:
    no drag of that kind."""

    drag_bcoef: float = 16.288
    drag_mcoef: float = 0.209
    air_density: float = 1.184

    def __post_init__(self) -> None:
        for name in ("drag_bcoef", "drag_mcoef", "air_density"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"airframe {name} must be a finite number >= 0, got {value!r}")

    def drag(self, airspeed_m_s: float) -> float:
        """Deceleration (m/s/s) at ``airspeed_m_s``."""
        quadratic = (0.5 * self.air_density / self.drag_bcoef * airspeed_m_s * airspeed_m_s
                     if self.drag_bcoef > 0 else 0.0)
        momentum = self.drag_mcoef * math.sqrt(self.air_density / SEA_LEVEL_DENSITY)
        return quadratic + momentum * airspeed_m_s


DEFAULT_AIRFRAME = Airframe()
DEFAULT_NAV = Navigation()


def _filter_alpha(hz: float) -> float:
    """AC_PID's low-pass coefficient at ``hz`` for one step (calc_lowpass_alpha_dt; 1: no
    filter)."""
    if hz <= 0:
        return 1.0
    rc = STEP_S * 2 * math.pi * hz
    return rc / (1 + rc)


class PositionFollower:
    """The copter's horizontal position and velocity as AC_PosControl makes it follow its
    target (see the module's docstring). Starts at ``position`` (ENU metres) with
    ``velocity``, its velocity integrator holding what that velocity's drag needs (a
    copter cruising, or hovering in ``wind``). ``step`` takes the target AC_WPNav set
    (position, velocity, acceleration, ENU) and returns the copter's new position."""

    def __init__(self, position, velocity=(0.0, 0.0), *, nav: Navigation = DEFAULT_NAV,
                 airframe: Airframe = DEFAULT_AIRFRAME, wind=(0.0, 0.0)) -> None:
        self.nav, self.airframe = nav, airframe
        self.px, self.py = float(position[0]), float(position[1])
        self.vx, self.vy = float(velocity[0]), float(velocity[1])
        self.wind = (float(wind[0]), float(wind[1]))
        ax, ay = self._drag()
        self._ix, self._iy = ax, ay  # the integrator holds the drag
        self._lx, self._ly = ax, ay  # the lean's acceleration, settled
        self._ex = self._ey = 0.0  # the filtered velocity error
        self._dx = self._dy = 0.0  # its filtered derivative
        self._alpha_e = _filter_alpha(nav.psc_velxy_flte)
        self._alpha_d = _filter_alpha(nav.psc_velxy_fltd)
        self._accel_max = GRAVITY_M_S2 * math.tan(nav.angle_max)
        self._lean = min(STEP_S / nav.atc_input_tc, 1.0) if nav.atc_input_tc > 0 else 1.0
        self._carry = 0.0

    @property
    def position(self) -> np.ndarray:
        return np.array([self.px, self.py])

    @property
    def velocity(self) -> np.ndarray:
        return np.array([self.vx, self.vy])

    def _drag(self) -> tuple[float, float]:
        """The drag's deceleration along the air's velocity past the copter."""
        ax, ay = self.vx - self.wind[0], self.vy - self.wind[1]
        speed = math.hypot(ax, ay)
        if speed < 1e-9:
            return 0.0, 0.0
        d = self.airframe.drag(speed) / speed
        return ax * d, ay * d

    def step(self, dt: float, target, target_vel, target_accel) -> np.ndarray:
        """Follow the target for ``dt`` seconds (in AC_PosControl's 400 Hz steps, the
        target held over them); the copter's position (ENU metres, 2)."""
        nav = self.nav
        kp, kvp, kvi, kvd = nav.psc_posxy_p, nav.psc_velxy_p, nav.psc_velxy_i, nav.psc_velxy_d
        imax = nav.psc_velxy_imax
        tx, ty = float(target[0]), float(target[1])
        tvx, tvy = float(target_vel[0]), float(target_vel[1])
        tax, tay = float(target_accel[0]), float(target_accel[1])
        pos_limit = nav.wp_accel  # AC_PosControl::init_xy_controller: _p_pos_xy.set_limits
        self._carry += dt
        while self._carry >= STEP_S - 1e-12:
            self._carry -= STEP_S
            # AC_P_2D::update_all: sqrt_controller on the error's length
            ex, ey = tx - self.px, ty - self.py
            err = math.hypot(ex, ey)
            if err > 1e-9:
                corr = sqrt_controller(err, kp, pos_limit, STEP_S) / err
                ex, ey = ex * corr, ey * corr
            # AC_PID_2D::update_all
            wx, wy = tvx + ex - self.vx, tvy + ey - self.vy
            last_x, last_y = self._ex, self._ey
            self._ex += (wx - self._ex) * self._alpha_e
            self._ey += (wy - self._ey) * self._alpha_e
            self._dx += ((self._ex - last_x) / STEP_S - self._dx) * self._alpha_d
            self._dy += ((self._ey - last_y) / STEP_S - self._dy) * self._alpha_d
            self._ix += self._ex * kvi * STEP_S
            self._iy += self._ey * kvi * STEP_S
            i_len = math.hypot(self._ix, self._iy)
            if i_len > imax:
                self._ix, self._iy = self._ix * imax / i_len, self._iy * imax / i_len
            ax = kvp * self._ex + self._ix + kvd * self._dx + tax
            ay = kvp * self._ey + self._iy + kvd * self._dy + tay
            # limit_accel_xy: within the lean angle's reach
            a_len = math.hypot(ax, ay)
            if a_len > self._accel_max:
                ax, ay = ax * self._accel_max / a_len, ay * self._accel_max / a_len
            # the attitude reaches its lean with ATC_INPUT_TC; the air holds it back
            self._lx += (ax - self._lx) * self._lean
            self._ly += (ay - self._ly) * self._lean
            dx, dy = self._drag()
            self.vx += (self._lx - dx) * STEP_S
            self.vy += (self._ly - dy) * STEP_S
            self.px += self.vx * STEP_S
            self.py += self.vy * STEP_S
        return self.position
