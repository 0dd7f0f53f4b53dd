"""Take-off and the synchronized start.

GUIDED, arm (retried while the autopilot still waits for its position estimate), take
off to the mission's takeoff altitude, all vehicles at once; wait until every vehicle is
within a tolerance of its altitude *and* has stopped climbing (a naive start, switching
to AUTO as soon as all are near altitude, lets one copter still climbing start late and
fly the legs behind the others). Then every vehicle's current item is set to where its
legs begin (:func:`first_leg`) and every vehicle is switched to AUTO in one burst of
messages; only afterwards are the switches confirmed, so that the formation leaves as one.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import NamedTuple

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as R

from ..geo import LocalFrame
from ..mission.items import (
    CMD_DO_CHANGE_SPEED,
    CMD_DO_SET_CAM_TRIGG_DIST,
    CMD_NAV_TAKEOFF,
    CMD_NAV_WAYPOINT,
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
        deadline = time.monotonic() + options.arm_budget_s
        v.set_mode("GUIDED", timeout_s=options.arm_budget_s)
        v.arm(budget_s=max(0.0, deadline - time.monotonic()))
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
        poll()
        pending[0].wait_for(hovering(targets[vehicles.index(pending[0])]), 0.1)


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
        starts.append(_Point(float(lat), float(lon), takeoff_item(mission)[1]))

    def away(v, start) -> float:
        if v.status.lat_deg is None:
            return float("inf")
        return _ground_distance(planned.frame, v.status, start)

    first = [away(v, st) for v, st in zip(vehicles, starts)]
    moving = [i for i, d in enumerate(first) if d > tolerance]
    if not moving:
        return
    say("moving to the start points first (each vehicle's own estimate): " + ", ".join(
        f"{vehicles[i].name} {first[i]:.2f} m off" for i in moving))
    for i in moving:
        vehicles[i].goto(*starts[i])
    deadline = time.monotonic() + options.align_timeout_s
    resent = time.monotonic()

    def there(v, st) -> bool:
        return away(v, st) <= tolerance and v.status.ground_speed_m_s <= options.settled_climb_m_s

    while True:
        if aborted(vehicles):
            raise FlightAborted(vehicles[0].name, vehicles[0].sysid, aborted(vehicles))
        pending = [i for i in moving if not there(vehicles[i], starts[i])]
        if not pending:
            return
        now = time.monotonic()
        if now >= deadline:
            say("not at the start point after {:g} s, starting anyway: {}".format(
                options.align_timeout_s, ", ".join(
                    f"{vehicles[i].name} {away(vehicles[i], starts[i]):.2f} m off"
                    for i in pending)))
            return
        if now - resent >= 2.0:  # SET_POSITION_TARGET is never acknowledged: say it again
            resent = now
            for i in pending:
                vehicles[i].goto(*starts[i])
        poll()
        vehicles[pending[0]].wait_for(lambda s: False, 0.1)


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


class _Point(NamedTuple):
    """A position as mission items and vehicle statuses give one (altitude above home)."""

    lat_deg: float
    lon_deg: float
    alt_m: float


def _ground_distance(frame: LocalFrame, a, b) -> float:
    """Horizontal metres between two items' positions, in the plan's ENU frame."""
    enu = frame.to_enu(lat_deg=[a.lat_deg, b.lat_deg], lon_deg=[a.lon_deg, b.lon_deg])
    return float(np.hypot(*(enu[0, :2] - enu[1, :2])))


def start_together(planned: PlannedFlight, vehicles: Sequence[FlightVehicle]) -> float:
    """Set every current item to the first real leg (:func:`first_leg`), then AUTO in
    one burst. Returns the monotonic time of the burst."""
    starts = [first_leg(m, planned.frame) for m in planned.missions]

    concurrently(lambda pair: pair[0].set_current(pair[1][0]), list(zip(vehicles, starts)))
    if aborted(vehicles):
        raise FlightAborted(vehicles[0].name, vehicles[0].sysid, aborted(vehicles))
    t = time.monotonic()
    for v in vehicles:
        v.send_mode("AUTO")
    concurrently(lambda v: v.set_mode("AUTO"), vehicles)

    def cruise(pair) -> None:  # skipped speeds: only AUTO keeps them (first_leg)
        v, (_seq, speeds) = pair
        for it in speeds:
            v.command(R.MAV_CMD_DO_CHANGE_SPEED, it.param1, it.param2, it.param3,
                      step="cruise speed")

    concurrently(cruise, list(zip(vehicles, starts)))
    return t
