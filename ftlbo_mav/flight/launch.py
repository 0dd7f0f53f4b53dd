"""Take-off, and the move to the start points before the synchronized start.

GUIDED, arm (retried while the autopilot still waits for its position estimate), take
off to the mission's takeoff altitude, all vehicles at once; wait until every vehicle is
within a tolerance of its altitude *and* has stopped climbing (a naive start, switching
to AUTO as soon as all are near altitude, lets one copter still climbing start late and
fly the legs behind the others), and its climb has settled (:func:`settle`, bounded);
then each moves to its start point where its own
estimate puts it off (:func:`align_at_start`). The start itself is :mod:`.start`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import NamedTuple

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as R

from .. import clock
from ..geo import LocalFrame
from ..mission.items import (
    CMD_DO_SET_CAM_TRIGG_DIST,
    CMD_NAV_TAKEOFF,
)
from .fleet import concurrently
from .outcome import abort, aborted
from .planned import PlannedFlight
from .vehicle import FlightAborted, FlightError, FlightVehicle


def takeoff_item(items) -> tuple[int, float]:
    """``(seq, altitude)`` of the mission's NAV_TAKEOFF."""
    for it in items:
        if it.command == CMD_NAV_TAKEOFF:
            return it.seq, it.alt_m
    raise ValueError("the mission has no NAV_TAKEOFF")


def take_off(planned: PlannedFlight, vehicles: Sequence[FlightVehicle], options,
             say: Callable[[str], None], poll: Callable[[], None] = lambda: None) -> None:
    """GUIDED, arm, take off, all at once; wait until all hover at their altitudes.

    ``options``: the flight's :class:`~ftlbo_mav.flight.fly.FlyOptions`; ``poll`` runs
    while the vehicles climb (the departure watch: it raises when one leaves the plan).
    """
    targets = [takeoff_item(m)[1] for m in planned.missions]
    cameras = [any(it.command == CMD_DO_SET_CAM_TRIGG_DIST for it in m) for m in planned.missions]

    def launch(pair) -> None:
        v, alt = pair
        if cameras[vehicles.index(v)]:
            camera_off(v, say)
        # ArduCopter refuses GUIDED, then arming, until its EKF has a position estimate
        # (SITL: about 18 s after the pre-arm checks pass): both wait within the budget
        deadline = clock.monotonic() + options.arm_budget_s
        v.set_mode("GUIDED", timeout_s=options.arm_budget_s)
        v.arm(budget_s=max(0.0, deadline - clock.monotonic()))
        v.takeoff(alt)

    say("arming and taking off")
    try:
        concurrently(launch, list(zip(vehicles, targets)))
    except FlightError:
        if not aborted(vehicles):
            abort(vehicles, mode="LAND")
        raise

    def hovering(alt: float):
        return lambda s: (abs(s.alt_m - alt) <= options.takeoff_tolerance_m
                          and abs(s.climb_m_s) <= options.settled_climb_m_s)

    deadline = clock.monotonic() + options.takeoff_timeout_s
    while True:
        if aborted(vehicles):
            raise FlightAborted(vehicles[0].name, vehicles[0].sysid, aborted(vehicles))
        pending = [v for v, alt in zip(vehicles, targets) if not hovering(alt)(v.status)]
        if not pending:
            settle(vehicles, options, say, poll)
            return
        if clock.monotonic() >= deadline:
            abort(vehicles, mode="LAND")
            raise FlightError(pending[0].name, pending[0].sysid, "takeoff",
                              f"not hovering at its altitude after {options.takeoff_timeout_s:g}"
                              f" s (at {pending[0].status.alt_m:.1f} m); all vehicles landing")
        poll()
        pending[0].wait_for(hovering(targets[vehicles.index(pending[0])]), 0.1)


def settle(vehicles: Sequence[FlightVehicle], options, say: Callable[[str], None],
           poll: Callable[[], None] = lambda: None) -> None:
    """Hovering, wait until every vehicle's climb rate has stayed within
    ``options.settle_climb_m_s`` for ``options.settle_hold_s``, at most
    ``options.settle_budget_s`` (then start anyway, said).

    A copter that has just reached its takeoff altitude is not still: it overshoots it
    and comes back over seconds (ArduCopter 4.5.6 SITL, 6 m: 6.05 m, then 5.97 m, still
    moving 0.04-0.08 m/s three seconds after its target stopped). AUTO starts its first leg
    from the stopping point (AC_WPNav::wp_and_spline_init, AC_PosControl::
    get_stopping_point_z_cm: the altitude plus the climb rate over PSC_POSZ_P, 1/s), so a
    copter still climbing 0.1 m/s flies its first leg 0.1 m above the plan and the others.
    The wait costs its seconds in the air (the flight's time and battery)."""
    budget, hold, limit = options.settle_budget_s, options.settle_hold_s, options.settle_climb_m_s
    if budget <= 0:
        return
    start = clock.monotonic()
    quiet_since: list[float | None] = [None] * len(vehicles)

    def pending() -> list[int]:
        now = clock.monotonic()
        for i, v in enumerate(vehicles):
            if abs(v.status.climb_m_s) > limit:
                quiet_since[i] = None
            elif quiet_since[i] is None:
                quiet_since[i] = now
        return [i for i, since in enumerate(quiet_since) if since is None or now - since < hold]

    late = wait_while(vehicles, pending, start + budget, poll, step_s=0.1)
    if late:
        say("still settling after {:g} s, starting anyway: {}".format(budget, ", ".join(
            f"{vehicles[i].name} climbing {vehicles[i].status.climb_m_s:+.2f} m/s"
            for i in late)))


