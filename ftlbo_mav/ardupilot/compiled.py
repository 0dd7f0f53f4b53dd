"""The flown-path model of :mod:`.flight_path`, compiled: one loop over the mission.

:func:`.flight_path.fly_path_stepwise` flies a mission with the model's own objects
(:class:`.wpnav.WaypointNav` moving the target along :class:`.scurve.SCurve` legs,
:class:`.poscontrol.PositionFollower` flying the copter after it), as the emulator does,
a step at a time. The planner predicts thousands of seconds of flight per plan; there the
same arithmetic runs here as one numba-compiled loop (:func:`fly`), on the legs as the
SCurve objects planned them (:func:`legs_of`: their pieces, tracks and speeds), with the
state the objects would hold in plain numbers. Every function here mirrors one of those
methods, line by line and in the same order of operations, and names it;
``tests/ardupilot/test_compiled.py`` holds the two to one another (within 1e-6 m over
random missions, holds, speeds and parameters), ``tests/conformance`` the result to
recorded ArduCopter SITL tracks.

ArduPilot sources followed (through the methods mirrored): libraries/AP_Math/SCurve.cpp
(get_jerk_accel_vel_pos_at_time, advance_target_along_track), libraries/AC_WPNav/
AC_WPNav.cpp (advance_wp_target_along_track), libraries/AC_AttitudeControl/
AC_PosControl.cpp (update_xy_controller), AP_Math/control.cpp (sqrt_controller,
shape_vel_accel, limit_accel_xy), ArduCopter/mode_auto.cpp (the waypoint sequence).

numba compiles on first use and caches the machine code beside this file (or in its user
cache when that is read-only); while it is not cached, callers fly stepwise and have it
compiled in the background (:mod:`..compiling`, :func:`.flight_path.compile_now`).

Kept whole: one loop and the functions it inlines, each mirroring one method of the
model's objects in their order; held to them line by line, they read best in one place.
"""

from __future__ import annotations

import math

import numpy as np

from ..compiling import njit, ready
from . import navigation, poscontrol, scurve
from .navigation import GRAVITY_M_S2, Navigation
from .poscontrol import SEA_LEVEL_DENSITY, Airframe, _filter_alpha
from .poscontrol import STEP_S as PSC_STEP_S
from .scurve import ACCEL_END, ACCEL_MAX, CONST, DECEL_END, FLAT, PIECES, SCurve
from .wpnav import WP_RADIUS_MIN

_EPS = 1.1920929e-07  # scurve._EPS: ArduPilot's float32 is_zero
# columns of a leg's pieces: end time, kind, jerk, accel, vel, pos (scurve.Piece)
_T, _K, _J, _A, _V, _X = range(6)
# nav parameters, in this order (see _nav_params)
NAV_FIELDS = ("radius", "corner_accel", "psc_posxy_p", "wp_accel", "wp_jerk", "psc_jerk_xy",
              "desired_speed", "psc_velxy_p", "psc_velxy_i", "psc_velxy_d", "psc_velxy_imax",
              "alpha_e", "alpha_d", "accel_max", "lean", "quad", "mom", "handover_46",
              "accel_z", "scaler_floor")
OK, OUT_OF_TIME = 0, 1

# the model's pure arithmetic, compiled as it stands (one source for both loops)
_along = njit(cache=True)(scurve._along)
_sqrt_controller = njit(cache=True)(navigation.sqrt_controller)
_limit_accel = njit(cache=True)(poscontrol._limit_accel)


