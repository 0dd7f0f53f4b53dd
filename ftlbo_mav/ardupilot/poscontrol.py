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
0.03 m (median) and 0.12 m (worst) of where SITL's was, over the 54 s of that flight in
AUTO; at 9.6 m/s on a survey's lanes within 0.03 m (median) and 0.21 m (worst, at the
right-angle turns at the lane ends: SITL's drag is per body axis and the copter turns its
heading there, which this model does not fly) (``tests/conformance/test_tracking.py``,
``tests/data/ardupilot-4.5.6/tracking.json``).

Vertically (:class:`VerticalFollower`, AC_PosControl::update_z_controller) the loops end
in the throttle, and the airframe's thrust follows it through the motors' 2 Hz filter:
given the vertical targets SITL logged from its takeoff into AUTO (PSCD, six copters of
two flights), the model put the copter within 0.022-0.036 m RMS of SITL's altitude,
against 0.038-0.058 m for a copter on its target, and climbing 0.11-0.135 m/s where AUTO
started (SITL 0.08-0.12) (``tests/conformance/test_climb.py``,
``tests/data/ardupilot-4.5.6/climb.json``). Where AUTO starts its first leg,
:func:`stopping_point_z`, agrees with SITL's target within 0.004-0.012 m.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .navigation import GRAVITY_M_S2, Navigation, sqrt_controller
from .wpnav import stopping_distance

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
    hover_throttle: float = 0.387
    """MOT_THST_HOVER: the throttle (0-1) that holds it up, learnt in flight (SITL's default
    quad: 0.387 at its first hover, 0.390 later, in the DataFlash PARM of three copters,
    tests/data/ardupilot-4.5.6/climb.json)."""

    def __post_init__(self) -> None:
        for name in ("drag_bcoef", "drag_mcoef", "air_density", "hover_throttle"):
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


def _limit_accel(vx: float, vy: float, ax: float, ay: float,
                 accel_max: float) -> tuple[float, float]:
    """AP_Math/control.cpp limit_accel_xy: ``(ax, ay)`` within ``accel_max``, keeping the
    part across the velocity ``(vx, vy)`` first."""
    speed = math.hypot(vx, vy)
    if speed < 1e-9:
        n = math.hypot(ax, ay)
        return ax * accel_max / n, ay * accel_max / n
    ux, uy = vx / speed, vy / speed
    along = ux * ax + uy * ay
    cx, cy = ax - ux * along, ay - uy * along
    cross = math.hypot(cx, cy)
    if cross > accel_max:
        return cx * accel_max / cross, cy * accel_max / cross
    room = math.sqrt(max(accel_max * accel_max - cross * cross, 0.0))
    along = max(-room, min(room, along))
    return cx + ux * along, cy + uy * along


