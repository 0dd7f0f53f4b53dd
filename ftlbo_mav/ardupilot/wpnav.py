"""AC_WPNav's straight-line waypoint navigation, as ArduCopter 4.5.6 flies a mission.

Follows ``libraries/AC_WPNav/AC_WPNav.cpp`` (class AC_WPNav): ``wp_and_spline_init``,
``set_wp_destination`` / ``set_wp_destination_next`` (each straight leg an S-curve,
:mod:`.scurve`, planned rest to rest at WPNAV_SPEED / WPNAV_ACCEL / WPNAV_JERK, blended
into the next leg at a "fast" waypoint, one with a next destination),
``advance_wp_target_along_track`` (the target moved along the S-curves at their own pace
scaled by ``_offset_vel``), ``set_speed_xy`` (what DO_CHANGE_SPEED does), ``set_pause`` /
``set_resume`` and ``get_stopping_point`` (AC_PosControl). No splines, no terrain.

One model, two users: the emulator (``ftlbo_mav.sim``) flies with it and the planner
predicts the flown path with it (:mod:`.flight_path`); ``tests/conformance`` holds it to
recorded ArduCopter SITL tracks. Pure code on ENU metres.
"""

from __future__ import annotations

import math

import numpy as np

from .navigation import Navigation
from .scurve import SCurve

WP_SPEED_MIN = 0.2  # AC_WPNav.cpp WPNAV_WP_SPEED_MIN (20 cm/s)
WP_RADIUS_MIN = 0.05  # WPNAV_WP_RADIUS_MIN


def stopping_distance(speed: float, p: float, accel: float) -> float:
    """AC_PosControl's stopping_distance (control.cpp): how far a controller with gain
    ``p`` and acceleration ``accel`` moves before it stops from ``speed``."""
    if speed <= 0 or p <= 0 or accel <= 0:
        return 0.0
    if speed < accel / p:
        return speed / p
    return accel / (2 * p * p) + speed * speed / (2 * accel)