def legs_of(points: np.ndarray, nav: Navigation, desired_speed: float, *, first: int = 1,
            known: dict | None = None) -> tuple:
    """Every leg ``points[k-1] -> points[k]`` planned as AC_WPNav plans it
    (:meth:`.wpnav.WaypointNav._plan`: SCurve.calculate_track from rest to rest), as
    arrays indexed by the leg's end point ``k`` (row 0 unused): ``pieces`` ``(P, 23, 6)``,
    ``planned`` ``(P,)``, ``track`` and ``unit`` ``(P, 3)``, ``vel_max`` ``(P,)``.

    ``first``: only the legs from the one ending at ``points[first]`` on (the rows before
    stay empty: a flight resumed there never reads them). ``known``: the legs planned
    already, by their two ends (a leg depends on nothing else, once ``nav`` and
    ``desired_speed`` are fixed: the caller keeps one per pair of them); the legs planned
    here are added."""
    P = len(points)
    pieces = np.zeros((P, PIECES, 6))
    planned = np.zeros(P, np.bool_)
    track, unit, vel_max = np.zeros((P, 3)), np.zeros((P, 3)), np.zeros(P)
    jerk, snap = nav.scurve_jerk_snap()
    for k in range(max(first, 1), P):
        key = points[k - 1:k + 1].tobytes()
        row = known.get(key) if known is not None else None
        if row is None:
            row = _leg(points[k - 1], points[k], nav, desired_speed, jerk, snap)
            if known is not None:
                known[key] = row
        pieces[k], planned[k], track[k], unit[k], vel_max[k] = row
    return pieces, planned, track, unit, vel_max


def _leg(a: np.ndarray, b: np.ndarray, nav: Navigation, desired_speed: float, jerk: float,
         snap: float) -> tuple:
    """One row of :func:`legs_of`: the leg ``a -> b``'s pieces, planned, track, unit,
    vel_max."""
    leg = SCurve()
    leg.calculate_track(a, b, desired_speed, nav.wp_speed_up, nav.wp_speed_dn, nav.wp_accel,
                        nav.wp_accel_z, snap, jerk)
    pieces = np.zeros((PIECES, 6))
    if leg.planned:
        pieces[:] = [(q.end_time, q.kind, q.jerk, q.accel, q.vel, q.pos) for q in leg.p]
    else:
        pieces[0] = [leg.p[0].end_time, FLAT, 0.0, 0.0, 0.0, 0.0]
    return pieces, bool(leg.planned), np.array(leg.track, float), np.array(leg.unit, float), \
        float(leg.vel_max)


def nav_params(nav: Navigation, airframe: Airframe | None, desired_speed: float) -> np.ndarray:
    """The numbers :func:`fly` needs of ``nav``, the airframe and the speed, in the order
    of :data:`NAV_FIELDS` (as :class:`.wpnav.WaypointNav` and
    :class:`.poscontrol.PositionFollower` derive them)."""
    air = airframe if airframe is not None else Airframe()
    quad = 0.5 * air.air_density / air.drag_bcoef if air.drag_bcoef > 0 else 0.0
    mom = air.drag_mcoef * math.sqrt(air.air_density / SEA_LEVEL_DENSITY)
    lean = min(PSC_STEP_S / nav.atc_input_tc, 1.0) if nav.atc_input_tc > 0 else 1.0
    values = dict(radius=max(nav.wp_radius, WP_RADIUS_MIN), corner_accel=nav.corner_accel(),
                  psc_posxy_p=nav.psc_posxy_p, wp_accel=nav.wp_accel, wp_jerk=nav.wp_jerk,
                  psc_jerk_xy=nav.psc_jerk_xy, desired_speed=desired_speed,
                  psc_velxy_p=nav.psc_velxy_p, psc_velxy_i=nav.psc_velxy_i,
                  psc_velxy_d=nav.psc_velxy_d, psc_velxy_imax=nav.psc_velxy_imax,
                  alpha_e=_filter_alpha(nav.psc_velxy_flte),
                  alpha_d=_filter_alpha(nav.psc_velxy_fltd),
                  accel_max=GRAVITY_M_S2 * math.tan(nav.angle_max), lean=lean, quad=quad,
                  mom=mom, handover_46=1.0 if nav.handover_46 else 0.0,
                  accel_z=nav.wp_accel_z, scaler_floor=nav.track_scaler_floor)
    return np.array([values[name] for name in NAV_FIELDS], float)