class PositionFollower:
    """The copter's horizontal position and velocity as AC_PosControl makes it follow its
    target (see the module's docstring). Starts at ``position`` (ENU metres) with
    ``velocity``, its velocity integrator holding what that velocity's drag needs (a
    copter cruising, or hovering in ``wind``; nothing for one leaving the ground,
    ``airborne`` False). ``step`` takes the target AC_WPNav set
    (position, velocity, acceleration, ENU) and returns the copter's new position."""

    def __init__(self, position, velocity=(0.0, 0.0), *, nav: Navigation = DEFAULT_NAV,
                 airframe: Airframe = DEFAULT_AIRFRAME, wind=(0.0, 0.0),
                 airborne: bool = True) -> None:
        self.nav, self.airframe = nav, airframe
        self.px, self.py = float(position[0]), float(position[1])
        self.vx, self.vy = float(velocity[0]), float(velocity[1])
        self.wind = (float(wind[0]), float(wind[1]))
        # leaving the ground (``airborne`` False): while landed, _AutoTakeoff::run
        # (ArduCopter/takeoff.cpp) runs AC_PosControl::relax_velocity_controller_xy, which
        # decays the acceleration target to zero and init_xy_controller sets the I term
        # from it: the copter lifts off level, with nothing against the wind
        ax, ay = self._drag() if airborne else (0.0, 0.0)
        self._ix, self._iy = ax, ay  # the integrator holds the drag
        self._lx, self._ly = ax, ay  # the lean's acceleration, settled
        self._ex = self._ey = 0.0  # the filtered velocity error
        self._dx = self._dy = 0.0  # its filtered derivative
        self._alpha_e = _filter_alpha(nav.psc_velxy_flte)
        self._alpha_d = _filter_alpha(nav.psc_velxy_fltd)
        self._accel_max = GRAVITY_M_S2 * math.tan(nav.angle_max)
        self._lean = min(STEP_S / nav.atc_input_tc, 1.0) if nav.atc_input_tc > 0 else 1.0
        self._carry = 0.0
        self._limit = (0.0, 0.0)  # the acceleration asked beyond the limit (AC_PID_2D limit)

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
        nav, air = self.nav, self.airframe
        kp, kvp, kvi, kvd = nav.psc_posxy_p, nav.psc_velxy_p, nav.psc_velxy_i, nav.psc_velxy_d
        imax, accel_max, lean = nav.psc_velxy_imax, self._accel_max, self._lean
        alpha_e, alpha_d = self._alpha_e, self._alpha_d
        # AC_PosControl::init_xy_controller: _p_pos_xy.set_limits (WPNAV_ACCEL)
        pos_limit = nav.wp_accel
        linear = pos_limit / (kp * kp) if kp > 0 and pos_limit > 0 else math.inf
        quad = 0.5 * air.air_density / air.drag_bcoef if air.drag_bcoef > 0 else 0.0
        mom = air.drag_mcoef * math.sqrt(air.air_density / SEA_LEVEL_DENSITY)
        wx, wy = self.wind
        tx, ty = float(target[0]), float(target[1])
        tvx, tvy = float(target_vel[0]), float(target_vel[1])
        tax, tay = float(target_accel[0]), float(target_accel[1])
        px, py, vx, vy = self.px, self.py, self.vx, self.vy
        ex_f, ey_f, dx_f, dy_f = self._ex, self._ey, self._dx, self._dy
        ix, iy, lx, ly = self._ix, self._iy, self._lx, self._ly
        limit_x, limit_y = self._limit
        h = STEP_S
        self._carry += dt
        while self._carry >= h - 1e-12:
            self._carry -= h
            # AC_P_2D::update_all: sqrt_controller on the error's length
            ex, ey = tx - px, ty - py
            err = math.hypot(ex, ey)
            if err > linear:
                corr = sqrt_controller(err, kp, pos_limit, h) / err
            else:
                corr = min(kp, 1.0 / h)  # proportional (at most the error in one step)
            # AC_PID_2D::update_all
            last_x, last_y = ex_f, ey_f
            ex_f += (tvx + ex * corr - vx - ex_f) * alpha_e
            ey_f += (tvy + ey * corr - vy - ey_f) * alpha_e
            dx_f += ((ex_f - last_x) / h - dx_f) * alpha_d
            dy_f += ((ey_f - last_y) / h - dy_f) * alpha_d
            # update_i: the integrator does not grow towards the last step's limit
            dix, diy = ex_f * kvi * h, ey_f * kvi * h
            i_len = math.hypot(ix, iy)
            ix, iy = ix + dix, iy + diy
            if dix * limit_x + diy * limit_y > 0:
                grown = math.hypot(ix, iy)
                if grown > i_len:
                    ix, iy = ix * i_len / grown, iy * i_len / grown
            i_len = math.hypot(ix, iy)
            if i_len > imax:
                ix, iy = ix * imax / i_len, iy * imax / i_len
            ax = kvp * ex_f + ix + kvd * dx_f + tax
            ay = kvp * ey_f + iy + kvd * dy_f + tay
            # limit_accel_xy (AP_Math/control.cpp): within the lean angle's reach, the
            # acceleration across the desired velocity first
            limit_x = limit_y = 0.0
            if ax * ax + ay * ay > accel_max * accel_max:
                limit_x, limit_y = ax, ay
                ax, ay = _limit_accel(tvx, tvy, ax, ay, accel_max)
            # the attitude reaches its lean with ATC_INPUT_TC; the air holds it back
            lx += (ax - lx) * lean
            ly += (ay - ly) * lean
            rx, ry = vx - wx, vy - wy
            speed = math.hypot(rx, ry)
            d = quad * speed + mom  # the drag's deceleration over the airspeed
            vx += (lx - rx * d) * h
            vy += (ly - ry * d) * h
            px += vx * h
            py += vy * h
        self.px, self.py, self.vx, self.vy = px, py, vx, vy
        self._ex, self._ey, self._dx, self._dy = ex_f, ey_f, dx_f, dy_f
        self._ix, self._iy, self._lx, self._ly = ix, iy, lx, ly
        self._limit = (limit_x, limit_y)
        return np.array([px, py])


