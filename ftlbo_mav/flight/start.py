"""The synchronized start: every vehicle begins its legs at one moment.

Every vehicle's current item is set to where its legs begin (:func:`first_leg`). With a
start gate in every mission (a NAV_DELAY after the start point, :func:`start_gate`, which
``plan`` writes) and every vehicle's GPS clock known, the gates are written with one
instant of GPS time (:func:`choose_start`) and the legs begin then, whatever the radio
did to each AUTO; otherwise they begin as one burst of AUTOs arrives, confirmed only
afterwards (:func:`start_together`). The gates are restored after the flight
(:func:`restore_gates`). Take-off and the move to the start points come before, in
:mod:`.launch`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as R

from .. import clock
from ..errors import FtlboError
from ..geo import LocalFrame
from ..link.codec import item_differences
from ..link.mission_protocol import MissionTransferError, Timing, read_items, write_items
from ..mission import items
from ..mission.items import (
    CMD_DO_CHANGE_SPEED,
    CMD_NAV_DELAY,
    CMD_NAV_WAYPOINT,
)
from .fleet import concurrently
from .launch import ground_distance, takeoff_item, wait_while
from .outcome import aborted
from .planned import PlannedFlight
from .vehicle import FlightAborted, FlightError, FlightVehicle


def first_leg(mission, frame: LocalFrame, *, hold_m: float = 0.5) -> tuple[int, list]:
    """``(seq, speed items)``: where AUTO starts, and the DO_CHANGE_SPEED items it skips
    (to be sent as commands once AUTO runs).

    After the takeoff each vehicle already hovers at its start point, which is also the
    mission's first waypoint. Starting AUTO there makes ArduCopter fly a zero-length leg
    first, whose jerk-limited S-curve lasts about a second and differs from copter to
    copter with its residual altitude error (on SITL the higher copter began the real legs
    0.4 s late: 0.44 m RMS formation error; starting at the first real leg: 0.09 m). So AUTO
    starts after the start point: at the start gate (the NAV_DELAY ``plan`` writes there,
    :func:`~ftlbo_mav.mission.items.start_gate`), else at the DO_CHANGE_SPEED that follows
    it, which ArduCopter runs as the mission resumes, before the first leg
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
        if it.command in (CMD_DO_CHANGE_SPEED, CMD_NAV_DELAY):
            if passed_start:
                return it.seq, speeds
            if it.command == CMD_DO_CHANGE_SPEED:
                speeds.append(it)
                continue
        at_start = (it.command == CMD_NAV_WAYPOINT and it.param1 == 0
                    and ground_distance(frame, it, home) <= hold_m
                    and abs(it.alt_m - takeoff.alt_m) <= hold_m)
        if at_start and not passed_start and it.seq + 1 < len(mission):
            passed_start = True
            continue
        return it.seq, speeds
    return seq + 1, []


def start_gate(mission, frame: LocalFrame) -> int | None:
    """The seq of the mission's start gate (the NAV_DELAY right after its start point,
    where :func:`first_leg` starts AUTO), or None: a mission without one starts when its
    AUTO arrives."""
    return _gate_at(mission, first_leg(mission, frame)[0])


def _gate_at(mission, seq: int) -> int | None:
    """``seq`` when the mission's item there is a start gate (a NAV_DELAY), else None."""
    item = next((it for it in mission if it.seq == seq), None)
    return seq if item is not None and item.command == CMD_NAV_DELAY else None


START_LEAD_S = 0.5
"""Ground seconds at least between choosing the start time and the start."""
START_LEAD_RTTS = 6
"""... and round trips of the slowest vehicle (timed on its set-current): the gate's write
and read-back (3), AUTO (1) and two to spare (a frame lost on the way)."""
GATE_TIMING = Timing()
RESTORE_TIMING = Timing(timeout_s=1.0, retries=3)  # after the flight: best effort
START_ATTEMPTS = 3
FIRST_RTT_MAX_S = 0.4
CLOCKS_AGREE_S = 0.2
"""Vehicles' UTC clocks further apart than this (on the ground's estimate) are not one
GPS time: the start is then the radio's burst."""
MOVING_M_S = 0.5  # a copter this fast has begun its legs, whatever its last MISSION_CURRENT
LATE_AFTER_S = 1.5
"""Ground seconds after the start time by which every vehicle must report its legs begun
(MISSION_CURRENT past the gate, at 2 Hz); one that does not missed the time."""
LATE_SILENT_S = 2.0
"""A vehicle whose reports from ``LATE_AFTER_S`` after the start have not come is waited for
this much longer (the departure watch's lost link is 1.8 s of silence)."""


