"""Pre-flight: every vehicle holds exactly its planned mission and fence (read back and
compared as ``upload`` verifies) and the ``[vehicle]`` parameters its flown path was
predicted with (plan.json ``vehicle``: WPNAV_SPEED, WPNAV_ACCEL, ...), has a 3D GPS fix,
passes its pre-arm checks, runs the firmware the flight model follows
(AUTOPILOT_VERSION: ArduCopter 4.5.x or 4.6.x, :mod:`ftlbo_mav.ardupilot.firmware`), and has a
GPS fix, accuracy and EKF that hold it to the plan's navigation budget
(:mod:`.navigation`). Any failure stops the flight here, one line per vehicle, before
anything is armed."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

from .. import clock
from ..ardupilot.copters import FLIGHT_PARAMS, Copter, release_for
from ..ardupilot.firmware import any_firmware_warning, firmware_problem
from ..ardupilot.navigation import vehicle_param_differences
from ..errors import FtlboError
from ..link.codec import mission_differences
from ..link.discovery import is_ready, readiness_problems
from ..link.geofence import fence_differences
from ..link.mission_protocol import download_mission
from ..link.params import read_params
from ..link.transfer import Timing
from .battery import CopterBattery, OwnBatteries, own_batteries_for
from .fit import fit_fleet, predict_fleet
from .fleet import concurrently
from .navigation import describe, ekf_report, gps_report, preflight_problems
from .planned import PlannedFlight
from .start import gate_as_onboard
from .vehicle import FlightVehicle

NAVIGATION_SETTLE_S = 5.0
"""How long after readiness a vehicle's navigation may take to meet the plan's budget."""


class PreflightError(FtlboError):
    """Pre-flight checks failed; ``problems`` holds one line per failing vehicle."""

    def __init__(self, problems: list[str]) -> None:
        self.problems = problems
        super().__init__("pre-flight failed, nothing armed:\n  " + "\n  ".join(problems))


def vehicle_param_problem(differences: Sequence[tuple[str, float | None, float]]
                          ) -> str | None:
    """One sentence for a vehicle that does not hold the navigation values the plan sets
    (``(name, onboard or None, planned)``, :func:`~ftlbo_mav.link.params.read_vehicle_params`);
    None when there are none."""
    if not differences:
        return None
    held = [(n, have, want) for n, have, want in differences if have is not None]
    silent = [n for n, have, _want in differences if have is None]
    parts = [f"{n} is {have:g} on the vehicle, the plan sets {want:g}"
             for n, have, want in held]
    if silent:
        parts.append(f"{', '.join(silent)} not answered (PARAM_REQUEST_READ): the path the "
                     "plan predicts cannot be checked")
    text = "; ".join(parts)
    if held:
        text += " (`ftlbo-mav upload` sets the values the scenario names)"
    return text


def copters_as_they_are(planned: PlannedFlight, vehicles: Sequence[FlightVehicle],
                        onboard: Sequence[Mapping[str, float | None]],
                        versions: Sequence[int | None]) -> list[Copter]:
    """Each UAV's copter with its flight parameters as read (``onboard``) and the release
    it runs (``versions``: AUTOPILOT_VERSION, None: the plan's)."""
    return [c.with_onboard({n: x for n, x in values.items() if x is not None},
                           release=release_for(version, c.release), source=f"sysid {v.sysid}")
            for c, v, values, version in zip(planned.fleet(), vehicles, onboard, versions)]


def navigation_problems(planned: PlannedFlight, v: FlightVehicle) -> list[str]:
    """Why vehicle ``v``'s GPS and EKF do not hold it to the plan's navigation budget
    (:func:`~ftlbo_mav.flight.navigation.preflight_problems`), with what it reports."""
    s = v.status
    gps = gps_report(s.gps_raw, planned.frame)
    ekf = ekf_report(s.ekf_raw)
    short = preflight_problems(planned.navigation, gps, ekf)
    if not short:
        return []
    return [f"navigation: {'; '.join(short)} (reports {describe(gps, ekf)}; the plan "
            f"assumes [navigation] {planned.navigation.describe()})"]


def firmware_problems(vehicles: Sequence[FlightVehicle], *, timeout_s: float
                      ) -> list[str | None]:
    """Per vehicle why its firmware is not one the flight model follows, or None
    (:func:`~ftlbo_mav.ardupilot.firmware.firmware_problem`), asked concurrently."""
    def one(v: FlightVehicle) -> str | None:
        version = v.request_version(timeout_s=timeout_s)
        return firmware_problem(vehicle_type=v.status.vehicle_type,
                                autopilot=v.status.autopilot, version=version)

    return concurrently(one, list(vehicles))


def preflight(planned: PlannedFlight, vehicles: Sequence[FlightVehicle], *,
              timing: Timing, ready_timeout_s: float, any_firmware: bool = False,
              any_params: bool = False,
              say: Callable[[str], None] = lambda _t: None) -> OwnBatteries | None:
    """Raise :class:`PreflightError` unless every vehicle is ready to fly its mission.
    A vehicle whose firmware is not ArduCopter 4.5.x or 4.6.x is one that is not, unless
    ``any_firmware``: then ``say`` hears what is no longer promised for it.

    A plan without a ``[battery]``: each copter's own battery as read from it, for the
    flight's battery watch (a copter that has not the charge for its mission and its
    floor is refused); None with a ``[battery]`` (the plan's) or when it could not be
    read."""
    fleet = planned.fleet()
    firmware = firmware_problems(vehicles, timeout_s=timing.timeout_s)
    for v, problem in zip(vehicles, firmware):
        if problem is not None and any_firmware:
            say(f"warning: {v.name} (sysid {v.sysid}): {any_firmware_warning(problem)}")

    values: dict[int, Mapping[str, float | None]] = {}
    batteries: dict[int, CopterBattery] = {}

    def onboard_problems(pair) -> list[str]:
        vehicle, expected, fence, copter = pair
        try:
            with vehicle.link.channel(vehicle.sysid) as channel:
                onboard = download_mission(channel, timing=timing, expect=len(expected))
                fence_diff = ([] if fence is None
                              else fence_differences(channel, fence, timing=timing))
                # its battery's values too without a [battery], in the same exchange
                extra = CopterBattery.PARAMS if planned.battery is None else ()
                read = read_params(channel, (*FLIGHT_PARAMS, *extra), timing=timing)
                values[vehicle.sysid] = {n: read[n] for n in FLIGHT_PARAMS}
                if extra:
                    batteries[vehicle.sysid] = CopterBattery.from_params(read)
        except FtlboError as exc:
            return [f"cannot read its mission or fence back: {exc}"]
        param_diff = vehicle_param_differences(copter.to_set(), values[vehicle.sysid])
        why = []
        diff = mission_differences(gate_as_onboard(expected, onboard, planned.frame), onboard)
        if diff:
            why.append(f"holds a different mission than {vehicle.name}.waypoints "
                       f"({diff[0]}); run `ftlbo-mav upload` first")
        if fence_diff:  # the fence, rally points and FENCE_* of uavN.fence/.rally, fence.parm
            why.append(f"holds a different fence than {vehicle.name}.fence "
                       f"({fence_diff[0]}); run `ftlbo-mav upload` first")
        param_problem = vehicle_param_problem(param_diff)
        if param_problem:
            why.append(param_problem)
        return why

    fences = planned.fences or (None,) * len(planned.missions)
    onboard = concurrently(onboard_problems, list(zip(vehicles, planned.missions, fences,
                                                      fleet)))
    if len(values) == len(vehicles):
        actual = copters_as_they_are(planned, vehicles, [values[v.sysid] for v in vehicles],
                                     [v.status.firmware_version for v in vehicles])
        verdict = fit_fleet(planned, actual, [f"{v.name} (sysid {v.sysid})" for v in vehicles])
        for line in verdict.notes(any_params=any_params):
            say(f"note: {line}")
        if verdict.broken and not any_params:
            onboard = [list(why) + [f"the plan does not fit it: {b}" for b in verdict.broken
                                    if b.startswith(f"{v.name} (sysid {v.sysid})")]
                       for v, why in zip(vehicles, onboard)]
            if not any(onboard):  # a promise lost by all of them: said for each
                onboard = [[f"the plan does not fit the fleet: {'; '.join(verdict.broken)}"]
                           for _v in vehicles]
        own = batteries_as_read(planned, actual, [batteries.get(v.sysid) for v in vehicles])
    else:
        own = None
    deadline = clock.monotonic() + ready_timeout_s

    def reported(v: FlightVehicle, i: int) -> bool:
        watched = planned.battery is not None or (own is not None and own.copters[i].watched)
        return (v.status.gps_raw is not None and v.status.ekf_raw is not None
                and (not watched or v.status.battery_pct is not None))

    while clock.monotonic() < deadline and not all(
            is_ready(v.link, v.sysid) and reported(v, i) for i, v in enumerate(vehicles)):
        clock.sleep(0.1)
    # an EKF that has not yet got its absolute position is waited for a few seconds more
    # (SITL through a radio: one copter's EKF_STATUS_REPORT lacked it at the first look
    # after the upload, and a flight was refused); a receiver short of the budget does
    # not come good by waiting, and is refused then
    settle = min(deadline, clock.monotonic() + NAVIGATION_SETTLE_S)
    while clock.monotonic() < settle and any(navigation_problems(planned, v) for v in vehicles):
        clock.sleep(0.1)
    problems = []
    for i, (v, why, problem) in enumerate(zip(vehicles, onboard, firmware)):
        why = list(why)
        if problem is not None and not any_firmware:
            why.append(problem)
        if not is_ready(v.link, v.sysid):
            why += readiness_problems(v.link, v.sysid)
        why += navigation_problems(planned, v)
        batt = planned.battery if planned.battery is not None else own
        if batt is not None:
            short = batt.preflight_problem(i, v.status.battery_pct)
            why += [short] if short else []
        if own is not None and (unwatched := own.unwatched(i, v.status.battery_pct)):
            say(f"note: {v.name} (sysid {v.sysid}) {unwatched}")
        if v.status.armed:
            why.append("already armed")
        if why:
            problems.append(f"{v.name} (sysid {v.sysid}): " + "; ".join(why))
    if problems:
        raise PreflightError(problems)
    return own


def batteries_as_read(planned: PlannedFlight, copters, batteries) -> OwnBatteries | None:
    """Without a ``[battery]``: each copter's battery (``batteries``, as read; None where
    not) against its mission predicted with its own values (``copters``)."""
    if planned.battery is not None or any(b is None for b in batteries):
        return None
    prediction = predict_fleet(planned, copters)
    if prediction is None:
        return None
    return own_batteries_for(planned.missions, prediction, [c.nav for c in copters],
                             batteries)
