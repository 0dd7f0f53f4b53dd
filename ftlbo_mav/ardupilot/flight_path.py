"""The path ArduCopter 4.5.6 flies through a run of waypoints: predicted, not assumed.

A copter in AUTO does not fly the straight segments between its waypoints: AC_WPNav
plans every leg as an S-curve (:mod:`.scurve`) and, at a waypoint with no hold time
whose next navigation command is a waypoint, starts the next leg before this one ends,
so the corner is rounded (ModeAuto::do_nav_wp -> ModeAuto::set_next_wp ->
AC_WPNav::set_wp_destination_next; SCurve::advance_target_along_track decides when the
next leg begins). :func:`fly_path` runs the same model the emulator flies with
(:class:`.wpnav.WaypointNav`) through the mission's waypoints, as ModeAuto sequences
them (ArduCopter/mode_auto.cpp):

- the lead-in: the mission starts with the copter hovering at the first point (after
  its takeoff; ``fly`` starts AUTO there), so AC_WPNav::wp_and_spline_init starts from
  rest at that point, with the speed a DO_CHANGE_SPEED before the first leg set
  (ModeAuto::do_change_speed -> AC_WPNav::set_speed_xy), else WPNAV_SPEED;
- every waypoint without a hold time is flown through (set_next_wp), one with a hold
  (``param1`` seconds, ModeAuto::verify_nav_wp counts whole seconds) is stopped at;
- the last point is stopped at (the NAV_LAND / RTL after it is not a waypoint: set_next_wp
  adds no next destination), and the path ends when it is reached.

The step is the emulator's (:data:`STEP_S`). Positions are the copter's, following
AC_PosControl's target as :class:`.poscontrol.PositionFollower` has it: behind it by the
airframe's drag, outside it in turns, past it where it stops (0.4-0.9 m on SITL after
6-10 m/s), and AC_WPNav's track clock slows where the copter falls behind
(``tests/conformance`` holds this to recorded SITL tracks). Without an airframe
(``airframe=None``) the path is the target itself.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass

import numpy as np

from ..compiling import compile_later, ready
from .navigation import Navigation
from .poscontrol import DEFAULT_AIRFRAME, Airframe, PositionFollower
from .wpnav import WaypointNav

STEP_S = 0.02  # the emulator's step (sim.autopilot STEP_S); ArduCopter runs at 400 Hz
DEFAULT_NAV = Navigation()  # ArduCopter 4.5.6's defaults (copter.parm keeps them)
_MIN_PACE_M_S = 0.05  # for the step budget: no leg is flown slower on average
# after its goal (the mission's NAV_LAND holds it there, ModeAuto::land_start) the path
# goes on until the copter is at rest on the goal
SETTLED_M, SETTLED_M_S, SETTLE_BUDGET_S = 0.01, 0.02, 15.0
STEPWISE_UP_TO_S = 60.0
"""Flights expected to last up to this many seconds (length over speed, and the holds)
are flown stepwise, not compiled: numba's start-up in a new process whose cache holds the
compiled loop (about 0.3 s) is what the stepwise loop takes for some 200 s of flight.
Inside :func:`stepwise_budget` the seconds are counted over all the flights flown there."""
COLD_STEPWISE_UP_TO_S = 6000.0
"""Seconds of flight a process flies stepwise beyond :data:`STEPWISE_UP_TO_S` while the
compiled loop is not cached (the first run after an install or upgrade,
:func:`..compiling.ready`): compiling it takes some 11 s on 2 cores, what the stepwise loop
takes for 6,000-7,000 s of flight. The example's plan predicts some 2,000 s: it is planned
without a compile; a survey that predicts more compiles once, saying so on stderr."""

_STEPWISE_LEFT: ContextVar[float | None] = ContextVar("stepwise_left", default=None)
_compiled_loaded = False  # whether this process has flown a path compiled: its start-up paid
_cold_left = COLD_STEPWISE_UP_TO_S  # what this process may still fly stepwise, cache cold


@contextmanager
def stepwise_budget(seconds: float = STEPWISE_UP_TO_S) -> Iterator[None]:
    """Within: flights are flown stepwise while together they are expected to last at
    most ``seconds``, and compiled from the first that would go over (one plan, which
    predicts its flights again and again while it keeps the clearance, pays numba's
    start-up once the stepwise loop would cost more), or, while the compiled loop is not
    cached, once they also go over what is left of :data:`COLD_STEPWISE_UP_TO_S`. In a
    process that has already flown a path compiled every flight is compiled, inside or
    not; the two loops fly the same path (within 1e-6 m, ``tests/ardupilot/
    test_compiled.py``)."""
    token = _STEPWISE_LEFT.set(seconds)
    try:
        yield
    finally:
        _STEPWISE_LEFT.reset(token)


def _stepwise(expected_s: float) -> bool:
    """Whether a flight expected to last ``expected_s`` is flown stepwise (and counted):
    never once the process has loaded the compiled loop, whose start-up is then paid."""
    global _cold_left
    if _compiled_loaded:
        return False
    left = _STEPWISE_LEFT.get()
    if left is None:
        left = STEPWISE_UP_TO_S
    else:
        _STEPWISE_LEFT.set(left - expected_s if expected_s <= left else 0.0)
    if expected_s <= left:
        return True
    if expected_s > _cold_left:
        return False
    from . import compiled

    if ready(compiled.fly):
        return False
    compile_in_background()
    _cold_left -= expected_s
    return True


def compile_now() -> None:
    """Compile the flown-path model into numba's cache, as a plan's flights
    (:func:`.compiled.fly`) and the emulator (:class:`.compiled.CompiledFollower`) call
    it: what :func:`..compiling.compile_later` runs in the background while a first run
    after an install flies stepwise."""
    global _cold_left
    _cold_left = 0.0
    points = np.array([[0.0, 0.0, 5.0], [30.0, 0.0, 5.0], [30.0, 30.0, 6.0]])
    with stepwise_budget(0.0):
        fly_path(points)
        fly_path(points + [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])  # taken up
    from .compiled import CompiledFollower

    CompiledFollower(points[0]).step(0.0025, points[1], np.zeros(3), np.zeros(3))


def compile_in_background() -> bool:
    """:func:`compile_now` in the background (:func:`..compiling.compile_later`); whether
    it was started (not when the tests or the user say no)."""
    from . import compiled

    return compile_later(compiled.__name__, f"{__name__}:compile_now")


@dataclass(frozen=True, eq=False)
class FlownPath:
    """``times``: ``(T,)`` seconds since the first leg began; ``positions``: ``(T, 3)``
    metres ENU, the copter's (on to where it has come to rest on the goal); ``reached``:
    ``(P,)`` when each point was reached (0 for the first, where the copter starts; the
    last when AC_WPNav had it reached, before the copter came to rest)."""

    times: np.ndarray
    positions: np.ndarray
    reached: np.ndarray

    @property
    def seconds(self) -> float:
        return float(self.times[-1]) if len(self.times) else 0.0

    def leg_seconds(self) -> np.ndarray:
        """``(P-1,)`` seconds from each point to the next (a hold included in the leg
        after it)."""
        return np.diff(self.reached)

    def translated(self, by: np.ndarray) -> FlownPath:
        return FlownPath(self.times, self.positions + np.asarray(by, float), self.reached)


def _checked(points, holds_s) -> tuple[np.ndarray, np.ndarray]:
    points = np.asarray(points, float)
    if points.ndim != 2 or points.shape[1] != 3 or len(points) < 2:
        raise ValueError(f"points must be (P >= 2, 3), got {points.shape}")
    holds = np.zeros(len(points)) if holds_s is None else np.asarray(holds_s, float)
    return points, holds


def _budget(points: np.ndarray, holds: np.ndarray, nav: Navigation, desired_speed: float,
            dt: float) -> int:
    """Steps the mission may take before it counts as not flown."""
    pace = max(min(desired_speed, nav.wp_speed_up, nav.wp_speed_dn), _MIN_PACE_M_S)
    length = float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum())
    return max(int((length / pace + 10.0 * len(points) + holds.sum()) / dt), 0)


def fly_path(points: np.ndarray, *, nav: Navigation = DEFAULT_NAV,
             speed_m_s: float | None = None, holds_s: np.ndarray | None = None,
             dt: float = STEP_S, airframe: Airframe | None = DEFAULT_AIRFRAME) -> FlownPath:
    """Fly ``points`` ``(P, 3)`` metres ENU (the copter hovering at the first) as
    ArduCopter's AUTO does (see the module's docstring). ``speed_m_s``: the
    DO_CHANGE_SPEED before the first leg (None: WPNAV_SPEED); ``holds_s``: ``(P,)`` whole
    seconds held at each point (its waypoint's ``param1``; default none); ``airframe``:
    the drag the copter follows its target with (None: on its target).

    The model's arithmetic, compiled (:mod:`.compiled`): the same path as
    :func:`fly_path_stepwise` flies with the model's objects, 40 times faster; a short
    flight (up to :data:`STEPWISE_UP_TO_S`, or within what is left of a
    :func:`stepwise_budget`; more while the compiled loop is not cached,
    :data:`COLD_STEPWISE_UP_TO_S`) is flown stepwise, since numba's start-up costs more
    than that; once a process has flown one path compiled, every later one is (the two loops
    fly the same path within 1e-6 m, so the choice never changes a plan beyond that)."""
    points, holds = _checked(points, holds_s)
    desired = WaypointNav(nav, points[0].copy(), speed_m_s).desired_speed
    budget = _budget(points, holds, nav, desired, dt)
    length = float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum())
    if _stepwise(length / desired + float(holds.sum())):
        return fly_path_stepwise(points, nav=nav, speed_m_s=speed_m_s, holds_s=holds, dt=dt,
                                 airframe=airframe)
    from . import compiled

    global _compiled_loaded
    prm = compiled.nav_params(nav, airframe, desired)
    model = (prm.tobytes(), dt, airframe is not None)
    flown = _FLOWN.get(model, points, holds)
    if isinstance(flown, FlownPath):  # flown compiled before in this process
        _compiled_loaded = True
        return flown
    legs = compiled.legs_of(points, nav, desired, first=flown.k - 1 if flown else 1,
                            known=_FLOWN.legs(model, nav, desired))
    resume = (flown.resume() if flown else
              (np.zeros(compiled.SNAP_INTS, np.int64), np.zeros(compiled.SNAP_FLOATS),
               np.zeros(0), np.zeros((0, 3)), np.zeros(0)))
    status, n, times, positions, reached, snap_i, snap_f = compiled.fly(
        points, holds, *legs, prm, dt, budget, airframe is not None, SETTLED_M, SETTLED_M_S,
        int(SETTLE_BUDGET_S / dt), *resume)
    _compiled_loaded = True
    if status != compiled.OK:
        raise RuntimeError(f"the path of {len(points)} points was not flown within "
                           f"{budget * dt:.0f} s")
    path = FlownPath(times[:n].copy(), positions[:n].copy(), reached)
    _FLOWN.add(model, points, holds, path, snap_i, snap_f)
    return path


@dataclass(frozen=True, eq=False)
class _Resume:
    """Where a flight flown before can be taken up: waypoint ``k``'s snapshot."""

    k: int
    path: FlownPath
    snap_i: np.ndarray
    snap_f: np.ndarray

    def resume(self) -> tuple:
        return (self.snap_i[self.k], self.snap_f[self.k], self.path.times,
                self.path.positions, self.path.reached)


class _Flown:
    """The flights flown compiled lately, and the legs planned for them: a plan predicts
    one mission again and again while it moves a corner here and there
    (:func:`..planning.predicted.keep_clearance`), and none of what comes before the
    first point moved changes. A mission that shares its first points with one flown here
    is taken up at the last waypoint they share (:func:`.compiled.fly`'s snapshots: the
    state there depends on the points up to it and the holds before it only), and every
    leg whose two ends were planned before is not planned again; the numbers are the
    ones the whole flight gives (``tests/ardupilot/test_compiled.py``)."""

    FLIGHTS = 8  # flights kept, the newest first
    SAMPLES = 2_000_000  # and at most this many positions in all (64 MB)
    LEGS = 20_000  # legs kept per model, then forgotten all at once

    def __init__(self) -> None:
        self._flights: list[tuple] = []
        self._legs: dict[tuple, dict] = {}

    def legs(self, model: tuple, nav: Navigation, desired: float) -> dict:
        key = (model[0], nav.scurve_jerk_snap(), nav.wp_speed_up, nav.wp_speed_dn,
               nav.wp_accel, nav.wp_accel_z, desired)
        known = self._legs.setdefault(key, {})
        if len(known) > self.LEGS:
            known.clear()
        return known

    def get(self, model: tuple, points: np.ndarray, holds: np.ndarray
            ) -> FlownPath | _Resume | None:
        """The flight of ``points`` itself when it was flown, else where the flight that
        shares most of its start can be taken up (None: nowhere past its first leg)."""
        best: _Resume | None = None
        P = len(points)
        for key, old_points, old_holds, path, snap_i, snap_f in self._flights:
            if key != model:
                continue
            m = min(len(old_points), P)
            same = np.all(old_points[:m] == points[:m], axis=1)
            shared = int(np.argmin(same)) if not same.all() else m
            held = old_holds[:m] == holds[:m]
            same_holds = int(np.argmin(held)) if not held.all() else m
            if shared == P == len(old_points) and same_holds == P:
                return FlownPath(path.times.copy(), path.positions.copy(),
                                 path.reached.copy())
            # the state at waypoint k depends on points[:k + 1] and holds[:k]
            k = min(shared - 1, same_holds, m - 1)
            if k >= 2 and snap_i[k, 3] == k and (best is None or k > best.k):
                best = _Resume(k, path, snap_i, snap_f)
        return best

    def add(self, model, points, holds, path, snap_i, snap_f) -> None:
        kept = FlownPath(path.times.copy(), path.positions.copy(), path.reached.copy())
        self._flights.insert(0, (model, points.copy(), holds.copy(), kept, snap_i, snap_f))
        del self._flights[self.FLIGHTS:]
        while (len(self._flights) > 1
               and sum(len(f[3].times) for f in self._flights) > self.SAMPLES):
            self._flights.pop()


_FLOWN = _Flown()


def fly_path_stepwise(points: np.ndarray, *, nav: Navigation = DEFAULT_NAV,
                      speed_m_s: float | None = None, holds_s: np.ndarray | None = None,
                      dt: float = STEP_S, airframe: Airframe | None = DEFAULT_AIRFRAME
                      ) -> FlownPath:
    """:func:`fly_path` flown a step at a time with the model's own objects (AC_WPNav's
    :class:`.wpnav.WaypointNav`, AC_PosControl's :class:`.poscontrol.PositionFollower`),
    as the emulator flies them: the reference the compiled loop is held to."""
    points, holds = _checked(points, holds_s)
    wp = WaypointNav(nav, points[0].copy(), speed_m_s)
    budget = _budget(points, holds, nav, wp.desired_speed, dt)

    def start(k: int) -> None:  # ModeAuto::do_nav_wp / set_next_wp
        wp.set_destination(points[k])
        if holds[k] <= 0 and k + 1 < len(points):
            wp.set_destination_next(points[k + 1])

    times, positions = [0.0], [points[0].copy()]
    reached = np.zeros(len(points))
    k, t, wait_until = 1, 0.0, None
    follower = (None if airframe is None
                else PositionFollower(points[0], nav=nav, airframe=airframe))
    here, velocity = points[0].copy(), np.zeros(3)
    start(k)
    for _ in range(budget):
        t += dt
        if follower is None:
            wp.advance(dt, wp.target)
            here = wp.target.copy()
        else:
            wp.advance(dt, here, velocity)
            here = np.array([*follower.step(dt, wp.target, wp.target_vel, wp.target_accel),
                             wp.target[2]])
            velocity = np.array([follower.vx, follower.vy, wp.target_vel[2]])
        times.append(t)
        positions.append(here)
        if not wp.reached:
            continue
        if holds[k] > 0 and wait_until is None:  # ModeAuto::verify_nav_wp: the hold
            reached[k] = t
            wait_until = t + holds[k]
        if wait_until is not None and t < wait_until - 1e-9:
            continue
        if wait_until is None:
            reached[k] = t
        wait_until = None
        k += 1
        if k == len(points):
            break
        start(k)
    else:
        raise RuntimeError(f"the path of {len(points)} points was not flown within "
                           f"{budget * dt:.0f} s")
    if follower is not None:  # the copter comes to rest on its goal (past it, and back)
        for _ in range(int(SETTLE_BUDGET_S / dt)):
            if (float(np.hypot(*(here[:2] - points[-1, :2]))) < SETTLED_M
                    and float(np.hypot(follower.vx, follower.vy)) < SETTLED_M_S):
                break
            t += dt
            here = np.array([*follower.step(dt, points[-1], np.zeros(3), np.zeros(3)),
                             points[-1, 2]])
            times.append(t)
            positions.append(here)
    return FlownPath(np.array(times), np.array(positions), reached)


def fly_groups(paths: np.ndarray, *, nav: Navigation = DEFAULT_NAV,
               speed_m_s: float | None = None, holds_s: np.ndarray | None = None,
               dt: float = STEP_S, airframe: Airframe | None = DEFAULT_AIRFRAME,
               navs: Sequence[Navigation] | None = None
               ) -> tuple[list[FlownPath], np.ndarray, np.ndarray]:
    """Every row of ``paths`` ``(N, P, 3)`` flown, as ``(shapes, group, shift)``: the model
    is the same wherever a path lies (AC_WPNav works on offsets from its origin), so paths
    that are translations of one another (a formation's, each UAV at a fixed offset) are
    flown once, from the origin: path ``n`` is ``shapes[group[n]]`` moved by ``shift[n]``
    ``(N, 3)`` (its first point). ``navs``: one copter's parameters per path (a fleet of
    different copters; default ``nav`` for all): paths flown with other parameters are
    flown apart."""
    paths = np.asarray(paths, float)
    if navs is not None and len(navs) != len(paths):
        raise ValueError(f"navs: {len(navs)} for {len(paths)} paths")
    keys: dict[tuple, int] = {}
    shapes: list[FlownPath] = []
    group = np.empty(len(paths), int)
    for n, path in enumerate(paths):
        own = nav if navs is None else navs[n]
        shape = np.round(path - path[0], 6)
        key = (shape.tobytes(), own)
        if key not in keys:
            keys[key] = len(shapes)
            shapes.append(fly_path(shape, nav=own, speed_m_s=speed_m_s, holds_s=holds_s,
                                   dt=dt, airframe=airframe))
        group[n] = keys[key]
    return shapes, group, paths[:, 0].copy()


def fly_paths(paths: np.ndarray, *, nav: Navigation = DEFAULT_NAV,
              speed_m_s: float | None = None, holds_s: np.ndarray | None = None,
              dt: float = STEP_S, airframe: Airframe | None = DEFAULT_AIRFRAME,
              navs: Sequence[Navigation] | None = None) -> list[FlownPath]:
    """:func:`fly_path` for every row of ``paths`` ``(N, P, 3)`` (translations of one
    another flown once: :func:`fly_groups`; ``navs``: one copter's parameters per path)."""
    shapes, group, shift = fly_groups(paths, nav=nav, speed_m_s=speed_m_s, holds_s=holds_s,
                                      dt=dt, airframe=airframe, navs=navs)
    return [shapes[g].translated(s) for g, s in zip(group, shift)]