MIN_TRIM_S = 0.001
"""A trim's least (a NAV_DELAY of 0 s would be one of a time of day)."""
MAX_TRIM_S = CLOCKS_AGREE_S
TRIM_MIN_SPREAD_S = 0.1
"""No trim unless the copters' clocks, as measured, are this far apart: the ground measures
them no better than 11 ms through TCP and 20-40 ms through a radio (SITL; the emulator's
good-day radio, one flight: 41 ms for clocks that agree), copters of one release agree
within 5 ms (fifteen SITL flights) and those of 4.5.6 and 4.6.3 SITL are 0.17 s apart. A
trim for clocks that agree only adds the measurement's error (the emulator's good-day
radio, held 41 and 16 ms: 0.81 m from its slot, a departure without the keeper)."""
TRIM_MAX_JITTER_S = 0.14
"""No trim on a link whose reports' delays vary more (the 90th percentile beyond the least
delayed, :meth:`~.status.Status.jitter_s`): the keeper's own bound, the good-day radio's
0.07-0.125 s under it, the rough day's 0.148-0.48 s over (docs/flight.md)."""


MAX_LEAD_S = 45
"""The gate gives the second of the minute only (a gate left behind by a flight that could
not restore it holds a copter flown by another ground station a minute at most), so the
start is never further ahead than this many of the vehicles' seconds."""


@dataclass(frozen=True)
class TimedStart:
    """The legs begin when every vehicle's GPS clock reads ``utc_s`` (whole seconds since
    the epoch), ``ground_t`` on the ground's monotonic clock."""

    utc_s: int
    ground_t: float
    # per vehicle, how long after its clock reads ``utc_s`` it begins (its seconds): its
    # clock is ahead of the latest one's by that much (:func:`start_together`)
    trims_s: tuple[float, ...] = ()

    @property
    def hms(self) -> tuple[int, int, int]:
        """The gate's fields: hour and minute not given, the second of the minute."""
        return -1, -1, self.utc_s % 60


def choose_start(vehicles: Sequence[FlightVehicle], *, rtt_s: float, now: float
                 ) -> TimedStart | str:
    """When the legs begin: the next whole second of GPS time at least ``START_LEAD_S``
    and ``START_LEAD_RTTS`` round trips ahead (in the vehicles' seconds), or why there can
    be no timed start (a vehicle without a clock, clocks that disagree)."""
    utc = [v.status.utc_now(now) for v in vehicles]
    missing = [v.name for v, u in zip(vehicles, utc) if u is None]
    if missing:
        return f"no GPS time (SYSTEM_TIME) from {', '.join(missing)}"
    if max(utc) - min(utc) > CLOCKS_AGREE_S:
        return "the vehicles' GPS clocks differ by {:.2f} s ({})".format(
            max(utc) - min(utc), ", ".join(f"{v.name} {u % 60:.2f}" for v, u in zip(
                vehicles, utc)))
    rate = max(v.status.clock_rate for v in vehicles)
    lead = max(START_LEAD_S, START_LEAD_RTTS * rtt_s) * rate
    if lead > MAX_LEAD_S - 1:
        return (f"the start would be {lead:.0f} of the vehicles' seconds ahead (round trip "
                f"{rtt_s:.2f} s), more than a gate can say ({MAX_LEAD_S} s)")
    utc_s = math.ceil(max(utc) + lead)
    trims = _trims(vehicles, utc_s)
    if trims is not None:
        return TimedStart(utc_s, trims[0], trims[1])
    ground = [v.status.clock_offset_s + (utc_s - v.status.utc_offset_s) / v.status.clock_rate
              for v in vehicles]
    return TimedStart(utc_s, float(np.mean(ground)))


def _trims(vehicles: Sequence[FlightVehicle], utc_s: int
           ) -> tuple[float, tuple[float, ...]] | None:
    """When the last of them begins at ``utc_s`` of GPS time, on the ground's clock, and
    how long each is to be held after its own clock reads it (its seconds): when each one's
    clock reads it on the ground's clock, from its clock against its boot clock
    (SYSTEM_TIME sends both at once) and its boot clock against the ground's (the least
    delayed of its last minute of reports, :meth:`~.status.Status.clock_line`). None on a
    link whose delays vary more than ``TRIM_MAX_JITTER_S``: the least delayed reports of
    one copter and another then differ by tens of milliseconds, as much as the clocks
    (SITL through the rough-day radio: a copter held 55 ms that began with the others),
    before a minute of reports has the line, or when the clocks are less than
    :data:`TRIM_MIN_SPREAD_S` apart."""
    lines = [v.status.clock_line() for v in vehicles]
    jitter = [v.status.jitter_s() for v in vehicles]
    if any(x is None for x in lines) or any(j is None or j > TRIM_MAX_JITTER_S
                                             for j in jitter):
        return None
    ground = [offset + (utc_s - v.status.utc_offset_s) / rate
              for v, (offset, rate) in zip(vehicles, lines)]
    latest = max(ground)
    if latest - min(ground) < TRIM_MIN_SPREAD_S:
        return None
    return latest, tuple(min((latest - g) * rate, MAX_TRIM_S)
                         for g, (_o, rate) in zip(ground, lines))