class WaypointNav:
    """AC_WPNav's straight-line waypoint controller for one copter (no splines, no
    terrain). ``init`` is wp_and_spline_init, ``set_destination`` / ``set_destination_next``
    are set_wp_destination / set_wp_destination_next, ``set_speed_xy`` is set_speed_xy
    and ``advance`` is advance_wp_target_along_track. The target runs at the S-curve's own
    pace scaled by the speed offset (``_offset_vel`` / ``_wp_desired_speed_xy_cms``, which
    a pause shapes towards 0 and a resume back to 1, jerk-limited); the tracking scaler
    stays 1 (the emulated copter is always on its target)."""

    def __init__(self, nav: Navigation, stopping_point: np.ndarray,
                 speed_m_s: float | None = None) -> None:
        self.nav = nav
        self.init(stopping_point, speed_m_s)

    def init(self, stopping_point: np.ndarray, speed_m_s: float | None = None) -> None:
        nav = self.nav
        self.radius = max(nav.wp_radius, WP_RADIUS_MIN)
        # _check_wp_speed_change: follow WPNAV_SPEED changes unless a speed was given
        self.follows_param = not (speed_m_s and speed_m_s > 0)
        wanted = speed_m_s if speed_m_s and speed_m_s > 0 else max(nav.wp_speed, WP_SPEED_MIN)
        self.desired_speed = max(wanted, WP_SPEED_MIN)
        # _offset_vel / _offset_accel: the S-curve's time runs at offset_vel / desired_speed
        self.offset_vel, self.offset_accel, self.paused = self.desired_speed, 0.0, False
        self.speed_up, self.speed_down = nav.wp_speed_up, nav.wp_speed_dn
        self.jerk, self.snap = nav.scurve_jerk_snap()
        self.prev, self.this, self.next = SCurve(), SCurve(), SCurve()
        self.reached = True
        self.fast = False
        self.origin = np.array(stopping_point, float)
        self.destination = self.origin.copy()
        self.target = self.origin.copy()
        self.target_vel = np.zeros(3)
        self.target_accel = np.zeros(3)
        self.track_scaler = 1.0  # _track_scalar_dt

    def _plan(self, leg: SCurve, origin: np.ndarray, destination: np.ndarray) -> None:
        leg.calculate_track(origin, destination, self.desired_speed, self.speed_up,
                            self.speed_down, self.nav.wp_accel, self.nav.wp_accel_z,
                            self.snap, self.jerk)

    def stopping_point(self) -> np.ndarray:
        """AC_PosControl get_stopping_point_xy/z_cm from the target's position and
        velocity."""
        point = self.target.copy()
        v = self.target_vel
        speed = math.hypot(v[0], v[1])
        d = stopping_distance(min(speed, self.desired_speed), self.nav.psc_posxy_p,
                              self.nav.wp_accel)
        if speed > 0 and d > 0:
            point[:2] += v[:2] * (d / speed)
        point[2] += math.copysign(stopping_distance(abs(v[2]), self.nav.psc_posz_p,
                                                    self.nav.wp_accel_z), v[2])
        return point

    def set_destination(self, destination: np.ndarray) -> None:
        if not self.reached:  # interrupted: start again from where it can stop
            keep = None if self.follows_param else self.desired_speed
            self.init(self.stopping_point(), keep)
        self.prev = self.this.copy()
        self.origin = self.destination.copy()
        self.destination = np.array(destination, float)
        if self.fast and not self.next.finished():
            self.this = self.next.copy()
        else:
            self.this = SCurve()
            self._plan(self.this, self.origin, self.destination)
        self.next = SCurve()
        self.fast = False
        self.reached = False

    def set_destination_next(self, destination: np.ndarray) -> None:
        self.next = SCurve()
        self._plan(self.next, self.destination, np.array(destination, float))
        self.fast = True

    def set_speed_xy(self, speed_m_s: float) -> None:
        """AC_WPNav::set_speed_xy: a new horizontal speed, applied to the leg being flown
        and the next (SCurve::set_speed_max); below 20 cm/s ignored."""
        if speed_m_s < WP_SPEED_MIN or self.desired_speed <= 0:
            return
        self.offset_vel = speed_m_s * self.offset_vel / self.desired_speed  # same time scale
        self.desired_speed = speed_m_s
        self.this.set_speed_max(speed_m_s, self.speed_up, self.speed_down)
        self.next.set_speed_max(speed_m_s, self.speed_up, self.speed_down)

    def param_speed_changed(self, speed_m_s: float) -> None:
        """AC_WPNav::update_wpnav: WPNAV_SPEED changed while flying (only followed when
        no speed was set for this navigation)."""
        if self.follows_param:
            self.set_speed_xy(speed_m_s)

    def set_pause(self, paused: bool) -> None:
        """AC_WPNav::set_pause / set_resume: the track's time is shaped to a stop (or back
        to its pace) in advance; the copter brakes along its path, it does not leave it."""
        self.paused = paused

    def _time_scale(self, dt: float) -> float:
        """advance_wp_target_along_track's vel_scaler_dt (Navigation.track_clock_step)."""
        self.offset_vel, self.offset_accel = self.nav.track_clock_step(
            self.offset_vel, self.offset_accel, 0.0 if self.paused else self.desired_speed, dt)
        return self.offset_vel / self.desired_speed

    def _track_scale(self, dt: float, position: np.ndarray, velocity: np.ndarray | None) -> float:
        """advance_wp_target_along_track's _track_scalar_dt: the track's clock slows where
        the copter falls behind its target (its along-track error and velocity, with a 5%
        buffer), filtered with a time constant of WPNAV_ACCEL / WPNAV_JERK. On its target
        (the emulated copter without wind) it stays 1."""
        if velocity is None:
            return self.track_scaler
        # in plain floats: numpy's per-call cost on three numbers would be most of it
        tvx, tvy, tvz = self.target_vel.tolist()
        speed = math.sqrt(tvx * tvx + tvy * tvy + tvz * tvz)
        wanted = 1.0
        if speed > 0:
            dx, dy, dz = tvx / speed, tvy / speed, tvz / speed
            tx, ty, tz = self.target.tolist()
            px, py, pz = position.tolist()
            vx, vy, vz = (velocity.tolist() if isinstance(velocity, np.ndarray)
                          else map(float, velocity))
            track_error = (tx - px) * dx + (ty - py) * dy + (tz - pz) * dz
            track_velocity = vx * dx + vy * dy + vz * dz
            wanted = min(max(0.05 + (track_velocity - self.nav.psc_posxy_p * track_error)
                             / speed, self.nav.track_scaler_floor), 1.0)
        tc = self.nav.wp_accel / self.nav.wp_jerk if self.nav.wp_jerk > 0 else 1.0
        self.track_scaler += (wanted - self.track_scaler) * min(dt / tc, 1.0)
        return self.track_scaler

    def advance(self, dt: float, position: np.ndarray,
                velocity: np.ndarray | None = None) -> None:
        scale = self._time_scale(dt)
        done, pos, vel, acc = self.this.advance_target_along_track(
            self.prev, self.next, self.radius, self.nav.corner_accel(), self.fast,
            dt * scale * self._track_scale(dt, position, velocity), self.origin,
            handover_46=self.nav.handover_46, accel_z=self.nav.wp_accel_z)
        # accel_offset: track direction x _offset_accel x |target_vel| / desired speed
        k = self.offset_accel / self.desired_speed
        self.target = np.array(pos)
        self.target_vel = np.array([vel[0] * scale, vel[1] * scale, vel[2] * scale])
        self.target_accel = np.array([acc[0] * scale * scale + vel[0] * k,
                                      acc[1] * scale * scale + vel[1] * k,
                                      acc[2] * scale * scale + vel[2] * k])
        if not self.reached and done:
            if self.fast or float(np.linalg.norm(position - self.destination)) <= self.radius:
                self.reached = True