@njit(cache=True)
def _state_at(pieces, planned, leg, t):
    """SCurve.state_at: (jerk, accel, speed, distance) of leg ``leg`` at ``t`` (-1: an
    empty SCurve)."""
    if leg < 0 or not planned[leg]:
        return 0.0, 0.0, 0.0, 0.0
    p = pieces[leg]
    i = PIECES
    for k in range(PIECES):
        if t < p[k, _T]:
            i = k
            break
    if i == 0:
        j, a, v, x = _along(FLAT, 0.0, 0.0, t - p[0, _T], p[0, _A], p[0, _V], p[0, _X])
    elif i == PIECES:
        q = PIECES - 1
        j, a, v, x = _along(FLAT, 0.0, 0.0, t - p[q, _T], p[q, _A], p[q, _V], p[q, _X])
    else:
        j, a, v, x = _along(int(p[i, _K]), p[i, _J], p[i, _T] - p[i - 1, _T], t - p[i - 1, _T],
                            p[i - 1, _A], p[i - 1, _V], p[i - 1, _X])
    return j, a, v, max(0.0, x)


@njit(cache=True)
def _time_end(pieces, planned, leg):
    """SCurve.time_end (time_turn_in / time_turn_out with ACCEL_MAX / CONST)."""
    if leg < 0 or not planned[leg]:
        return 0.0
    return pieces[leg, DECEL_END, _T]


@njit(cache=True)
def _piece_end(pieces, planned, leg, piece):
    if leg < 0 or not planned[leg]:
        return 0.0
    return pieces[leg, piece, _T]


@njit(cache=True)
def _track_sq(track, leg):
    if leg < 0:
        return 0.0
    return track[leg, 0] * track[leg, 0] + track[leg, 1] * track[leg, 1] \
        + track[leg, 2] * track[leg, 2]


@njit(cache=True)
def _advance_curve(pieces, planned, unit, leg, time, dt, out):
    """SCurve._advance: the leg's time moved on by ``dt``; its position, velocity and
    acceleration (along its unit vector) added to the rows of ``out`` (3, 3); returns the
    new time and position_sq."""
    time = min(time + dt, _time_end(pieces, planned, leg))
    _j, a, v, x = _state_at(pieces, planned, leg, time)
    if leg >= 0:
        for i in range(3):
            out[0, i] += unit[leg, i] * x
            out[1, i] += unit[leg, i] * v
            out[2, i] += unit[leg, i] * a
    return time, x * x


@njit(cache=True)
def _follow(f, prm, dt, tx, ty, tvx, tvy, tax, tay, wx, wy):
    """PositionFollower.step with its state in ``f``: px, py, vx, vy, ex, ey, dx, dy, ix,
    iy, lx, ly, carry, limit_x, limit_y; the wind ``(wx, wy)`` (the planner's copters fly
    in still air: 0, 0)."""
    kp, kvp, kvi, kvd = prm[2], prm[7], prm[8], prm[9]
    imax, accel_max, lean = prm[10], prm[13], prm[14]
    alpha_e, alpha_d, quad, mom = prm[11], prm[12], prm[15], prm[16]
    pos_limit = prm[3]
    linear = pos_limit / (kp * kp) if kp > 0 and pos_limit > 0 else math.inf
    px, py, vx, vy = f[0], f[1], f[2], f[3]
    ex_f, ey_f, dx_f, dy_f = f[4], f[5], f[6], f[7]
    ix, iy, lx, ly = f[8], f[9], f[10], f[11]
    carry, limit_x, limit_y = f[12], f[13], f[14]
    h = PSC_STEP_S
    carry += dt
    while carry >= h - 1e-12:
        carry -= h
        ex, ey = tx - px, ty - py
        err = math.hypot(ex, ey)
        if err > linear:
            corr = _sqrt_controller(err, kp, pos_limit, h) / err
        else:
            corr = min(kp, 1.0 / h)
        last_x, last_y = ex_f, ey_f
        ex_f += (tvx + ex * corr - vx - ex_f) * alpha_e
        ey_f += (tvy + ey * corr - vy - ey_f) * alpha_e
        dx_f += ((ex_f - last_x) / h - dx_f) * alpha_d
        dy_f += ((ey_f - last_y) / h - dy_f) * alpha_d
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
        limit_x = limit_y = 0.0
        if ax * ax + ay * ay > accel_max * accel_max:
            limit_x, limit_y = ax, ay
            ax, ay = _limit_accel(tvx, tvy, ax, ay, accel_max)
        lx += (ax - lx) * lean
        ly += (ay - ly) * lean
        rx, ry = vx - wx, vy - wy
        speed = math.hypot(rx, ry)
        d = quad * speed + mom
        vx += (lx - rx * d) * h
        vy += (ly - ry * d) * h
        px += vx * h
        py += vy * h
    f[0], f[1], f[2], f[3] = px, py, vx, vy
    f[4], f[5], f[6], f[7] = ex_f, ey_f, dx_f, dy_f
    f[8], f[9], f[10], f[11] = ix, iy, lx, ly
    f[12], f[13], f[14] = carry, limit_x, limit_y


