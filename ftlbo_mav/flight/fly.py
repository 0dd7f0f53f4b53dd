"""Fly a planned formation: pre-flight, synchronized takeoff and start, watch, abort.

The steps, each with a timeout and a clear error naming the vehicle:

1. Pre-flight: every vehicle holds exactly its planned mission (read back and compared
   as ``upload`` verifies), has a 3D GPS fix and passes its pre-arm checks. Any failure
   stops here, one line per vehicle, before anything is armed.
2. GUIDED, arm (retried while the autopilot still waits for its position estimate),
   take off to the mission's takeoff altitude, all vehicles at once.
3. Wait until every vehicle is within a tolerance of its altitude *and* has stopped
   climbing: a naive start (switch to AUTO as soon as all are near altitude) lets one
   copter still climbing start late and fly the legs behind the others.
4. Synchronized start: every vehicle's current item is set to where its legs begin,
   after the start point it already hovers at (:func:`first_leg`); then every
   vehicle is switched to AUTO in one burst of messages, and only afterwards are the
   switches confirmed, so that the formation leaves as one.
5. Watch until every vehicle has landed (disarmed) or ended its mission, the formation
   keeper (:mod:`.keeper`) pausing leaders briefly on the legs (on by default).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as R

from ..errors import FtlboError
from ..geo import LocalFrame
from ..link.codec import mission_differences
from ..link.endpoints import (
    LinkError,
    describe_missing,
    discover,
    is_ready,
    open_links,
    readiness_problems,
)
from ..link.geofence import fence_differences
from ..link.mission_protocol import download_mission
from ..link.transfer import Timing
from ..mission.items import (
    CMD_DO_CHANGE_SPEED,
    CMD_NAV_LOITER_UNLIM,
    CMD_NAV_TAKEOFF,
    CMD_NAV_WAYPOINT,
)
from .keeper import FormationKeeper, KeeperOptions, planned_speed
from .planned import PlannedFlight
from .vehicle import FlightAborted, FlightError, FlightVehicle

LOITER_REACHED_M = 2.0  # ArduCopter's default waypoint radius (WPNAV_RADIUS)


class PreflightError(FtlboError):
    """Pre-flight checks failed; ``problems`` holds one line per failing vehicle."""

    def __init__(self, problems: list[str]) -> None:
        self.problems = problems
        super().__init__("pre-flight failed, nothing armed:\n  " + "\n  ".join(problems))


@dataclass(frozen=True)
class FlyOptions:
    ready_timeout_s: float = 60.0
    arm_budget_s: float = 60.0
    takeoff_timeout_s: float = 60.0
    takeoff_tolerance_m: float = 0.3
    settled_climb_m_s: float = 0.15
    position_hz: float = 10.0
    flight_timeout_s: float = 900.0
    abort_mode: str = "RTL"
    keeper: KeeperOptions = KeeperOptions()


class Fleet:
    """The vehicles of a flight on their links: open, discover by HEARTBEAT, close.

    ``with Fleet(names, sysids, urls) as fleet:`` gives ``fleet.vehicles``, one
    :class:`FlightVehicle` per requested id, in order.
    """

    def __init__(self, names: Sequence[str], sysids: Sequence[int], urls: Sequence[str], *,
                 signing_key: bytes | None = None, discover_timeout_s: float = 5.0,
                 on_position: Callable | None = None, position_hz: float = 10.0) -> None:
        self.names, self.sysids, self.urls = list(names), list(sysids), list(urls)
        self.position_hz = position_hz
        self.signing_key, self.discover_timeout_s = signing_key, discover_timeout_s
        self.on_position = on_position
        self.links: list = []
        self.vehicles: list[FlightVehicle] = []

    def __enter__(self) -> Fleet:
        self.links = open_links(self.urls, signing_key=self.signing_key,
                                connect_timeout_s=self.discover_timeout_s)
        try:
            found, missing = discover(self.links, self.sysids, timeout_s=self.discover_timeout_s)
            if missing:
                raise LinkError("; ".join(describe_missing(s, self.links, self.discover_timeout_s)
                                          for s in missing))
            self.vehicles = [FlightVehicle(n, s, found[s], on_position=self.on_position,
                                           position_hz=self.position_hz)
                             for n, s in zip(self.names, self.sysids)]
        except BaseException:
            self.__exit__()
            raise
        return self

    def __exit__(self, *exc) -> None:
        for v in self.vehicles:
            v.close()
        for link in self.links:
            link.close()


def _concurrently(fn: Callable, args: Sequence) -> list:
    """``fn(arg)`` for every arg at once (one thread each); after all have finished,
    re-raises the first error."""
    with ThreadPoolExecutor(max_workers=max(1, len(args))) as pool:
        futures = [pool.submit(fn, a) for a in args]
        errors = [f.exception() for f in futures]
    for e in errors:
        if e is not None:
            raise e
    return [f.result() for f in futures]


def takeoff_item(items) -> tuple[int, float]:
    """``(seq, altitude)`` of the mission's NAV_TAKEOFF."""
    for it in items:
        if it.command == CMD_NAV_TAKEOFF:
            return it.seq, it.alt_m
    raise ValueError("the mission has no NAV_TAKEOFF")


