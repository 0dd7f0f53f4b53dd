"""Watching a formation: the recorder behind every position report, and the live view.

:class:`Monitor` is handed to each :class:`~ftlbo_mav.flight.vehicle.FlightVehicle` as
its ``on_position`` hook; it records samples (time since the monitor started) and
renders a few lines per vehicle plus one for the group.
"""

from __future__ import annotations

import shutil
import threading

import numpy as np

from .. import clock
from .metrics import min_clearance, min_separation, slot_errors
from .navigation import navigation_short
from .planned import PlannedFlight
from .record import FlightRecord, Photo, Sample


class Monitor:
    """Records every position report; ``planned`` (optional) gives offsets and obstacles."""

    def __init__(self, planned: PlannedFlight | None = None) -> None:
        self.planned = planned
        self.record = FlightRecord()
        self.t0 = clock.monotonic()
        self._lock = threading.Lock()
        self.vehicles: list = []
        self.link_bytes_per_s: float | None = None  # the link fly was told of (--link)
        self._link_seen: list[tuple[float, int]] = []

    def __call__(self, vehicle) -> None:
        s = vehicle.status
        if s.lat_deg is None:
            return
        sample = Sample(s.position_t - self.t0, vehicle.sysid, s.lat_deg, s.lon_deg, s.alt_m,
                        s.mode, s.armed, s.seq if s.mode == "AUTO" else -1, s.position_boot_s,
                        s.battery_pct if s.battery_pct is not None else -1,
                        getattr(getattr(vehicle, "link", None), "bytes_in", {}).get(
                            vehicle.sysid, -1))
        with self._lock:
            self.record.add(sample)

    def photo(self, vehicle, msg, arrival: float) -> None:
        """A CAMERA_FEEDBACK of ``vehicle`` (its ``on_photo`` hook), recorded."""
        photo = Photo(arrival - self.t0, vehicle.sysid, msg.lat * 1e-7, msg.lng * 1e-7,
                      float(msg.alt_rel), int(msg.img_idx))
        with self._lock:
            self.record.add_photo(photo)

    def positions(self) -> np.ndarray | None:
        """Latest positions ``(N, 3)`` metres ENU in the plan's frame (None if unknown)."""
        if self.planned is None or any(v.status.lat_deg is None for v in self.vehicles):
            return None
        st = [v.status for v in self.vehicles]
        return self.planned.frame.to_enu(lat_deg=[s.lat_deg for s in st],
                                         lon_deg=[s.lon_deg for s in st],
                                         alt_m=[s.alt_m for s in st])

    def lines(self, max_lines: int | None = None) -> list[str]:
        """The live view: one line per vehicle, one for the group. With more vehicles than
        ``max_lines`` allows, a summary instead (:meth:`_summary`): the states counted,
        and the vehicles that need a look (no heartbeat, farthest from their slots)."""
        pos = self.positions()
        slots = slot_errors(pos, self.planned.offsets) if pos is not None else None
        if max_lines is not None and len(self.vehicles) + 1 > max_lines:
            return self._summary(pos, slots, max(max_lines, 5))
        out = [self._vehicle_line(n, slots) for n in range(len(self.vehicles))]
        if pos is not None:
            out.append(self._group_line(pos, slots))
        return out

    def _vehicle_line(self, n: int, slots) -> str:
        v = self.vehicles[n]
        s = v.status
        total = len(self.planned.missions[n]) - 1 if self.planned else None
        item = "-" if s.seq < 0 else f"{s.seq}/{total}" if total else str(s.seq)
        slot = f"slot {slots[n]:5.2f} m" if slots is not None else ""
        age = clock.monotonic() - s.heartbeat_t if s.heartbeat_t else float("inf")
        stale = "  NO HEARTBEAT" if age > 3.0 else ""
        battery = f"  batt {s.battery_pct:3d} %" if s.battery_pct is not None else ""
        return (f"{v.name:>5} sysid {v.sysid:<3} {s.mode:<9} "
                f"{'ARMED' if s.armed else 'disarmed':<8} alt {s.alt_m:5.1f} m  "
                f"item {item:<6} {slot}{battery}{navigation_short(s.gps_raw, s.ekf_raw)}"
                f"{stale}")

    def _group_line(self, pos: np.ndarray, slots: np.ndarray) -> str:
        err = float(np.sqrt(np.mean(slots**2)))
        sep = float(min_separation(pos))
        clear = float(min_clearance(pos, self.planned.centres, self.planned.radii))
        return (f"formation error {err:.2f} m RMS   smallest separation {sep:.2f} m   "
                f"smallest clearance {clear:.2f} m{self._link_text()}")

    def _link_text(self) -> str:
        """The links' use now (bytes a second both ways, of ``link_bytes_per_s`` when
        known) and the ground radio's RADIO_STATUS, when one reports."""
        links = {id(k): k for k in (getattr(v, "link", None) for v in self.vehicles)
                 if hasattr(k, "bytes_in")}.values()
        if not links:
            return ""
        now = clock.monotonic()
        total = sum(sum(k.bytes_in.values()) + k.bytes_out for k in links)
        self._link_seen.append((now, total))
        while len(self._link_seen) > 2 and now - self._link_seen[0][0] > 5.0:
            self._link_seen.pop(0)
        (t0, b0), (t1, b1) = self._link_seen[0], self._link_seen[-1]
        text = ""
        if t1 - t0 >= 1.0:
            clock_rate = self.vehicles[0].status.clock_rate if self.vehicles else 1.0
            rate = (b1 - b0) / (t1 - t0) / max(clock_rate, 1e-9)  # per second of their clock
            text = f"   link {rate:,.0f} B/s"
            if self.link_bytes_per_s:
                text += f" ({100 * rate / self.link_bytes_per_s:.0f} %)"
        radio = [k.radio_status for k in links if k.radio_status is not None]
        if radio:
            r = radio[0]
            text += f"   radio txbuf {r.txbuf} % rssi {r.rssi}/{r.remrssi}"
        return text

    def _summary(self, pos, slots, max_lines: int) -> list[str]:
        """At most ``max_lines`` lines for a swarm too large for a line each."""
        st = [v.status for v in self.vehicles]
        now = clock.monotonic()
        modes: dict[str, int] = {}
        for s in st:
            modes[s.mode] = modes.get(s.mode, 0) + 1
        armed = sum(bool(s.armed) for s in st)
        alts = [s.alt_m for s in st if s.alt_m is not None]
        items = [s.seq for s in st if s.seq >= 0]
        head = (f"{len(st)} vehicles: " + ", ".join(f"{m} {c}" for m, c in sorted(modes.items()))
                + f"; {armed} armed"
                + (f"; alt {min(alts):.1f}..{max(alts):.1f} m" if alts else "")
                + (f"; items {min(items)}..{max(items)}" if items else ""))
        out = [head]
        stale = [v.name for v, s in zip(self.vehicles, st)
                 if not s.heartbeat_t or now - s.heartbeat_t > 3.0]
        if stale:
            shown = ", ".join(stale[:8]) + (f" and {len(stale) - 8} more" if len(stale) > 8
                                            else "")
            out.append(f"NO HEARTBEAT: {shown}")
        if slots is not None:  # the vehicles farthest from their slots, a line each
            room = max_lines - len(out) - 2
            if room >= 1:
                worst = np.argsort(-slots, kind="stable")[:room]
                out.append(f"farthest from their slots ({len(worst)} of {len(st)}):")
                out += [self._vehicle_line(int(n), slots) for n in worst]
            out.append(self._group_line(pos, slots))
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
        now = clock.monotonic()
        if not force and now < self._next:
            return
        self._next = now + self.period_s
        # a terminal shows what fits on its screen; a log gets every vehicle
        height = shutil.get_terminal_size((80, 24)).lines - 1 if self.tty else None
        lines = self.monitor.lines(max_lines=height)
        self._clear()
        self.stream.write("\n".join(lines) + "\n")
        self.stream.flush()
        self._drawn = len(lines) if self.tty else 0