def trim_at(mission, gate: int | None) -> int | None:
    """The seq before the start gate (item ``gate``, :func:`start_gate`) when the start
    can be trimmed there: the start point's waypoint, which AUTO skips
    (:func:`first_leg`), so that ``fly`` can write the gate into it and a trim into the
    gate's place (:func:`_gate_items`); else None."""
    before = None if gate is None else next((it for it in mission if it.seq == gate - 1), None)
    return gate - 1 if before is not None and before.command == CMD_NAV_WAYPOINT else None


def _gate_items(planned: PlannedFlight, i: int, seq: int, start: TimedStart | None,
                trimmed: bool) -> list:
    """What vehicle ``i``'s gate (item ``seq``) is written as. Untrimmed: the gate with
    ``start``'s second (None: the plan's placeholder). Trimmed: the gate one item earlier,
    in the start point's place, and in its own a relative NAV_DELAY of the vehicle's trim
    (ArduPilot times it on its own clock to the loop: ModeAuto::do_nav_delay, seconds > 0),
    which puts back what its clock of the day is ahead of the latest one's; None: both
    back as planned."""
    mission = planned.missions[i]
    planned_gate = next(it for it in mission if it.seq == seq)
    if start is None:
        return ([next(it for it in mission if it.seq == seq - 1)] if trimmed else []) + [
            planned_gate]
    fields = items.start_gate(start.hms)
    gate = replace(planned_gate, **{k: fields[k] for k in ("param1", "param2", "param3",
                                                           "param4")})
    if not trimmed:
        return [gate]
    trim = max(start.trims_s[i], MIN_TRIM_S) if start.trims_s else MIN_TRIM_S
    return [replace(gate, seq=seq - 1),
            replace(planned_gate, param1=round(trim, 3), param2=-1.0, param3=-1.0,
                    param4=-1.0)]


def _write_gate(planned: PlannedFlight, vehicle: FlightVehicle, i: int, seq: int,
                start: TimedStart | None, timing: Timing, trimmed: bool = False) -> None:
    """Vehicle ``i``'s start gate (item ``seq``) set to ``start`` (None: back to the plan),
    trimmed or not (:func:`_gate_items`), written in place and read back."""
    written = _gate_items(planned, i, seq, start, trimmed)
    try:
        with vehicle.link.channel(vehicle.sysid) as channel:
            write_items(channel, written, timing=timing)
            back = read_items(channel, [it.seq for it in written], timing=timing)
    except MissionTransferError as exc:
        raise FlightError(vehicle.name, vehicle.sysid, "start time", str(exc)) from exc
    for it, got in zip(written, back):
        if differences := item_differences(it, got):
            raise FlightError(vehicle.name, vehicle.sysid, "start time",
                              f"item {it.seq} read back as {'; '.join(differences)}")


def _write_gates(planned: PlannedFlight, vehicles: Sequence[FlightVehicle], gates: list,
                 start: TimedStart | None, timing: Timing, trimmed: bool = False) -> None:
    """Every vehicle's start gate set to ``start`` at once (:func:`_write_gate`)."""
    concurrently(lambda i: _write_gate(planned, vehicles[i], i, gates[i], start, timing,
                                       trimmed),
                 list(range(len(vehicles))))


def gate_as_onboard(mission, onboard, frame: LocalFrame) -> list:
    """``mission`` with its start gate's time as ``onboard`` holds it: a time a flight
    wrote and could not take back is no difference (the next flight writes its own), nor
    a trimmed start left so (the gate in the start point's place, a trim in its own)."""
    seq = start_gate(mission, frame)
    there = next((it for it in onboard if it.seq == seq), None)
    if seq is None or there is None or there.command != CMD_NAV_DELAY:
        return list(mission)
    before = next((it for it in onboard if it.seq == seq - 1), None)
    if there.param1 > 0:  # a trim: the gate went one item earlier
        if before is None or before.command != CMD_NAV_DELAY or trim_at(mission, seq) is None:
            return list(mission)
        return [before if it.seq == seq - 1 else there if it.seq == seq else it
                for it in mission]
    return [replace(it, param2=there.param2, param3=there.param3, param4=there.param4)
            if it.seq == seq else it for it in mission]


