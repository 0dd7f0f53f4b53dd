"""One telemetry radio for the whole swarm: a shared, slow, lossy, half-duplex link.

In the field a ground station reaches its copters through one multipoint radio (SiK,
RFD900, a mesh radio) or one WiFi network: every copter's telemetry and every command
share one air time. :class:`SharedRadio` models that between the emulator's vehicles
and the ground station (``ftlbo-mav sim --radio``):

- **air time**: ``bytes_per_s`` of MAVLink frames (plus ``frame_overhead`` bytes of the
  radio's own framing each) for both directions together, one frame on the air at a time,
  in the order the frames were handed to the radios (half duplex);
- **a buffer per radio**: ``buffer_bytes`` waiting for air time at each copter's radio
  and at the ground's; a frame that does not fit is dropped, as a SiK radio drops serial
  data it has no room for;
- **latency**: ``latency_s`` after its air time, give or take ``jitter_s`` (uniform), a
  frame arrives; frames of one direction arrive in the order they were sent;
- **loss**: ``loss`` of the frames on the air are lost, in bursts of ``burst`` frames on
  average (a two-state channel: a frame is lost in the bad state, the good one loses
  none), and nothing gets through during an outage of ``outage_s`` every ``outage_every_s``
  seconds (a copter behind a tree line).

Time is the vehicles' (seconds of the emulator's clock, which a time scale runs faster):
the radio is as fast as the copters' clock. Pure and seeded: a run is repeatable.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, replace

import numpy as np

UP, DOWN = "up", "down"
"""To the vehicles, from the vehicles."""
RADIO_SYSID, RADIO_COMPID = 51, 68
"""What a SiK radio's own RADIO_STATUS comes from ('3', 'D')."""
RADIO_STATUS_S = 1.0
"""How often each radio reports RADIO_STATUS to its end."""


