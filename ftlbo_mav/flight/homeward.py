"""The collective return: when a flight ends early, the vehicles ``fly`` still answers for
fly home on routes planned at that moment (:mod:`ftlbo_mav.planning.homeward`).

Flown as missions, not as GUIDED targets: each vehicle's route is uploaded and read back
(:func:`~ftlbo_mav.link.swarm.upload_and_verify`) while it holds in BRAKE, then started in
AUTO from where it hovers, as ``fly`` starts a plan's legs. ArduCopter flies a mission's
waypoints as the copter model predicts them (AC_WPNav's S-curves, the DO_CHANGE_SPEED
speed, NAV_WAYPOINT holds, NAV_LAND's descent: :mod:`ftlbo_mav.ardupilot.flight_path`,
held to SITL), so the clearance and separation the plan keeps on the predicted flown
paths are the ones flown; a GUIDED target has no such prediction (ModeGuided's position
controller shapes its own path to each target, and every target would be a command on
the link). The price: an upload of a few items per vehicle, a second or so.

:class:`GoingHome` plans at once (on the watch's thread, at most about a second) and
uploads and starts in the background (one thread per vehicle), so the watch goes on
looking at the vehicles meanwhile; :meth:`GoingHome.results` hands each vehicle's outcome
to the policy (:mod:`.policy`) as it comes.
"""

from __future__ import annotations

import math
import queue
from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace

import numpy as np

from .. import clock
from ..ardupilot.navigation import vehicle_navigation
from ..geo import segment_distance
from ..link.swarm import upload_and_verify
from ..link.transfer import Timing
from ..mission.items import CMD_DO_SET_CAM_TRIGG_DIST, build_return
from ..planning.homeward import KeepOut, ReturnPlan, World, plan_return
from ..planning.predicted import FlightModel
from .keeper import planned_speed
from .planned import PlannedFlight
from .vehicle import FlightError, FlightVehicle

ON_GROUND_M, AT_HOME_M = 0.5, 2.0
ROUTE_START_M = 0.5
"""How far from where its route home begins (where it stopped) a vehicle may be when the
route is started: its first leg keeps the clearance from there. Through a rough radio the
position a route was planned from can be a second old (an outage) and the copter not
stopped yet: on SITL one started 5 m off its route's first point, crossed a tree's fence
and ended 0.39 m inside the tree's radius."""
"""A vehicle below this height within this distance of its home is on the ground there."""
ESCAPE_MARGIN_M = 0.3
"""How far past the reach of a vehicle in doubt a vehicle inside it first flies, straight
out at its own height, before its way home (which then keeps clear of that reach)."""
KEEP_OUT_SPEED_M_S = 5.0
"""How fast a vehicle that left is taken to move, at the least (its last ground speed if
faster), for how far it can have gone since it was last heard of."""


def return_world(planned: PlannedFlight) -> World:
    """The plan's world for the routes home: its obstacles, the clearance with the
    navigation budget, its area and band, ``min_separation`` and the copters' model (the
    plan's ``[vehicle]`` and the missions' speed)."""
    nav = vehicle_navigation(planned.vehicle or {})
    if planned.area is not None:
        lower, upper = planned.area
    else:  # an old plan.json: the area the paths span
        xy = planned.paths[..., :2].reshape(-1, 2)
        lower, upper = xy.min(axis=0), xy.max(axis=0)
    alts = planned.paths[..., 2]
    band = planned.band if planned.band is not None else (float(alts.min()), float(alts.max()))
    return World(centres=planned.centres, radii=planned.radii,
                 clearance_m=planned.clearance_m + planned.navigation.horizontal_m,
                 area_lower=np.asarray(lower, float), area_upper=np.asarray(upper, float),
                 band=band, min_separation_m=planned.min_separation_m,
                 model=FlightModel(nav=nav, speed_m_s=planned_speed(planned.missions)),
                 pair_error_m=planned.navigation.pair_m)