def follower_ready() -> bool:
    """Whether :class:`CompiledFollower`'s loop is compiled or cached (:mod:`..compiling`)."""
    return ready(_follow)


class CompiledFollower(poscontrol.PositionFollower):
    """:class:`~.poscontrol.PositionFollower` whose 400 Hz steps run in :func:`_follow`:
    the same arithmetic (held equal in tests/ardupilot/test_compiled.py), for the
    emulator on a simulated clock, which steps three copters every 20 ms (loading the
    compiled loop takes most of a second, once). Its state lives in the array the loop
    works on (:data:`FOLLOWER_STATE`)."""

    def __init__(self, position, velocity=(0.0, 0.0), **kwargs) -> None:
        self._f = np.zeros(len(FOLLOWER_STATE) + 2)
        super().__init__(position, velocity, **kwargs)
        self._prm = nav_params(self.nav, self.airframe, 0.0)

    @property
    def _limit(self) -> tuple[float, float]:
        return float(self._f[13]), float(self._f[14])

    @_limit.setter
    def _limit(self, value) -> None:
        self._f[13], self._f[14] = value

    def step(self, dt: float, target, target_vel, target_accel) -> np.ndarray:
        tx, ty = target[:2].tolist() if isinstance(target, np.ndarray) else target[:2]
        tvx, tvy = (target_vel[:2].tolist() if isinstance(target_vel, np.ndarray)
                    else target_vel[:2])
        tax, tay = (target_accel[:2].tolist() if isinstance(target_accel, np.ndarray)
                    else target_accel[:2])
        _follow(self._f, self._prm, float(dt), float(tx), float(ty), float(tvx), float(tvy),
                float(tax), float(tay), *self.wind)
        return self._f[:2].copy()


FOLLOWER_STATE = ("px", "py", "vx", "vy", "_ex", "_ey", "_dx", "_dy", "_ix", "_iy", "_lx",
                  "_ly", "_carry")
"""PositionFollower's state in the order :func:`_follow` keeps it (then its limit's x, y)."""


def _state_slot(k: int) -> property:
    def get(self) -> float:
        return float(self._f[k])

    def put(self, value: float) -> None:
        self._f[k] = value

    return property(get, put)


for _k, _name in enumerate(FOLLOWER_STATE):
    setattr(CompiledFollower, _name, _state_slot(_k))


SNAP_INTS = 8  # prev, this, nxt, k, n, wp_reached, fast, waiting
SNAP_FLOATS = 47  # see _pack
"""The loop's state when it starts a waypoint (:func:`fly`'s snapshots): every number that
lives from one step to the next."""


@njit(cache=True)
def _pack(si, sf, prev, this, nxt, k, n, wp_reached, fast, waiting, prev_t, this_t, nxt_t,
          prev_sq, this_sq, nxt_sq, offset_vel, offset_accel, track_scaler, t, wait_until,
          origin, destination, target, target_vel, target_accel, f, here, velocity):
    si[0], si[1], si[2], si[3], si[4] = prev, this, nxt, k, n
    si[5], si[6], si[7] = wp_reached, fast, waiting
    sf[0], sf[1], sf[2], sf[3], sf[4], sf[5] = prev_t, this_t, nxt_t, prev_sq, this_sq, nxt_sq
    sf[6], sf[7], sf[8], sf[9], sf[10] = offset_vel, offset_accel, track_scaler, t, wait_until
    sf[11:14], sf[14:17], sf[17:20] = origin, destination, target
    sf[20:23], sf[23:26], sf[26:41] = target_vel, target_accel, f
    sf[41:44], sf[44:47] = here, velocity