# AC_PosControl.cpp (Copter-4.5.6) defaults for a multicopter: the vertical loops' gains
# that are not navigation parameters here (PSC_VELZ_FLTE, PSC_ACCZ_P/_I/_IMAX/_FLTE), and
# AC_PosControl.h POSCONTROL_THROTTLE_CUTOFF_FREQ_HZ, the motors' throttle filter that
# update_z_controller asks for (AC_AttitudeControl::set_throttle_out ->
# AP_MotorsMulticopter::update_throttle_filter). Read back from SITL's DataFlash PARM.
VELZ_FLTE_HZ = 5.0
ACCZ_P, ACCZ_I, ACCZ_IMAX, ACCZ_FLTE_HZ = 0.5, 1.0, 800.0, 20.0
THROTTLE_CUTOFF_HZ = 2.0
STOPPING_DIST_UP_MAX_M, STOPPING_DIST_DOWN_MAX_M = 3.0, 2.0  # AC_PosControl.h


def stopping_point_xy(position, velocity, nav: Navigation = DEFAULT_NAV) -> np.ndarray:
    """AC_PosControl::get_stopping_point_xy_cm: where a copter at ``position`` moving at
    ``velocity`` (ENU m, m/s; the first two used) stops: ``stopping_distance``
    (AP_Math/control.cpp) with PSC_POSXY_P and WPNAV_ACCEL along its velocity, the speed at
    most WPNAV_SPEED. AC_WPNav::wp_and_spline_init starts there
    (init_xy_controller_stopping_point)."""
    x, y = float(position[0]), float(position[1])
    vx, vy = float(velocity[0]), float(velocity[1])
    speed = math.hypot(vx, vy)
    dist = stopping_distance(min(speed, nav.wp_speed), nav.psc_posxy_p, nav.wp_accel)
    if speed <= 0 or dist <= 0:
        return np.array([x, y])
    return np.array([x + vx * dist / speed, y + vy * dist / speed])


def stopping_point_z(position_z: float, velocity_z: float, nav: Navigation = DEFAULT_NAV
                     ) -> float:
    """AC_PosControl::get_stopping_point_z_cm: where a copter at ``position_z`` climbing at
    ``velocity_z`` (m, m/s, up) stops: ``stopping_distance`` (AP_Math/control.cpp,
    inv_sqrt_controller with PSC_POSZ_P and WPNAV_ACCEL_Z), at most 3 m up and 2 m down.
    AC_WPNav::wp_and_spline_init starts a mission's first leg there (ModeAuto::init), so a
    copter still climbing 0.1 m/s starts it 0.1 m above itself."""
    dist = math.copysign(stopping_distance(abs(velocity_z), nav.psc_posz_p, nav.wp_accel_z),
                         velocity_z)
    return position_z + max(-STOPPING_DIST_DOWN_MAX_M, min(dist, STOPPING_DIST_UP_MAX_M))


