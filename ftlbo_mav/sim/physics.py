"""How the emulated copter moves: ArduCopter's waypoint navigation and vertical shaping.

Pure code on ENU metres relative to home. What ArduCopter 4.5.6 asks for is
re-implemented from its source (how the copter follows it, horizontally and vertically, is
:mod:`ftlbo_mav.ardupilot.poscontrol`):

- :class:`WaypointNav`, AC_WPNav: ArduCopter's model of how it flies a mission lives in
  :mod:`ftlbo_mav.ardupilot.wpnav` (and :mod:`ftlbo_mav.ardupilot.scurve`), shared with
  the planner's prediction of the flown path (:mod:`ftlbo_mav.ardupilot.flight_path`);
  re-exported here for the emulator.
- :class:`VerticalShaper`, AC_PosControl's vertical kinematic shaping
  (``input_pos_vel_accel_z``, ``input_vel_accel_z``; libraries/AP_Math/control.cpp
  ``shape_pos_vel_accel``, ``shape_vel_accel``, ``sqrt_controller``): takeoff climbs and
  landing descents, jerk- and acceleration-limited.

Its parameters are :class:`ftlbo_mav.ardupilot.navigation.Navigation`, ArduCopter's
defaults unless told.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..ardupilot.navigation import (
    LAND_RATE_ACHIEVED,
    TAKEOFF_DELAY_S,
    TOUCHDOWN_TO_DISARM_S,
    Navigation,
    sqrt_controller,
)
from ..ardupilot.poscontrol import DEFAULT_AIRFRAME, Airframe
from ..ardupilot.wpnav import (  # re-exported: the emulator's autopilot imports them here
    WP_RADIUS_MIN,
    WP_SPEED_MIN,
    WaypointNav,
    stopping_distance,
)
from ..energy import Battery

__all__ = ["FlightLimits", "VerticalShaper", "WP_RADIUS_MIN", "WP_SPEED_MIN", "WaypointNav",
           "landing_rate", "stopping_distance", "varied"]


SITL_POWER = Battery(capacity_mah=3300.0, hover_current_a=28.12, cruise_current_a=30.55,
                     cruise_speed_m_s=9.85, induced_velocity_m_s=15.0,
                     source="ArduCopter 4.5.6 SITL, default quad (battery.json)")
"""What SITL's default quad draws (tests/data/ardupilot-4.5.6/battery.json ``summary``,
BATT_CAPACITY 3300 mAh, 12.6 V held): 28.12 A hovering at 10 m, 30.55 A cruising at
9.85 m/s, 30.7 A climbing at 2.5 m/s and 26.9 A descending at 1.5 m/s (the climb and
descent ratios, 1.093 and 0.958, give momentum theory's ``v_h`` 14 and 17.5 m/s: 15 m/s
is taken). 0 A on the ground, armed or not, until the takeoff spools the motors up."""


@dataclass(frozen=True)
class FlightLimits:
    """One copter's flight: its parameters (``nav``) and what its airframe adds.

    ``takeoff_delay_s``: NAV_TAKEOFF to liftoff (spool-up and throttle slew; recorded).
    ``disarm_after_touchdown_s``: touchdown to the land detector's disarm (recorded).
    ``start_latency_s``: a mission (AUTO) starts moving this much after it is entered (0
    on ArduPilot itself; per-vehicle variation, :func:`varied`).
    ``airframe``: its drag, with which it follows its position target
    (:mod:`ftlbo_mav.ardupilot.poscontrol`; SITL's default frame).
    ``jerk_factor``: this airframe flies its S-curves with its WPNAV_JERK times this (1 on
    ArduPilot itself; per-vehicle variation, :func:`varied`). It is not a parameter: the
    vehicle holds and reports the WPNAV_JERK it was given, as every copter of a fleet set
    up from one parameter file does.
    ``power``: the current its motors draw in the air (:class:`~ftlbo_mav.energy.Battery`'s
    model; :data:`SITL_POWER`, SITL's default quad; none on the ground, as recorded).
    """

    nav: Navigation = field(default_factory=Navigation)
    takeoff_delay_s: float = TAKEOFF_DELAY_S
    disarm_after_touchdown_s: float = TOUCHDOWN_TO_DISARM_S
    land_rate_achieved: float = LAND_RATE_ACHIEVED
    start_latency_s: float = 0.0
    jerk_factor: float = 1.0
    airframe: Airframe = DEFAULT_AIRFRAME
    power: Battery = field(default_factory=lambda: SITL_POWER)
    velocity_estimate_error: tuple[float, float] = (0.0, 0.0)
    """East, north m/s: how the velocity AC_WPNav's track scaler reads
    (AC_WPNav::advance_wp_target_along_track, ``_inav.get_velocity_neu_cms()``) is off
    where a mission starts from the hover after the takeoff, the copter still settling:
    fading with :data:`SETTLING_S` (0 on an exact copter; :func:`hovering` draws one)."""

    @property
    def speed_m_s(self) -> float:
        return self.nav.wp_speed

    @classmethod
    def with_speed(cls, speed_m_s: float, **kw) -> FlightLimits:
        """ArduCopter's defaults with WPNAV_SPEED ``speed_m_s``."""
        return cls(nav=replace(Navigation(), wp_speed=speed_m_s), **kw)


SETTLING_S = 2.0
"""Seconds over which a hovering copter's settling drift fades (SITL: the copters drifted
about 1 cm/s, wandering 3.5 cm, after the takeoff; a constant error would be an estimate
bias, which EKF3 does not hold for minutes)."""
HOVER_VELOCITY_ERROR_M_S = 0.003
"""Per axis, the spread (one standard deviation) of the velocity a hovering copter's
navigation reads against its target where AUTO starts a leg: measured, not from the code.
ArduCopter 4.5.6 and 4.6.3 SITL (copter.parm), three copters each at the start gate of
three flights: the track scaler's ``v - PSC_POSXY_P x error`` along the first leg was
+0.53, -0.17, +0.30 / +0.31, +0.09, +0.12 / +0.06, -0.04, 0.00 cm/s (DataFlash PSC, EKF
and SIM2 records). A leg that starts from a hover divides it by a target speed of mm/s
(AC_WPNav::advance_wp_target_along_track), so its sign decides whether that copter's
track clock starts at 0.1 or at full pace: its target ran 120-185 ms late in one flight,
the largest part of SITL's formation error at the start of legs (0.065 m along the track
RMS, against 0.015 m here without it). Fading with :data:`SETTLING_S`, it brings the
emulator's formation error on the risk calibration from 0.070 to 0.119 m worst (median of
ten; SITL 0.203 m, docs/risk.md)."""


def hovering(limits: FlightLimits, rng: np.random.Generator, *,
             spread_m_s: float = HOVER_VELOCITY_ERROR_M_S) -> FlightLimits:
    """``limits`` with the velocity error its navigation reads drawn per axis, normal
    with ``spread_m_s`` (:data:`HOVER_VELOCITY_ERROR_M_S`), unless it has one: every
    ArduCopter has it, alike copters too (the emulator's :class:`~.server.Simulator`
    draws one per copter from its seed)."""
    if limits.velocity_estimate_error != (0.0, 0.0):
        return limits
    east, north = (float(v) for v in rng.normal(0.0, spread_m_s, 2))
    return replace(limits, velocity_estimate_error=(east, north))


def varied(limits: FlightLimits, rng: np.random.Generator, *, latency_s: float = 0.3,
           jerk_spread: float = 0.05) -> FlightLimits:
    """``limits`` as one copter of a real fleet differs: a start latency drawn from
    [0, ``latency_s``] and the jerk it flies with scaled by a factor drawn from 1 +-
    ``jerk_spread`` (short legs are jerk-limited, so their speed and duration differ by a
    few percent, as ``benchmarks/flight.py --set SYSID:WPNAV_JERK=..`` shows on SITL).
    Its parameters stay those of ``limits``: the fleet holds what the plan predicted
    with, and `fly`'s pre-flight check of them passes."""
    factor = 1.0 + float(rng.uniform(-jerk_spread, jerk_spread))
    return replace(limits, start_latency_s=float(rng.uniform(0.0, latency_s)),
                   jerk_factor=limits.jerk_factor * factor)


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


def landing_rate(nav: Navigation, alt_above_ground: float, dt: float) -> float:
    """Mode::land_run_vertical_control: the climb rate (negative) asked while landing:
    towards LAND_ALT_LOW at the square-root controller's rate, between LAND_SPEED and
    the fastest landing descent."""
    low = max(nav.land_alt_low, 1.0)
    rate = sqrt_controller(low - alt_above_ground, nav.psc_posz_p, nav.wp_accel_z, dt)
    return max(-nav.land_descent_speed(), min(rate, -abs(nav.land_speed)))
