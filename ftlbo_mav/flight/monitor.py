"""Watching a formation: the recorder behind every position report, and the live view.

:class:`Monitor` is handed to each :class:`~ftlbo_mav.flight.vehicle.FlightVehicle` as
its ``on_position`` hook; it records samples (time since the monitor started) and
renders a few lines per vehicle plus one for the group.
"""

from __future__ import annotations

import threading
import time

import numpy as np

from .metrics import min_clearance, min_separation, slot_errors
from .planned import PlannedFlight
from .record import FlightRecord, Sample


class Monitor:
    """Records every position report; ``planned`` (optional) gives offsets and obstacles."""

    def __init__(self, planned: PlannedFlight | None = None) -> None:
        self.planned = planned
        self.record = FlightRecord()
        self.t0 = time.monotonic()
        self._lock = threading.Lock()
        self.vehicles: list = []

    def __call__(self, vehicle) -> None:
        s = vehicle.status
        if s.lat_deg is None:
            return
        sample = Sample(s.position_t - self.t0, vehicle.sysid, s.lat_deg, s.lon_deg, s.alt_m,
                        s.mode, s.armed, s.seq if s.mode == "AUTO" else -1, s.position_boot_s)
        with self._lock:
            self.record.add(sample)

    def positions(self) -> np.ndarray | None:
        """Latest positions ``(N, 3)`` metres ENU in the plan's frame (None if unknown)."""
        if self.planned is None or any(v.status.lat_deg is None for v in self.vehicles):
            return None
        st = [v.status for v in self.vehicles]
        return self.planned.frame.to_enu(lat_deg=[s.lat_deg for s in st],
                                         lon_deg=[s.lon_deg for s in st],
                                         alt_m=[s.alt_m for s in st])

    def lines(self) -> list[str]:
        """The live view: one line per vehicle, one for the group."""
        out = []
        pos = self.positions()
        slots = slot_errors(pos, self.planned.offsets) if pos is not None else None
        for n, v in enumerate(self.vehicles):
            s = v.status
            total = len(self.planned.missions[n]) - 1 if self.planned else None
            item = "-" if s.seq < 0 else f"{s.seq}/{total}" if total else str(s.seq)
            slot = f"slot {slots[n]:5.2f} m" if slots is not None else ""
            age = time.monotonic() - s.heartbeat_t if s.heartbeat_t else float("inf")
            stale = "  NO HEARTBEAT" if age > 3.0 else ""
            out.append(f"{v.name:>5} sysid {v.sysid:<3} {s.mode:<9} "
                       f"{'ARMED' if s.armed else 'disarmed':<8} alt {s.alt_m:5.1f} m  "
                       f"item {item:<6} {slot}{stale}")
        if pos is not None:
            err = float(np.sqrt(np.mean(slots**2)))
            sep = float(min_separation(pos))
            clear = float(min_clearance(pos, self.planned.centres, self.planned.radii))
            out.append(f"formation error {err:.2f} m RMS   smallest separation {sep:.2f} m   "
                       f"smallest clearance {clear:.2f} m")
        return out


class LiveView:
    """Redraws the monitor's lines in place on a terminal, or prints them every few
    seconds into a log or pipe."""

    def __init__(self, monitor: Monitor, stream, *, period_s: float = 0.5) -> None:
        self.monitor, self.stream = monitor, stream
        self.tty = hasattr(stream, "isatty") and stream.isatty()
        self.period_s = period_s if self.tty else max(period_s, 5.0)
        self._drawn = 0
        self._next = 0.0

    def message(self, text: str) -> None:
        self._clear()
        self.stream.write(text + "\n")
        self.stream.flush()

    def _clear(self) -> None:
        if self.tty and self._drawn:
            self.stream.write(f"\x1b[{self._drawn}F\x1b[J")
        self._drawn = 0

    def update(self, *, force: bool = False) -> None:
        now = time.monotonic()
        if not force and now < self._next:
            return
        self._next = now + self.period_s
        lines = self.monitor.lines()
        self._clear()
        self.stream.write("\n".join(lines) + "\n")
        self.stream.flush()
        self._drawn = len(lines) if self.tty else 0