@dataclass(frozen=True)
class RadioOptions:
    """The radio's figures (module notes). The defaults are the issue's good day: 6,000
    bytes a second, 60 +- 40 ms, 3 % of frames lost, a 2 KiB buffer."""

    bytes_per_s: float = 6000.0
    latency_s: float = 0.06
    jitter_s: float = 0.04
    loss: float = 0.03
    burst: float = 1.0
    buffer_bytes: int = 2048
    frame_overhead: int = 0
    outage_s: float = 0.0
    outage_every_s: float = 0.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.bytes_per_s) and self.bytes_per_s > 0):
            raise ValueError(f"bytes_per_s must be > 0, got {self.bytes_per_s!r}")
        for name in ("latency_s", "jitter_s", "outage_s", "outage_every_s"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
        if self.jitter_s > self.latency_s:
            raise ValueError(f"jitter_s ({self.jitter_s:g}) must not exceed latency_s "
                             f"({self.latency_s:g}): a frame cannot arrive before it is sent")
        if not 0.0 <= self.loss < 1.0:
            raise ValueError(f"loss must be within [0, 1), got {self.loss!r}")
        if not self.burst >= 1.0:
            raise ValueError(f"burst must be >= 1 frame, got {self.burst!r}")
        if self.buffer_bytes < 280:  # one MAVLink 2 frame, signed, at its longest
            raise ValueError(f"buffer_bytes must hold a frame (>= 280), got {self.buffer_bytes}")
        if self.frame_overhead < 0:
            raise ValueError(f"frame_overhead must be >= 0, got {self.frame_overhead}")
        if self.outage_s and not self.outage_every_s > self.outage_s:
            raise ValueError("outage_every_s must be longer than outage_s")


ROUGH_DAY = RadioOptions(latency_s=0.12, jitter_s=0.08, loss=0.10, burst=3.0, outage_s=1.0,
                         outage_every_s=15.0)
"""The issue's rough day on the same radio: 120 +- 80 ms, 10 % lost in bursts, a 1 s
outage every 15 s."""


@dataclass
class RadioCounts:
    """What went over the radio: frames and bytes handed to it each way, delivered,
    dropped at a full buffer, lost on the air; the air time used (seconds)."""

    sent: dict
    delivered: dict
    sent_bytes: dict
    full: dict
    lost: dict
    air_s: float = 0.0

    @classmethod
    def empty(cls) -> RadioCounts:
        zero = {UP: 0, DOWN: 0}
        return cls(dict(zero), dict(zero), dict(zero), dict(zero), dict(zero))


class SharedRadio:
    """The shared link (module notes): ``send(direction, size, now, radio)`` hands a frame
    of ``size`` bytes to ``radio`` (0 the ground's, a copter's system id); it returns when
    the frame arrives on the other side (seconds of the same clock), or None when it is
    dropped (a full buffer) or lost (the air)."""

    def __init__(self, options: RadioOptions, rng: np.random.Generator) -> None:
        self.options = options
        self.rng = rng
        self.air_free = 0.0  # when the air is next free
        self._queued: dict = {}  # (direction, radio) -> (air start, air end, bytes) waiting
        self._last_arrival = {UP: -math.inf, DOWN: -math.inf}
        self._bad = False  # the two-state channel's state
        self.counts = RadioCounts.empty()

    def buffered(self, direction: str, now: float, radio=0) -> int:
        """Bytes of ``direction`` still waiting in ``radio``'s buffer at ``now`` (the
        ground's: 0; a copter's: its system id)."""
        q = self._queued.setdefault((direction, radio), deque())
        while q and q[0][0] <= now:  # on the air: out of the buffer
            q.popleft()
        return sum(n for _start, _end, n in q)

    def txbuf_pct(self, direction: str, now: float, radio=0) -> int:
        """RADIO_STATUS's ``txbuf``: the free share of that radio's buffer, per cent."""
        free = 1.0 - self.buffered(direction, now, radio) / self.options.buffer_bytes
        return int(round(100 * max(0.0, free)))

    def send(self, direction: str, size: int, now: float, radio=0) -> float | None:
        o, c = self.options, self.counts
        c.sent[direction] += 1
        c.sent_bytes[direction] += size
        if self.buffered(direction, now, radio) + size > o.buffer_bytes:
            c.full[direction] += 1
            return None
        air = (size + o.frame_overhead) / o.bytes_per_s
        start = max(now, self.air_free)
        self.air_free = start + air
        c.air_s += air
        self._queued[(direction, radio)].append((start, self.air_free, size))
        if self._lost(start):
            c.lost[direction] += 1
            return None
        arrival = self.air_free + o.latency_s + (
            self.rng.uniform(-o.jitter_s, o.jitter_s) if o.jitter_s else 0.0)
        # in order, each way: strictly later than the last (frames due at one instant
        # were delivered in any order by the event loop's timer heap)
        arrival = max(arrival, self._last_arrival[direction] + 1e-6)
        self._last_arrival[direction] = arrival
        c.delivered[direction] += 1
        return arrival

    def _lost(self, when: float) -> bool:
        o = self.options
        if o.outage_s and (when % o.outage_every_s) >= o.outage_every_s - o.outage_s:
            return True
        if not o.loss:
            return False
        # two states: bad -> good after ``burst`` frames on average; good -> bad so that
        # the bad state's share of frames is ``loss``
        to_good = 1.0 / o.burst
        to_bad = o.loss * to_good / (1.0 - o.loss)
        self._bad = (self.rng.random() >= to_good) if self._bad else (self.rng.random() < to_bad)
        return self._bad


class StatusSender:
    """A radio's RADIO_STATUS frames (MAVLink 2, from system 51 component 68, as SiK
    radios send them): ``frame(txbuf)`` with the radio's counts of lost frames as
    ``rxerrors``; its own sequence numbers."""

    def __init__(self, radio: SharedRadio) -> None:
        from pymavlink.dialects.v20 import ardupilotmega as mavlink2

        self.radio = radio
        self._msg = mavlink2.MAVLink_radio_status_message
        self._mav = mavlink2.MAVLink(None, srcSystem=RADIO_SYSID, srcComponent=RADIO_COMPID)

    def frame(self, txbuf: int) -> bytes:
        c = self.radio.counts
        msg = self._msg(rssi=200, remrssi=200, txbuf=txbuf, noise=40, remnoise=40,
                        rxerrors=min(c.lost[UP] + c.lost[DOWN], 65535), fixed=0)
        buf = bytes(msg.pack(self._mav))
        self._mav.seq = (self._mav.seq + 1) % 256
        return buf


def split_frames(buffer: bytearray) -> list[bytes]:
    """The whole MAVLink frames at the front of ``buffer`` (a byte stream, as a serial
    port or TCP gives it), taken out of it; bytes before a frame's start (0xFE, MAVLink
    1; 0xFD, MAVLink 2, with its signature when flagged) are dropped, a partial frame
    stays for the next call. Frames are not checked (the radio carries bytes)."""
    out = []
    while buffer:
        starts = [k for k in (buffer.find(0xFD), buffer.find(0xFE)) if k >= 0]
        if not starts:
            buffer.clear()
            break
        del buffer[:min(starts)]
        if len(buffer) < 3:
            break
        n = buffer[1]
        size = 8 + n if buffer[0] == 0xFE else 12 + n + (13 if buffer[2] & 1 else 0)
        if len(buffer) < size:
            break
        out.append(bytes(buffer[:size]))
        del buffer[:size]
    return out


_KEYS = {"bytes": "bytes_per_s", "latency": "latency_s", "jitter": "jitter_s", "loss": "loss",
         "burst": "burst", "buffer": "buffer_bytes", "overhead": "frame_overhead",
         "outage": "outage_s", "every": "outage_every_s"}


def parse_radio(text: str) -> RadioOptions:
    """``sim --radio``: ``good`` (:class:`RadioOptions`' defaults), ``rough``
    (:data:`ROUGH_DAY`), optionally followed by ``,key=value`` pairs that change it
    (``bytes``, ``latency``, ``jitter`` seconds, ``loss``, ``burst`` frames, ``buffer``
    bytes, ``overhead`` bytes a frame, ``outage`` and ``every`` seconds), or the pairs
    alone on the good day. ValueError naming what is wrong."""
    parts = [p.strip() for p in text.split(",") if p.strip()]
    base = RadioOptions()
    if parts and "=" not in parts[0]:
        name = parts.pop(0).lower()
        if name not in ("good", "rough"):
            raise ValueError(f"{name!r}: good, rough, or key=value pairs")
        base = ROUGH_DAY if name == "rough" else base
    changes = {}
    for part in parts:
        key, _, value = part.partition("=")
        if key.strip() not in _KEYS or not value:
            raise ValueError(f"{part!r}: one of {', '.join(_KEYS)} = a number")
        field = _KEYS[key.strip()]
        try:
            changes[field] = int(value) if field in ("buffer_bytes", "frame_overhead") \
                else float(value)
        except ValueError:
            raise ValueError(f"{part!r}: not a number") from None
    return replace(base, **changes)


__all__ = ["DOWN", "RADIO_COMPID", "RADIO_STATUS_S", "RADIO_SYSID", "ROUGH_DAY", "UP",
           "parse_radio", "split_frames", "RadioCounts", "RadioOptions", "SharedRadio",
           "StatusSender"]