def keep_out(planned: PlannedFlight, v: FlightVehicle, now: float, *, doubt_m: float = 0.0
             ) -> KeepOut | None:
    """Where vehicle ``v`` (one that left) may be: its last known position, grown by
    ``min_separation``, by how far it can have moved since (its last ground speed, at
    least :data:`KEEP_OUT_SPEED_M_S`, times the age of that position) and by ``doubt_m``
    (how far from its estimate it may truly be: a GPS jump); None when it was never
    placed."""
    s = v.status
    if s.lat_deg is None:
        return None
    here = np.asarray(planned.frame.to_enu(lat_deg=s.lat_deg, lon_deg=s.lon_deg,
                                           alt_m=s.alt_m), float)[:2]
    age = max(now - s.position_t, 0.0) * s.clock_rate  # its seconds (a simulator run fast)
    radius = (planned.min_separation_m + planned.navigation.pair_m
              + max(s.ground_speed_m_s, KEEP_OUT_SPEED_M_S) * age)
    if doubt_m <= 0:
        return KeepOut(here, radius, float(s.alt_m))
    # in doubt after its GPS jumped by J: held where its estimate is, it truly drifts by
    # up to -J as EKF3 takes the jump up (flight/navigation.py jump_vector): it is truly
    # somewhere from here to here - J, and within the rest of its doubt of that
    jump = np.asarray(s.gps_jump_enu, float) if doubt_m >= s.gps_jump_m else np.zeros(2)
    half = float(np.hypot(*jump)) / 2.0
    return KeepOut(here - jump / 2.0, radius + doubt_m - half, float(s.alt_m))


def escape(here: np.ndarray, reaches: Sequence[KeepOut], planned: PlannedFlight,
           others: Sequence[np.ndarray] = ()) -> np.ndarray | None:
    """Where a vehicle stopped at ``here`` ``(3,)`` inside the reach of a vehicle in doubt
    (``reaches``: their keep-outs) first flies: straight out of it at its own height, to
    the nearest point :data:`ESCAPE_MARGIN_M` past its edge (every 15 degrees around it)
    whose line from ``here`` keeps the plan's clearance from the obstacles and
    ``min_separation`` and the navigation budget from the ``others`` (the other vehicles,
    ``(2,)`` or ``(3,)`` each; from one already nearer, no nearer than it is). None when
    it is in no reach or no such line is found: its way home then begins where it is, as
    any other's. A vehicle in doubt drifts within its reach, at its own height and down
    through every layer as it lands: a way home that climbs or descends to its layer
    inside that reach could meet it there (the emulator, a 3 m GPS jump: 1.5 m)."""
    here = np.asarray(here, float)
    apart = planned.min_separation_m + planned.navigation.pair_m
    kept = planned.clearance_m + planned.navigation.horizontal_m
    near = np.array([np.asarray(o, float)[:2] for o in others]).reshape(-1, 2)
    # never closer to one than it is already, if that is nearer
    floor = np.minimum(apart, np.hypot(*(near - here[:2]).T) - 1e-6)

    def fits(q: np.ndarray) -> bool:
        if len(near) and np.any(segment_distance(near, here[:2], q) < floor):
            return False
        return not (len(planned.centres) and float((segment_distance(
            np.asarray(planned.centres)[:, :2], here[:2], q) - planned.radii).min()) < kept)

    q, reach = _just_out(here[:2], reaches, fits)
    return None if q is None else np.array([*q, _escape_height(here[2], reach, planned)])


def _just_out(point: np.ndarray, reaches: Sequence[KeepOut],
              fits: Callable[[np.ndarray], bool]) -> tuple[np.ndarray | None, KeepOut | None]:
    """``(q, reach)``: the nearest point to ``point`` ``(2,)`` just past the edge of the
    first ``reach`` it lies in (:func:`_ring`) that lies in none of the ``reaches`` and
    ``fits``; ``(None, reach)`` when none does, ``(None, None)`` when ``point`` lies in no
    reach."""
    reach = next((k for k in reaches if float(np.hypot(*(point - k.centre))) < k.radius_m),
                 None)
    if reach is None:
        return None, None
    for q in _ring(reach, point):
        if not any(float(np.hypot(*(q - r.centre))) < r.radius_m for r in reaches) and fits(q):
            return q, reach
    return None, reach


def _escape_height(alt: float, reach: KeepOut, planned: PlannedFlight) -> float:
    """The height a vehicle at ``alt`` leaves a reach at: one at or above the vehicle in
    doubt climbs to ``min_separation`` and the navigation budget above it (within the
    altitude band), so that wherever its drift takes it below, they stay apart (SITL, a
    3 m jump in the take-off: the one beside it, 0.5 m higher and leaving level, came
    within 1.8 m); one below it stays at its height (it is not flown towards it)."""
    if reach.alt_m is None or alt < reach.alt_m - 0.5:
        return float(alt)
    top = planned.band[1] if planned.band is not None else float(planned.paths[..., 2].max())
    above = reach.alt_m + planned.min_separation_m + planned.navigation.pair_m
    return float(max(alt, min(above, top)))


def _ring(reach: KeepOut, near: np.ndarray) -> np.ndarray:
    """Points :data:`ESCAPE_MARGIN_M` past the edge of ``reach``, every 15 degrees, the
    nearest to ``near`` first."""
    angles = np.radians(np.arange(0, 360, 15))
    ring = reach.centre + (reach.radius_m + ESCAPE_MARGIN_M) * np.column_stack(
        [np.cos(angles), np.sin(angles)])
    return ring[np.argsort(np.hypot(*(ring - near).T))]