def preflight(planned: PlannedFlight, vehicles: Sequence[FlightVehicle], *,
              timing: Timing, ready_timeout_s: float) -> None:
    """Raise :class:`PreflightError` unless every vehicle is ready to fly its mission."""

    def mission_problem(pair) -> str | None:
        vehicle, expected, fence = pair
        try:
            with vehicle.link.channel(vehicle.sysid) as channel:
                onboard = download_mission(channel, timing=timing)
                fence_diff = ([] if fence is None
                              else fence_differences(channel, fence, timing=timing))
        except FtlboError as exc:
            return f"cannot read its mission or fence back: {exc}"
        diff = mission_differences(expected, onboard)
        if diff:
            return (f"holds a different mission than {vehicle.name}.waypoints "
                    f"({diff[0]}); run `ftlbo-mav upload` first")
        if fence_diff:  # the fence, rally points and FENCE_* of uavN.fence/.rally, fence.parm
            return (f"holds a different fence than {vehicle.name}.fence "
                    f"({fence_diff[0]}); run `ftlbo-mav upload` first")
        return None

    fences = planned.fences or (None,) * len(planned.missions)
    missions = _concurrently(mission_problem, list(zip(vehicles, planned.missions, fences)))
    deadline = time.monotonic() + ready_timeout_s
    while time.monotonic() < deadline and not all(is_ready(v.link, v.sysid) for v in vehicles):
        time.sleep(0.1)
    problems = []
    for v, mission in zip(vehicles, missions):
        why = [mission] if mission else []
        if not is_ready(v.link, v.sysid):
            why += readiness_problems(v.link, v.sysid)
        if v.status.armed:
            why.append("already armed")
        if why:
            problems.append(f"{v.name} (sysid {v.sysid}): " + "; ".join(why))
    if problems:
        raise PreflightError(problems)


def take_off(planned: PlannedFlight, vehicles: Sequence[FlightVehicle], options: FlyOptions,
             say: Callable[[str], None]) -> None:
    """GUIDED, arm, take off, all at once; wait until all hover at their altitudes."""
    targets = [takeoff_item(m)[1] for m in planned.missions]

    def launch(pair) -> None:
        v, alt = pair
        # ArduCopter refuses GUIDED, then arming, until its EKF has a position estimate
        # (SITL: about 18 s after the pre-arm checks pass): both wait within the budget
        deadline = time.monotonic() + options.arm_budget_s
        v.set_mode("GUIDED", timeout_s=options.arm_budget_s)
        v.arm(budget_s=max(0.0, deadline - time.monotonic()))
        v.takeoff(alt)

    say("arming and taking off")
    try:
        _concurrently(launch, list(zip(vehicles, targets)))
    except FlightError:
        if not aborted(vehicles):
            abort(vehicles, mode="LAND")
        raise

    def hovering(alt: float):
        return lambda s: (abs(s.alt_m - alt) <= options.takeoff_tolerance_m
                          and abs(s.climb_m_s) <= options.settled_climb_m_s)

    deadline = time.monotonic() + options.takeoff_timeout_s
    while True:
        if aborted(vehicles):
            raise FlightAborted(vehicles[0].name, vehicles[0].sysid, aborted(vehicles))
        pending = [v for v, alt in zip(vehicles, targets) if not hovering(alt)(v.status)]
        if not pending:
            return
        if time.monotonic() >= deadline:
            abort(vehicles, mode="LAND")
            raise FlightError(pending[0].name, pending[0].sysid, "takeoff",
                              f"not hovering at its altitude after {options.takeoff_timeout_s:g}"
                              f" s (at {pending[0].status.alt_m:.1f} m); all vehicles landing")
        pending[0].wait_for(hovering(targets[vehicles.index(pending[0])]), 0.2)


