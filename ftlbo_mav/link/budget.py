"""What a flight asks of the link, against what the link carries.

Every copter sends what ``fly`` asks for (:func:`~ftlbo_mav.ardupilot.streams.flight_streams`:
the position at ``position_hz``, SYS_STATUS, GPS_RAW_INT, MISSION_CURRENT,
EKF_STATUS_REPORT) and what ArduPilot sends unasked (HEARTBEAT, TIMESYNC; STATUSTEXT and
the answers to our commands now and then); the ground station sends its HEARTBEAT and,
on the legs, the formation keeper's pauses and continues. Each frame is MAVLink 2: 10
bytes of header, the payload (its full length: ArduPilot trims trailing zero bytes, so
frames are often shorter) and 2 of checksum, 13 more when signed. Pure.

A link is given as bytes a second (``--link 6000``) or by name (:data:`LINKS`). One air
time serves both directions and every copter (a telemetry radio is half duplex); a
flight fits when it needs at most :data:`HEADROOM` of it, and :func:`choose` takes the
fastest rates of :data:`RATES` that fit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as R

from ..ardupilot.streams import flight_streams
from ..errors import BadInput

HEADER, CHECKSUM, SIGNATURE = 10, 2, 13

USABLE_SHARE = 0.75
"""Of a radio's air rate, the share that carries our frames (the rest: its time-division
slots' sync and turnaround, its own headers). An assumption, stated: a SiK radio at its
default 64 kbit/s then carries 6,000 bytes a second, the figure of the shared-radio
trials in docs/link.md."""

LINKS = {
    # SiK firmware's AIR_SPEED choices (kbit/s) most used on copters; the RFD900 runs the
    # same firmware
    "sik-64": 64_000 / 8 * USABLE_SHARE,
    "sik-128": 128_000 / 8 * USABLE_SHARE,
    "sik-250": 250_000 / 8 * USABLE_SHARE,
    "wifi": 1_000_000.0,  # a local WiFi network: not what limits a swarm of copters
}
"""Named links, bytes a second for both directions together."""

HEADROOM = 0.7
"""The share of the link a flight may ask for: the rest for retries, bursts, the mission
protocol's replies and what we did not count."""
RATES = ((10.0, 2.0), (5.0, 2.0), (5.0, 1.0), (4.0, 1.0), (2.0, 1.0), (2.0, 0.5), (1.0, 0.5))
"""``(position, status)`` rates (Hz) tried, fastest first. The formation keeper measures
at 20 Hz and the departure watch expects a position within a second; below 10 Hz both
see later."""

STATUSTEXT_PER_S = 0.2  # ArduPilot's texts in flight, a few a minute
KEEPER_COMMANDS_PER_S = 1.0  # pauses and continues per copter at most, with the repeats
GCS_HEARTBEAT_HZ = 1.0


def frame_bytes(msgid: int, *, signed: bool = False) -> int:
    """The longest MAVLink 2 frame of message ``msgid``."""
    payload = R.mavlink_map[msgid].unpacker.size
    return HEADER + payload + CHECKSUM + (SIGNATURE if signed else 0)


@dataclass(frozen=True)
class Budget:
    """Bytes a second a flight asks for: ``down`` from each copter, ``up`` to each
    copter, ``shared`` the ground station's own (its HEARTBEAT, once per link);
    ``position_hz`` and ``status_hz`` the rates it was made for."""

    copters: int
    position_hz: float
    status_hz: float
    down: float
    up: float
    shared: float

    @property
    def total(self) -> float:
        return self.copters * (self.down + self.up) + self.shared

    def share(self, link_bytes_per_s: float) -> float:
        return self.total / link_bytes_per_s

    def describe(self, link_bytes_per_s: float | None = None) -> str:
        text = (f"{self.copters} copter(s) at {self.position_hz:g} Hz positions "
                f"({self.status_hz:g} Hz status) ask "
                f"{self.down:,.0f} B/s down and {self.up:,.0f} B/s up each, "
                f"{self.total:,.0f} B/s in all")
        if link_bytes_per_s:
            text += f": {100 * self.share(link_bytes_per_s):.0f} % of {link_bytes_per_s:,.0f} B/s"
        return text


def flight_budget(copters: int, position_hz: float, status_hz: float = 2.0, *,
                  signed: bool = False) -> Budget:
    """What a flight of ``copters`` asks of the link at these rates."""
    down = sum(hz * frame_bytes(m, signed=signed)
               for m, hz in flight_streams(position_hz, status_hz).items())
    down += frame_bytes(R.MAVLINK_MSG_ID_HEARTBEAT, signed=signed) * 1.0
    down += frame_bytes(R.MAVLINK_MSG_ID_TIMESYNC, signed=signed) * 0.1
    down += frame_bytes(R.MAVLINK_MSG_ID_STATUSTEXT, signed=signed) * STATUSTEXT_PER_S
    down += frame_bytes(R.MAVLINK_MSG_ID_COMMAND_ACK, signed=signed) * KEEPER_COMMANDS_PER_S
    up = frame_bytes(R.MAVLINK_MSG_ID_COMMAND_LONG, signed=signed) * KEEPER_COMMANDS_PER_S
    shared = frame_bytes(R.MAVLINK_MSG_ID_HEARTBEAT, signed=signed) * GCS_HEARTBEAT_HZ
    return Budget(copters, position_hz, status_hz, down, up, shared)


def parse_link(text: str) -> tuple[float, str]:
    """``(bytes a second, name)`` of ``--link``: a number (bytes a second) or a name of
    :data:`LINKS`; :class:`BadInput` otherwise."""
    key = text.strip().lower()
    if key in LINKS:
        return LINKS[key], key
    try:
        value = float(key)
    except ValueError:
        raise BadInput(f"--link {text!r}: bytes a second (e.g. 6000) or one of "
                       f"{', '.join(LINKS)}") from None
    if not (math.isfinite(value) and value > 0):
        raise BadInput(f"--link {text!r}: bytes a second must be a number above 0")
    return value, f"{value:,.0f} B/s"


def choose(copters: int, link_bytes_per_s: float, *, wanted_hz: float = 10.0,
           signed: bool = False) -> Budget:
    """The fastest rates of :data:`RATES` (positions up to ``wanted_hz``) whose flight
    fits :data:`HEADROOM` of the link; :class:`BadInput` with the figures when not even
    the slowest does."""
    rates = [r for r in RATES if r[0] <= wanted_hz] or [RATES[-1]]
    for position_hz, status_hz in rates:
        b = flight_budget(copters, position_hz, status_hz, signed=signed)
        if b.total <= HEADROOM * link_bytes_per_s:
            return b
    slowest = flight_budget(copters, *rates[-1], signed=signed)
    most = max(0, int((HEADROOM * link_bytes_per_s - slowest.shared)
                      // (slowest.down + slowest.up)))
    raise BadInput(f"the link cannot carry this swarm: {slowest.describe(link_bytes_per_s)}, "
                   f"more than the {100 * HEADROOM:.0f} % a flight may use; at most {most} "
                   "copter(s) fit this link (a faster radio, or fewer copters per radio)")


__all__ = ["Budget", "HEADROOM", "LINKS", "RATES", "USABLE_SHARE", "choose",
           "flight_budget", "frame_bytes", "parse_link"]