def camera_off(v: FlightVehicle, say: Callable[[str], None]) -> None:
    """Distance triggering off (MAV_CMD_DO_SET_CAM_TRIGG_DIST 0) before a survey copter
    takes off: ArduCopter keeps a trigger distance until it is changed, armed or not
    (AP_Camera_Backend::update has no arming check), so a copter whose last flight ended
    in a lane (its pilot's RTL, a failsafe) would take photos from its take-off on to its
    first lane. Its missions turn the trigger on at each lane. A refusal is said, not
    fatal: a copter without a camera has no photos to take."""
    try:
        result = v.command(R.MAV_CMD_DO_SET_CAM_TRIGG_DIST, 0.0, 0.0, 0.0, step="camera off")
    except FlightError as exc:
        result = str(exc)
    if result != R.MAV_RESULT_ACCEPTED:
        say(f"{v.name} (sysid {v.sysid}): its camera's distance trigger could not be turned "
            f"off before take-off ({result}): it may take photos before its first lane")


def align_at_start(planned: PlannedFlight, vehicles: Sequence[FlightVehicle], options,
                   say: Callable[[str], None], poll: Callable[[], None] = lambda: None
                   ) -> None:
    """Hovering, each vehicle moves (GUIDED) to its leg's start point where its own
    estimate puts it off by more than ``options.start_tolerance_m`` (horizontally).

    A copter is placed at its home; with an uncorrected GPS its estimate is off by the
    GPS error, it takes off where it believes it stands, and starts its legs from there
    (ArduCopter SITL, GPS wander 0.7 m per axis: estimates 0.2-1.3 m from their start
    points, 1.2 m along the track). Started so, a copter ahead of its start is ahead in
    space, not in time; the formation keeper, which answers leads as time (every copter
    leaves together), paused the others for it in turn: leads of 3 m for the whole
    flight. Moved to the start point first, every copter starts where the plan and the
    keeper expect, in its own estimate; where it truly is stays off by its GPS error,
    as it is anywhere on its path (the plan's navigation budget)."""
    tolerance = options.start_tolerance_m
    starts = []
    for i, mission in enumerate(planned.missions):
        lat, lon, _alt = planned.frame.to_lla(planned.paths[i][0])
        starts.append(Point(float(lat), float(lon), takeoff_item(mission)[1]))

    def away(v, start) -> float:
        if v.status.lat_deg is None:
            return float("inf")
        return ground_distance(planned.frame, v.status, start)

    first = [away(v, st) for v, st in zip(vehicles, starts)]
    moving = [i for i, d in enumerate(first) if d > tolerance]
    if not moving:
        return
    say("moving to the start points first (each vehicle's own estimate): " + ", ".join(
        f"{vehicles[i].name} {first[i]:.2f} m off" for i in moving))
    for i in moving:
        vehicles[i].goto(*starts[i])
    resent = [clock.monotonic()]

    def pending() -> list[int]:
        return [i for i in moving if not (away(vehicles[i], starts[i]) <= tolerance and
                vehicles[i].status.ground_speed_m_s <= options.settled_climb_m_s)]

    def again(now: float, waiting: list[int]) -> None:
        if now - resent[0] >= 2.0:  # SET_POSITION_TARGET is never acknowledged: say it again
            resent[0] = now
            for i in waiting:
                vehicles[i].goto(*starts[i])

    late = wait_while(vehicles, pending, clock.monotonic() + options.align_timeout_s, poll,
                       each_turn=again, step_s=0.1)
    if late:
        say("not at the start point after {:g} s, starting anyway: {}".format(
            options.align_timeout_s, ", ".join(
                f"{vehicles[i].name} {away(vehicles[i], starts[i]):.2f} m off" for i in late)))


def wait_while(vehicles: Sequence[FlightVehicle], pending: Callable[[], list[int]],
                deadline: float, poll: Callable[[], None], *,
                each_turn: Callable[[float, list[int]], None] | None = None,
                step_s: float) -> list[int]:
    """Watch the vehicles until ``pending()`` (indices of the ones not there yet) is empty
    or ``deadline`` (``clock.monotonic()``) passes; the ones still pending then. An abort
    raises :class:`FlightAborted`; ``each_turn(now, pending)`` runs every turn (a resend),
    ``poll()`` too (the live view, the departure watch)."""
    while True:
        if aborted(vehicles):
            raise FlightAborted(vehicles[0].name, vehicles[0].sysid, aborted(vehicles))
        waiting = pending()
        now = clock.monotonic()
        if not waiting or now >= deadline:
            return waiting
        if each_turn is not None:
            each_turn(now, waiting)
        poll()
        vehicles[waiting[0]].wait_for(lambda s: False, min(step_s, max(deadline - now, 0.0)))


class Point(NamedTuple):
    """A position as mission items and vehicle statuses give one (altitude above home)."""

    lat_deg: float
    lon_deg: float
    alt_m: float


def ground_distance(frame: LocalFrame, a, b) -> float:
    """Horizontal metres between two items' positions, in the plan's ENU frame."""
    enu = frame.to_enu(lat_deg=[a.lat_deg, b.lat_deg], lon_deg=[a.lon_deg, b.lon_deg])
    return float(np.hypot(*(enu[0, :2] - enu[1, :2])))