def landing_out_of_reach(land: np.ndarray, reaches: Sequence[KeepOut],
                         planned: PlannedFlight, others: Sequence[np.ndarray]
                         ) -> np.ndarray | None:
    """Where a vehicle whose landing point ``land`` ``(2,)`` lies in the reach of a vehicle
    in doubt lands instead (None: it does not lie in one): the nearest point just out of
    that reach (:data:`ESCAPE_MARGIN_M` past its edge, every 15 degrees around it) that
    keeps the plan's clearance from the obstacles, lies in its area and keeps
    ``min_separation`` and the navigation budget from the ``others``' landing points. The
    one in doubt lands somewhere in its reach, drifting as it comes down (the emulator, a
    3 m jump at take-off: it drifted onto the home of the copter beside it). No such
    point: its own (the way home is then refused there)."""
    apart = planned.min_separation_m + planned.navigation.pair_m
    kept = planned.clearance_m + planned.navigation.horizontal_m

    def fits(q: np.ndarray) -> bool:
        if any(float(np.hypot(*(q - np.asarray(o, float)[:2]))) < apart for o in others):
            return False
        if len(planned.centres) and float((np.hypot(*(np.asarray(planned.centres)[:, :2]
                                                      - q).T) - planned.radii).min()) < kept:
            return False
        return planned.area is None or bool(np.all(q >= planned.area[0])
                                            and np.all(q <= planned.area[1]))

    return _just_out(np.asarray(land, float), reaches, fits)[0]


