"""What a vehicle last said about itself, seen from the ground: :class:`Status`.

The mode, arming, position and the rest a flight reads, with what the ground learns of
the link from the same reports: the gaps between position reports (:class:`GapLog`),
their delays and jitter, the vehicle's clock against the ground's. Plain values: the
:class:`~.vehicle.FlightVehicle` that owns a Status keeps it up to date.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field

GAP_REPORTS = 400  # 40 s of positions at 10 Hz
CLOCK_REPORTS = 20  # a report's time is judged against the least delayed of this many
DELAY_REPORTS = 50  # a link's delays are judged over this many reports (5 s at 10 Hz)
CLOCK_LINE_REPORTS = 600
"""The vehicle's clock against the ground's, for a start timed to the millisecond
(:meth:`Status.clock_line`), from this many reports (a minute at 10 Hz): over 25 s of a
flight's reports SITL's three copters' clocks came out within 11 ms of each other's truth
through TCP, 20 ms through the good-day radio, 38 ms through the rough day's; over 20
reports, 40-300 ms (sitl.truth's GPS-timed logs, 2026-12-07)."""


def quantile(values, q: float) -> float:
    """``numpy.quantile(values, q)`` (its default, linear method) on a few plain floats,
    without numpy's set-up: the same number, computed as numpy computes it."""
    a = sorted(float(v) for v in values)
    n = len(a)
    index = (n - 1) * q  # numpy's "linear" virtual index
    lo = min(max(math.floor(index), 0), n - 1)
    hi = min(lo + 1, n - 1)
    t = index - math.floor(index)
    diff = a[hi] - a[lo]
    return a[hi] - diff * (1.0 - t) if t >= 0.5 else a[lo] + diff * t  # numpy's _lerp


class GapLog:
    """The silences between position reports: ``(arrival, seconds since the one before)``
    of the last ``maxlen`` reports (arrivals in order), and the longest since a time
    without a scan (the keeper asks 20 times a second over 200 reports): a queue of the
    reports that no later one matches, longest first."""

    def __init__(self, maxlen: int) -> None:
        self._all: deque = deque(maxlen=maxlen)
        self._peaks: deque = deque()  # (count, arrival, gap), gaps strictly decreasing
        self._count = 0

    def append(self, item: tuple[float, float]) -> None:
        t, gap = item
        self._all.append(item)
        self._count += 1
        while self._peaks and self._peaks[-1][2] <= gap:
            self._peaks.pop()
        self._peaks.append((self._count, t, gap))
        oldest = self._count - len(self._all) + 1  # the reports still kept
        while self._peaks[0][0] < oldest:
            self._peaks.popleft()

    def extend(self, items) -> None:
        for item in items:
            self.append(item)

    def longest_since(self, since: float) -> float | None:
        """The longest gap that arrived at ``since`` or later (None: none did)."""
        for _n, t, gap in self._peaks:
            if t >= since:
                return gap
        return None

    def __iter__(self):
        return iter(self._all)

    def __reversed__(self):
        return reversed(self._all)

    def __len__(self) -> int:
        return len(self._all)


@dataclass
class Status:
    """What the vehicle last said about itself; ``t`` values are ``clock.monotonic()``."""

    mode: str = "?"
    armed: bool = False
    lat_deg: float | None = None
    lon_deg: float | None = None
    alt_m: float = 0.0
    climb_m_s: float = 0.0
    ground_speed_m_s: float = 0.0
    velocity_enu: tuple[float, float, float] = (0.0, 0.0, 0.0)
    seq: int = -1
    position_t: float = 0.0
    position_boot_s: float = 0.0
    # when the vehicle's clock read 0 on the ground clock, from the least-delayed of its
    # recent reports: a report's own time on the ground clock is clock_offset_s +
    # position_boot_s / clock_rate (reports can arrive in bursts, so the arrival time
    # overstates how fresh a position is)
    clock_offset_s: float | None = None
    # vehicle seconds per ground second (1 but on a simulator run faster than real time:
    # an emulator's time scale, SITL's --speedup), from the reports of the last while
    clock_rate: float = 1.0
    # (arrival, its boot time) of its last reports: the least delayed of the last
    # CLOCK_REPORTS place each report, of all of them the clock line (:meth:`clock_line`)
    _clock_pairs: deque = field(default_factory=lambda: deque(maxlen=CLOCK_LINE_REPORTS))
    # each position report's delay beyond the least delayed of its neighbours (the
    # vehicle's seconds), the last DELAY_REPORTS: how much a link's latency varies
    delays: deque = field(default_factory=lambda: deque(maxlen=DELAY_REPORTS))
    _rate_since: tuple[float, float] | None = None  # (ground, vehicle) seconds
    _jitter: tuple | None = None  # ((report time, count), jitter_s) last computed
    # silences between position reports: (arrival, seconds since the one before, both
    # ground), the last GAP_REPORTS
    gaps: GapLog = field(default_factory=lambda: GapLog(GAP_REPORTS))
    heartbeat_t: float = 0.0
    heard_t: float = 0.0  # the last message of any kind from the vehicle
    # every STATUSTEXT as (arrival time, severity, text), the last 50; text_count counts
    # them all, so a watcher knows which ones are new
    text_log: list[tuple[float, int, str]] = field(default_factory=list)
    text_count: int = 0
    acks: dict[int, int] = field(default_factory=dict)
    params: dict[str, float] = field(default_factory=dict)
    # the last GPS_RAW_INT and EKF_STATUS_REPORT as received (flight/navigation.py
    # reads them: gps_report, ekf_report)
    gps_raw: object | None = None
    ekf_raw: object | None = None
    gps_jump_m: float = 0.0  # the largest GPS jump while armed (flight/navigation.py)
    gps_jump_enu: tuple[float, float] = (0.0, 0.0)  # that jump, east and north (m)
    # SYS_STATUS: the charge left (per cent; None: not reported, -1 on the wire) and the
    # current drawn (A)
    battery_pct: int | None = None
    battery_current_a: float = 0.0
    photos: int = 0  # CAMERA_FEEDBACK messages received
    # what the vehicle says it is: HEARTBEAT type and autopilot, AUTOPILOT_VERSION's
    # flight_sw_version (asked for at pre-flight; ardupilot/firmware.py judges them)
    vehicle_type: int | None = None
    autopilot: int | None = None
    firmware_version: int | None = None
    # SYSTEM_TIME: its UTC clock (AP_RTC, from its GPS) less its boot clock, seconds;
    # None until it has one
    utc_offset_s: float | None = None

    def vehicle_now(self, now: float) -> float | None:
        """Its boot clock at ground time ``now`` (seconds; None before a position report)."""
        if self.clock_offset_s is None:
            return None
        return (now - self.clock_offset_s) * self.clock_rate

    def clock_line(self) -> tuple[float, float] | None:
        """``(offset_s, rate)``: when the vehicle's clock read 0 on the ground clock, and
        its seconds per ground second, from the least delayed of the last
        :data:`CLOCK_LINE_REPORTS` reports: the rate between the least delayed of the
        first and of the last third of them (two noisy arrivals a minute apart would be
        tens of milliseconds out over a minute), the offset from the least delayed of the
        last third. None before there are 30."""
        pairs = list(self._clock_pairs)
        if len(pairs) < 30:
            return None
        third = len(pairs) // 3
        first = min(pairs[:third], key=lambda p: p[0] - p[1] / self.clock_rate)
        last = min(pairs[-third:], key=lambda p: p[0] - p[1] / self.clock_rate)
        rate = self.clock_rate
        if last[0] - first[0] > 1.0 and last[1] > first[1]:
            rate = (last[1] - first[1]) / (last[0] - first[0])
        return min(t - b / rate for t, b in pairs[-third:]), rate

    def utc_now(self, now: float) -> float | None:
        """Its UTC clock at ground time ``now`` (seconds since the epoch), or None."""
        boot = self.vehicle_now(now)
        return None if boot is None or self.utc_offset_s is None else boot + self.utc_offset_s

    def longest_gap_s(self, now: float, window_s: float) -> float:
        """The longest silence between position reports in the last ``window_s`` of the
        vehicle's seconds (and the one going on now), in its seconds."""
        rate = self.clock_rate
        since = now - window_s / rate
        longest = now - self.position_t if self.position_t else 0.0
        recent = self.gaps.longest_since(since)
        if recent is not None:
            longest = max(longest, recent)
        return longest * rate

    def jitter_s(self) -> float | None:
        """The 90th percentile of the recent reports' delays beyond the least delayed
        (the vehicle's seconds); None before there are 20."""
        if len(self.delays) < 20:
            return None
        key = (self.position_t, len(self.delays))  # a delay is added with each report
        if self._jitter is None or self._jitter[0] != key:
            self._jitter = (key, quantile(self.delays, 0.9))
        return self._jitter[1]

    @property
    def texts(self) -> list[str]:
        """The last 20 STATUSTEXTs' words."""
        return [text for _t, _severity, text in self.text_log[-20:]]