def restore_gates(planned: PlannedFlight, vehicles: Sequence[FlightVehicle],
                  which: Sequence[int], *,
                  timing: Timing = RESTORE_TIMING) -> list[str]:
    """The start gates of vehicles ``which`` written back to the plan's placeholder (no
    time) after a flight, so that the mission flies in any ground station as planned;
    the vehicles it could not reach, with why."""
    gates = [start_gate(m, planned.frame) for m in planned.missions]
    trims = [trim_at(m, g) for m, g in zip(planned.missions, gates)]
    failed = []

    def one(i: int) -> None:
        try:  # both items back where a start may have been trimmed (harmless if not)
            _write_gate(planned, vehicles[i], i, gates[i], None, timing,
                        trimmed=trims[i] is not None)
        except (FtlboError, OSError) as exc:  # best effort: said, never raised
            failed.append(f"{vehicles[i].name}: {exc}")

    concurrently(one, [i for i in which if gates[i] is not None])
    return failed


def start_together(planned: PlannedFlight, vehicles: Sequence[FlightVehicle], *,
                   say: Callable[[str], None] = lambda _s: None,
                   poll: Callable[[], None] = lambda: None, timing: Timing = GATE_TIMING
                   ) -> float:
    """Set every current item to where its legs begin (:func:`first_leg`), then AUTO in
    one burst. Returns the ground's monotonic time at which the legs began.

    With a start gate in every mission (``plan`` writes one) and every vehicle's GPS
    clock known, the legs begin at one instant of GPS time, the same for every copter
    whatever the radio did to its AUTO (:func:`choose_start`, ModeAuto::do_nav_delay):
    through a shared radio the burst's AUTOs arrive tens to hundreds of milliseconds
    apart, lost ones later, and every 0.1 s between two copters is 0.5 m of formation at
    5 m/s for the whole flight (SITL behind the rough-day radio without the keeper: 0.37-
    0.40 m worst). A vehicle whose legs have not begun ``LATE_AFTER_S`` after that time
    missed it (its AUTO came late: ArduCopter would wait for that time the next day) and
    is started at once. Otherwise the legs begin as the burst arrives.

    Each copter's gate opens by its own clock of the day, which ArduPilot sets once, from
    its first GPS fix (AP_RTC.cpp), and copters' clocks need not agree: ArduCopter 4.6.3
    SITL's is 0.17 s behind 4.5.6's (ardupilot/copters.py ``SITL_CLOCK_BEHIND_S``: in a
    fleet of both its gate opened 163-170 ms late, 0.85 m behind its slot at 5 m/s). Where
    every mission has its start point's waypoint before the gate (AUTO skips it), the
    start is trimmed: the gate goes in that item, and in the gate's a relative NAV_DELAY
    holds each copter for what its clock is ahead of the latest one's (the clocks
    measured by :func:`choose_start`), so that all begin together."""
    starts = [first_leg(m, planned.frame) for m in planned.missions]
    gates = [_gate_at(m, seq) for m, (seq, _speeds) in zip(planned.missions, starts)]
    trimmed = all(trim_at(m, g) is not None for m, g in zip(planned.missions, gates))
    # trimmed, AUTO starts at the gate's new place (the start point's, skipped else)
    current = [g - 1 if trimmed else seq for g, (seq, _s) in zip(gates, starts)]

    t = clock.monotonic()
    concurrently(lambda pair: pair[0].set_current(pair[1]), list(zip(vehicles, current)))
    rtt = clock.monotonic() - t
    if aborted(vehicles):
        raise FlightAborted(vehicles[0].name, vehicles[0].sysid, aborted(vehicles))
    # (a lost acknowledgement makes that seconds: a first guess, bounded; a start time
    # written too late is chosen again)
    timed = _timed_start(planned, vehicles, gates, rtt_s=min(rtt, FIRST_RTT_MAX_S),
                         timing=timing, say=say, trimmed=trimmed)
    if timed is None and all(g is not None for g in gates):
        # the radio's timing: AUTO starts past the gates (which may hold a time)
        concurrently(lambda pair: pair[0].set_current(pair[1] + 1), list(zip(vehicles, gates)))
    t = clock.monotonic()
    for v in vehicles:
        v.send_mode("AUTO")
    concurrently(lambda v: v.set_mode("AUTO"), vehicles)

    def cruise(pair) -> None:  # skipped speeds: only AUTO keeps them (first_leg)
        v, (_seq, speeds) = pair
        for it in speeds:
            v.command(R.MAV_CMD_DO_CHANGE_SPEED, it.param1, it.param2, it.param3,
                      step="cruise speed")

    concurrently(cruise, list(zip(vehicles, starts)))
    if timed is None:
        return t
    _start_late_ones(vehicles, gates, timed, say=say, poll=poll, trimmed=trimmed)
    return timed.ground_t


