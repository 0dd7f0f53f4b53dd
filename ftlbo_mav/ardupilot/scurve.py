"""ArduPilot's S-curve legs, re-implemented: jerk- and acceleration-limited straight
tracks planned rest to rest, whose ends blend into the next leg at "fast" waypoints.

Follows ``libraries/AP_Math/SCurve.cpp`` of ArduPilot 4.5.6 (class SCurve), which
AC_WPNav uses for every straight waypoint leg; the equations are derived here, not copied.
A leg is 23 pieces along the track (the layout SCurve uses, so that a speed change mid-leg
rewrites the same pieces it does): a start piece, seven that accelerate, seven that change
speed, one at constant speed and seven that decelerate. Jerk rises and falls as a raised
cosine over ``tj`` seconds (its "snap" limit), holds at ``Jm`` in between.

Any consistent units work; its users (:mod:`.wpnav`: the emulator and the planner's
prediction of the flown path) use metres and seconds.

Kept whole: one class, method for method ArduPilot's SCurve (planning a leg's pieces,
changing its speeds, reading it at a time, handing over to the next leg per release), and
the helpers that build its pieces; split, a reader would hold SCurve.cpp beside two files.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

# piece indices (SCurve.cpp: SEG_INIT, SEG_ACCEL_MAX/TURN_IN, SEG_ACCEL_END,
# SEG_SPEED_CHANGE_END, SEG_CONST/TURN_OUT, SEG_DECEL_END)
INIT, ACCEL_MAX, ACCEL_END, CHANGE_END, CONST, DECEL_END = 0, 4, 7, 14, 15, 22
PIECES = 23
FLAT, RISE, FALL = 0, 1, 2  # constant jerk; jerk rising / falling as a raised cosine
_EPS = 1.1920929e-07  # float32 epsilon: ArduPilot's is_zero / is_equal / is_positive


def _zero(x: float) -> bool:
    return abs(x) < _EPS


def _pos(x: float) -> bool:
    return x >= _EPS


@dataclass(frozen=True)
class Piece:
    end_time: float
    kind: int
    jerk: float
    accel: float
    vel: float
    pos: float


def _along(kind: int, jerk: float, span: float, t: float, a0: float, v0: float,
           p0: float) -> tuple[float, float, float, float]:
    """Jerk, acceleration, speed and distance ``t`` seconds into a piece of ``span``
    seconds starting at ``(a0, v0, p0)``. RISE: j = J/2 (1 - cos(pi t / span));
    FALL: j = J/2 (1 + cos(pi t / span)); FLAT: j = J (integrated in closed form)."""
    if kind == FLAT:
        return (jerk, a0 + jerk * t, v0 + a0 * t + jerk * t * t / 2,
                p0 + v0 * t + a0 * t * t / 2 + jerk * t ** 3 / 6)
    if span <= 0:
        return 0.0, a0, v0, p0
    h, w = jerk / 2, span / math.pi
    s, c = math.sin(t / w), math.cos(t / w)
    sign = 1.0 if kind == RISE else -1.0
    j = h * (1 - sign * c)
    a = a0 + h * (t - sign * w * s)
    v = v0 + a0 * t + h * (t * t / 2 + sign * w * w * (c - 1))
    p = p0 + v0 * t + a0 * t * t / 2 + h * (t ** 3 / 6 - sign * w * w * t + sign * w ** 3 * s)
    return j, a, v, p


def _root(f, lo: float, hi: float) -> float:
    """The root of increasing ``f`` in [lo, hi] (bisection to float64 precision)."""
    for _ in range(200):
        mid = (lo + hi) / 2
        if mid in (lo, hi):
            break
        if f(mid) < 0:
            lo = mid
        else:
            hi = mid
    return (lo + hi) / 2


def plan_speed_change(snap: float, jerk: float, v0: float, accel: float, vmax: float,
                      length: float) -> tuple[float, float, float, float, float]:
    """``(Jm, tj, t2, t4, t6)`` of the fastest speed change from ``v0`` towards ``vmax``
    within ``length`` (SCurve::calculate_path): a jerk pulse (rise ``tj``, hold ``t2``,
    fall ``tj``) up to acceleration A = Jm (tj + t2), A held ``t4``, and the mirror pulse
    (``t6`` = ``t2``) back to zero acceleration. Then the speed gained is
    A (tj + A/Jm + t4) and the distance (v0 + gain/2) (2 (tj + A/Jm) + t4).

    As calculate_path: ``tj`` = Jm pi / (2 snap); when even the shortest pulse is too
    much, from rest the pulse is shortened (tj, hence Jm and A, scaled down), otherwise
    Jm is lowered; else A is lowered until speed or distance fit, then ``t4`` is the
    longest hold that fits both. Its test for the short-pulse case uses
    (length + 4 v0 tj) / (4 tj^2), as ArduPilot writes it."""
    if not (_pos(snap) and _pos(jerk) and _pos(accel) and _pos(vmax) and _pos(length)):
        return 0.0, 0.0, 0.0, 0.0, 0.0
    if v0 >= vmax:
        return 0.0, 0.0, 0.0, 0.0, 0.0
    jm, am = jerk, accel
    tj = jm * math.pi / (2 * snap)
    a_short = min(am, (vmax - v0) / (2 * tj), (length + 4 * v0 * tj) / (4 * tj * tj))

    def hold(a: float, jm: float) -> float:
        """The longest constant-acceleration time within speed and distance."""
        r = tj + a / jm
        by_speed = (vmax - v0) / a - r
        b = v0 + 1.5 * a * r
        disc = b * b - 2 * a * (2 * r * v0 + a * r * r - length)
        by_distance = (-b + math.sqrt(max(disc, 0.0))) / a
        return max(min(by_speed, by_distance), 0.0)

    if abs(a_short) < jm * tj:
        if _zero(v0):  # a shorter raised-cosine pulse: distance, speed and accel bound tj
            tj = min(tj, (length * math.pi / (8 * snap)) ** 0.25,
                     (vmax * math.pi / (4 * snap)) ** (1 / 3),
                     math.sqrt(max(am * math.pi / (2 * snap), 0.0)))
            jm = 2 * snap * tj / math.pi
            am = jm * tj
        else:
            am = a_short
            jm = am / tj
        if vmax <= v0 + 2 * am * tj or length <= 4 * v0 * tj + 4 * am * tj * tj:
            t2 = t4 = 0.0
        else:
            t2, t4 = 0.0, hold(am, jm)
        t6 = 0.0
    else:
        def gain(a: float) -> float:
            return a * (tj + a / jm)

        def dist(a: float) -> float:
            return (v0 + gain(a) / 2) * 2 * (tj + a / jm)

        if vmax < v0 + gain(am) or length < dist(am):
            a_speed = jm * (math.sqrt(tj * tj + 4 * (vmax - v0) / jm) - tj) / 2
            a_dist = _root(lambda a: dist(a) - length, 0.0, am) if dist(am) > length else am
            am = min(am, a_speed, a_dist)
            t2, t4 = am / jm - tj, 0.0
        else:
            t2 = am / jm - tj
            t4 = hold(am, jm)
        t6 = t2
    out = (jm, tj, t2, t4, t6)
    if not all(math.isfinite(x) and x > -_EPS for x in out):
        return 0.0, tj, 0.0, 0.0, 0.0
    return jm, tj, max(t2, 0.0), max(t4, 0.0), max(t6, 0.0)


def kinematic_limit(direction: np.ndarray, max_xy: float, max_up: float,
                    max_down: float) -> float:
    """The largest magnitude along ``direction`` (ENU) within a horizontal limit and
    separate up and down limits (AP_Math/control.cpp kinematic_limit)."""
    n = float(np.linalg.norm(direction))
    if _zero(n * n) or _zero(max_xy) or _zero(max_up) or _zero(max_down):
        return 0.0
    max_xy, max_up, max_down = abs(max_xy), abs(max_up), abs(max_down)
    d = np.asarray(direction, float) / n
    xy = math.hypot(d[0], d[1])
    if _zero(xy):
        return max_up if d[2] > 0 else max_down
    if _zero(d[2]):
        return max_xy
    vertical = max_up if d[2] > 0 else max_down
    if abs(d[2] / xy) < vertical / max_xy:
        return max_xy / xy
    return abs(vertical / d[2])


class SCurve:
    """One straight leg's path (ArduPilot's SCurve)."""

    def __init__(self) -> None:
        self.init()

    def init(self) -> None:
        """SCurve::init: an empty path (one piece), nothing travelled."""
        self.snap = self.jerk = self.accel_max = self.vel_max = 0.0
        self.time = 0.0
        self.position_sq = 0.0
        self._set_track(np.zeros(3), np.zeros(3))
        self.p: list[Piece] = [Piece(0.0, FLAT, 0.0, 0.0, 0.0, 0.0)]
        self._hint = 0  # where state_at's last search ended

    def _set_track(self, track: np.ndarray, unit: np.ndarray) -> None:
        """The leg's track and its direction, also as plain floats (a step of the target
        along the track is scalar arithmetic: numpy's per-call cost on three numbers
        would be most of it)."""
        self.track, self.unit = track, unit
        self._track_xyz, self._unit_xyz = tuple(track.tolist()), tuple(unit.tolist())
        self._track_sq = float(track @ track)

    def copy(self) -> SCurve:
        other = SCurve()
        other.__dict__.update({k: (v.copy() if isinstance(v, (list, np.ndarray)) else v)
                               for k, v in self.__dict__.items()})
        return other

    @property
    def planned(self) -> bool:
        return len(self.p) == PIECES

    # -- building pieces (SCurve::add_segment_*)
    def _push(self, kind: int, span: float, jerk: float) -> None:
        last = self.p[-1]
        if span <= 0 or not _pos(span):
            self.p.append(Piece(last.end_time, FLAT, jerk if kind == FLAT else 0.0,
                                last.accel, last.vel, last.pos))
            return
        _j, a, v, x = _along(kind, jerk, span, span, last.accel, last.vel, last.pos)
        self.p.append(Piece(last.end_time + span, kind, jerk, a, v, x))

    def _pulse(self, tj: float, jm: float, hold: float) -> None:
        self._push(RISE, tj, jm)
        self._push(FLAT, hold, jm)
        self._push(FALL, tj, jm)

    def _change(self, jm: float, tj: float, t2: float, t4: float, t6: float) -> None:
        """A full speed change: pulse, acceleration held, mirror pulse."""
        self._pulse(tj, jm, t2)
        self._push(FLAT, t4, 0.0)
        self._pulse(tj, -jm, t6)

    def _rest_at(self, i: int) -> None:
        """Zero the acceleration of piece ``i`` (ArduPilot's "remove numerical errors")."""
        self.p[i] = replace(self.p[i], accel=0.0)

    def _flat_copies(self, first: int, last: int, source: int) -> None:
        """Pieces first..last (inclusive, replacing or appending) hold piece ``source``."""
        src = self.p[source]
        for i in range(first, last + 1):
            piece = Piece(src.end_time, FLAT, 0.0, 0.0, src.vel, src.pos)
            if i < len(self.p):
                self.p[i] = piece
            else:
                self.p.append(piece)

    def _stretch_const(self, length: float) -> None:
        """Lengthen the constant-speed piece so the path ends at ``length``."""
        dp = max(0.0, length - self.p[DECEL_END].pos)
        dt = dp / self.p[CONST].vel if dp > 0 else 0.0
        for i in range(CONST, DECEL_END + 1):
            q = self.p[i]
            self.p[i] = replace(q, end_time=q.end_time + dt, pos=q.pos + dp)

    def _truncate(self, n: int) -> None:
        del self.p[n:]

    # -- planning
    def calculate_track(self, origin, destination, speed_xy: float, speed_up: float,
                        speed_down: float, accel_xy: float, accel_z: float, snap: float,
                        jerk: float) -> None:
        """SCurve::calculate_track: plan origin -> destination from rest to rest."""
        self.init()
        track = np.asarray(destination, float) - np.asarray(origin, float)
        if _zero(float(track @ track)):
            return
        self.snap, self.jerk = snap, jerk
        self.vel_max = kinematic_limit(track, speed_xy, speed_up, speed_down)
        self.accel_max = kinematic_limit(track, accel_xy, accel_z, accel_z)
        if not (_pos(snap) and _pos(jerk) and _pos(self.accel_max) and _pos(self.vel_max)):
            return
        length = float(np.linalg.norm(track))
        self._set_track(track, track / length)
        self._add_rest_to_rest(length)
        if not self.valid():
            self.init()

    def _add_rest_to_rest(self, length: float) -> None:
        """SCurve::add_segments: accelerate over the first half at most, cruise, mirror."""
        jm, tj, t2, t4, t6 = plan_speed_change(self.snap, self.jerk, 0.0, self.accel_max,
                                               self.vel_max, length / 2)
        self._change(jm, tj, t2, t4, t6)
        self._rest_at(ACCEL_END)
        for _ in range(ACCEL_END + 1, CHANGE_END + 1):
            self._push(FLAT, 0.0, 0.0)
        mid = self.p[CHANGE_END]
        cruise = max(0.0, (length - 2 * mid.pos) / mid.vel) if mid.vel > 0 else 0.0
        self._push(FLAT, cruise, 0.0)
        self._change(-jm, tj, t6, t4, t2)
        self.p[DECEL_END] = replace(self.p[DECEL_END], accel=0.0, vel=0.0)

    def valid(self) -> bool:
        """SCurve::valid: 23 finite pieces, time and distance never decreasing, speed never
        negative, ending without acceleration."""
        if not self.planned:
            return False
        for i, q in enumerate(self.p):
            if not all(math.isfinite(x) for x in (q.jerk, q.end_time, q.accel, q.vel, q.pos)):
                return False
            if q.vel <= -_EPS:
                return False
            if i and (q.end_time - self.p[i - 1].end_time <= -_EPS
                      or q.pos - self.p[i - 1].pos <= -_EPS):
                return False
        return _zero(self.p[-1].accel)

    def set_origin_speed_max(self, speed: float) -> float:
        """SCurve::set_origin_speed_max: start the leg at up to ``speed``; returns the
        speed it will start at."""
        if not self.planned:
            return 0.0
        if abs(self.p[INIT].vel - speed) < _EPS:
            return speed
        vm = self.p[ACCEL_END].vel
        length = float(np.linalg.norm(self.track))
        speed = min(speed, vm)
        jm, tj, t2, t4, t6 = plan_speed_change(self.snap, self.jerk, speed, self.accel_max,
                                               vm, length / 2)
        self.p = [Piece(0.0, FLAT, 0.0, 0.0, speed, 0.0)]
        self._change(jm, tj, t2, t4, t6)
        self._rest_at(ACCEL_END)
        end = self.p[ACCEL_END]
        shift_p = min(0.0, length / 2 - end.pos)
        shift_t = shift_p / end.vel if end.vel > 0 else 0.0
        for i in range(INIT, ACCEL_END + 1):
            q = self.p[i]
            self.p[i] = replace(q, end_time=q.end_time + shift_t, pos=q.pos + shift_p)
        self._flat_copies(ACCEL_END + 1, CHANGE_END, ACCEL_END)
        self._push(FLAT, 0.0, 0.0)
        jm, tj, t2, t4, t6 = plan_speed_change(self.snap, self.jerk, 0.0, self.accel_max,
                                               self.p[CONST].vel, length / 2)
        self._change(-jm, tj, t6, t4, t2)
        self.p[DECEL_END] = replace(self.p[DECEL_END], accel=0.0,
                                    vel=max(0.0, self.p[DECEL_END].vel))
        self._stretch_const(length)
        if not self.valid():
            self.init()
            return 0.0
        return speed

    def set_destination_speed_max(self, speed: float) -> None:
        """SCurve::set_destination_speed_max: end the leg at up to ``speed``."""
        if not self.planned:
            return
        if abs(self.p[-1].vel - speed) < _EPS:
            return
        vm = self.p[CONST].vel
        length = float(np.linalg.norm(self.track))
        speed = min(speed, vm)
        jm, tj, t2, t4, t6 = plan_speed_change(self.snap, self.jerk, speed, self.accel_max,
                                               vm, length / 2)
        self._truncate(CONST)
        self._push(FLAT, 0.0, 0.0)
        self._change(-jm, tj, t6, t4, t2)
        self.p[DECEL_END] = replace(self.p[DECEL_END], accel=0.0,
                                    vel=max(0.0, self.p[DECEL_END].vel))
        self._stretch_const(length)
        if not self.valid():
            self.init()

    def set_speed_max(self, speed_xy: float, speed_up: float, speed_down: float) -> None:
        """SCurve::set_speed_max: a new speed limit mid-leg. The pieces still ahead are
        re-planned: before the leg starts, all of it; while still accelerating, the
        acceleration is cut short (never below what is already reached); then the
        speed-change pieces move towards the new speed, and the deceleration follows."""
        if not self.planned:
            return
        new = kinematic_limit(self.unit, speed_xy, speed_up, abs(speed_down))
        if abs(self.vel_max - new) < _EPS or _zero(new):
            return
        self.vel_max = new
        p, t = self.p, self.time
        if t >= p[CONST].end_time:
            return
        end_pos = p[DECEL_END].pos
        end_vel = min(self.vel_max, p[DECEL_END].vel)
        if _zero(t):
            start_vel = min(self.vel_max, p[INIT].vel)
            self.p = [Piece(0.0, FLAT, 0.0, 0.0, 0.0, 0.0)]
            self._add_rest_to_rest(end_pos)
            self.set_origin_speed_max(start_vel)
            self.set_destination_speed_max(end_vel)
            return
        if p[ACCEL_END].end_time <= t <= p[CHANGE_END].end_time:
            # mid speed change: its pieces become the acceleration, so it can change again
            a_end = p[ACCEL_END]
            p[INIT] = Piece(a_end.end_time, FLAT, 0.0, a_end.accel, a_end.vel, a_end.pos)
            for i in range(INIT + 1, ACCEL_END + 1):
                p[i] = p[i + 7]
            self._flat_copies(ACCEL_END + 1, CHANGE_END, ACCEL_END)
        elif p[CHANGE_END].end_time < t <= p[CONST].end_time:
            # cruising: everything before now collapses onto the present
            c_end = p[CHANGE_END]
            p[INIT] = Piece(c_end.end_time, FLAT, 0.0, 0.0, c_end.vel, c_end.pos)
            _j, _a, v_now, x_now = self.state_at(t)
            for i in range(INIT + 1, CHANGE_END + 1):
                p[i] = Piece(t, FLAT, 0.0, 0.0, v_now, x_now)
        if (t <= p[ACCEL_MAX].end_time and _pos(p[ACCEL_MAX].end_time - p[ACCEL_MAX - 1].end_time)
                and self.vel_max < p[ACCEL_END].vel and _pos(p[ACCEL_MAX].accel)):
            # still at full acceleration: stop accelerating as close to the new speed as
            # the time left at full acceleration allows
            v_start = p[INIT].vel
            v_least = p[ACCEL_END].vel - p[ACCEL_MAX].accel * (
                p[ACCEL_MAX].end_time - max(t, p[ACCEL_MAX - 1].end_time))
            target = max(v_least, self.vel_max)
            plan = plan_speed_change(self.snap, self.jerk, v_start, self.accel_max, target,
                                     end_pos / 2)
            self._truncate(INIT + 1)
            self._change(*plan)
            self._rest_at(ACCEL_END)
            self._flat_copies(ACCEL_END + 1, CONST, ACCEL_END)
            jm, tj, t2, t4, t6 = plan_speed_change(self.snap, self.jerk, 0.0, self.accel_max,
                                                   target, end_pos / 2)
            self._change(-jm, tj, t6, t4, t2)
            self.p[DECEL_END] = replace(self.p[DECEL_END], accel=0.0,
                                        vel=max(0.0, self.p[DECEL_END].vel))
            self._stretch_const(end_pos)
            p = self.p
        # the speed-change pieces, from the end of the acceleration towards the new speed
        room = p[CONST].pos - p[ACCEL_END].pos
        self._truncate(ACCEL_END + 1)
        self._flat_copies(ACCEL_END + 1, CHANGE_END, ACCEL_END)
        v_acc = self.p[ACCEL_END].vel
        if abs(self.vel_max - v_acc) >= _EPS:
            # ArduPilot estimates the time the change needs as twelve jerk times; its
            # jerk time is min(powf(x, 1/3), tj) with an integer 1/3, i.e. min(1 s, tj)
            jerk_time = min(1.0, self.jerk * math.pi / (2 * self.snap))
            plan = None
            if self.vel_max < v_acc and v_acc > 0 and jerk_time * 12 < room / v_acc:
                jm, tj, t2, t4, t6 = plan_speed_change(self.snap, self.jerk, self.vel_max,
                                                       self.accel_max, v_acc, room / 2)
                plan = (-jm, tj, t6, t4, t2)
            elif self.vel_max > v_acc and room / (jerk_time * 12) > v_acc:
                vm = min(self.vel_max, room / (jerk_time * 12))
                plan = plan_speed_change(self.snap, self.jerk, v_acc, self.accel_max, vm,
                                         room / 2)
            if plan is not None and not _zero(plan[0]) and min(plan[2:]) >= 0:
                self._truncate(ACCEL_END + 1)
                self._change(*plan)
                self._rest_at(CHANGE_END)
        # the deceleration
        v_end = min(end_vel, self.p[CHANGE_END].vel)
        self._truncate(CONST)
        self._push(FLAT, 0.0, 0.0)
        if v_end < self.p[CHANGE_END].vel:
            jm, tj, t2, t4, t6 = plan_speed_change(self.snap, self.jerk, v_end,
                                                   self.accel_max, self.p[CONST].vel,
                                                   end_pos - self.p[CONST].pos)
            self._change(-jm, tj, t6, t4, t2)
        else:
            self._flat_copies(CONST + 1, DECEL_END, CONST)
        self.p[DECEL_END] = replace(self.p[DECEL_END], accel=0.0,
                                    vel=max(0.0, self.p[DECEL_END].vel))
        self._stretch_const(end_pos)
        if not self.valid():
            self.init()

    # -- moving along
    def state_at(self, t: float) -> tuple[float, float, float, float]:
        """Jerk, acceleration, speed and distance along the track at time ``t``
        (SCurve::get_jerk_accel_vel_pos_at_time)."""
        if not self.planned:
            return 0.0, 0.0, 0.0, 0.0
        p = self.p
        # the piece t falls in: the first ending after it. The pieces' end times never
        # go down, so the search may start where the last one ended when t is not before
        # that piece's start (time moves on: most steps stay in the same piece)
        h = self._hint
        if h and t < p[h - 1].end_time:
            h = 0
        i = PIECES
        for k in range(h, PIECES):
            if t < p[k].end_time:
                i = k
                break
        self._hint = i
        if i == 0:
            q = p[0]
            j, a, v, x = _along(FLAT, 0.0, 0.0, t - q.end_time, q.accel, q.vel, q.pos)
        elif i == PIECES:
            q = p[-1]
            j, a, v, x = _along(FLAT, 0.0, 0.0, t - q.end_time, q.accel, q.vel, q.pos)
        else:
            q0, q = p[i - 1], p[i]
            j, a, v, x = _along(q.kind, q.jerk, q.end_time - q0.end_time, t - q0.end_time,
                                q0.accel, q0.vel, q0.pos)
        return j, a, v, max(0.0, x)

    def time_end(self) -> float:
        return self.p[DECEL_END].end_time if self.planned else 0.0

    def time_remaining(self) -> float:
        return self.p[DECEL_END].end_time - self.time if self.planned else 0.0

    def time_turn_in(self) -> float:
        return self.p[ACCEL_MAX].end_time if self.planned else 0.0

    def time_turn_out(self) -> float:
        return self.p[CONST].end_time if self.planned else 0.0

    def time_accel_end(self) -> float:
        """4.6's SCurve::time_accel_end: the end of the acceleration (SEG_ACCEL_END)."""
        return self.p[ACCEL_END].end_time if self.planned else 0.0

    def time_decel_start(self) -> float:
        """4.6's SCurve::time_decel_start: the start of the deceleration (SEG_DECEL_START,
        the same piece as 4.5's SEG_TURN_OUT)."""
        return self.p[CONST].end_time if self.planned else 0.0

    def braking(self) -> bool:
        return self.time >= self.p[CONST].end_time if self.planned else True

    def finished(self) -> bool:
        """SCurve::finished: the time is up or the distance travelled."""
        return self.time >= self.time_end() or self.position_sq >= self._track_sq

    def _advance(self, dt: float) -> tuple[float, float, float]:
        """Move the time on by ``dt``: distance, speed and acceleration along the track."""
        self.time = min(self.time + dt, self.time_end())
        _j, a, v, x = self.state_at(self.time)
        self.position_sq = x * x
        return x, v, a

    def advance_target_along_track(self, prev: SCurve, nxt: SCurve, wp_radius: float,
                                   accel_corner: float, fast: bool, dt: float,
                                   origin: np.ndarray, *, handover_46: bool = False,
                                   accel_z: float = 0.0):
        """SCurve::advance_target_along_track: the target moved on by ``dt`` as the sum of
        what remains of the previous leg, this leg and, once the turn has begun, the
        next. The next leg begins (at a fast waypoint) once this one is past its
        turn-out time less the next one's turn-in time and a quarter of the way, if the
        point half-way between now and the end of this leg is within ``wp_radius`` of
        the waypoint, below both legs' speeds and within ``accel_corner``. Returns
        ``(finished, position, velocity, acceleration)`` (three floats each, ENU):
        finished once this leg is done, or once the next leg has run as long as this
        one has left. (Each leg's vector is its unit vector times a distance, speed or
        acceleration along it, in plain floats: the same arithmetic, element by element,
        as on numpy's arrays.)

        ``handover_46``: ArduCopter 4.6's hand-over instead
        (:attr:`.navigation.Navigation.handover_46`): the next leg may begin once this one
        is past its deceleration's start and has no more time left than the next one's
        acceleration takes, and the turn's mid point must also move slower than both
        legs in 3D and accelerate vertically less than ``accel_z`` (WPNAV_ACCEL_Z, m/s/s;
        SCurve::calculate_track keeps it as ``accel_z_max``)."""
        x1, v1, a1 = prev._advance(dt)
        (ux, uy, uz), (kx, ky, kz) = prev._unit_xyz, prev._track_xyz
        ox, oy, oz = origin.tolist()
        px, py, pz = ox + ux * x1 - kx, oy + uy * x1 - ky, oz + uz * x1 - kz
        vx, vy, vz = ux * v1, uy * v1, uz * v1
        ax, ay, az = ux * a1, uy * a1, uz * a1
        x2, v2, a2 = self._advance(dt)
        ux, uy, uz = self._unit_xyz
        px, py, pz = px + ux * x2, py + uy * x2, pz + uz * x2
        vx, vy, vz = vx + ux * v2, vy + uy * v2, vz + uz * v2
        ax, ay, az = ax + ux * a2, ay + uy * a2, az + uz * a2
        done = self.finished()
        left = self.time_remaining()
        if handover_46:  # SCurve.cpp at Copter-4.6.3
            begin = (self.time >= self.time_decel_start()
                     and left <= nxt.time_accel_end())
        else:  # at Copter-4.5.6
            begin = (self.time >= self.time_turn_out() - nxt.time_turn_in()
                     and self.position_sq >= 0.25 * self._track_sq)
        if fast and _zero(nxt.time) and begin:
            _j, ta, tv, tx = self.state_at(self.time + left / 2)
            _j, na, nv, nx = nxt.state_at(left / 2)
            (kx, ky, kz), (wx, wy, wz) = self._track_xyz, nxt._unit_xyz
            tp = np.array([ux * tx - kx + wx * nx, uy * tx - ky + wy * nx,
                           uz * tx - kz + wz * nx])
            speed_min = min(self.vel_max, nxt.vel_max)
            if handover_46:
                turn = (math.sqrt((ux * tv + wx * nv) ** 2 + (uy * tv + wy * nv) ** 2
                                  + (uz * tv + wz * nv) ** 2) < speed_min
                        and abs(uz * ta + wz * na) < accel_z)
            else:
                turn = (self.time_remaining() < nxt.time_end() / 2
                        and math.hypot(ux * tv + wx * nv, uy * tv + wy * nv) < speed_min)
            if (turn and np.linalg.norm(tp) < wp_radius
                    and math.hypot(ux * ta + wx * na, uy * ta + wy * na) < accel_corner):
                x3, v3, a3 = nxt._advance(dt)
                px, py, pz = px + wx * x3, py + wy * x3, pz + wz * x3
                vx, vy, vz = vx + wx * v3, vy + wy * v3, vz + wz * v3
                ax, ay, az = ax + wx * a3, ay + wy * a3, az + wz * a3
        elif not _zero(nxt.time):
            x3, v3, a3 = nxt._advance(dt)
            wx, wy, wz = nxt._unit_xyz
            px, py, pz = px + wx * x3, py + wy * x3, pz + wz * x3
            vx, vy, vz = vx + wx * v3, vy + wy * v3, vz + wz * v3
            ax, ay, az = ax + wx * a3, ay + wy * a3, az + wz * a3
            if nxt.time >= self.time_remaining():
                done = True
        return done, (px, py, pz), (vx, vy, vz), (ax, ay, az)