class GoingHome:
    """The collective return of one flight: :meth:`start` once, :meth:`results` every
    cycle after."""

    def __init__(self, planned: PlannedFlight, vehicles: Sequence[FlightVehicle], *,
                 timing: Timing | None = None,
                 say: Callable[[str], None] = lambda _t: None) -> None:
        self.planned, self.vehicles, self.say = planned, list(vehicles), say
        self.timing = timing or Timing()
        self.plan: ReturnPlan | None = None  # every route home planned so far
        self.stopped_at: dict[int, np.ndarray] = {}  # where a vehicle that escapes first is
        self.moved_landing: dict[int, float] = {}  # landing moved out of a reach: how far
        self.started_t: float | None = None  # when the first were planned
        self._done: queue.SimpleQueue = clock.SimpleQueue()

    def start(self, answered: Sequence[int], left: Sequence[int], now: float, *,
              doubt: Mapping[int, float] | None = None) -> dict[int, str]:
        """Plan the way home of the ``answered`` vehicles (stopped where they are), the
        ``left`` ones kept out (grown by their ``doubt``, metres: a position in doubt),
        and start flying it; returns the vehicles that have no
        way home and why (they are left to the policy's RTL-or-LAND). Called again for a
        vehicle answered later (its link back), its route keeps clear of those already
        flying home, on their clock."""
        planned = self.planned
        where = {k: q for k in range(len(self.vehicles)) if (q := self._where(k)) is not None}
        positions: dict[int, np.ndarray] = {}
        refused: dict[int, str] = {}
        for j in answered:
            if j not in where:
                refused[j] = "its position is unknown"
                continue
            here = where[j]
            home = np.asarray(planned.paths[j][0][:2], float)
            if here[2] < ON_GROUND_M and float(np.hypot(*(here[:2] - home))) < AT_HOME_M:
                # stopped in its take-off before it left the ground: ArduCopter refuses
                # AUTO there ("Auto: Missing Takeoff Cmd", ModeAuto::init), nothing to fly
                refused[j] = "still on the ground at its home"
                continue
            positions[j] = here
        doubt = doubt or {}
        kept = {j: k for j in left if (k := keep_out(planned, self.vehicles[j], now,
                                                     doubt_m=doubt.get(j, 0.0))) is not None}
        outs = tuple(kept.values())
        doubted = [k for j, k in kept.items() if j in doubt]
        for j, here in list(positions.items()):
            others = [q for k, q in where.items() if k != j and k not in doubt]
            out = escape(here, doubted, planned, others)
            if out is not None:
                self.stopped_at[j], positions[j] = here, out
        landings = {j: np.asarray(planned.paths[j][0][:2], float) for j in positions}
        for j, land in list(landings.items()):  # a landing in the reach of one in doubt
            others = [q for k, q in landings.items() if k != j]
            out = landing_out_of_reach(land, doubted, planned, others)
            if out is not None:
                landings[j] = out
                self.moved_landing[j] = float(np.hypot(*(out - land)))
        before = self.plan
        if before is None:
            self.started_t = now
        plan = plan_return(positions, landings, return_world(planned), keep_out=outs,
                           flying=tuple(before.routes.values()) if before else (),
                           elapsed_s=now - self.started_t,
                           roadmaps={j: planned.paths[j] for j in positions})
        if before is not None:  # a vehicle answered late: its route joins the others'
            plan = replace(plan, routes={**before.routes, **plan.routes},
                           refused={**before.refused, **plan.refused})
        self.plan = plan
        self.say(f"routes home planned in {plan.seconds:.2f} s for "
                 f"{len(plan.routes)} vehicle(s)" + (
                     f"; predicted separation {plan.separation_m:.1f} m"
                     if math.isfinite(plan.separation_m) else ""))
        refused.update(plan.refused)
        for j in positions:
            if j not in plan.routes:
                continue
            clock.Thread(target=self._fly_home, args=(j,), daemon=True,
                             name=f"{self.vehicles[j].name} home").start()
        return refused

    def _where(self, k: int) -> np.ndarray | None:
        """Vehicle k's last reported position (ENU), None when it has none."""
        s = self.vehicles[k].status
        if s.lat_deg is None:
            return None
        return np.asarray(self.planned.frame.to_enu(lat_deg=s.lat_deg, lon_deg=s.lon_deg,
                                                    alt_m=s.alt_m), float)

    def mission(self, j: int) -> list:
        """Vehicle j's mission home (:func:`~ftlbo_mav.mission.items.build_return`)."""
        route = self.plan.routes[j]
        frame = self.planned.frame
        lat, lon, alt = frame.to_lla(route.points)
        home = self.planned.missions[j][0]
        land_lat, land_lon, _ = frame.to_lla(route.land)
        return build_return(home=(home.lat_deg, home.lon_deg),
                            path=list(zip(lat.tolist(), lon.tolist(), alt.tolist())),
                            holds_s=[float(h) for h in route.holds_s],
                            land=(float(land_lat), float(land_lon)),
                            speed_m_s=planned_speed(self.planned.missions),
                            camera_off=any(it.command == CMD_DO_SET_CAM_TRIGG_DIST
                                           for it in self.planned.missions[j]))

    def _fly_home(self, j: int) -> None:
        v, route = self.vehicles[j], self.plan.routes[j]
        t0 = clock.monotonic()
        try:
            items = self.mission(j)
            v.set_mode("BRAKE")  # holds where it stopped while its mission is replaced
            with v.link.channel(v.sysid) as channel:
                ok, why = upload_and_verify(channel, items, timing=self.timing)
            if not ok:
                self._done.put((j, False, f"its route home was not uploaded ({why})"))
                return
            off = self._off_start(j)
            if off is not None:
                self._done.put((j, False, f"its route home was not started: {off}"))
                return
            v.set_current(1)
            v.set_mode("AUTO")
        except FlightError as exc:
            self._done.put((j, False, f"its route home could not be started ({exc})"))
            return
        wait = f", waiting {route.wait_s:.0f} s on it" if route.wait_s else ""
        if j in self.stopped_at:
            wait += ", first straight out of the reach of the one in doubt"
        if j in self.moved_landing:
            wait += (f", landing {self.moved_landing[j]:.1f} m from its home, out of the "
                     "reach of the one in doubt")
        self._done.put((j, True, (
            f"flying home on a planned route ({len(route.points) - 2} waypoint(s) at "
            f"{route.layer_m:.1f} m{wait}; predicted clearance {route.clearance_m:.2f} m, "
            f"{route.seconds:.0f} s to the ground; uploaded, verified and started in "
            f"{clock.monotonic() - t0:.1f} s)")))

    def _off_start(self, j: int) -> str | None:
        """Why vehicle j is not where its route home begins (a fresh report, within
        :data:`ROUTE_START_M`), or None when it is."""
        s = self.vehicles[j].status
        here = self._where(j)
        if here is None:
            return "its position is unknown"
        start = np.asarray(self.stopped_at.get(j, self.plan.routes[j].points[0]), float)
        off = float(np.linalg.norm(here[:2] - start[:2]))
        age = clock.monotonic() - s.position_t
        if age > 1.0:
            return f"its last position is {age:.1f} s old"
        if off > ROUTE_START_M:
            return (f"it is {off:.1f} m from where the route begins (it had not stopped "
                    f"where it was planned from; at most {ROUTE_START_M:g} m)")
        return None

    def results(self) -> list[tuple[int, bool, str]]:
        """The vehicles whose start home has ended since the last call: (vehicle, started,
        what happened)."""
        out = []
        while True:
            try:
                out.append(self._done.get_nowait())
            except queue.Empty:
                return out
