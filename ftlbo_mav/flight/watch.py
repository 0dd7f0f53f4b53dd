"""Watching a flight: until every vehicle is done, the formation keeper on the legs, and
the departure watch (:mod:`.departures`) whose events the policy (:mod:`.policy`)
answers.

Kept whole: one loop and what it reads each cycle; the departures, the policy and the
keeper it drives are modules of their own.

:class:`FlightWatch` turns what the vehicles say into events once per cycle (``poll``)
and has the policy answer them; :func:`watch` is the loop after the synchronized start.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from .. import clock
from ..ardupilot.fence import rtl_target
from ..geo import segment_distance
from ..mission.items import CMD_NAV_LAND, CMD_NAV_LOITER_UNLIM, CMD_NAV_WAYPOINT
from ..planning.homeward import KeepOut
from .battery import BatteryWatch, OwnBatteries
from .departures import (
    DEFAULT_WATCH,
    DepartureWatch,
    Event,
    FormationBound,
    Seen,
    Together,
    WatchOptions,
)
from .homeward import GoingHome, keep_out
from .keeper import FormationKeeper
from .navigation import ekf_report, gps_report
from .outcome import FlightLeftPlan, aborted
from .planned import PlannedFlight
from .policy import FaultPolicy, Response
from .vehicle import FlightAborted, FlightError, FlightVehicle

LOITER_REACHED_M = 2.0  # ArduCopter's default waypoint radius (WPNAV_RADIUS)
MAX_REPORT_DELAY_S = 0.15  # a position report older than its arrival by more: a stale offset
FRESH_S = 0.3  # the formation is judged only while every position report is this fresh


class LeftPlan(Exception):  # noqa: N818 - a signal inside the flight, not an error
    """Raised by :meth:`FlightWatch.check` before the start when a vehicle left the plan."""


def landing_points(planned: PlannedFlight) -> list[np.ndarray | None]:
    """Where each mission lands (its last NAV_LAND with a position), ENU; None if not."""
    out: list[np.ndarray | None] = []
    for mission in planned.missions:
        land = [it for it in mission if it.command == CMD_NAV_LAND
                and not (it.lat_deg == 0 and it.lon_deg == 0)]
        out.append(None if not land else planned.frame.to_enu(
            lat_deg=land[-1].lat_deg, lon_deg=land[-1].lon_deg, alt_m=0.0))
    return out


def rally_points(planned: PlannedFlight, j: int) -> np.ndarray:
    """Vehicle j's rally points, (K, 2) ENU east/north."""
    fence = planned.fences[j] if j < len(planned.fences) else None
    if fence is None or not fence.rally:
        return np.zeros((0, 2))
    enu = planned.frame.to_enu(lat_deg=[r.lat_deg for r in fence.rally],
                               lon_deg=[r.lon_deg for r in fence.rally],
                               alt_m=[0.0] * len(fence.rally))
    return np.asarray(enu, float).reshape(-1, 3)[:, :2]


