"""ArduCopter 4.5's navigation parameters: their defaults, units and MAVLink types.

The parameters ftlbo-mav and its emulator depend on, as ArduCopter 4.5.6 defines them
(the source of each default is given with it), and the same values in SI units as
:class:`Navigation`. ``tests/data/ardupilot-4.5.6/flight.json`` ``params`` holds what
ArduCopter 4.5.6 SITL with copter.parm answered to PARAM_REQUEST_READ; a test holds
these defaults to it (copter.parm changes none of them).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields, replace

GRAVITY_M_S2 = 9.80665  # AP_Math/definitions.h GRAVITY_MSS

# MAV_PARAM_TYPE (MAVLink common.xml), written out: importing pymavlink's dialect for four
# numbers cost every plan process 33 ms (tests/ardupilot/test_vehicle_params.py holds them to it)
REAL32, INT8, INT16, INT32 = 9, 2, 4, 6

# PARAM_VALUE param_count on ArduCopter 4.5.6 SITL with copter.parm (flight.json)
PARAM_COUNT = 1390


def sqrt_controller(error: float, p: float, second_ord_lim: float, dt: float) -> float:
    """AP_Math/control.cpp sqrt_controller: a rate that closes ``error``: proportional
    near zero, then the square root of the distance (a constant deceleration
    ``second_ord_lim``), never overshooting in ``dt``."""
    if second_ord_lim <= 0:
        rate = error * p
    elif p == 0:
        rate = math.copysign(math.sqrt(2 * second_ord_lim * abs(error)), error)
    else:
        linear = second_ord_lim / (p * p)
        if abs(error) > linear:
            rate = math.copysign(math.sqrt(2 * second_ord_lim * (abs(error) - linear / 2)),
                                 error)
        else:
            rate = error * p
    if dt > 0:
        rate = max(-abs(error) / dt, min(rate, abs(error) / dt))
    return rate



@dataclass(frozen=True)
class ParamDefault:
    value: float   # in the parameter's own units (cm, cm/s, cdeg, ...)
    type: int      # MAV_PARAM_TYPE, as PARAM_VALUE reports it
    source: str    # where ArduPilot 4.5.6 defines it


_WPNAV = "libraries/AC_WPNav/AC_WPNav.cpp var_info"
_COPTER = "ArduCopter/Parameters.cpp"
_PSC = "libraries/AC_AttitudeControl/AC_PosControl.cpp var_info"
_ATC = "libraries/AC_AttitudeControl/AC_AttitudeControl.cpp var_info"

DEFAULTS: Mapping[str, ParamDefault] = {
    "WPNAV_SPEED": ParamDefault(1000.0, REAL32, _WPNAV + " (WPNAV_WP_SPEED, cm/s)"),
    "WPNAV_RADIUS": ParamDefault(200.0, REAL32, _WPNAV + " (WPNAV_WP_RADIUS, cm)"),
    "WPNAV_SPEED_UP": ParamDefault(250.0, REAL32, _WPNAV + " (WPNAV_WP_SPEED_UP, cm/s)"),
    "WPNAV_SPEED_DN": ParamDefault(150.0, REAL32, _WPNAV + " (WPNAV_WP_SPEED_DOWN, cm/s)"),
    "WPNAV_ACCEL": ParamDefault(250.0, REAL32, "AC_WPNav.h WPNAV_ACCELERATION (cm/s/s)"),
    "WPNAV_ACCEL_Z": ParamDefault(100.0, REAL32, _WPNAV + " (WPNAV_WP_ACCEL_Z_DEFAULT)"),
    "WPNAV_JERK": ParamDefault(1.0, REAL32, _WPNAV + " (m/s/s/s)"),
    "WPNAV_ACCEL_C": ParamDefault(0.0, REAL32, _WPNAV + " (0: twice WPNAV_ACCEL)"),
    "WPNAV_TER_MARGIN": ParamDefault(10.0, REAL32, _WPNAV + " (m)"),
    "LAND_SPEED": ParamDefault(50.0, INT16, _COPTER + " (LAND_SPEED, cm/s)"),
    "LAND_SPEED_HIGH": ParamDefault(0.0, INT16, _COPTER + " (0: WPNAV_SPEED_DN)"),
    "LAND_ALT_LOW": ParamDefault(1000.0, INT16, _COPTER + " (cm)"),
    "PILOT_SPEED_UP": ParamDefault(250.0, INT16, _COPTER + " (cm/s)"),
    "PILOT_SPEED_DN": ParamDefault(0.0, INT16, _COPTER + " (0: PILOT_SPEED_UP)"),
    "PILOT_TKOFF_ALT": ParamDefault(0.0, REAL32, _COPTER + " (cm)"),
    "WP_YAW_BEHAVIOR": ParamDefault(2.0, INT8, _COPTER + " (2: face the next waypoint)"),
    "RTL_ALT": ParamDefault(1500.0, INT32, _COPTER + " (RTL_ALT, cm)"),
    "RTL_SPEED": ParamDefault(0.0, INT16, _COPTER + " (0: WPNAV_SPEED)"),
    "RTL_ALT_FINAL": ParamDefault(0.0, INT16, _COPTER + " (cm; 0: land)"),
    "RTL_LOIT_TIME": ParamDefault(5000.0, INT32, _COPTER + " (ms)"),
    "DISARM_DELAY": ParamDefault(10.0, INT8, "ArduCopter/Parameters.cpp (s)"),
    "PSC_JERK_XY": ParamDefault(5.0, REAL32, _PSC + " (POSCONTROL_JERK_XY, m/s/s/s)"),
    "PSC_JERK_Z": ParamDefault(5.0, REAL32, _PSC + " (POSCONTROL_JERK_Z, m/s/s/s)"),
    "PSC_POSZ_P": ParamDefault(1.0, REAL32, _PSC + " (POSCONTROL_POS_Z_P)"),
    "PSC_POSXY_P": ParamDefault(1.0, REAL32, _PSC + " (POSCONTROL_POS_XY_P)"),
    "PSC_VELZ_P": ParamDefault(5.0, REAL32, _PSC + " (POSCONTROL_VEL_Z_P)"),
    "PSC_VELXY_P": ParamDefault(2.0, REAL32, _PSC + " (POSCONTROL_VEL_XY_P)"),
    "PSC_VELXY_I": ParamDefault(1.0, REAL32, _PSC + " (POSCONTROL_VEL_XY_I)"),
    "PSC_VELXY_D": ParamDefault(0.5, REAL32, _PSC + " (POSCONTROL_VEL_XY_D)"),
    "PSC_VELXY_IMAX": ParamDefault(1000.0, REAL32, _PSC + " (POSCONTROL_VEL_XY_IMAX, cm/s/s)"),
    "PSC_VELXY_FLTE": ParamDefault(5.0, REAL32, _PSC + " (POSCONTROL_VEL_XY_FILT_HZ)"),
    "PSC_VELXY_FLTD": ParamDefault(5.0, REAL32, _PSC + " (POSCONTROL_VEL_XY_FILT_D_HZ)"),
    "ANGLE_MAX": ParamDefault(3000.0, INT16, _COPTER + " (DEFAULT_ANGLE_MAX, cdeg)"),
    "ATC_INPUT_TC": ParamDefault(0.15, REAL32, _ATC + " (AC_ATTITUDE_CONTROL_INPUT_TC_DEFAULT)"),
    "ATC_ACCEL_R_MAX": ParamDefault(110000.0, REAL32, _ATC + " (cdeg/s/s)"),
    "ATC_ACCEL_P_MAX": ParamDefault(110000.0, REAL32, _ATC + " (cdeg/s/s)"),
    "ATC_RATE_R_MAX": ParamDefault(0.0, REAL32, _ATC + " (deg/s; 0: unlimited)"),
    "ATC_RATE_P_MAX": ParamDefault(0.0, REAL32, _ATC + " (deg/s; 0: unlimited)"),
    "TKOFF_SLEW_TIME": ParamDefault(2.0, REAL32, _COPTER + " (s)"),
    "MOT_SPOOL_TIME": ParamDefault(0.5, REAL32, "libraries/AP_Motors/AP_MotorsMulticopter.cpp"),
}


RELEASE_DEFAULTS: Mapping[str, Mapping[str, float]] = {
    "4.5": {},
    # libraries/AC_AttitudeControl/AC_PosControl.cpp at Copter-4.6.3: POSCONTROL_VEL_XY_D
    # 0.25f for a multicopter (0.5f at Copter-4.5.6); 4.6.3 SITL with copter.parm reads
    # PSC_VELXY_D 0.25 back, every other of these parameters as 4.5.6's
    "4.6": {"PSC_VELXY_D": 0.25},
}
"""Where a release's defaults differ from :data:`DEFAULTS` (4.5.6's), by series."""


def with_release(nav: Navigation, release: str) -> Navigation:
    """``nav`` flown by a copter of ``release``: every parameter still at 4.5.6's default
    takes that release's own (a value never set is the firmware's default)."""
    own = {name: value for name, value in RELEASE_DEFAULTS[release].items()
           if math.isclose(nav.to_params()[name], DEFAULTS[name].value)}
    return replace(nav.with_params(own), release=release)


@dataclass(frozen=True)
class Navigation:
    """The navigation parameters in SI units (metres, seconds, radians)."""

    wp_speed: float = 10.0        # WPNAV_SPEED
    wp_radius: float = 2.0        # WPNAV_RADIUS
    wp_speed_up: float = 2.5      # WPNAV_SPEED_UP
    wp_speed_dn: float = 1.5      # WPNAV_SPEED_DN
    wp_accel: float = 2.5         # WPNAV_ACCEL
    wp_accel_z: float = 1.0       # WPNAV_ACCEL_Z
    wp_jerk: float = 1.0          # WPNAV_JERK
    wp_accel_c: float = 0.0       # WPNAV_ACCEL_C
    land_speed: float = 0.5       # LAND_SPEED
    land_speed_high: float = 0.0  # LAND_SPEED_HIGH
    land_alt_low: float = 10.0    # LAND_ALT_LOW
    rtl_alt: float = 15.0         # RTL_ALT
    rtl_speed: float = 0.0        # RTL_SPEED
    rtl_alt_final: float = 0.0    # RTL_ALT_FINAL
    rtl_loit_time: float = 5.0    # RTL_LOIT_TIME
    disarm_delay: float = 10.0    # DISARM_DELAY
    psc_jerk_xy: float = 5.0      # PSC_JERK_XY
    psc_jerk_z: float = 5.0       # PSC_JERK_Z
    psc_posz_p: float = 1.0       # PSC_POSZ_P
    psc_posxy_p: float = 1.0      # PSC_POSXY_P
    psc_velz_p: float = 5.0       # PSC_VELZ_P
    psc_velxy_p: float = 2.0      # PSC_VELXY_P
    psc_velxy_i: float = 1.0      # PSC_VELXY_I
    psc_velxy_d: float = 0.5      # PSC_VELXY_D
    psc_velxy_imax: float = 10.0  # PSC_VELXY_IMAX, m/s/s
    psc_velxy_flte: float = 5.0   # PSC_VELXY_FLTE, Hz
    psc_velxy_fltd: float = 5.0   # PSC_VELXY_FLTD, Hz
    angle_max: float = math.radians(30.0)  # ANGLE_MAX, rad
    atc_input_tc: float = 0.15    # ATC_INPUT_TC
    atc_accel_rp_max: float = math.radians(1100.0)  # ATC_ACCEL_R_MAX / _P_MAX, rad/s/s
    atc_rate_rp_max: float = 0.0  # ATC_RATE_R_MAX / _P_MAX, rad/s (0: unlimited)
    release: str = "4.5"          # the ArduCopter series flown (AUTOPILOT_VERSION; not a parameter)

    # -- where the releases differ (each in one place, chosen by ``release``)
    @property
    def handover_46(self) -> bool:
        """Which SCurve::advance_target_along_track hands a leg over to the next:
        ArduCopter 4.6's (libraries/AP_Math/SCurve.cpp at Copter-4.6.3: the next leg starts
        once this one is decelerating, ``time_decel_start``, and will end before the next
        one's acceleration ends, ``time_accel_end``; the turn's mid point is judged on its
        3D speed and also on its vertical acceleration, within WPNAV_ACCEL_Z) or 4.5's
        (at Copter-4.5.6: this leg past ``time_turn_out - next.time_turn_in`` and a quarter
        of its track, the turn judged on its horizontal speed and on this leg's time left
        being under half the next one's)."""
        return self.release != "4.5"

    @property
    def track_scaler_floor(self) -> float:
        """AC_WPNav::advance_wp_target_along_track: the floor of ``track_scaler_dt``, the
        factor by which the track's clock slows for a copter behind its target: 0.1 in
        4.5.6 (constrain_float(..., 0.1f, 1.0f)), 0 in 4.6.3 (a copter held back stops its
        track's clock)."""
        return 0.1 if self.release == "4.5" else 0.0

    @property
    def land_descent_delay_s(self) -> float:
        """Seconds a landing's descent (AUTO's NAV_LAND) holds its altitude before it
        starts: measured, not taken from the code. ArduCopter 4.6.3 SITL held 6 m for 1.06
        to 1.16 s more than 4.5.6 after "Mission: N Land" (the same altitude profile
        afterwards, 0.5 m/s; flight.json and flight_speed.json of both releases); the
        vertical controller's rework between them (AC_PosControl's terrain offsets,
        ``init_terrain`` / ``update_terrain``) is the likely cause. 0 for 4.5."""
        return 0.0 if self.release == "4.5" else LAND_DELAY_46_S

    def corner_accel(self) -> float:
        """AC_WPNav::get_corner_acceleration: WPNAV_ACCEL_C, or twice WPNAV_ACCEL."""
        return self.wp_accel_c if self.wp_accel_c > 0 else 2.0 * self.wp_accel

    def scurve_jerk_snap(self) -> tuple[float, float]:
        """AC_WPNav::calc_scurve_jerk_and_snap: the S-curve's jerk (WPNAV_JERK, at most
        what the rate limits allow) and snap (the jerk over the attitude time constant,
        at most the angular acceleration limit, then halved)."""
        jerk = self.wp_jerk
        if self.atc_rate_rp_max > 0:
            jerk = min(jerk, self.atc_rate_rp_max * GRAVITY_M_S2)
        snap = jerk * math.pi / (2.0 * max(self.atc_input_tc, 0.1))
        if self.atc_accel_rp_max > 0:
            snap = min(snap, self.atc_accel_rp_max * GRAVITY_M_S2)
        return jerk, snap * 0.5

    def track_clock_step(self, offset_vel: float, offset_accel: float, target: float,
                         dt: float) -> tuple[float, float]:
        """One step of AC_WPNav::advance_wp_target_along_track's speed offset
        (``_offset_vel``, ``_offset_accel``): update_vel_accel, then shape_vel_accel towards
        ``target`` (the desired speed; 0 while paused) within WPNAV_ACCEL and PSC_JERK_XY
        (AP_Math/control.cpp). The track's clock runs at offset_vel / desired speed."""
        offset_vel += offset_accel * dt
        jerk, accel = self.psc_jerk_xy, self.wp_accel
        want = sqrt_controller(target - offset_vel, jerk / accel, jerk, dt)
        want = max(-accel, min(accel, want))
        offset_accel += max(-jerk * dt, min(jerk * dt, want - offset_accel))
        return offset_vel, offset_accel

    def pause_loss(self, pause_s: float, speed_m_s: float, dt: float = 0.01) -> list[float]:
        """The seconds of track a pause has cost, every ``dt`` from its start until the
        clock is back at pace (:meth:`pause_cost_s` is the last)."""
        vel, acc, lost, t, out = speed_m_s, 0.0, 0.0, 0.0, [0.0]
        while t < pause_s + 30.0:
            vel, acc = self.track_clock_step(vel, acc, 0.0 if t < pause_s else speed_m_s, dt)
            lost += (1.0 - vel / speed_m_s) * dt
            t += dt
            out.append(lost)
            if t >= pause_s and abs(speed_m_s - vel) < 1e-4 and abs(acc) < 1e-4:
                break
        return out

    def pause_cost_s(self, pause_s: float, speed_m_s: float, dt: float = 0.01) -> float:
        """Seconds of its track a copter loses to MAV_CMD_DO_PAUSE_CONTINUE: paused for
        ``pause_s``, then continued (ModeAuto::pause / resume -> AC_WPNav set_pause /
        set_resume), until its track's clock is back to full pace, with its navigation
        set to ``speed_m_s`` (the clock's pace is the speed offset over that speed). A
        copter flying along its track at ``v`` ends ``v`` times that many metres behind
        one that was not paused."""
        return self.pause_loss(pause_s, speed_m_s, dt)[-1]

    def land_descent_speed(self) -> float:
        """Mode::land_run_vertical_control: the fastest descent while landing (m/s,
        positive): LAND_SPEED_HIGH, else WPNAV_SPEED_DN, never slower than LAND_SPEED."""
        high = self.land_speed_high if self.land_speed_high > 0 else self.wp_speed_dn
        return max(high, abs(self.land_speed))

    # -- as parameters
    def to_params(self) -> dict[str, float]:
        """These values as ArduPilot parameters, in their own units."""
        out = {name: d.value for name, d in DEFAULTS.items()}
        for name, attr, scale in _SCALES:
            out[name] = getattr(self, attr) * scale
        return out

    def with_params(self, values: Mapping[str, float]) -> Navigation:
        """A copy with the named parameters (ArduPilot units) set; others ignored."""
        change = {attr: float(values[name]) / scale for name, attr, scale in _SCALES
                  if name in values}
        return replace(self, **change)


# parameter, Navigation field, units per SI unit
_SCALES = (
    ("WPNAV_SPEED", "wp_speed", 100.0), ("WPNAV_RADIUS", "wp_radius", 100.0),
    ("WPNAV_SPEED_UP", "wp_speed_up", 100.0), ("WPNAV_SPEED_DN", "wp_speed_dn", 100.0),
    ("WPNAV_ACCEL", "wp_accel", 100.0), ("WPNAV_ACCEL_Z", "wp_accel_z", 100.0),
    ("WPNAV_JERK", "wp_jerk", 1.0), ("WPNAV_ACCEL_C", "wp_accel_c", 100.0),
    ("LAND_SPEED", "land_speed", 100.0), ("LAND_SPEED_HIGH", "land_speed_high", 100.0),
    ("LAND_ALT_LOW", "land_alt_low", 100.0), ("RTL_ALT", "rtl_alt", 100.0),
    ("RTL_SPEED", "rtl_speed", 100.0), ("RTL_ALT_FINAL", "rtl_alt_final", 100.0),
    ("RTL_LOIT_TIME", "rtl_loit_time", 1000.0), ("DISARM_DELAY", "disarm_delay", 1.0),
    ("PSC_JERK_XY", "psc_jerk_xy", 1.0), ("PSC_JERK_Z", "psc_jerk_z", 1.0),
    ("PSC_POSZ_P", "psc_posz_p", 1.0), ("PSC_POSXY_P", "psc_posxy_p", 1.0),
    ("PSC_VELZ_P", "psc_velz_p", 1.0),
    ("PSC_VELXY_P", "psc_velxy_p", 1.0), ("PSC_VELXY_I", "psc_velxy_i", 1.0),
    ("PSC_VELXY_D", "psc_velxy_d", 1.0), ("PSC_VELXY_IMAX", "psc_velxy_imax", 100.0),
    ("PSC_VELXY_FLTE", "psc_velxy_flte", 1.0), ("PSC_VELXY_FLTD", "psc_velxy_fltd", 1.0),
    ("ANGLE_MAX", "angle_max", math.degrees(1.0) * 100.0),
    ("ATC_INPUT_TC", "atc_input_tc", 1.0),
    ("ATC_ACCEL_R_MAX", "atc_accel_rp_max", math.degrees(1.0) * 100.0),
    ("ATC_ACCEL_P_MAX", "atc_accel_rp_max", math.degrees(1.0) * 100.0),
    ("ATC_RATE_R_MAX", "atc_rate_rp_max", math.degrees(1.0)),
    ("ATC_RATE_P_MAX", "atc_rate_rp_max", math.degrees(1.0)),
)
assert {f.name for f in fields(Navigation)} - {"release"} == {attr for _n, attr, _s in _SCALES}


# Every parameter the flown path, the landing and RTL depend on (:data:`NAV_PARAMS`), with
# the range ArduCopter 4.5.6 documents for it (the ``@Range`` of its var_info entry;
# ArduPilot itself does not enforce it, a ground station warns).
VEHICLE_PARAMS: Mapping[str, tuple[float, float]] = {
    # libraries/AC_WPNav/AC_WPNav.cpp var_info @Range (4.5.6; WPNAV_SPEED's minimum is 10
    # from 4.6.0, the 4.5 one is kept: a copter of either release accepts 20)
    "WPNAV_SPEED": (20.0, 2000.0), "WPNAV_RADIUS": (5.0, 1000.0),
    "WPNAV_SPEED_UP": (10.0, 1000.0), "WPNAV_SPEED_DN": (10.0, 500.0),
    "WPNAV_ACCEL": (50.0, 500.0), "WPNAV_ACCEL_Z": (50.0, 500.0),
    "WPNAV_JERK": (1.0, 20.0), "WPNAV_ACCEL_C": (0.0, 500.0),
    # ArduCopter/Parameters.cpp @Range
    "LAND_SPEED": (30.0, 200.0), "LAND_SPEED_HIGH": (0.0, 500.0),
    "LAND_ALT_LOW": (100.0, 10000.0), "RTL_ALT": (200.0, 300000.0),
    "RTL_SPEED": (0.0, 2000.0), "RTL_ALT_FINAL": (0.0, 1000.0),
    "RTL_LOIT_TIME": (0.0, 60000.0), "DISARM_DELAY": (0.0, 127.0),
    "ANGLE_MAX": (1000.0, 8000.0),
    # libraries/AC_AttitudeControl/AC_PosControl.cpp @Range
    "PSC_JERK_XY": (1.0, 20.0), "PSC_JERK_Z": (5.0, 50.0),
    "PSC_POSZ_P": (1.0, 3.0), "PSC_POSXY_P": (0.5, 2.0), "PSC_VELZ_P": (1.0, 8.0),
    "PSC_VELXY_P": (0.1, 6.0), "PSC_VELXY_I": (0.02, 1.0), "PSC_VELXY_D": (0.0, 1.0),
    "PSC_VELXY_IMAX": (0.0, 4500.0), "PSC_VELXY_FLTE": (0.0, 100.0),
    "PSC_VELXY_FLTD": (0.0, 100.0),
    # libraries/AC_AttitudeControl/AC_AttitudeControl.cpp @Range
    "ATC_INPUT_TC": (0.0, 1.0), "ATC_ACCEL_R_MAX": (0.0, 180000.0),
    "ATC_ACCEL_P_MAX": (0.0, 180000.0), "ATC_RATE_R_MAX": (0.0, 1080.0),
    "ATC_RATE_P_MAX": (0.0, 1080.0),
}


def vehicle_navigation(values: Mapping[str, float]) -> Navigation:
    """ArduCopter's defaults with ``values`` (names of :data:`VEHICLE_PARAMS`, ArduPilot
    units) set; a name it does not know or a value outside its range is a ValueError
    naming it."""
    for name, value in values.items():
        if name not in VEHICLE_PARAMS:
            raise ValueError(f"{name}: not a parameter the flown path depends on "
                             f"(known: {', '.join(VEHICLE_PARAMS)})")
        lo, hi = VEHICLE_PARAMS[name]
        if not (math.isfinite(value) and lo <= value <= hi):
            raise ValueError(f"{name}: {value:g} is outside ArduCopter's range [{lo:g}, {hi:g}]")
    return Navigation().with_params(values)


assert set(VEHICLE_PARAMS) == {name for name, _attr, _scale in _SCALES}


def vehicle_params(nav: Navigation) -> dict[str, float]:
    """The :data:`VEHICLE_PARAMS` of ``nav``, in ArduPilot's units."""
    params = nav.to_params()
    return {name: round(params[name], 6) for name in VEHICLE_PARAMS}


# float32 keeps 24 significant bits (a relative step of 6e-8) and plan.json writes the
# [vehicle] values with 6 decimals: values this close are the same parameter value.
PARAM_REL_TOL = 1e-6
PARAM_ABS_TOL = 1e-6


def param_matches(name: str, planned: float, onboard: float) -> bool:
    """A vehicle holds ``planned`` as AP_Param keeps it: an integer type as the whole
    number it was cast to, a REAL32 as a float32 (PARAM_VALUE carries a float32), within
    float32's precision of the 6 decimals plan.json writes."""
    d = DEFAULTS.get(name)
    if d is not None and d.type != REAL32:
        return int(planned) == int(onboard)
    return math.isclose(planned, onboard, rel_tol=PARAM_REL_TOL, abs_tol=PARAM_ABS_TOL)


def vehicle_param_differences(planned: Mapping[str, float],
                              onboard: Mapping[str, float | None]
                              ) -> list[tuple[str, float | None, float]]:
    """``(name, onboard value, planned value)`` for every planned parameter the vehicle
    holds another value of (``None``: it did not answer for it), in ``planned`` order."""
    out = []
    for name, want in planned.items():
        have = onboard.get(name)
        if have is None or not param_matches(name, want, have):
            out.append((name, have, want))
    return out


def param_value(name: str, value: float) -> float:
    """A value as PARAM_VALUE carries it: integer types are whole numbers (AP_Param
    casts on set), REAL32 a float32."""
    d = DEFAULTS.get(name)
    if d is not None and d.type != REAL32:
        return float(int(value))
    return value


# Taking off and landing on ArduCopter 4.5.6 SITL (flight.json, flight_speed.json):
# NAV_TAKEOFF to liftoff (0.1 m) 3.29 s (landed state TAKEOFF 2.96 s after the command):
# the motors spool up (MOT_SPOOL_TIME 0.5 s) and the throttle then slews up for
# TKOFF_SLEW_TIME (2 s) until the copter leaves the ground (ArduCopter/takeoff.cpp
# _AutoTakeoff::run, set_land_complete(false)). The emulator waits 2.75 s, then its
# jerk-limited climb (PSC_JERK_Z) takes ~0.55 s to the first 0.1 m: 3.3 s, as recorded.
TAKEOFF_DELAY_S = 2.75
# Touchdown ("SIM Hit ground") to "Disarming motors": 2.08 s and 2.7 s recorded; the land
# detector needs low throttle and no climb for LAND_DETECTOR_TRIGGER_SEC (1 s) after
# the throttle has wound down (ArduCopter/land_detector.cpp), then ModeAuto / ModeLand
# disarm (AP_Arming::Method::LANDED).
TOUCHDOWN_TO_DISARM_S = 2.1
# Measured, not from ArduPilot's code: SITL's copter descends at 0.46-0.48 m/s while
# LAND_SPEED asks 0.5 m/s ("SIM Hit ground at 0.474127 m/s"): the vertical controller's
# steady lag. The emulator's copter lands at this fraction of the commanded rate.
LAND_RATE_ACHIEVED = 0.95
# BRAKE (the fence's FENCE_ACTION 4) measured on ArduCopter 4.5.6 SITL, not taken from
# the code: a copter flying GUIDED at 5.7 m/s when the fence breached slowed as
# min(3 m/s/s, v / 1.6 s), that deceleration ramping in over 0.4 s, and stood still
# 9.94 m later (this model: 9.9 m). ArduCopter/mode_brake.cpp asks AC_PosControl for
# BRAKE_MODE_DECEL_RATE (7.5 m/s/s); its jerk-limited shaping and position loop give less.
BRAKE_DECEL_MAX_M_S2 = 3.0
BRAKE_TIME_CONSTANT_S = 1.6
BRAKE_RAMP_S = 0.4
LAND_DELAY_46_S = 1.1  # Navigation.land_descent_delay_s (4.6.3 SITL, measured)
NAV_PARAMS = tuple(name for name, _attr, _scale in _SCALES)
"""The parameters :meth:`Navigation.with_params` reads."""