@njit(cache=True)
def fly(points, holds, pieces, planned, track, unit, vel_max, prm, dt, budget, follow,
        settled_m, settled_m_s, settle_steps, resume_i, resume_f, prior_times,
        prior_positions, prior_reached):
    """flight_path.fly_path_stepwise as one loop: ``(status, steps, times, positions,
    reached, snap_i, snap_f)``, the first ``steps`` rows of ``times`` and ``positions``
    filled (status :data:`OUT_OF_TIME` when the mission was not flown within ``budget``
    steps); ``snap_i (P, SNAP_INTS)``, ``snap_f (P, SNAP_FLOATS)``: row ``k`` the loop's
    state as it starts waypoint ``k`` (``snap_i[k, 3] == k`` where it did), which depends
    on ``points[:k + 1]`` and ``holds[:k]`` only.

    A flight resumed from such a row (``resume_i``, ``resume_f``; the rows before it of
    ``prior_times``, ``prior_positions`` and ``prior_reached`` from the same flight)
    goes on exactly as the whole flight would from there (the same numbers in the same
    order); ``resume_i[3] == 0``: from the start."""
    P = points.shape[0]
    rows = budget + settle_steps + 1
    times = np.empty(rows)
    positions = np.empty((rows, 3))
    reached = np.zeros(P)
    snap_i = np.zeros((P, SNAP_INTS), np.int64)
    snap_f = np.zeros((P, SNAP_FLOATS))
    radius, corner_accel, posxy_p = prm[0], prm[1], prm[2]
    wp_accel, wp_jerk, jerk_xy, desired = prm[3], prm[4], prm[5], prm[6]
    handover_46, accel_z, scaler_floor = prm[17] != 0.0, prm[18], prm[19]
    out = np.zeros((3, 3))
    if resume_i[3] == 0:
        # WaypointNav state: the three legs (-1: an empty SCurve), their times and
        # position_sq; origin, destination, target, its velocity and acceleration
        prev, this, nxt = -1, -1, -1
        prev_t = this_t = nxt_t = 0.0
        _prev_sq = this_sq = nxt_sq = 0.0
        wp_reached, fast = True, False
        origin = points[0].copy()
        destination = points[0].copy()
        target = points[0].copy()
        target_vel = np.zeros(3)
        target_accel = np.zeros(3)
        offset_vel, offset_accel, track_scaler = desired, 0.0, 1.0
        f = np.zeros(15)  # PositionFollower at rest on the first point
        f[0], f[1] = points[0, 0], points[0, 1]
        here = points[0].copy()
        velocity = np.zeros(3)
        times[0] = 0.0
        positions[0] = points[0]
        n = 1
        k, t, waiting, wait_until = 1, 0.0, False, 0.0
    else:
        prev, this, nxt, k, n = resume_i[0], resume_i[1], resume_i[2], resume_i[3], resume_i[4]
        wp_reached, fast, waiting = resume_i[5] != 0, resume_i[6] != 0, resume_i[7] != 0
        prev_t, this_t, nxt_t = resume_f[0], resume_f[1], resume_f[2]
        _prev_sq, this_sq, nxt_sq = resume_f[3], resume_f[4], resume_f[5]
        offset_vel, offset_accel, track_scaler = resume_f[6], resume_f[7], resume_f[8]
        t, wait_until = resume_f[9], resume_f[10]
        origin, destination = resume_f[11:14].copy(), resume_f[14:17].copy()
        target, target_vel = resume_f[17:20].copy(), resume_f[20:23].copy()
        target_accel, f = resume_f[23:26].copy(), resume_f[26:41].copy()
        here, velocity = resume_f[41:44].copy(), resume_f[44:47].copy()
        times[:n] = prior_times[:n]
        positions[:n] = prior_positions[:n]
        reached[:k] = prior_reached[:k]
    done_all = False
    steps_left = budget - (n - 1)
    while True:
        # start(k): ModeAuto::do_nav_wp / set_next_wp (set_destination, set_destination_next;
        # reached already, so no re-init)
        _pack(snap_i[k], snap_f[k], prev, this, nxt, k, n, wp_reached, fast, waiting, prev_t,
              this_t, nxt_t, _prev_sq, this_sq, nxt_sq, offset_vel, offset_accel,
              track_scaler, t, wait_until, origin, destination, target, target_vel,
              target_accel, f, here, velocity)
        prev, prev_t, _prev_sq = this, this_t, this_sq
        origin = destination.copy()
        destination = points[k].copy()
        if fast and not (nxt_t >= _time_end(pieces, planned, nxt)
                         or nxt_sq >= _track_sq(track, nxt)):
            this, this_t, this_sq = nxt, nxt_t, nxt_sq
        else:
            this, this_t, this_sq = k, 0.0, 0.0
        nxt, nxt_t, nxt_sq = -1, 0.0, 0.0
        fast, wp_reached = False, False
        if holds[k] <= 0 and k + 1 < P:
            nxt, nxt_t, nxt_sq, fast = k + 1, 0.0, 0.0, True
        # fly until waypoint k is reached (and held)
        next_point = False
        while steps_left > 0:
            steps_left -= 1
            t += dt
            # WaypointNav.advance: _time_scale (Navigation.track_clock_step)
            offset_vel += offset_accel * dt
            want = _sqrt_controller(desired - offset_vel, jerk_xy / wp_accel, jerk_xy, dt)
            want = max(-wp_accel, min(wp_accel, want))
            offset_accel += max(-jerk_xy * dt, min(jerk_xy * dt, want - offset_accel))
            scale = offset_vel / desired
            # _track_scale
            if follow:
                speed = math.sqrt(target_vel[0] ** 2 + target_vel[1] ** 2 + target_vel[2] ** 2)
                wanted = 1.0
                if speed > 0:
                    track_error = 0.0
                    track_velocity = 0.0
                    for i in range(3):
                        direction = target_vel[i] / speed
                        track_error += (target[i] - here[i]) * direction
                        track_velocity += velocity[i] * direction
                    wanted = min(max(0.05 + (track_velocity - posxy_p * track_error) / speed,
                                     scaler_floor), 1.0)
                tc = wp_accel / wp_jerk if wp_jerk > 0 else 1.0
                track_scaler += (wanted - track_scaler) * min(dt / tc, 1.0)
            step = dt * scale * track_scaler
            # SCurve.advance_target_along_track
            out[:] = 0.0
            prev_t, _prev_sq = _advance_curve(pieces, planned, unit, prev, prev_t, step, out)
            if prev >= 0:
                for i in range(3):
                    out[0, i] -= track[prev, i]
            this_t, this_sq = _advance_curve(pieces, planned, unit, this, this_t, step, out)
            this_end = _time_end(pieces, planned, this)
            done = this_t >= this_end or this_sq >= _track_sq(track, this)
            left = this_end - this_t if (this >= 0 and planned[this]) else 0.0
            if handover_46:  # SCurve.advance_target_along_track (handover_46)
                begin = (this_t >= _piece_end(pieces, planned, this, CONST)
                         and left <= _piece_end(pieces, planned, nxt, ACCEL_END))
            else:
                begin = (this_t >= _piece_end(pieces, planned, this, CONST)
                         - _piece_end(pieces, planned, nxt, ACCEL_MAX)
                         and this_sq >= 0.25 * _track_sq(track, this))
            if fast and abs(nxt_t) < _EPS and begin:
                _j, a1, v1, x1 = _state_at(pieces, planned, this, this_t + left / 2)
                _j, a2, v2, x2 = _state_at(pieces, planned, nxt, left / 2)
                tp0 = tp1 = tp2 = 0.0
                tv0 = tv1 = tv2 = ta0 = ta1 = ta2 = 0.0
                if this >= 0:
                    tp0 = unit[this, 0] * x1 - track[this, 0]
                    tp1 = unit[this, 1] * x1 - track[this, 1]
                    tp2 = unit[this, 2] * x1 - track[this, 2]
                    tv0, tv1 = unit[this, 0] * v1, unit[this, 1] * v1
                    tv2, ta2 = unit[this, 2] * v1, unit[this, 2] * a1
                    ta0, ta1 = unit[this, 0] * a1, unit[this, 1] * a1
                if nxt >= 0:
                    tp0 += unit[nxt, 0] * x2
                    tp1 += unit[nxt, 1] * x2
                    tp2 += unit[nxt, 2] * x2
                    tv0 += unit[nxt, 0] * v2
                    tv1 += unit[nxt, 1] * v2
                    tv2 += unit[nxt, 2] * v2
                    ta0 += unit[nxt, 0] * a2
                    ta1 += unit[nxt, 1] * a2
                    ta2 += unit[nxt, 2] * a2
                speed_min = min(vel_max[this] if this >= 0 else 0.0,
                                vel_max[nxt] if nxt >= 0 else 0.0)
                if handover_46:
                    turn = (math.sqrt(tv0 * tv0 + tv1 * tv1 + tv2 * tv2) < speed_min
                            and abs(ta2) < accel_z)
                else:
                    turn = (left < _time_end(pieces, planned, nxt) / 2
                            and math.hypot(tv0, tv1) < speed_min)
                if (turn and math.sqrt(tp0 * tp0 + tp1 * tp1 + tp2 * tp2) < radius
                        and math.hypot(ta0, ta1) < corner_accel):
                    nxt_t, nxt_sq = _advance_curve(pieces, planned, unit, nxt, nxt_t, step,
                                                   out)
            elif not abs(nxt_t) < _EPS:
                nxt_t, nxt_sq = _advance_curve(pieces, planned, unit, nxt, nxt_t, step, out)
                if nxt_t >= (this_end - this_t if (this >= 0 and planned[this]) else 0.0):
                    done = True
            # back in WaypointNav.advance: the speed offset's acceleration, the time scale
            for i in range(3):
                pos_i = origin[i] + out[0, i]
                vel_i = out[1, i]
                offset = vel_i * (offset_accel / desired)
                target[i] = pos_i
                target_vel[i] = vel_i * scale
                target_accel[i] = out[2, i] * scale * scale + offset
            if not wp_reached and done:
                if fast:
                    wp_reached = True
                else:
                    gap = math.sqrt((here[0] - destination[0]) ** 2
                                    + (here[1] - destination[1]) ** 2
                                    + (here[2] - destination[2]) ** 2)
                    if gap <= radius:
                        wp_reached = True
            # the copter follows (fly_path_stepwise)
            if follow:
                _follow(f, prm, dt, target[0], target[1], target_vel[0], target_vel[1],
                        target_accel[0], target_accel[1], 0.0, 0.0)
                here[0], here[1], here[2] = f[0], f[1], target[2]
                velocity[0], velocity[1], velocity[2] = f[2], f[3], target_vel[2]
            else:
                here[:] = target
            times[n] = t
            positions[n] = here
            n += 1
            if not wp_reached:
                continue
            if holds[k] > 0 and not waiting:  # ModeAuto::verify_nav_wp: the hold
                reached[k] = t
                waiting, wait_until = True, t + holds[k]
            if waiting and t < wait_until - 1e-9:
                continue
            if not waiting:
                reached[k] = t
            waiting = False
            next_point = True
            break
        if not next_point:
            break  # out of steps
        k += 1
        if k == P:
            done_all = True
            break
    if not done_all:
        return OUT_OF_TIME, n, times, positions, reached, snap_i, snap_f
    if follow:  # the copter comes to rest on its goal (past it, and back)
        gx, gy, gz = points[P - 1, 0], points[P - 1, 1], points[P - 1, 2]
        for _s in range(settle_steps):
            if (math.hypot(here[0] - gx, here[1] - gy) < settled_m
                    and math.hypot(f[2], f[3]) < settled_m_s):
                break
            t += dt
            _follow(f, prm, dt, gx, gy, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
            here[0], here[1], here[2] = f[0], f[1], gz
            times[n] = t
            positions[n] = here
            n += 1
    return OK, n, times, positions, reached, snap_i, snap_f