def _timed_start(planned: PlannedFlight, vehicles: Sequence[FlightVehicle],
                 gates: list[int | None], *, rtt_s: float, timing: Timing,
                 say: Callable[[str], None], trimmed: bool = False) -> TimedStart | None:
    """Choose the start time and write it to every gate, again (up to
    ``START_ATTEMPTS`` times, further ahead) when the writing took so long that the AUTOs
    might not arrive before it; None: no timed start (said why)."""
    if not all(g is not None for g in gates):
        return None
    for _attempt in range(START_ATTEMPTS):
        chosen = choose_start(vehicles, rtt_s=rtt_s, now=clock.monotonic())
        if isinstance(chosen, str):
            say(f"starting on the radio's timing, not at one GPS time: {chosen}")
            return None
        t = clock.monotonic()
        _write_gates(planned, vehicles, gates, chosen, timing, trimmed)
        took = clock.monotonic() - t
        left = chosen.ground_t - clock.monotonic()
        if left >= max(START_LEAD_S / 2, took / 2):  # AUTO: one way, a resend to spare
            held = [f"{v.name} {1000 * t:.0f} ms" for v, t in zip(vehicles, chosen.trims_s)
                    if t >= 0.005]
            say(f"the legs begin at second {chosen.hms[2]:02d} of the minute, GPS time "
                f"(in {left:.1f} s)" + (f"; held for their clocks: {', '.join(held)}"
                                        if trimmed and held else ""))
            return chosen
        rtt_s = max(rtt_s, took / 3)  # the write and read-back: three round trips
        say(f"the start time took {took:.1f} s to write, {left:.1f} s before it: "
            "choosing a later one")
    say(f"starting on the radio's timing: the start time could not be written in time "
        f"({START_ATTEMPTS} attempts)")
    return None


def _start_late_ones(vehicles: Sequence[FlightVehicle], gates: list[int], start: TimedStart,
                     *, say: Callable[[str], None], poll: Callable[[], None],
                     trimmed: bool = False) -> None:
    """Wait until every vehicle's legs have begun (MISSION_CURRENT past its gate, and its
    trim), at most ``LATE_AFTER_S`` after the start; a vehicle still at its gate then, by
    a position it reported at least that long after the start (its own clock), is started
    at once (its current item moved past the gate). One that reported nothing that late
    is waited for ``LATE_SILENT_S`` more, then left to its gate: a report held back by
    the link is no evidence, and a start sent to a copter already on its leg restarts
    the leg from where it is (the emulator's rough-day radio: two copters' reports lost
    in an outage, each started again on its leg, 4.9 m from its slot)."""
    first = 1 if trimmed else 0

    def at_gate(i: int) -> bool:
        st = vehicles[i].status
        return gates[i] - first <= st.seq <= gates[i] and st.ground_speed_m_s < MOVING_M_S

    def seen_late(i: int) -> bool:
        st = vehicles[i].status
        start_boot = st.vehicle_now(start.ground_t)
        return start_boot is not None and st.position_boot_s >= start_boot + LATE_AFTER_S

    started: list[int] = []

    def start_seen() -> None:  # as soon as each is seen late, not when all are
        for i, v in enumerate(vehicles):
            if i not in started and at_gate(i) and seen_late(i):
                say(f"{v.name} (sysid {v.sysid}): its legs had not begun {LATE_AFTER_S:g} s "
                    "after the start time (its AUTO came late, or its clock is not GPS "
                    "time): started now")
                v.set_current(gates[i] + 1)
                started.append(i)

    silent = wait_while(vehicles, lambda: [i for i in range(len(vehicles)) if i not in started
                                           and at_gate(i) and not seen_late(i)],
                        start.ground_t + LATE_AFTER_S + LATE_SILENT_S, poll,
                        each_turn=lambda _now, _waiting: start_seen(), step_s=0.05)
    start_seen()
    for i in silent:
        v = vehicles[i]
        say(f"{v.name} (sysid {v.sysid}): no report of its legs {LATE_AFTER_S + LATE_SILENT_S:g} "
            "s after the start time (its link is silent): left to its gate")
