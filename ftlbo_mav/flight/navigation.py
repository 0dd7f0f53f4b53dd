"""Is each copter held to the plan's navigation budget? Its GPS and EKF, judged before
and during the flight.

A plan keeps its clearance where the copters truly are only while their position error
stays within its budget (:mod:`ftlbo_mav.gnss`). Before the flight
(:func:`preflight_problems`) a copter must report a fix at least as good as the budget's
class, an accuracy within the budget and an EKF with an absolute position whose variance
is under ArduCopter's own threshold (:mod:`ftlbo_mav.ardupilot.gps`). During it
(:class:`NavigationWatch`) a copter whose fix or reported accuracy degrades past the
budget or whose EKF position variance passes that threshold, for longer than a moment,
or whose GPS position jumps (moves further between two reports than its velocity
carries it: a glitch, as a multipath reflection or a receiver reset gives) has left
what the plan promised. Pure: the reports and the time are given.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..ardupilot.gps import EKF_POS_HORIZ_ABS, FS_EKF_THRESH, h_acc_m
from ..ardupilot.navigation import GRAVITY_M_S2, Navigation
from ..gnss import FIX_NAMES, NavigationBudget

GLITCH_MIN_M = 1.0
"""The smallest jump counted as a glitch (metres), whatever the budget: a receiver's
position wanders by decimetres between reports."""
PERSIST_S = 1.0
"""A degraded fix, accuracy or EKF variance counts once it lasts this long."""
GPS_STALE_S = 3.0
"""Reports further apart than this are not compared for a jump (a link outage)."""
ACCEL_MAX_M_S2 = GRAVITY_M_S2 * math.tan(Navigation().angle_max)
"""The most a copter accelerates across the ground at ArduCopter's default ANGLE_MAX (30
degrees, g tan 30 = 5.7 m/s/s, AC_PosControl's lean limit). Between two reports ``dt``
apart whose velocities are known, a copter accelerating at most this much ends within
``ACCEL_MAX_M_S2 dt^2 / 4`` of where their mean velocity puts it: a jump no larger is its
own motion (through the rough-day radio the emulator's uav1, from a hover to 3 m/s
across a 2.8 s silence, was 1.2 m from the mean velocity's guess, and was taken for a
glitch)."""


@dataclass(frozen=True)
class GpsReport:
    """One GPS_RAW_INT: ``fix_type``; ``h_acc_m`` (None: not reported); ``satellites``
    (None: unknown); ``east``/``north`` metres in the plan's frame; ``velocity`` ``(2,)``
    east/north m/s (None: unknown); ``t`` the vehicle's time of the fix (seconds)."""

    fix_type: int
    h_acc_m: float | None
    satellites: int | None
    east: float
    north: float
    velocity: tuple[float, float] | None
    t: float


@dataclass(frozen=True)
class EkfReport:
    """One EKF_STATUS_REPORT: its ``flags`` and ``pos_horiz_variance``."""

    flags: int
    pos_horiz_variance: float


def fix_name(fix_type: int) -> str:
    return FIX_NAMES.get(fix_type, f"fix type {fix_type}")


def describe(gps: GpsReport | None, ekf: EkfReport | None) -> str:
    """The GPS and EKF in a few words, as ``monitor`` and the pre-flight say them."""
    if gps is None:
        what = "no GPS_RAW_INT"
    else:
        acc = "accuracy not reported" if gps.h_acc_m is None else f"{gps.h_acc_m:.2f} m"
        sats = "" if gps.satellites is None else f", {gps.satellites} satellites"
        what = f"{fix_name(gps.fix_type)}, {acc}{sats}"
    if ekf is None:
        return what + ", no EKF_STATUS_REPORT"
    return what + f", EKF position variance {ekf.pos_horiz_variance:.2f}"


def _shortfalls(budget: NavigationBudget, gps: GpsReport | None,
                ekf: EkfReport | None) -> list[str]:
    """What in these reports falls short of ``budget``, in words."""
    out = []
    if gps is None:
        return ["no GPS_RAW_INT received"]
    if gps.fix_type < budget.min_fix_type:
        out.append(f"{fix_name(gps.fix_type)}, the plan's [navigation] {budget.name} needs "
                   f"{fix_name(budget.min_fix_type)} or better")
    if budget.horizontal_m > 0:
        if gps.h_acc_m is None:
            out.append("its GPS reports no accuracy (GPS_RAW_INT h_acc): the plan's "
                       f"{budget.horizontal_m:g} m budget cannot be checked")
        elif gps.h_acc_m > budget.horizontal_m:
            out.append(f"GPS accuracy {gps.h_acc_m:.2f} m, worse than the plan's budget "
                       f"{budget.horizontal_m:g} m ([navigation] {budget.describe()})")
    if ekf is None:
        out.append("no EKF_STATUS_REPORT received")
    else:
        if not ekf.flags & EKF_POS_HORIZ_ABS:
            out.append("its EKF has no absolute horizontal position")
        if ekf.pos_horiz_variance >= FS_EKF_THRESH:
            out.append(f"EKF position variance {ekf.pos_horiz_variance:.2f}, at or over "
                       f"ArduCopter's FS_EKF_THRESH {FS_EKF_THRESH:g}")
    return out


def preflight_problems(budget: NavigationBudget, gps: GpsReport | None,
                       ekf: EkfReport | None) -> list[str]:
    """Why a copter with these reports may not fly a plan with ``budget`` (empty: it
    may)."""
    return _shortfalls(budget, gps, ekf)


@dataclass
class _Track:
    short_since: float | None = None
    reported: set = field(default_factory=set)


