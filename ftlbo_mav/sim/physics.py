"""How the emulated copter moves: ArduCopter's waypoint navigation and vertical shaping.

Pure code on ENU metres relative to home. The copter is where ArduCopter's position
controller is asked to be (its target), a point mass: no attitude, no wind, no controller
lag. What ArduCopter 4.5.6 asks for is re-implemented from its source:

- :class:`WaypointNav`, AC_WPNav (libraries/AC_WPNav/AC_WPNav.cpp): each straight leg an
  S-curve (:mod:`.scurve`) planned rest to rest at WPNAV_SPEED / WPNAV_ACCEL /
  WPNAV_JERK, blended into the next leg at a "fast" waypoint (one with a next
  destination), reached when the S-curve finishes; ``set_speed_xy`` as
  DO_CHANGE_SPEED applies it.
- :class:`VerticalShaper`, AC_PosControl's vertical kinematic shaping
  (``input_pos_vel_accel_z``, ``input_vel_accel_z``; libraries/AP_Math/control.cpp
  ``shape_pos_vel_accel``, ``shape_vel_accel``, ``sqrt_controller``): takeoff climbs and
  landing descents, jerk- and acceleration-limited.

Its parameters are :class:`ftlbo_mav.ardupilot.navigation.Navigation`, ArduCopter's
defaults unless told.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..ardupilot.navigation import (
    LAND_RATE_ACHIEVED,
    TAKEOFF_DELAY_S,
    TOUCHDOWN_TO_DISARM_S,
    Navigation,
    sqrt_controller,
)
from .scurve import SCurve

WP_SPEED_MIN = 0.2  # AC_WPNav.cpp WPNAV_WP_SPEED_MIN (20 cm/s)
WP_RADIUS_MIN = 0.05  # WPNAV_WP_RADIUS_MIN


@dataclass(frozen=True)
class FlightLimits:
    """One copter's flight: its parameters (``nav``) and what its airframe adds.

    ``takeoff_delay_s``: NAV_TAKEOFF to liftoff (spool-up and throttle slew; recorded).
    ``disarm_after_touchdown_s``: touchdown to the land detector's disarm (recorded).
    ``start_latency_s``: a mission (AUTO) starts moving this much after it is entered (0
    on ArduPilot itself; per-vehicle variation, :func:`varied`).
    ``hover_error_m``: how far below its altitude target the copter hovers after a
    takeoff (SITL: 5.975 m for 6 m when AUTO started, flight.json and flight_speed.json;
    it is why the first leg of a mission started where the copter hovers still takes
    about a second: AC_WPNav starts at the copter's own position, and the S-curve of a
    leg a few centimetres long lasts that long).
    """

    nav: Navigation = field(default_factory=Navigation)
    takeoff_delay_s: float = TAKEOFF_DELAY_S
    disarm_after_touchdown_s: float = TOUCHDOWN_TO_DISARM_S
    land_rate_achieved: float = LAND_RATE_ACHIEVED
    start_latency_s: float = 0.0
    hover_error_m: float = 0.025

    @property
    def speed_m_s(self) -> float:
        return self.nav.wp_speed

    @classmethod
    def with_speed(cls, speed_m_s: float, **kw) -> FlightLimits:
        """ArduCopter's defaults with WPNAV_SPEED ``speed_m_s``."""
        return cls(nav=replace(Navigation(), wp_speed=speed_m_s), **kw)


def varied(limits: FlightLimits, rng: np.random.Generator, *, latency_s: float = 0.3,
           jerk_spread: float = 0.05) -> FlightLimits:
    """``limits`` as one copter of a real fleet differs: a start latency drawn from
    [0, ``latency_s``] and WPNAV_JERK scaled by a factor drawn from 1 +- ``jerk_spread``
    (short legs are jerk-limited, so their speed and duration differ by a few percent,
    as ``benchmarks/flight.py --set SYSID:WPNAV_JERK=..`` shows on SITL)."""
    factor = 1.0 + float(rng.uniform(-jerk_spread, jerk_spread))
    return replace(limits, start_latency_s=float(rng.uniform(0.0, latency_s)),
                   nav=replace(limits.nav, wp_jerk=limits.nav.wp_jerk * factor))