def first_leg(mission, frame: LocalFrame, *, hold_m: float = 0.5) -> tuple[int, list]:
    """``(seq, speed items)``: where AUTO starts, and the DO_CHANGE_SPEED items it skips
    (to be sent as commands once AUTO runs).

    After the takeoff each vehicle already hovers at its start point, which is also the
    mission's first waypoint. Starting AUTO there makes ArduCopter fly a zero-length leg
    first, whose jerk-limited S-curve lasts about a second and differs from copter to
    copter with its residual altitude error (on SITL the higher copter began the real legs
    0.4 s late: 0.44 m RMS formation error; starting at the first real leg: 0.09 m). So AUTO
    starts after the start point: at the DO_CHANGE_SPEED that follows it (as ``plan``
    writes missions), which ArduCopter runs as the mission resumes, before the first leg
    (AP_Mission::set_current_cmd loads it with the next navigation command, and
    AP_Mission::resume starts both), else at the first real leg.

    A DO_CHANGE_SPEED *before* the start point (missions of other tools) is skipped with
    it and returned: a speed sent before AUTO is lost (ModeAuto::init clears
    desired_speed_override and AC_WPNav::wp_and_spline_init goes back to WPNAV_SPEED), so
    it must be sent after the switch.
    """
    seq, _alt = takeoff_item(mission)
    home = mission[0]
    takeoff = next(it for it in mission if it.seq == seq)
    speeds, passed_start = [], False
    for it in mission[seq + 1:]:
        if it.command == CMD_DO_CHANGE_SPEED:
            if passed_start:
                return it.seq, speeds
            speeds.append(it)
            continue
        at_start = (it.command == CMD_NAV_WAYPOINT and it.param1 == 0
                    and _ground_distance(frame, it, home) <= hold_m
                    and abs(it.alt_m - takeoff.alt_m) <= hold_m)
        if at_start and not passed_start and it.seq + 1 < len(mission):
            passed_start = True
            continue
        return it.seq, speeds
    return seq + 1, []


def _ground_distance(frame: LocalFrame, a, b) -> float:
    """Horizontal metres between two items' positions, in the plan's ENU frame."""
    enu = frame.to_enu(lat_deg=[a.lat_deg, b.lat_deg], lon_deg=[a.lon_deg, b.lon_deg])
    return float(np.hypot(*(enu[0, :2] - enu[1, :2])))


def start_together(planned: PlannedFlight, vehicles: Sequence[FlightVehicle]) -> float:
    """Set every current item to the first real leg (:func:`first_leg`), then AUTO in
    one burst. Returns the monotonic time of the burst."""
    starts = [first_leg(m, planned.frame) for m in planned.missions]

    _concurrently(lambda pair: pair[0].set_current(pair[1][0]), list(zip(vehicles, starts)))
    if aborted(vehicles):
        raise FlightAborted(vehicles[0].name, vehicles[0].sysid, aborted(vehicles))
    t = time.monotonic()
    for v in vehicles:
        v.send_mode("AUTO")
    _concurrently(lambda v: v.set_mode("AUTO"), vehicles)

    def cruise(pair) -> None:  # skipped speeds: only AUTO keeps them (first_leg)
        v, (_seq, speeds) = pair
        for it in speeds:
            v.command(R.MAV_CMD_DO_CHANGE_SPEED, it.param1, it.param2, it.param3,
                      step="cruise speed")

    _concurrently(cruise, list(zip(vehicles, starts)))
    return t