def rtl_line_problem(planned: PlannedFlight, j: int, position: np.ndarray,
                     others: Sequence[np.ndarray], *, separation_m: float = 2.0,
                     routes: Sequence[np.ndarray] = (),
                     reaches: Sequence[tuple[str, KeepOut]] = ()) -> str | None:
    """Why ArduCopter's RTL from ``position`` (ENU) would not be safe for vehicle j, or
    None: RTL climbs where it is and flies straight to its rally point or home
    (:func:`~ftlbo_mav.ardupilot.fence.rtl_target`); that line must keep the plan's
    clearance from every obstacle and ``separation_m`` from the other vehicles, where they
    are and along the ``routes`` home they fly (``(P, 3)`` each: RTL climbs through their
    layers; on SITL one sent to RTL for want of a route came 0.65 m from one on its
    route), and stay out of the ``reaches`` (``(name, keep-out)``) of those whose position
    is in doubt (each drifts within its own)."""
    home = np.asarray(planned.paths[j][0][:2], float)
    rally = rally_points(planned, j)
    k = rtl_target(position[:2], home, rally)
    target, name = (home, "home") if k is None else (rally[k], "its rally point")
    here = np.asarray(position[:2], float)
    if len(planned.centres):
        gap = segment_distance(np.asarray(planned.centres)[:, :2], here, target) - planned.radii
        worst = int(np.argmin(gap))
        if gap[worst] < planned.clearance_m:
            return (f"the straight line to {name} passes {gap[worst]:.1f} m from an obstacle "
                    f"(clearance {planned.clearance_m:g} m); landing where it stopped")
    if others:
        near = float(np.min(segment_distance(np.asarray(others)[:, :2], here, target)))
        if near < separation_m:
            return (f"the straight line to {name} passes {near:.1f} m from another vehicle; "
                    "landing where it stopped")
    for route in routes:
        near = float(np.min(segment_distance(_along(np.asarray(route, float)[:, :2]),
                                             here, target)))
        if near < separation_m:
            return (f"the straight line to {name} passes {near:.1f} m from another "
                    "vehicle's route home; landing where it stopped")
    for who, reach in reaches:
        if float(segment_distance(reach.centre[None], here, target)[0]) < reach.radius_m:
            return (f"the straight line to {name} crosses the reach of {who}, whose position "
                    "is in doubt; landing where it stopped")
    return None


def _along(points: np.ndarray, step_m: float = 0.25) -> np.ndarray:
    """Points every ``step_m`` along a polyline ``(P, 2)`` (its corners among them)."""
    out = [points[:1]]
    for a, b in zip(points[:-1], points[1:]):
        n = max(1, int(np.ceil(np.linalg.norm(b - a) / step_m)))
        out.append(a + (b - a) * (np.arange(1, n + 1) / n)[:, None])
    return np.vstack(out)


def last_leg_seq(mission) -> int:
    """The last item flown as a leg: before the final landing (or the final loiter)."""
    return mission[-1].seq - 1 if mission[-1].command != CMD_NAV_LOITER_UNLIM else mission[-1].seq


def battery_watch(planned: PlannedFlight | None, own: OwnBatteries | None = None
                  ) -> BatteryWatch | None:
    """The in-flight battery watch: of the plan's ``[battery]``, else of the copters' own
    batteries as read before the flight (``own``); None with neither."""
    if planned is None or (planned.battery is None and own is None):
        return None
    return BatteryWatch(planned.battery or own, planned.missions)


def observe(v: FlightVehicle, planned: PlannedFlight | None, *,
            memo: dict | None = None) -> Seen:
    """A snapshot of ``v`` for the departure watch (no position without a plan).
    ``memo``: a dict that keeps each vehicle's last GPS report (its GPS_RAW_INT comes at
    2 Hz, the watch looks at 20)."""
    s = v.status
    position = None
    if s.lat_deg is not None and planned is not None:
        position = planned.frame.to_enu(lat_deg=s.lat_deg, lon_deg=s.lon_deg, alt_m=s.alt_m)
    gps = None
    if planned is not None:
        fallback = s.velocity_enu[:2]
        known = memo.get(v) if memo is not None else None
        if known is not None and known[0] is s.gps_raw and known[1] == fallback:
            gps = known[2]
        else:
            gps = gps_report(s.gps_raw, planned.frame, fallback_velocity=fallback)
            if memo is not None:
                memo[v] = (s.gps_raw, fallback, gps)
    return Seen(mode=s.mode, armed=s.armed, alt_m=s.alt_m, heard_t=s.heard_t,
                link_up=v.link_up, asked_mode=v.asked_mode, asked_t=v.asked_t,
                texts=tuple(s.text_log), text_count=s.text_count, position=position,
                seq=s.seq, gps=gps, ekf=ekf_report(s.ekf_raw), gps_jump_m=s.gps_jump_m,
                battery_pct=s.battery_pct, battery_current_a=s.battery_current_a)


def watch_from_outside(departures: DepartureWatch, vehicles: Sequence[FlightVehicle],
                       planned: PlannedFlight | None) -> None:
    """What ``monitor`` expects, flying nothing itself: a vehicle seen in AUTO on its
    mission stays in AUTO until its last item (a mode after that is its own)."""
    for i, v in enumerate(vehicles):
        s = v.status
        last = planned.missions[i][-1].seq if planned is not None else None
        if s.armed and s.mode == "AUTO" and (last is None or 0 < s.seq < last):
            departures.expect(i, "AUTO")
        elif last is not None and s.seq >= last or not s.armed:
            departures.expect(i, None)


