"""The telemetry a ground station must ask ArduPilot for, and how it asks.

ArduPilot sends a link nothing but HEARTBEAT (1 Hz), TIMESYNC (every 10 s) and, once
home is set, HOME_POSITION and GPS_GLOBAL_ORIGIN, until someone asks (recorded on
ArduCopter 4.5.6 SITL with copter.parm: ``tests/data/ardupilot-4.5.6/boot.json``). Rates
are per link (per serial port), set by

- MAV_CMD_SET_MESSAGE_INTERVAL, one message at a time (GCS_MAVLINK::
  handle_command_set_message_interval, libraries/GCS_MAVLink/GCS_Common.cpp), or
- REQUEST_DATA_STREAM, a whole group of messages (GCS_MAVLINK::handle_request_data_stream;
  the groups are ArduCopter/GCS_Mavlink.cpp's ``STREAM_*_msgs``), the older way, kept as
  the fallback for firmware that refuses the first.

SITL acknowledges an interval set in its first ~40 ms after a client connects and then
drops it, so a request is not done when acknowledged, only when the message arrives:
:class:`StreamRequests` re-asks until it does.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass, field

from pymavlink.dialects.v20 import ardupilotmega as R

# What ArduPilot sends on a link that has asked for nothing (GCS_MAVLINK::update_send:
# HEARTBEAT and TIMESYNC are sent unconditionally; HOME_POSITION / GPS_GLOBAL_ORIGIN once
# when home is set, AP_AHRS). STATUSTEXT goes to a link only once it has sent something.
UNASKED = frozenset({"HEARTBEAT", "TIMESYNC", "HOME_POSITION", "GPS_GLOBAL_ORIGIN"})

# ArduCopter/GCS_Mavlink.cpp: the REQUEST_DATA_STREAM group each message belongs to
STREAM_OF = {
    R.MAVLINK_MSG_ID_SYS_STATUS: R.MAV_DATA_STREAM_EXTENDED_STATUS,
    R.MAVLINK_MSG_ID_GPS_RAW_INT: R.MAV_DATA_STREAM_EXTENDED_STATUS,
    R.MAVLINK_MSG_ID_MISSION_CURRENT: R.MAV_DATA_STREAM_EXTENDED_STATUS,
    R.MAVLINK_MSG_ID_NAV_CONTROLLER_OUTPUT: R.MAV_DATA_STREAM_EXTENDED_STATUS,
    R.MAVLINK_MSG_ID_GLOBAL_POSITION_INT: R.MAV_DATA_STREAM_POSITION,
    R.MAVLINK_MSG_ID_LOCAL_POSITION_NED: R.MAV_DATA_STREAM_POSITION,
    R.MAVLINK_MSG_ID_ATTITUDE: R.MAV_DATA_STREAM_EXTRA1,
    R.MAVLINK_MSG_ID_VFR_HUD: R.MAV_DATA_STREAM_EXTRA2,
    R.MAVLINK_MSG_ID_EKF_STATUS_REPORT: R.MAV_DATA_STREAM_EXTRA3,
    R.MAVLINK_MSG_ID_SYSTEM_TIME: R.MAV_DATA_STREAM_EXTRA3,
}

# What each part of ftlbo-mav reads, messages per second.
# Readiness to fly: the 3D fix (GPS_RAW_INT) and the pre-arm bit (SYS_STATUS).
READINESS: Mapping[int, float] = {
    R.MAVLINK_MSG_ID_SYS_STATUS: 2.0,
    R.MAVLINK_MSG_ID_GPS_RAW_INT: 2.0,
}


PARAM_REQUEST_QUEUE = 20
"""PARAM_REQUEST_READs ArduPilot holds before it answers them, for all its links together
(``GCS_MAVLINK::param_requests``, libraries/GCS_MAVLink/GCS_Param.cpp): one more is
dropped (handle_param_request_read: no space)."""

MAX_SLOWDOWN_MS = 2000
"""GCS_MAVLINK::handle_radio_status grows the slowdown no further once it reaches this."""


def radio_slowdown(slowdown_ms: int, txbuf: int) -> int:
    """ArduPilot's software flow control: a link's ``stream_slowdown_ms`` after a
    RADIO_STATUS whose ``txbuf`` (the radio's free buffer, per cent) is given
    (GCS_MAVLINK::handle_radio_status, libraries/GCS_MAVLink/GCS_Common.cpp): below 20 %
    60 ms more, below 50 % 20 ms more (while under 2 s); above 95 % 40 ms less (while over
    200 ms), above 90 % 20 ms less."""
    if txbuf < 20 and slowdown_ms < MAX_SLOWDOWN_MS:
        return slowdown_ms + 60
    if txbuf < 50 and slowdown_ms < MAX_SLOWDOWN_MS:
        return slowdown_ms + 20
    if txbuf > 95 and slowdown_ms > 200:
        return slowdown_ms - 40
    if txbuf > 90 and slowdown_ms != 0:
        return slowdown_ms - 20 if slowdown_ms > 20 else 0
    return slowdown_ms


def reschedule_interval_s(interval_s: float, slowdown_ms: int) -> float:
    """A stream message's next interval on a slowed link: its interval plus the slowdown,
    at most 60 s (GCS_MAVLINK::get_reschedule_interval_ms, GCS_Common.cpp; the x4 while
    parameters or mission items are being sent is not modelled)."""
    return min(interval_s + slowdown_ms / 1000.0, 60.0)


CLOCK_HZ = 1.0
"""SYSTEM_TIME (the vehicle's UTC clock, AP_RTC, beside its boot clock) during a flight:
the timed start of the legs is set by it (:mod:`ftlbo_mav.flight.launch`)."""


def flight_streams(position_hz: float, status_hz: float = 2.0) -> dict[int, float]:
    """A flight's needs: readiness, the position at ``position_hz``, the current item and
    the EKF's health (the navigation budget is watched on GPS_RAW_INT and it), these at
    ``status_hz`` (a slow shared radio: less, :mod:`ftlbo_mav.link.budget`), and the
    vehicle's clock at :data:`CLOCK_HZ`."""
    return {R.MAVLINK_MSG_ID_SYS_STATUS: status_hz, R.MAVLINK_MSG_ID_GPS_RAW_INT: status_hz,
            R.MAVLINK_MSG_ID_GLOBAL_POSITION_INT: position_hz,
            R.MAVLINK_MSG_ID_MISSION_CURRENT: status_hz,
            R.MAVLINK_MSG_ID_EKF_STATUS_REPORT: status_hz,
            R.MAVLINK_MSG_ID_SYSTEM_TIME: CLOCK_HZ}


def message_name(msgid: int) -> str:
    cls = R.mavlink_map.get(msgid)
    return cls.msgname if cls is not None else str(msgid)


RATE_WINDOW_S = 2.0
"""A stream counts as flowing once it arrives at half its rate or more over this long (on
SITL one copter's GLOBAL_POSITION_INT, asked at 10 Hz, once came at 1 Hz for a whole
flight: arriving, so never asked again, and the keeper measured on a position up to a
second old)."""


@dataclass
class _Want:
    hz: float
    last_seen: float | None = None
    last_asked: float | None = None
    asked: int = 0
    refused: bool = False  # SET_MESSAGE_INTERVAL answered with anything but ACCEPTED
    arrivals: deque = field(default_factory=deque)  # the last RATE_WINDOW_S of them
    since: float | None = None  # seen since then without a gap (its rate can be judged)

    def arrived(self, now: float) -> None:
        if self.last_seen is None or now - self.last_seen > RATE_WINDOW_S:
            self.since = now
        self.last_seen = now
        self.arrivals.append(now)
        while self.arrivals and now - self.arrivals[0] > RATE_WINDOW_S:
            self.arrivals.popleft()

    def too_slow(self, now: float) -> bool:
        """Arriving, for long enough to tell, at less than half the rate asked."""
        if self.since is None or now - self.since < RATE_WINDOW_S:
            return False
        return self._recent(now) < 0.5 * self.hz * RATE_WINDOW_S

    def rate(self, now: float) -> float:
        return self._recent(now) / RATE_WINDOW_S

    def _recent(self, now: float) -> int:
        """How many arrived within the window before ``now`` (in order: the old ones lead)."""
        n = len(self.arrivals)
        for t in self.arrivals:
            if now - t <= RATE_WINDOW_S:
                break
            n -= 1
        return n


@dataclass
class StreamRequests:
    """The streams one vehicle on one link should send us, and what to send to get them.

    A pure state machine (no I/O): :meth:`want` adds messages and rates, :meth:`seen` and
    :meth:`on_ack` feed what arrives, :meth:`due` returns the requests to send now. A
    message that has not arrived within ``patience(hz)`` of being asked is asked again
    every ``retry_s``; from the ``legacy_after``-th try, or once SET_MESSAGE_INTERVAL is
    refused, REQUEST_DATA_STREAM for its group goes with it.
    """

    sysid: int
    compid: int = 1
    retry_s: float = 2.0
    legacy_after: int = 3
    wants: dict[int, _Want] = field(default_factory=dict)

    def want(self, rates: Mapping[int, float]) -> None:
        """Ask for each message at (at least) its rate; a higher rate asks again at once."""
        for msgid, hz in rates.items():
            w = self.wants.get(msgid)
            if w is None:
                self.wants[msgid] = _Want(hz=hz)
            elif hz > w.hz:
                w.hz, w.last_asked, w.last_seen, w.since = hz, None, None, None

    def seen(self, msgid: int, now: float) -> None:
        w = self.wants.get(msgid)
        if w is not None:
            w.arrived(now)

    def on_ack(self, msgid: int | None, result: int) -> None:
        """A COMMAND_ACK of SET_MESSAGE_INTERVAL (ArduPilot's ack names no message: a
        refusal marks every message asked for and not yet flowing)."""
        if result == R.MAV_RESULT_ACCEPTED:
            return
        for m, w in self.wants.items():
            if msgid in (None, m) and w.last_seen is None:
                w.refused = True

    @staticmethod
    def patience(hz: float) -> float:
        """How long a message may be missing before it is asked for again."""
        return max(1.5, 3.0 / hz)

    def flowing(self, msgid: int, now: float) -> bool:
        """Arriving, and at half its rate or more (:data:`RATE_WINDOW_S`)."""
        w = self.wants.get(msgid)
        return (w is not None and w.last_seen is not None
                and now - w.last_seen <= self.patience(w.hz) and not w.too_slow(now))

    def due(self, now: float) -> list:
        """The requests to send now (COMMAND_LONG and REQUEST_DATA_STREAM messages)."""
        out, groups = [], {}
        for msgid, w in self.wants.items():
            if self.flowing(msgid, now):
                continue
            if w.last_asked is not None and now - w.last_asked < self.retry_s:
                continue
            w.last_asked, w.asked = now, w.asked + 1
            out.append(R.MAVLink_command_long_message(
                self.sysid, self.compid, R.MAV_CMD_SET_MESSAGE_INTERVAL, 0, msgid,
                1e6 / w.hz, 0, 0, 0, 0, 0))
            if (w.refused or w.asked >= self.legacy_after) and msgid in STREAM_OF:
                group = STREAM_OF[msgid]
                groups[group] = max(groups.get(group, 0), w.hz)
        for group, hz in groups.items():
            out.append(R.MAVLink_request_data_stream_message(
                self.sysid, self.compid, group, max(1, round(hz)), 1))
        return out

    def stop(self, msgids) -> list:
        """Want these no more: the requests that stop them (SET_MESSAGE_INTERVAL with an
        interval of -1, GCS_Common.cpp ``handle_command_set_message_interval``: the
        message is no longer sent on that link; a fresh ArduCopter 4.5.6 sends neither
        on SERIAL0 unasked, tests/data boot recording)."""
        out = []
        for msgid in msgids:
            if self.wants.pop(msgid, None) is not None:
                out.append(R.MAVLink_command_long_message(
                    self.sysid, self.compid, R.MAV_CMD_SET_MESSAGE_INTERVAL, 0, msgid, -1,
                    0, 0, 0, 0, 0))
        return out

    def missing(self, now: float) -> list[str]:
        """Names of the wanted messages not arriving, with how often each was asked."""
        return [f"{message_name(m)} (asked {w.asked}x"
                + (f"; {w.rate(now):.1f}/s of {w.hz:g}/s)" if w.too_slow(now) else ")")
                for m, w in self.wants.items() if not self.flowing(m, now)]


# REQUEST_DATA_STREAM groups (ArduCopter/GCS_Mavlink.cpp ``STREAM_*_msgs`` and
# ``all_stream_entries``), as the MAVLink messages they send; MAV_DATA_STREAM_ALL sets
# every group (GCS_MAVLINK::handle_request_data_stream).
STREAM_MESSAGES: Mapping[int, tuple[int, ...]] = {
    R.MAV_DATA_STREAM_RAW_SENSORS: (
        R.MAVLINK_MSG_ID_RAW_IMU, R.MAVLINK_MSG_ID_SCALED_IMU2, R.MAVLINK_MSG_ID_SCALED_IMU3,
        R.MAVLINK_MSG_ID_SCALED_PRESSURE, R.MAVLINK_MSG_ID_SCALED_PRESSURE2,
        R.MAVLINK_MSG_ID_SCALED_PRESSURE3),
    R.MAV_DATA_STREAM_EXTENDED_STATUS: (
        R.MAVLINK_MSG_ID_SYS_STATUS, R.MAVLINK_MSG_ID_POWER_STATUS, R.MAVLINK_MSG_ID_MEMINFO,
        R.MAVLINK_MSG_ID_MISSION_CURRENT, R.MAVLINK_MSG_ID_GPS_RAW_INT,
        R.MAVLINK_MSG_ID_GPS_RTK, R.MAVLINK_MSG_ID_GPS2_RAW, R.MAVLINK_MSG_ID_GPS2_RTK,
        R.MAVLINK_MSG_ID_NAV_CONTROLLER_OUTPUT, R.MAVLINK_MSG_ID_FENCE_STATUS,
        R.MAVLINK_MSG_ID_POSITION_TARGET_GLOBAL_INT),
    R.MAV_DATA_STREAM_POSITION: (
        R.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, R.MAVLINK_MSG_ID_LOCAL_POSITION_NED),
    R.MAV_DATA_STREAM_RC_CHANNELS: (
        R.MAVLINK_MSG_ID_SERVO_OUTPUT_RAW, R.MAVLINK_MSG_ID_RC_CHANNELS),
    R.MAV_DATA_STREAM_EXTRA1: (
        R.MAVLINK_MSG_ID_ATTITUDE, R.MAVLINK_MSG_ID_SIMSTATE, R.MAVLINK_MSG_ID_AHRS2),
    R.MAV_DATA_STREAM_EXTRA2: (R.MAVLINK_MSG_ID_VFR_HUD,),
    R.MAV_DATA_STREAM_EXTRA3: (
        R.MAVLINK_MSG_ID_AHRS, R.MAVLINK_MSG_ID_SYSTEM_TIME, R.MAVLINK_MSG_ID_WIND,
        R.MAVLINK_MSG_ID_BATTERY_STATUS, R.MAVLINK_MSG_ID_EKF_STATUS_REPORT,
        R.MAVLINK_MSG_ID_VIBRATION, R.MAVLINK_MSG_ID_ESC_TELEMETRY_1_TO_4),
}


def data_stream_messages(stream_id: int) -> tuple[int, ...]:
    """The messages REQUEST_DATA_STREAM ``stream_id`` sets the rate of."""
    if stream_id == R.MAV_DATA_STREAM_ALL:
        return tuple(m for group in STREAM_MESSAGES.values() for m in group)
    return STREAM_MESSAGES.get(stream_id, ())