class NavigationWatch:
    """Per vehicle: ``check(i, gps, ekf, now)`` returns the words of a new departure
    (a glitch: a jump measured by the vehicle's reader on each report, :func:`report_jump`;
    or a shortfall lasting :data:`PERSIST_S`), else None; each kind once."""

    def __init__(self, count: int, budget: NavigationBudget) -> None:
        self.budget = budget
        self.glitch_m = max(GLITCH_MIN_M, budget.horizontal_m)
        self.tracks = [_Track() for _ in range(count)]

    def check(self, i: int, gps: GpsReport | None, ekf: EkfReport | None,
              now: float, *, jump_m: float = 0.0) -> str | None:
        """``jump_m``: the largest GPS jump the vehicle's reports showed while armed
        (:func:`report_jump`, measured on every report as it arrives)."""
        tr = self.tracks[i]
        if jump_m > self.glitch_m and "glitch" not in tr.reported:
            tr.reported.add("glitch")
            return (f"GPS position jumped {jump_m:.1f} m in one report, more than its "
                    f"velocity carries it (a glitch; at most {self.glitch_m:g} m counts as "
                    "wander)")
        if gps is None:
            return None
        short = _shortfalls(self.budget, gps, ekf)
        if not short:
            tr.short_since = None
            return None
        if tr.short_since is None:
            tr.short_since = now
        if now - tr.short_since >= PERSIST_S and "short" not in tr.reported:
            tr.reported.add("short")
            return "; ".join(short) + f" for {now - tr.short_since:.1f} s"
        return None


M_PER_DEGREE = 111_319.49  # metres per degree of latitude (spherical, for a few metres)


def report_jump(prev, cur, fallback_velocity=None) -> float:
    """How far GPS_RAW_INT ``cur`` is from where ``prev`` and their mean velocity put it,
    metres (0 when they cannot be compared: no fix, out of order, far apart in time)."""
    return float(np.hypot(*jump_vector(prev, cur, fallback_velocity)))


def jump_vector(prev, cur, fallback_velocity=None) -> np.ndarray:
    """:func:`report_jump` as ``(east, north)`` metres: which way the GPS jumped. A copter
    holds its estimate where it was (every mode flies on it) while EKF3 takes the jump up
    (:mod:`ftlbo_mav.sim.gps`): it drifts the other way by as much, where it truly is."""
    if prev is None or cur.fix_type < 3 or prev.fix_type < 3:
        return np.zeros(2)
    dt = (cur.time_usec - prev.time_usec) * 1e-6
    if not 0 < dt <= GPS_STALE_S:
        return np.zeros(2)
    north = (cur.lat - prev.lat) * 1e-7 * M_PER_DEGREE
    east = ((cur.lon - prev.lon) * 1e-7 * M_PER_DEGREE
            * float(np.cos(np.radians(cur.lat * 1e-7))))
    v = [w for w in (_velocity(prev, fallback_velocity), _velocity(cur, fallback_velocity))
         if w is not None]
    mean = np.mean(v, axis=0) if v else np.zeros(2)
    jump = np.array([east - mean[0] * dt, north - mean[1] * dt])
    if len(v) == 2 and float(np.hypot(*jump)) <= ACCEL_MAX_M_S2 * dt * dt / 4.0:
        return np.zeros(2)  # its own acceleration can carry it there
    return jump


def _velocity(msg, fallback):
    if msg.vel != 0xFFFF and msg.cog != 0xFFFF:
        speed, course = msg.vel / 100.0, np.radians(msg.cog / 100.0)
        return (speed * float(np.sin(course)), speed * float(np.cos(course)))
    return None if fallback is None else tuple(fallback[:2])


def gps_report(msg, frame, *, fallback_velocity=None) -> GpsReport | None:
    """A GPS_RAW_INT as a :class:`GpsReport` in ``frame`` (a LocalFrame); the velocity
    from its ``vel``/``cog``, else ``fallback_velocity`` (east, north: the EKF's)."""
    if msg is None:
        return None
    has_fix = msg.fix_type >= 2 and not (msg.lat == 0 and msg.lon == 0)
    east = north = 0.0
    if has_fix:
        east, north = (float(x) for x in frame.to_enu(lat_deg=msg.lat * 1e-7,
                                                      lon_deg=msg.lon * 1e-7)[:2])
    velocity = fallback_velocity
    if msg.vel != 0xFFFF and msg.cog != 0xFFFF:
        speed, course = msg.vel / 100.0, np.radians(msg.cog / 100.0)
        velocity = (speed * float(np.sin(course)), speed * float(np.cos(course)))
    sats = None if msg.satellites_visible == 255 else int(msg.satellites_visible)
    return GpsReport(int(msg.fix_type), h_acc_m(getattr(msg, "h_acc", 0)), sats, east, north,
                     None if velocity is None else tuple(velocity), msg.time_usec * 1e-6)


def ekf_report(msg) -> EkfReport | None:
    if msg is None:
        return None
    return EkfReport(int(msg.flags), float(msg.pos_horiz_variance))


_FIX_SHORT = {0: "none", 1: "nofix", 2: "2D", 3: "3D", 4: "DGPS", 5: "RTKflt", 6: "RTKfix",
              7: "static", 8: "PPP"}


def navigation_short(gps_msg, ekf_msg) -> str:
    """The live view's few characters for a vehicle's GPS and EKF (raw messages, None
    when not received): fix, accuracy, satellites, EKF position variance."""
    if gps_msg is None:
        return ""
    acc = h_acc_m(getattr(gps_msg, "h_acc", 0))
    text = (f"  gps {_FIX_SHORT.get(gps_msg.fix_type, gps_msg.fix_type)} "
            + ("-" if acc is None else f"{acc:.2f} m") + f" {gps_msg.satellites_visible} sat")
    if ekf_msg is not None:
        text += f" ekf {ekf_msg.pos_horiz_variance:.2f}"
    return text