# -- AP_Math/control.cpp, one axis
def stopping_distance(speed: float, p: float, accel: float) -> float:
    """AC_PosControl's stopping_distance (control.cpp): how far a controller with gain
    ``p`` and acceleration ``accel`` moves before it stops from ``speed``."""
    if speed <= 0 or p <= 0 or accel <= 0:
        return 0.0
    if speed < accel / p:
        return speed / p
    return accel / (2 * p * p) + speed * speed / (2 * accel)


@dataclass
class VerticalShaper:
    """The vertical target of AC_PosControl: position, velocity and acceleration shaped
    towards an altitude (``to_altitude``, input_pos_vel_accel_z) or a climb rate
    (``at_rate``, input_vel_accel_z), within climb/descent speeds, WPNAV_ACCEL_Z and
    PSC_JERK_Z."""

    pos: float = 0.0
    vel: float = 0.0
    accel: float = 0.0

    def _shape_vel(self, vel_in: float, accel_max: float, jerk: float, dt: float) -> None:
        # shape_vel_accel: an acceleration that closes the velocity error, jerk-limited
        err = vel_in - self.vel
        kpa = jerk / accel_max
        target = sqrt_controller(err, kpa, jerk, dt)
        target = max(-accel_max, min(target, accel_max))
        self.accel += max(-jerk * dt, min(target - self.accel, jerk * dt))  # shape_accel

    def _move(self, dt: float) -> None:  # update_pos_vel_accel
        self.pos += self.vel * dt + self.accel * dt * dt / 2
        self.vel += self.accel * dt

    def to_altitude(self, alt: float, dt: float, *, up: float, down: float,
                    accel_max: float, jerk: float) -> None:
        self._move(dt)
        # shape_pos_vel_accel: the square-root controller uses half the acceleration
        err = alt - self.pos
        kpv = 0.5 * jerk / accel_max
        vel = sqrt_controller(err, kpv, 0.5 * accel_max, dt)
        vel = max(-down, min(vel, up))
        self._shape_vel(vel, accel_max, jerk, dt)

    def at_rate(self, rate: float, dt: float, *, accel_max: float, jerk: float) -> None:
        self._move(dt)
        self._shape_vel(rate, accel_max, jerk, dt)


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
        speed = float(np.linalg.norm(self.target_vel))
        wanted = 1.0
        if speed > 0:
            direction = self.target_vel / speed
            track_error = float((self.target - position) @ direction)
            track_velocity = float(np.asarray(velocity) @ direction)
            wanted = min(max(0.05 + (track_velocity - self.nav.psc_posxy_p * track_error)
                             / speed, 0.1), 1.0)
        tc = self.nav.wp_accel / self.nav.wp_jerk if self.nav.wp_jerk > 0 else 1.0
        self.track_scaler += (wanted - self.track_scaler) * min(dt / tc, 1.0)
        return self.track_scaler

    def advance(self, dt: float, position: np.ndarray,
                velocity: np.ndarray | None = None) -> None:
        """``position`` (and ``velocity``, when the copter is not on its target: wind)
        are the copter's own."""
        track = self._track_scale(dt, position, velocity)
        scale = self._time_scale(dt)
        done, pos, vel, acc = self.this.advance_target_along_track(
            self.prev, self.next, self.radius, self.nav.corner_accel(), self.fast,
            dt * scale * track, self.origin)
        # accel_offset: track direction x _offset_accel x |target_vel| / desired speed
        offset = vel * (self.offset_accel / self.desired_speed)
        vel, acc = vel * scale, acc * scale * scale + offset
        self.target, self.target_vel, self.target_accel = pos, vel, acc
        if not self.reached and done:
            if self.fast or float(np.linalg.norm(position - self.destination)) <= self.radius:
                self.reached = True


def landing_rate(nav: Navigation, alt_above_ground: float, dt: float) -> float:
    """Mode::land_run_vertical_control: the climb rate (negative) asked while landing:
    towards LAND_ALT_LOW at the square-root controller's rate, between LAND_SPEED and
    the fastest landing descent."""
    low = max(nav.land_alt_low, 1.0)
    rate = sqrt_controller(low - alt_above_ground, nav.psc_posz_p, nav.wp_accel_z, dt)
    return max(-nav.land_descent_speed(), min(rate, -abs(nav.land_speed)))