class VerticalFollower:
    """The copter's altitude and climb rate as AC_PosControl::update_z_controller makes it
    follow its vertical target, in 400 Hz steps:

    - position: ``vel_target = sqrt_controller(pos_target - pos, PSC_POSZ_P, WPNAV_ACCEL_Z)
      + vel_desired`` (AC_P_1D::update_all);
    - velocity: ``accel_target = PSC_VELZ_P x error + accel_desired`` (AC_PID, the error
      low-passed at 5 Hz; PSC_VELZ_I is 0);
    - acceleration: ``throttle = MOT_THST_HOVER + (P e + I) / 1000`` with ``e`` the
      acceleration error in cm/s/s low-passed at 20 Hz, ``I`` its integral (PSC_ACCZ_*);
    - the motors low-pass the throttle at 2 Hz (POSCONTROL_THROTTLE_CUTOFF_FREQ_HZ) and
      their thrust is linear in it (MOT_THST_EXPO linearises it; SITL's frame has the same
      curve), so the copter accelerates ``g (throttle / MOT_THST_HOVER - 1)``.

    The acceleration loop's lag is why a copter is not on its target: it runs ahead of a
    takeoff's target while the target slows, overshoots the takeoff altitude and is still
    climbing when the target has stopped (ArduCopter 4.5.6 SITL: 0.04-0.11 m above its
    target in the last 3 m of a 6 m takeoff, climbing 0.1 m/s when its target stopped).
    Starts at ``z`` (m, up) climbing ``v`` at ``a`` (m/s/s), its integrator holding that
    acceleration (AC_PosControl::init_z_controller)."""

    def __init__(self, z: float, v: float = 0.0, a: float = 0.0, *,
                 nav: Navigation = DEFAULT_NAV, airframe: Airframe = DEFAULT_AIRFRAME) -> None:
        self.nav, self.hover = nav, airframe.hover_throttle
        self.z, self.v, self.a = float(z), float(v), float(a)
        self._ev = 0.0  # the filtered velocity error (m/s)
        self._ea = 0.0  # the filtered acceleration error (cm/s/s)
        self._thr = self.hover * (1.0 + self.a / GRAVITY_M_S2)  # the motors' throttle
        self._i = (self._thr - self.hover) * 1000.0  # init_z_controller: the current throttle
        self._alpha_v = _filter_alpha(VELZ_FLTE_HZ)
        self._alpha_a = _filter_alpha(ACCZ_FLTE_HZ)
        self._alpha_t = _filter_alpha(THROTTLE_CUTOFF_HZ)
        self._carry = 0.0

    def at_rest_on(self, target: float) -> bool:
        """Hovering still on ``target``: a step would change nothing worth a step."""
        return (abs(self.z - target) < 1e-5 and abs(self.v) < 1e-5 and abs(self.a) < 1e-5
                and abs(self._ev) < 1e-5 and abs(self._ea) < 1e-3)

    def step(self, dt: float, target: float, target_vel: float = 0.0,
             target_accel: float = 0.0) -> float:
        """Follow the vertical target (m, m/s, m/s/s, up) for ``dt`` seconds; the altitude."""
        nav, h = self.nav, STEP_S
        kp, kvp, accel_max = nav.psc_posz_p, nav.psc_velz_p, nav.wp_accel_z
        hover, g = self.hover, GRAVITY_M_S2
        z, v, ev, ea, i, thr = self.z, self.v, self._ev, self._ea, self._i, self._thr
        av, aa, at = self._alpha_v, self._alpha_a, self._alpha_t
        a = self.a
        self._carry += dt
        while self._carry >= h - 1e-12:
            self._carry -= h
            vel_target = sqrt_controller(target - z, kp, accel_max, h) + target_vel
            ev += (vel_target - v - ev) * av
            accel_target = kvp * ev + target_accel
            ea += ((accel_target - a) * 100.0 - ea) * aa
            i = max(-ACCZ_IMAX, min(i + ACCZ_I * ea * h, ACCZ_IMAX))
            thr += (hover + (ACCZ_P * ea + i) * 0.001 - thr) * at
            a = g * (thr / hover - 1.0)
            v += a * h
            z += v * h
        self.z, self.v, self.a, self._ev, self._ea, self._i, self._thr = z, v, a, ev, ea, i, thr
        return z