def finished(planned: PlannedFlight, vehicles: Sequence[FlightVehicle]) -> bool:
    """Every vehicle landed (disarmed), left AUTO after its last item, or holds at the
    point of a final NAV_LOITER_UNLIM (within the waypoint radius)."""

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

    return all(done(v, m) for v, m in zip(vehicles, planned.missions))


def abort(vehicles: Sequence[FlightVehicle], *, mode: str = "RTL",
          timeout_s: float = 3.0) -> list[str]:
    """Send every vehicle to ``mode`` at once (one burst), then confirm each; returns the
    names of those not confirmed. From then on the flight sends the vehicles nothing else
    (:class:`FlightAborted`)."""
    for v in vehicles:
        v.abort_to(mode)

    def confirm(v: FlightVehicle) -> str | None:
        try:
            v.set_mode(mode, timeout_s=timeout_s)
        except FlightError:
            return v.name
        return None

    return [name for name in _concurrently(confirm, list(vehicles)) if name]


def aborted(vehicles: Sequence[FlightVehicle]) -> str | None:
    """The mode of an abort already under way, if any."""
    return next((v.aborted_to for v in vehicles if v.aborted_to), None)


def make_keeper(planned: PlannedFlight, options: KeeperOptions) -> FormationKeeper:
    """A keeper for this plan; its cruise speed is learnt at pre-flight (cruise_speed)."""
    return FormationKeeper(planned.paths, planned_speed(planned.missions), options)


def cruise_speed(planned: PlannedFlight, vehicles: Sequence[FlightVehicle]) -> float | None:
    """The speed the vehicles' waypoint navigation is set to on the legs: the missions'
    DO_CHANGE_SPEED, else every vehicle's WPNAV_SPEED (read from it; None when a vehicle
    does not answer or they differ: how long a pause should last depends on it)."""
    speed = planned_speed(planned.missions)
    if speed is not None:
        return speed
    values = _concurrently(lambda v: v.read_param("WPNAV_SPEED"), list(vehicles))
    if any(v is None for v in values) or len({round(v) for v in values}) != 1:
        return None
    return values[0] / 100.0  # cm/s


def keep_formation(planned: PlannedFlight, vehicles: Sequence[FlightVehicle],
                   keeper: FormationKeeper) -> bool:
    """One step of the formation keeper; False once the legs are over (every pause
    continued)."""
    st = [v.status for v in vehicles]
    last_leg = [m[-1].seq - 1 if m[-1].command != CMD_NAV_LOITER_UNLIM else m[-1].seq
                for m in planned.missions]
    if any(s.seq > last for s, last in zip(st, last_leg)) or any(
            s.mode != "AUTO" for s in st):
        for i, pause in keeper.release().items():
            vehicles[i].send_pause(pause)
        return False
    if any(s.lat_deg is None for s in st):
        return True
    positions = planned.frame.to_enu(lat_deg=[s.lat_deg for s in st],
                                     lon_deg=[s.lon_deg for s in st],
                                     alt_m=[s.alt_m for s in st])
    # reports arrive up to 1/rate apart: bring each to the same instant, or a vehicle
    # reported 0.1 s earlier looks 0.3 m behind at 3 m/s
    now = time.monotonic()
    age = np.array([[now - (s.position_boot_s + s.clock_offset_s
                            if s.clock_offset_s is not None else s.position_t)] for s in st])
    positions = positions + np.array([s.velocity_enu for s in st]) * np.clip(age, 0, 0.5)
    speeds = np.array([s.ground_speed_m_s for s in st])
    # the keeper's periods run on the vehicles' clock (time_boot_ms, which an emulator
    # with a time scale runs faster than ours), carried on between reports (10 Hz) for
    # pauses timed to the hundredth; a vehicle whose reports stopped is as old as its
    # last report on our clock
    arrived = np.array([now - s.position_t for s in st])
    vehicle_now = max(s.position_boot_s + min(a, 0.1) for s, a in zip(st, arrived))
    for i, pause in keeper.update(positions, speeds, vehicle_now, ages_s=arrived).items():
        vehicles[i].send_pause(pause)
    return True