def formation_bound(planned: PlannedFlight) -> FormationBound | None:
    """The formation's watch from the plan's bound (None: a plan without one)."""
    if planned.formation_bound_m is None or planned.count < 2:
        return None
    return FormationBound(planned.offsets, planned.formation_bound_m,
                          planned.min_separation_m, names=planned.names)


def together_now(planned: PlannedFlight, vehicles: Sequence[FlightVehicle], *,
                 memo: dict | None = None) -> Together | None:
    """Every vehicle's position at one instant (:func:`positions_now`), or None while a
    report is older than :data:`FRESH_S` (a link's gap is no formation's fault) or
    missing."""
    st = [v.status for v in vehicles]
    if any(s.lat_deg is None for s in st):
        return None
    positions, arrived, _age, t = positions_now(planned, st, memo=memo)
    return Together(positions, t) if float(np.max(arrived)) <= FRESH_S else None


def describe(event: Event, vehicles: Sequence[FlightVehicle]) -> str:
    v = vehicles[event.index]
    return f"{v.name} (sysid {v.sysid}): {event.kind}: {event.detail}"


class FlightWatch:
    """The departure watch and the policy of one flight. ``say`` prints a line."""

    def __init__(self, planned: PlannedFlight, vehicles: Sequence[FlightVehicle], *,
                 policy: FaultPolicy = FaultPolicy.RALLY,
                 options: WatchOptions = DEFAULT_WATCH, budget_s: float = 50.0,
                 lost_wait_s: float = 15.0,
                 say: Callable[[str], None] = lambda _t: None,
                 on_event: Callable[[str], None] = lambda _t: None,
                 batteries: OwnBatteries | None = None) -> None:
        self.planned, self.vehicles, self.say = planned, list(vehicles), say
        self.on_event = on_event
        self.departures = DepartureWatch(len(vehicles), options=options,
                                         landing=landing_points(planned),
                                         navigation=planned.navigation,
                                         battery=battery_watch(planned, batteries),
                                         formation=formation_bound(planned))
        self.response = Response(policy, budget_s=budget_s,
                                 lost_wait_s=lost_wait_s,
                                 route_check=self.rtl_problem, landing=self.landing,
                                 homeward=GoingHome(planned, vehicles, say=say),
                                 doubt=self.doubt, clear_of=self.clear_of)
        self.keeper: FormationKeeper | None = None
        self.started = False
        self.memo: dict = {}  # positions_now's last answer (the keeper asks it again)
        self._gps_memo: dict = {}  # each vehicle's last GPS report (observe)

    def landing(self, j: int) -> bool:
        """Vehicle j flies its mission's final NAV_LAND."""
        mission, seq = self.planned.missions[j], self.vehicles[j].status.seq
        return 0 < seq < len(mission) and mission[seq].command == CMD_NAV_LAND and all(
            it.command != CMD_NAV_WAYPOINT for it in mission[seq + 1:])

    def doubt(self, j: int) -> float:
        """How far vehicle j may truly be from where it says it is, once its position is
        in doubt: the largest jump its GPS made, what its receiver says of its accuracy,
        at least the plan's navigation budget (m)."""
        s = self.vehicles[j].status
        gps = gps_report(s.gps_raw, self.planned.frame) if s.gps_raw is not None else None
        acc = gps.h_acc_m if gps is not None and gps.h_acc_m is not None else 0.0
        return max(s.gps_jump_m, acc, self.planned.navigation.horizontal_m)

    def clear_of(self, j: int) -> bool:
        """Every other vehicle is out of the reach of vehicle j, in doubt (its keep-out,
        :func:`~ftlbo_mav.flight.homeward.keep_out`): j may land, drifting within it."""
        reach = keep_out(self.planned, self.vehicles[j], clock.monotonic(),
                         doubt_m=self.response.doubtful.get(j, 0.0))
        if reach is None:
            return True
        for k, v in enumerate(self.vehicles):
            s = v.status
            if k == j or k in self.response.lost or s.lat_deg is None:
                continue
            here = self.planned.frame.to_enu(lat_deg=s.lat_deg, lon_deg=s.lon_deg,
                                             alt_m=s.alt_m)
            if float(np.hypot(*(np.asarray(here[:2], float) - reach.centre))) < reach.radius_m:
                return False
        return True

    def rtl_problem(self, j: int) -> str | None:
        """Why vehicle j's RTL from where it is now would not be safe, or None."""
        seen = [observe(v, self.planned) for v in self.vehicles]
        if seen[j].position is None:
            return "its position is unknown"
        others = [s.position for i, s in enumerate(seen) if i != j and s.position is not None]
        plan = self.response.homeward.plan if self.response.homeward is not None else None
        routes = [] if plan is None else [r.points for k, r in plan.routes.items() if k != j]
        now = clock.monotonic()
        reaches = [(self.vehicles[d].name, reach) for d, doubt in self.response.doubtful.items()
                   if d != j and (reach := keep_out(self.planned, self.vehicles[d], now,
                                                    doubt_m=doubt)) is not None]
        return rtl_line_problem(self.planned, j, seen[j].position, others, routes=routes,
                                reaches=reaches)

    def expect(self, mode: str | None) -> None:
        """The mode every vehicle still on the plan is in from now on."""
        for i in range(len(self.vehicles)):
            if i not in self.response.left and i not in self.response.answers:
                self.departures.expect(i, mode)

    def poll(self) -> list[Event]:
        """Look once: new events are said, the keeper stands down at the first
        departure, and the policy answers."""
        now = clock.monotonic()
        if self.started:
            self._legs()
        seen = [observe(v, self.planned, memo=self._gps_memo) for v in self.vehicles]
        together = None if not self.started or self.response.active else \
            together_now(self.planned, self.vehicles, memo=self.memo)
        events = self.departures.check(seen, now, together)
        for e in events:
            line = describe(e, self.vehicles)
            self.say(line)
            self.on_event(line)
        if any(e.departure for e in events):  # before the policy pauses the others
            self.stand_keeper_down(skip={e.index for e in events if e.vehicle_chose})
        self.response.react(events, self.vehicles, self.departures, now)
        if self.response.active:
            self.response.step(self.vehicles, self.departures, now)
        return events

    def check(self) -> None:
        """:meth:`poll`, then :class:`LeftPlan` if a vehicle has left (before the start)."""
        self.poll()
        if self.response.active:
            raise LeftPlan

    def _legs(self) -> None:
        for i, (v, mission) in enumerate(zip(self.vehicles, self.planned.missions)):
            if i in self.response.left or i in self.response.answers:
                continue
            s = v.status
            # (a landed copter's mission goes back to its first item: not on its legs)
            on = s.armed and s.mode == "AUTO" and 0 < s.seq <= last_leg_seq(mission)
            item = mission[s.seq] if 0 <= s.seq < len(mission) else None
            hold = float(item.param1) if item is not None and item.command == CMD_NAV_WAYPOINT \
                else 0.0
            self.departures.legs(i, on, hold_s=max(hold, 0.0))

    def stand_keeper_down(self, *, skip: set[int] = frozenset()) -> None:
        """No more pauses: every pause under way is continued, but on a vehicle that
        chose otherwise (``skip``, or earlier)."""
        if self.keeper is None:
            return
        keeper, self.keeper = self.keeper, None
        for i, pause in keeper.release().items():
            if i not in self.response.chose and i not in skip:
                _send_pause(self.vehicles[i], pause)

    def left_plan(self) -> FlightLeftPlan:
        return FlightLeftPlan(self.response.lines(self.vehicles))

    def until_ended(self, *, tick: Callable[[], None]) -> FlightLeftPlan:
        """After a departure: answer until every vehicle has landed or the budget is
        spent; returns the error to end the flight with."""
        while not self.response.ended(self.vehicles, clock.monotonic()):
            self.poll()
            tick()
            clock.sleep(0.05)
        return self.left_plan()


