"""Fly a planned formation: the phases, each in its own module.

1. Pre-flight (:mod:`.preflight`): every vehicle holds exactly its planned mission and
   fence, has a 3D GPS fix and passes its pre-arm checks; nothing is armed otherwise.
   What the link showed of itself meanwhile is judged (:mod:`.linkfit`): what the
   formation cannot count on through it is said before take-off.
2. Take-off (:mod:`.launch`): GUIDED, arm, take off, all at once; wait until every vehicle
   hovers at its altitude and has stopped climbing.
3. Synchronized start (:mod:`.start`): every current item set to where the legs begin,
   then AUTO in one burst.
4. Watch (:mod:`.watch`) until every vehicle has landed or ended its mission, the
   formation keeper (:mod:`.keeper`) pausing leaders briefly on the legs, the departure
   watch (:mod:`.departures`) looking for a vehicle that leaves the plan.
5. Outcome (:mod:`.policy`, :mod:`.outcome`): when one leaves, the others are answered by
   the formation policy (stop, then rally and land; or land; or carry on) and the flight
   ends with :class:`FlightLeftPlan`; Ctrl-C and ``ftlbo-mav abort`` send the vehicles
   to RTL or LAND.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from .. import clock
from ..link.transfer import Timing
from .departures import WatchOptions
from .fleet import Fleet, concurrently
from .keeper import FormationKeeper, KeeperOptions, planned_speed
from .launch import align_at_start, take_off, takeoff_item
from .linkfit import link_findings, look, seen
from .outcome import FlightLeftPlan, abort, aborted
from .planned import PlannedFlight
from .policy import FaultPolicy
from .preflight import PreflightError, preflight
from .start import first_leg, restore_gates, start_together
from .vehicle import FlightAborted, FlightError, FlightVehicle
from .watch import FlightWatch, LeftPlan, finished, keep_formation, watch, watch_abort

__all__ = ["Fleet", "FlightLeftPlan", "FlyOptions", "PreflightError", "abort", "aborted",
           "cruise_speed", "finished", "first_leg", "fly", "keep_formation", "make_keeper",
           "preflight", "start_together", "take_off", "takeoff_item", "watch", "watch_abort"]


@dataclass(frozen=True)
class FlyOptions:
    """``policy``: what the others do when one vehicle leaves the plan (:mod:`.policy`);
    ``departure_budget_s``: how long after the first departure the flight watches the
    answer before it ends (every vehicle landed, or this spent); ``lost_wait_s``: how
    long a vehicle whose link is lost is waited for before it is reported gone (within
    the budget); ``watch``: what counts
    as a departure (:class:`~ftlbo_mav.flight.departures.WatchOptions`)."""

    ready_timeout_s: float = 60.0
    arm_budget_s: float = 60.0
    takeoff_timeout_s: float = 60.0
    takeoff_tolerance_m: float = 0.3
    settled_climb_m_s: float = 0.15
    # launch.settle: then each vehicle's climb within settle_climb_m_s for settle_hold_s,
    # waited for at most settle_budget_s (0, the default: AUTO starts as soon as all
    # hover; on SITL the wait cost 2.3 s in the air and the formation figure did not
    # measurably improve, docs/risk.md)
    settle_climb_m_s: float = 0.05
    settle_hold_s: float = 1.0
    settle_budget_s: float = 0.0
    start_tolerance_m: float = 0.2  # launch.align_at_start
    align_timeout_s: float = 20.0
    position_hz: float = 10.0
    flight_timeout_s: float = 900.0
    abort_mode: str = "RTL"
    keeper: KeeperOptions = KeeperOptions()
    policy: FaultPolicy = FaultPolicy.RALLY
    departure_budget_s: float = 50.0
    lost_wait_s: float = 15.0
    watch: WatchOptions = WatchOptions()
    any_firmware: bool = False  # fly a vehicle whose firmware the model does not follow
    any_params: bool = False  # fly copters whose own values lose a promise (flight/fit.py)


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
    values = concurrently(lambda v: v.read_param("WPNAV_SPEED"), list(vehicles))
    if any(v is None for v in values) or len({round(v) for v in values}) != 1:
        return None
    return values[0] / 100.0  # cm/s


def fly(planned: PlannedFlight, vehicles: Sequence[FlightVehicle], *, options: FlyOptions,
        timing: Timing, say: Callable[[str], None], tick: Callable[[], None],
        keeper: FormationKeeper | None = None,
        on_event: Callable[[str], None] = lambda _t: None) -> float:
    """The whole flight; returns the monotonic time of the synchronized start.

    ``on_event`` gets a line for each departure the watch sees (and each link back).

    ``keeper``: the formation keeper to run on the legs (default: one made from
    ``options.keeper``, none when that is disabled); pass one to read its log afterwards.

    :class:`FlightLeftPlan` when a vehicle left the plan (after the policy's answer).
    On Ctrl-C (KeyboardInterrupt) every vehicle but those that left by their own choice
    is sent to ``options.abort_mode`` before the interrupt propagates.
    """
    say("pre-flight: firmware, missions, GPS, pre-arm checks")
    own = preflight(planned, vehicles, timing=timing, ready_timeout_s=options.ready_timeout_s,
                    any_firmware=options.any_firmware, any_params=options.any_params, say=say)
    if keeper is None and options.keeper.enabled:
        keeper = make_keeper(planned, options.keeper)
    if keeper is not None and keeper.options.enabled and keeper.cruise_speed_m_s is None:
        keeper.cruise_speed_m_s = cruise_speed(planned, vehicles)
        if keeper.cruise_speed_m_s is None:
            keeper.off_reason = ("the vehicles' cruise speed is unknown (no DO_CHANGE_SPEED "
                                 "in the missions, WPNAV_SPEED unanswered or not the same "
                                 "on every vehicle)")
            say(f"formation keeper off: {keeper.off_reason}")
    since = look([v.status for v in vehicles])
    now = clock.monotonic()
    for line in link_findings([seen(v.name, v.status, now, since=since) for v in vehicles],
                              keeper=keeper.options if keeper is not None and keeper.active
                              else None, watch=options.watch, position_hz=options.position_hz):
        say(f"warning: {line}")
    if aborted(vehicles):
        raise FlightAborted(vehicles[0].name, vehicles[0].sysid, aborted(vehicles))
    # before the start a departure ends the flight for all: the others land where they
    # are, or rally (they have not left their start points yet)
    policy = options.policy
    fw = FlightWatch(planned, vehicles, say=say, on_event=on_event, options=options.watch,
                     budget_s=options.departure_budget_s, lost_wait_s=options.lost_wait_s,
                     policy=FaultPolicy.LAND if policy is FaultPolicy.CONTINUE else policy,
                     batteries=own)
    gates_written = False
    try:
        try:
            fw.expect("GUIDED")
            take_off(planned, vehicles, options, say, poll=fw.check)
            align_at_start(planned, vehicles, options, say, poll=fw.check)
            say("all hovering at their start points: starting the missions together")
            fw.expect("AUTO")
            gates_written = True
            started = start_together(planned, vehicles, say=say, poll=fw.check,
                                     timing=timing)
        except LeftPlan:
            raise fw.until_ended(tick=tick) from None
        except FlightError as exc:  # a vehicle refused or could not be reached
            if not aborted(vehicles):  # (a failed takeoff already sent all to LAND)
                fw.poll()
                if fw.response.active:
                    raise fw.until_ended(tick=tick) from exc
            raise
        fw.response.policy = policy
        if not watch(planned, vehicles, timeout_s=options.flight_timeout_s, tick=tick,
                     keeper=keeper if keeper is not None and keeper.active else None,
                     flight_watch=fw):
            late = abort(vehicles, mode=options.abort_mode)
            raise FlightError(vehicles[0].name, vehicles[0].sysid, "flight",
                              f"not finished after {options.flight_timeout_s:g} s; sent every "
                              f"vehicle to {options.abort_mode}" + (f" (unconfirmed: {late})"
                                                                   if late else ""))
        return started
    except FlightAborted as exc:
        say(f"aborted: every vehicle sent to {exc.mode}; watching until they have landed")
        watch_abort(vehicles, timeout_s=min(options.flight_timeout_s, 60.0), tick=tick)
        raise
    except KeyboardInterrupt:
        gates_written = False  # out at once; the next flight writes its own time
        ours = [v for i, v in enumerate(vehicles) if i not in fw.response.chose]
        late = abort(ours, mode=options.abort_mode)
        say(f"interrupted: every vehicle sent to {options.abort_mode}"
            + (f" (unconfirmed: {', '.join(late)})" if late else "")
            + (f"; left alone (their own choice): "
               f"{', '.join(v.name for v in vehicles if v not in ours)}"
               if len(ours) < len(vehicles) else ""))
        raise
    finally:
        if gates_written:
            _restore_gates(planned, vehicles, say)


def _restore_gates(planned: PlannedFlight, vehicles: Sequence[FlightVehicle],
                   say: Callable[[str], None]) -> None:
    """The start gates back to the plan's placeholder on every vehicle that has landed
    (disarmed: a mission changed under a copter flying AUTO restarts its leg,
    ModeAuto::run's mis_change_detector)."""
    left = [f"{v.name}: still armed" for v in vehicles if v.status.armed]
    left += restore_gates(planned, vehicles,
                          [i for i, v in enumerate(vehicles) if not v.status.armed])
    if left:
        say("start time left in the mission of " + "; ".join(left) + " (the next flight "
            "writes its own; flown by another ground station it holds up to a minute at "
            "its start)")