def watch(planned: PlannedFlight, vehicles: Sequence[FlightVehicle], *, timeout_s: float,
          tick: Callable[[], None], keeper: FormationKeeper | None = None) -> bool:
    """Until every vehicle is done; ``tick`` runs a few times a second, the formation
    keeper (if any) every 50 ms while the legs last (10 ms during a pause). False on
    timeout."""
    deadline = time.monotonic() + timeout_s
    next_tick = 0.0
    while time.monotonic() < deadline:
        if aborted(vehicles):
            raise FlightAborted(vehicles[0].name, vehicles[0].sysid, aborted(vehicles))
        if finished(planned, vehicles):
            return True
        if keeper is not None and not keep_formation(planned, vehicles, keeper):
            keeper = None
        if time.monotonic() >= next_tick:
            tick()
            next_tick = time.monotonic() + 0.1
        # a pause's continue is timed to the hundredth (an emulator's time scale makes a
        # 50 ms wait tenths of a second of the vehicles' time)
        time.sleep(0.01 if keeper is not None and keeper.pausing else 0.05)
    return False


def watch_abort(vehicles: Sequence[FlightVehicle], *, timeout_s: float,
                tick: Callable[[], None]) -> bool:
    """After an abort: watch until every vehicle has landed (disarmed). False on timeout."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if not any(v.status.armed for v in vehicles):
            return True
        tick()
        time.sleep(0.1)
    return False


def fly(planned: PlannedFlight, vehicles: Sequence[FlightVehicle], *, options: FlyOptions,
        timing: Timing, say: Callable[[str], None], tick: Callable[[], None],
        keeper: FormationKeeper | None = None) -> float:
    """The whole flight; returns the monotonic time of the synchronized start.

    ``keeper``: the formation keeper to run on the legs (default: one made from
    ``options.keeper``, none when that is disabled); pass one to read its log afterwards.

    On Ctrl-C (KeyboardInterrupt) every vehicle is sent to ``options.abort_mode`` before
    the interrupt propagates.
    """
    say("pre-flight: missions, GPS, pre-arm checks")
    preflight(planned, vehicles, timing=timing, ready_timeout_s=options.ready_timeout_s)
    if keeper is None and options.keeper.enabled:
        keeper = make_keeper(planned, options.keeper)
    if keeper is not None and keeper.options.enabled and keeper.cruise_speed_m_s is None:
        keeper.cruise_speed_m_s = cruise_speed(planned, vehicles)
        if keeper.cruise_speed_m_s is None:
            keeper.off_reason = ("the vehicles' cruise speed is unknown (no DO_CHANGE_SPEED "
                                 "in the missions, WPNAV_SPEED unanswered or not the same "
                                 "on every vehicle)")
            say(f"formation keeper off: {keeper.off_reason}")
    if aborted(vehicles):
        raise FlightAborted(vehicles[0].name, vehicles[0].sysid, aborted(vehicles))
    try:
        take_off(planned, vehicles, options, say)
        say("all hovering at their altitudes: starting the missions together")
        started = start_together(planned, vehicles)
        if not watch(planned, vehicles, timeout_s=options.flight_timeout_s, tick=tick,
                     keeper=keeper if keeper is not None and keeper.active else None):
            late = abort(vehicles, mode=options.abort_mode)
            raise FlightError(vehicles[0].name, vehicles[0].sysid, "flight",
                              f"not finished after {options.flight_timeout_s:g} s; sent every "
                              f"vehicle to {options.abort_mode}" + (f" (unconfirmed: {late})"
                                                                   if late else ""))
        return started
    except FlightAborted as exc:
        say(f"aborted: every vehicle sent to {exc.mode}; watching until they have landed")
        watch_abort(vehicles, timeout_s=options.flight_timeout_s, tick=tick)
        raise
    except KeyboardInterrupt:
        late = abort(vehicles, mode=options.abort_mode)
        say(f"interrupted: every vehicle sent to {options.abort_mode}"
            + (f" (unconfirmed: {', '.join(late)})" if late else ""))
        raise