def finished(planned: PlannedFlight, vehicles: Sequence[FlightVehicle], *,
             skip: set[int] = frozenset()) -> bool:
    """Every vehicle (but those in ``skip``) landed (disarmed), left AUTO after its last
    item, or holds at the point of a final NAV_LOITER_UNLIM (within the waypoint radius)."""

    def done(v: FlightVehicle, mission) -> bool:
        s, last = v.status, mission[-1]
        if not s.armed:
            return True
        if s.seq < last.seq:
            return False
        if last.command != CMD_NAV_LOITER_UNLIM:
            return s.mode != "AUTO"
        here = planned.frame.to_enu(lat_deg=s.lat_deg, lon_deg=s.lon_deg, alt_m=s.alt_m)
        there = planned.frame.to_enu(lat_deg=last.lat_deg, lon_deg=last.lon_deg,
                                     alt_m=last.alt_m)
        return float(np.linalg.norm(here - there)) <= LOITER_REACHED_M

    return all(done(v, m) for i, (v, m) in enumerate(zip(vehicles, planned.missions))
               if i not in skip)


def positions_now(planned: PlannedFlight, st: Sequence, *, memo: dict | None = None
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Every vehicle's position (``(N, 3)`` ENU) brought to one instant from its last
    report (:class:`~.status.Status` each, every one with a position), how long ago each
    report arrived and how old it is (``(N,)`` seconds, ours), and that instant on the
    vehicles' clock. ``memo``: a dict that keeps the last answer, given again while the
    time and every report are the same (the watch and the keeper ask at one instant)."""
    if memo is not None:
        key = (clock.monotonic(), tuple(
            (s.lat_deg, s.lon_deg, s.alt_m, s.velocity_enu, s.position_t, s.position_boot_s,
             s.clock_offset_s, s.clock_rate) for s in st))
        if memo.get("key") == key:
            positions, arrived, age, vehicle_now = memo["value"]
            return positions.copy(), arrived.copy(), age.copy(), vehicle_now
        memo["value"] = positions_now(planned, st)
        memo["key"] = key
        positions, arrived, age, vehicle_now = memo["value"]
        return positions.copy(), arrived.copy(), age.copy(), vehicle_now
    enu = planned.frame.to_enu(lat_deg=[s.lat_deg for s in st],
                               lon_deg=[s.lon_deg for s in st],
                               alt_m=[s.alt_m for s in st]).tolist()
    # per vehicle in plain floats (a few vehicles, looked at 20 times a second: numpy's
    # per-call cost would be most of it)
    now = clock.monotonic()
    positions, arrived, age = [], [], []
    vehicle_now = -math.inf
    for s, (e, n, u) in zip(st, enu):
        a = now - s.position_t
        # reports arrive up to 1/rate apart: bring each to the same instant, or a vehicle
        # reported 0.1 s earlier looks 0.3 m behind at 3 m/s
        old = (now - (s.clock_offset_s + s.position_boot_s / s.clock_rate)
               if s.clock_offset_s is not None else a)
        # a report is no fresher than its arrival, and no older than its arrival plus a
        # link's delay: beyond that the clock offset (the least-delayed report's) has gone
        # stale, the vehicle's clock running slower than ours (SITL on a loaded machine: a
        # copter seen 1.6 m behind that was 0.4 m behind, and pauses for all three)
        old = min(max(old, a), a + MAX_REPORT_DELAY_S)
        # the velocity is per second of the vehicle's clock, the age on ours
        lead = min(max(old * s.clock_rate, 0.0), 0.5)
        ve, vn, vu = s.velocity_enu
        positions.append((e + ve * lead, n + vn * lead, u + vu * lead))
        arrived.append(a)
        age.append(old)
        # the keeper's periods run on the vehicles' clock (time_boot_ms, which an emulator
        # with a time scale runs faster than ours), carried on between reports (10 Hz) for
        # pauses timed to the hundredth; a vehicle whose reports stopped is as old as its
        # last report on our clock
        vehicle_now = max(vehicle_now, s.position_boot_s + min(a, 0.1) * s.clock_rate)
    return np.array(positions), np.array(arrived), np.array(age), vehicle_now


def keep_formation(planned: PlannedFlight, vehicles: Sequence[FlightVehicle],
                   keeper: FormationKeeper, *, memo: dict | None = None) -> bool:
    """One step of the formation keeper; False once the legs are over (every pause
    continued). ``memo``: :func:`positions_now`'s."""
    st = [v.status for v in vehicles]
    last_leg = [last_leg_seq(m) for m in planned.missions]
    if any(s.seq > last for s, last in zip(st, last_leg)) or any(
            s.mode != "AUTO" for s in st):
        for i, pause in keeper.release().items():
            _send_pause(vehicles[i], pause)
        return False
    if any(s.lat_deg is None for s in st):
        return True
    positions, arrived, age, vehicle_now = positions_now(planned, st, memo=memo)
    speeds = np.array([s.ground_speed_m_s for s in st])
    trace = getattr(keeper, "trace", None)
    if trace is not None:
        trace.append(("inputs", clock.monotonic(), vehicle_now, arrived.tolist(), age.tolist(),
                      [s.position_boot_s for s in st], positions.tolist()))
    jitters = [j for s in st if (j := s.jitter_s()) is not None]
    now = clock.monotonic()
    gap = max(s.longest_gap_s(now, keeper.options.gap_memory_s) for s in st)
    sent = keeper.update(positions, speeds, vehicle_now, ages_s=arrived,
                         jitter_s=max(jitters) if len(jitters) == len(st) else None,
                         gap_s=gap)
    if trace is not None and sent:
        trace.append(("sent", clock.monotonic(), vehicle_now, {int(i): p for i, p in sent.items()}))
    for i, pause in sent.items():
        _send_pause(vehicles[i], pause)
    return True


def _send_pause(v: FlightVehicle, pause: bool) -> None:
    try:
        v.send_pause(pause)
    except FlightError:
        pass  # a link down: the departure watch reports it within its timeout


def watch(planned: PlannedFlight, vehicles: Sequence[FlightVehicle], *, timeout_s: float,
          tick: Callable[[], None], keeper: FormationKeeper | None = None,
          flight_watch: FlightWatch | None = None) -> bool:
    """Until every vehicle is done; ``tick`` runs a few times a second, the formation
    keeper (if any) every 50 ms while the legs last (10 ms during a pause), the
    departure watch every cycle. False on timeout; :class:`FlightLeftPlan` once a
    vehicle left the plan and the policy's answer is over."""
    fw = flight_watch or FlightWatch(planned, vehicles)
    fw.keeper, fw.started = keeper, True
    fw.expect("AUTO")
    deadline = clock.monotonic() + timeout_s
    next_tick = 0.0
    while clock.monotonic() < deadline:
        if aborted(vehicles):
            raise FlightAborted(vehicles[0].name, vehicles[0].sysid, aborted(vehicles))
        fw.poll()
        response = fw.response
        if response.active and response.policy is not FaultPolicy.CONTINUE:
            raise fw.until_ended(tick=tick)
        if finished(planned, vehicles, skip=set(response.left)):
            if response.active:
                raise fw.left_plan()
            return True
        if fw.keeper is not None and not keep_formation(planned, vehicles, fw.keeper,
                                                        memo=fw.memo):
            fw.keeper = None
        if clock.monotonic() >= next_tick:
            tick()
            next_tick = clock.monotonic() + 0.1
        # a pause's continue is timed to the hundredth (an emulator's time scale makes a
        # 50 ms wait tenths of a second of the vehicles' time)
        clock.sleep(0.01 if fw.keeper is not None and fw.keeper.pausing else 0.05)
    return False


def watch_abort(vehicles: Sequence[FlightVehicle], *, timeout_s: float,
                tick: Callable[[], None]) -> bool:
    """After an abort: watch until every vehicle has landed (disarmed) or its link is
    down. False on timeout."""
    deadline = clock.monotonic() + timeout_s
    while clock.monotonic() < deadline:
        if not any(v.status.armed and v.link_up for v in vehicles):
            return True
        tick()
        clock.sleep(0.1)
    return False
