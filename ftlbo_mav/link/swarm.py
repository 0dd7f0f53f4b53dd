"""Every vehicle at once: upload, read back, compare; one result per vehicle.

:func:`upload_swarm` opens the links, finds each requested system id by its HEARTBEAT,
then runs :func:`upload_and_verify` for all found vehicles concurrently (one thread
each: the protocol waits are blocking queue reads with time-outs). A vehicle that is
missing or fails never stops the others; each gets a :class:`VehicleResult`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace

from pymavlink.dialects.v20 import ardupilotmega as R

from .. import clock
from ..ardupilot.copters import FLIGHT_PARAMS, Copter, is_tuning, release_for
from ..ardupilot.fence import param_equal
from ..ardupilot.firmware import (
    SUPPORTED,
    UNANSWERED,
    any_firmware_warning,
    firmware_problem,
    heartbeat_findings,
)
from ..errors import BadInput
from ..mission.fence_files import FenceSet
from ..mission.items import MissionItem
from .codec import mission_differences
from .discovery import describe_missing, discover, mavlink1_problem
from .endpoints import Heartbeat, open_links
from .firmware import request_version
from .geofence import upload_fence_set
from .mission_protocol import (
    MissionTransferError,
    Timing,
    Upload,
    clear_mission,
    download_mission,
    run_transfer,
)
from .params import ParamError, read_params, set_vehicle_params


class MissingParameter(BadInput):
    """A parameter the plan sets is one a copter does not have: nothing is sent."""


@dataclass(frozen=True)
class Assignment:
    """Which mission goes to which vehicle: ``uav1`` -> system id 1; ``fence``: its
    fence, rally points and fence parameters, sent after the mission (None: none);
    ``params``: the navigation values the scenario named (plan.json
    ``uavs[].vehicle.set``), set after the fence where the vehicle holds other values,
    and read back: never a tuning value (:func:`~ftlbo_mav.ardupilot.copters.is_tuning`);
    ``copter``: the copter its flight was predicted with (None: not checked)."""

    name: str
    sysid: int
    items: tuple[MissionItem, ...]
    fence: FenceSet | None = None
    params: Mapping[str, float] = field(default_factory=dict)
    copter: Copter | None = None

    def __post_init__(self) -> None:
        tuning = [n for n in self.params if is_tuning(n)]
        if tuning:
            raise ValueError(f"{self.name}: {', '.join(tuning)} is the copter's tuning: "
                             "upload never writes it")


@dataclass(frozen=True)
class VehicleResult:
    """How one vehicle ended: ``verified``, or why not, in one sentence."""

    name: str
    sysid: int
    verified: bool
    message: str
    seconds: float


@dataclass(frozen=True)
class ProgressEvent:
    """Where one vehicle is. ``step``: "discover", "upload", "read-back" (with ``done`` of
    ``total`` items), "clear", then "verified" or "failed" (with ``message``)."""

    name: str
    sysid: int
    step: str
    done: int = 0
    total: int = 0
    message: str = ""


OnProgress = Callable[[ProgressEvent], None]


# Vehicle sides known to drop an item whose seq is not the one they wait for: ArduPilot
# (MissionItemProtocol::handle_mission_item, INVALID_SEQUENCE) and PX4 (mavlink_mission.cpp).
# MAVSDK's MissionRawServer (autopilot GENERIC) stores every item it gets, so an early resend
# after a slow answer would store an item twice: for those, resends wait the full time-out.
SEQ_CHECKING_AUTOPILOTS = frozenset({R.MAV_AUTOPILOT_ARDUPILOTMEGA, R.MAV_AUTOPILOT_PX4})


def timing_for(heartbeat: Heartbeat, timing: Timing) -> Timing:
    """``timing``, with early resends only for autopilots that check item sequence numbers
    and items sent ahead of the requests only to ArduPilot (whose handling of them we
    follow: :data:`~.mission_protocol.SEND_AHEAD_ON_LINK`)."""
    if heartbeat.autopilot == R.MAV_AUTOPILOT_ARDUPILOTMEGA:
        return timing
    if heartbeat.autopilot in SEQ_CHECKING_AUTOPILOTS:
        return replace(timing, send_ahead=0)
    return replace(timing, adaptive=False, send_ahead=0)


def _clear_and_confirm(channel, timing: Timing, report: Callable[[str], None]) -> str:
    """Clear the mission after a failure and say what the vehicle holds now."""
    report("clear")
    try:
        clear_mission(channel, timing=timing)
        left = download_mission(channel, timing=timing)
    except MissionTransferError as exc:
        return (f"clearing its mission failed too ({exc.problem}): it may hold part of "
                f"a mission; check it with `ftlbo-mav download --sysid {channel.sysid}`")
    if len(left) <= 1:  # ArduPilot keeps home as item 0
        return "its mission was cleared (read back: no items): the vehicle now has no mission"
    return (f"after MISSION_CLEAR_ALL it still reports {len(left)} items: "
            "do not fly it before checking it by hand")


def upload_and_verify(channel, items: Sequence[MissionItem], *, timing: Timing,
                      progress: Callable[[str, int, int], None] | None = None) -> tuple[bool, str]:
    """Upload, read back, compare from item 1. ``(True, "verified ...")`` or ``(False, why)``.

    After a failed upload (or a read-back that differs) the vehicle's mission is cleared
    and the clear confirmed by read-back, so no partial mission is left silently.
    """
    progress = progress or (lambda _s, _d, _t: None)

    def report(step: str) -> None:
        progress(step, 0, 0)

    machine = Upload(items, sysid=channel.sysid, compid=1,
                     own=(channel.own_sysid, channel.own_compid), timing=timing,
                     progress=progress, srtt=channel.srtt,
                     sharing=getattr(channel, "sharing", 1))
    try:
        return _upload_and_verify(channel, items, machine, timing=timing, progress=progress,
                                  report=report)
    except OSError as exc:  # the link itself broke (closed, reset): nothing more can be sent
        sent = max(machine.highest + 1, 0)
        return False, (f"the link failed ({exc.strerror or exc}) after {sent} of {len(items)} "
                       "items were sent: the vehicle holds its old mission or part of this "
                       "one; check it with `ftlbo-mav download --sysid "
                       f"{channel.sysid}` before flying")


def _upload_and_verify(channel, items, machine, *, timing, progress, report):
    """:func:`upload_and_verify` over a link that holds: protocol failures are answered."""
    try:
        run_transfer(machine, channel)
    except MissionTransferError as exc:
        if machine.highest < 0 and exc.result is not None:
            # refused at MISSION_COUNT (NO_SPACE, DENIED): ArduPilot truncates nothing
            # before it asks for item 0 (MissionItemProtocol::handle_mission_count)
            return False, f"upload failed: {exc.problem}"
        if machine.highest < 0 and exc.result is None:
            return False, (f"upload failed: {exc.problem}; the vehicle never asked for an item, "
                           "so none was sent")
        cleared = _clear_and_confirm(channel, timing, report)
        return False, f"upload failed: {exc.problem}; {cleared}"
    try:
        back = download_mission(channel, timing=timing, progress=progress,
                                expect=len(items))
    except MissionTransferError as exc:
        return False, (f"uploaded, but the read-back failed ({exc.problem}): the mission is "
                       "NOT verified")
    problems = mission_differences(items, back)
    if problems:
        more = f"; ... {len(problems) - 3} more" if len(problems) > 3 else ""
        shown = "; ".join(problems[:3]) + more
        return False, f"read-back differs: {shown}; " + _clear_and_confirm(channel, timing, report)
    return True, f"verified ({len(items)} items)"


def _set_vehicle_params(channel, a: Assignment, timing: Timing) -> tuple[bool, str]:
    """The plan's [vehicle] parameters on one vehicle: ``(True, what changed)`` or
    ``(False, why)``."""
    try:
        changed = set_vehicle_params(channel, a.params, timing=timing)
    except ParamError as exc:
        return False, f"vehicle parameter {exc.name}: {exc.problem}"
    except OSError as exc:
        return False, (f"the link failed ({exc.strerror or exc}) while setting the vehicle "
                       "parameters: `ftlbo-mav fly` checks them before arming")
    if not changed:
        return True, f"{len(a.params)} vehicle parameters as planned"
    return True, "set " + ", ".join(f"{n} {old:g} -> {new:g}" for n, old, new in changed)


def _fit_check(todo: Sequence[Assignment], read: Mapping[int, Mapping[str, float | None]],
               versions: Mapping[int, int | None], fit, on_note, any_params: bool = False
               ) -> dict[int, str]:
    """Judge the plan with every vehicle's flight parameters as ``read`` (by system id;
    read while its firmware was asked: a round trip saved) and the release it runs
    (``fit``) and say what will be set; per system id why nothing may be sent (empty: go
    on)."""
    onboard = [read[a.sysid] for a in todo]
    actual = []
    for a, values in zip(todo, onboard):
        silent = [n for n in a.params if values.get(n) is None]
        if silent:
            raise MissingParameter(
                f"{a.name} (sysid {a.sysid}) does not answer for {silent[0]} "
                "(PARAM_REQUEST_READ), which the plan sets ([vehicle]): not a parameter this "
                "copter has; nothing was sent to any vehicle")
        held = {n: v for n, v in values.items() if v is not None}
        release = release_for(versions.get(a.sysid), a.copter.release)
        actual.append(a.copter.with_onboard(held, release=release,
                                            source=f"sysid {a.sysid}"))
    verdict = fit(actual)
    say = on_note or (lambda _t: None)
    for line in verdict.notes(any_params=any_params):
        say(line)
    if verdict.broken and not any_params:
        lost = "; ".join(verdict.broken)
        return {a.sysid: f"refused, nothing sent to any vehicle: {lost} (plan for these "
                "copters: `ftlbo-mav plan --fleet`, or [vehicle] params_file or values by "
                "name; --any-params goes on)" for a in todo}
    for a, values in zip(todo, onboard):
        sets = [(n, values[n], v) for n, v in a.params.items()
                if values[n] is None or not param_equal(n, v, values[n])]
        say(f"{a.name} (sysid {a.sysid}): " + (
            "sets " + ", ".join(f"{n} {old:g} -> {new:g}" for n, old, new in sets)
            if sets else "sets no parameter (its tuning is never written)"))
    return {}


def upload_swarm(assignments: Sequence[Assignment], urls: Sequence[str], *,
                 signing_key: bytes | None = None, timing: Timing | None = None,
                 discover_timeout_s: float = 5.0,
                 on_progress: OnProgress | None = None, any_firmware: bool = False,
                 on_warning=None, fit=None, on_note=None, any_params: bool = False
                 ) -> list[VehicleResult]:
    """Upload and verify every assignment concurrently; results in assignment order.

    First every vehicle found is asked which firmware it runs (:mod:`.firmware`): when
    one is not a firmware the flight model follows, nothing is sent to any vehicle and
    each result says why, unless ``any_firmware``: then ``on_warning(name, sysid, text)``
    hears what is no longer promised for it and the upload goes on.

    Then, with ``fit`` (a function of the copters as they are, one per assignment, to a
    :class:`~ftlbo_mav.flight.fit.Fit`), every vehicle's flight parameters are read and
    the plan judged with them and the release each runs: when a promise is lost, or a
    parameter the plan sets is one a vehicle does not have, nothing is sent to any
    vehicle and each result says why; else ``on_note(text)`` hears what differed, what
    the prediction with the copters' own values keeps, and what each vehicle will be
    set to, before anything is sent; with ``any_params`` a promise lost is said and the
    upload goes on."""
    timing = timing or Timing()
    emit = on_progress or (lambda _e: None)
    started = clock.monotonic()
    links = open_links(urls, signing_key=signing_key, connect_timeout_s=discover_timeout_s)
    try:
        for a in assignments:
            emit(ProgressEvent(a.name, a.sysid, "discover"))
        found, missing = discover(links, [a.sysid for a in assignments],
                                  timeout_s=discover_timeout_s)
        results: dict[int, VehicleResult] = {}
        for a in assignments:
            if a.sysid in missing:
                msg = describe_missing(a.sysid, links, discover_timeout_s)
                results[a.sysid] = VehicleResult(a.name, a.sysid, False, msg,
                                                 clock.monotonic() - started)
                emit(ProgressEvent(a.name, a.sysid, "failed", message=msg))

        def one(a: Assignment) -> VehicleResult:
            t0 = clock.monotonic()

            def progress(step: str, done: int, total: int) -> None:
                emit(ProgressEvent(a.name, a.sysid, step, done, total))

            link = found[a.sysid]
            own_timing = timing_for(link.heartbeats[a.sysid], timing)

            # the mission, the fence with its rally points and parameters, and the
            # [vehicle] parameters at once, each on a channel of its own (every channel
            # sees the vehicle's messages; each transfer takes those of its mission type,
            # each parameter exchange its names): ArduPilot keeps a protocol per mission
            # type (MissionItemProtocol) and answers parameters by name, so none waits
            # for another's round trips (through a shared radio, 60 ms each way: docs/link.md)
            def mission() -> tuple[bool, str]:
                with link.channel(a.sysid) as channel:
                    return upload_and_verify(channel, a.items, progress=progress,
                                             timing=own_timing)

            def fence() -> tuple[bool, str] | None:
                if a.fence is None:
                    return None
                try:
                    with link.channel(a.sysid) as channel:
                        return upload_fence_set(channel, a.fence, timing=own_timing,
                                                progress=progress,
                                                more_channels=lambda: link.channel(a.sysid))
                except OSError as exc:  # the link broke
                    return False, (f"the link failed ({exc.strerror or exc}) during the fence: "
                                   f"check it with `ftlbo-mav download --sysid {a.sysid}` "
                                   "before flying")

            def params() -> tuple[bool, str] | None:
                if not a.params:
                    return None
                progress("parameters", 0, len(a.params))
                with link.channel(a.sysid) as channel:
                    return _set_vehicle_params(channel, a, own_timing)

            with clock.Executor(3) as parts:
                futures = [parts.submit(f) for f in (mission, fence, params)]
            (ok, msg), fenced, paramed = (f.result() for f in futures)
            for part in (fenced, paramed):
                if part is None:
                    continue
                part_ok, part_msg = part
                if ok and part_ok:
                    msg = f"{msg[:-1]}; {part_msg})"
                elif ok:
                    ok, msg = False, f"mission {msg}, but {part_msg}"
                elif not part_ok:
                    msg = f"{msg}; and {part_msg}"
            if not ok and link.closed_by_peer and "closed by the other end" not in msg:
                msg += f" ({link.url} was closed by the other end)"
            emit(ProgressEvent(a.name, a.sysid, "verified" if ok else "failed",
                               len(a.items), len(a.items), msg))
            return VehicleResult(a.name, a.sysid, ok, msg, clock.monotonic() - t0)

        todo = [a for a in assignments if a.sysid in found]

        versions: dict[int, int | None] = {}

        def firmware(a: Assignment) -> tuple[bool, str | None]:
            emit(ProgressEvent(a.name, a.sysid, "firmware"))
            beat = found[a.sysid].heartbeats.get(a.sysid)
            kind = dict(vehicle_type=None if beat is None else beat.vehicle_type,
                        autopilot=None if beat is None else beat.autopilot)
            with found[a.sysid].channel(a.sysid) as channel:
                version = request_version(channel, timeout_s=timing.timeout_s)
            versions[a.sysid] = version
            silent = version is None and not heartbeat_findings(**kind)
            return silent, firmware_problem(**kind, version=version)

        def refuse_all(why: Mapping[int, str], default: str) -> list[VehicleResult]:
            for a in todo:
                msg = why.get(a.sysid, default)
                results[a.sysid] = VehicleResult(a.name, a.sysid, False, msg, 0.0)
                emit(ProgressEvent(a.name, a.sysid, "failed", message=msg))
            return [results[a.sysid] for a in assignments]

        old = [a for a in todo if found[a.sysid].heartbeats[a.sysid].mavlink1]
        if old:  # at once, not after a protocol's time-outs
            return refuse_all(
                {a.sysid: mavlink1_problem(a.sysid, found[a.sysid].url) for a in old},
                "not uploaded: " + ", ".join(f"sysid {a.sysid}" for a in old)
                + " speaks MAVLink 1 only; nothing was sent")
        judged = todo and fit is not None and len(todo) == len(assignments) and all(
            a.copter is not None for a in todo)
        onboard: dict[int, dict[str, float | None]] = {}

        def flight_params(a: Assignment) -> None:  # read while the firmware is asked
            emit(ProgressEvent(a.name, a.sysid, "parameters"))
            with found[a.sysid].channel(a.sysid) as channel:
                onboard[a.sysid] = read_params(channel, FLIGHT_PARAMS, timing=timing,
                                               alone=True)

        if todo:
            with clock.Executor(2 * len(todo)) as pool:
                reads = [pool.submit(flight_params, a) for a in todo] if judged else []
                answers = list(pool.map(firmware, todo))
                for r in reads:
                    r.result()
            problems = [p for _silent, p in answers]
            # a vehicle silent to the request is not refused here: the upload finds out
            # whether it answers at all, and fly's pre-flight refuses an unknown firmware
            refused = [(a, p) for a, (silent, p) in zip(todo, answers)
                       if p is not None and not silent]
            for a, (silent, _p) in zip(todo, answers):
                if silent and on_warning is not None:
                    on_warning(a.name, a.sysid, f"firmware: {UNANSWERED}; the flight model "
                               f"is {SUPPORTED}'s; uploading anyway, `fly` refuses it")
            if refused and not any_firmware:
                for a, p in zip(todo, problems):
                    msg = p or "not uploaded: " + ", ".join(
                        f"sysid {b.sysid}" for b, _ in refused) + " runs another firmware"
                    results[a.sysid] = VehicleResult(a.name, a.sysid, False, msg, 0.0)
                    emit(ProgressEvent(a.name, a.sysid, "failed", message=msg))
                return [results[a.sysid] for a in assignments]
            for a, p in refused:
                if on_warning is not None:
                    on_warning(a.name, a.sysid, any_firmware_warning(p))
        if judged:
            why = _fit_check(todo, onboard, versions, fit, on_note, any_params)
            if why:
                return refuse_all(why, "not uploaded: " + next(iter(why.values())))
        if todo:
            with clock.Executor(len(todo)) as pool:
                for r in pool.map(one, todo):
                    results[r.sysid] = r
        return [results[a.sysid] for a in assignments]
    finally:
        for link in links:
            link.close()
