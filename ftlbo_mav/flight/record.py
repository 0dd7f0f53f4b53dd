"""A flight record: telemetry samples per vehicle, resampled onto one time grid.

Pure data; writing it out goes through :func:`~ftlbo_mav.mission.files.write_atomic`.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass, fields

import numpy as np

from ..geo import LocalFrame


@dataclass(frozen=True)
class Sample:
    """One telemetry sample of one vehicle.

    ``t``: seconds since the recording started, when it arrived; ``boot_s``: the vehicle's
    own time stamp (GLOBAL_POSITION_INT ``time_boot_ms``), seconds since its boot.
    """

    t: float
    sysid: int
    lat_deg: float
    lon_deg: float
    alt_m: float
    mode: str
    armed: bool
    seq: int
    boot_s: float = float("nan")
    battery_pct: int = -1  # SYS_STATUS battery_remaining (-1: not reported)
    link_bytes: int = -1  # bytes received from the vehicle so far on its link (-1: unknown)


@dataclass(frozen=True)
class Photo:
    """One photo a vehicle said it took (CAMERA_FEEDBACK): ``t`` seconds since the
    recording started, when it arrived; where (``alt_m`` above home) and its image index."""

    t: float
    sysid: int
    lat_deg: float
    lon_deg: float
    alt_m: float
    image: int


class FlightRecord:
    """Samples in arrival order, with per-vehicle access and a common time grid; the
    photos the vehicles reported beside them."""

    def __init__(self, samples: list[Sample] | None = None,
                 photos: list[Photo] | None = None) -> None:
        self.samples: list[Sample] = list(samples or [])
        self.photos: list[Photo] = list(photos or [])

    def add(self, sample: Sample) -> None:
        self.samples.append(sample)

    def add_photo(self, photo: Photo) -> None:
        self.photos.append(photo)

    def photos_of(self, sysid: int) -> list[Photo]:
        return [p for p in self.photos if p.sysid == sysid]

    def photos_csv(self) -> str:
        """``photos.csv``: one row per photo, in arrival order."""
        buf = io.StringIO()
        writer = csv.writer(buf, lineterminator="\n")
        writer.writerow([f.name for f in fields(Photo)])
        for p in self.photos:
            writer.writerow([f"{p.t:.3f}", p.sysid, f"{p.lat_deg:.8f}", f"{p.lon_deg:.8f}",
                             f"{p.alt_m:.3f}", p.image])
        return buf.getvalue()

    @staticmethod
    def photos_from_csv(text: str) -> list[Photo]:
        return [Photo(float(r["t"]), int(r["sysid"]), float(r["lat_deg"]), float(r["lon_deg"]),
                      float(r["alt_m"]), int(r["image"]))
                for r in csv.DictReader(io.StringIO(text))]

    def of(self, sysid: int) -> list[Sample]:
        return [s for s in self.samples if s.sysid == sysid]

    def to_csv(self) -> str:
        buf = io.StringIO()
        writer = csv.writer(buf, lineterminator="\n")
        writer.writerow([f.name for f in fields(Sample)])
        for s in self.samples:
            writer.writerow(
                [f"{s.t:.3f}", s.sysid, f"{s.lat_deg:.8f}", f"{s.lon_deg:.8f}", f"{s.alt_m:.3f}",
                 s.mode, int(s.armed), s.seq, f"{s.boot_s:.3f}", s.battery_pct,
                 s.link_bytes]
            )
        return buf.getvalue()

    @classmethod
    def from_csv(cls, text: str) -> FlightRecord:
        rows = list(csv.DictReader(io.StringIO(text)))
        return cls(
            [
                Sample(float(r["t"]), int(r["sysid"]), float(r["lat_deg"]), float(r["lon_deg"]),
                       float(r["alt_m"]), r["mode"], r["armed"] in ("1", "True"), int(r["seq"]),
                       float(r.get("boot_s") or "nan"), int(r.get("battery_pct") or -1),
                       int(r.get("link_bytes") or -1))
                for r in rows
            ]
        )

    def battery(self, sysid: int) -> tuple[int, int] | None:
        """The first and the last charge (per cent) vehicle ``sysid`` reported, or None."""
        pct = [s.battery_pct for s in self.of(sysid) if s.battery_pct >= 0]
        return (pct[0], pct[-1]) if pct else None

    def link_bytes_per_s(self, sysid: int) -> float | None:
        """Bytes a second received from vehicle ``sysid`` over the record, per second of
        the vehicle's own clock (an emulator run faster than real time sends as much in
        its second as a copter does; None: not counted)."""
        rows = [(s.boot_s if math.isfinite(s.boot_s) else s.t, s.link_bytes)
                for s in self.of(sysid) if s.link_bytes >= 0]
        if len(rows) < 2 or rows[-1][0] <= rows[0][0]:
            return None
        return (rows[-1][1] - rows[0][1]) / (rows[-1][0] - rows[0][0])

    def clock_rate(self) -> float:
        """The vehicles' seconds per second of the record (1 but for a simulator run
        faster than real time), from the first vehicle's time stamps."""
        for sysid in sorted({s.sysid for s in self.samples}):
            rows = [(s.t, s.boot_s) for s in self.of(sysid) if math.isfinite(s.boot_s)]
            if len(rows) >= 2 and rows[-1][0] > rows[0][0] and rows[-1][1] > rows[0][1]:
                return (rows[-1][1] - rows[0][1]) / (rows[-1][0] - rows[0][0])
        return 1.0

    def rate_hz(self, sysid: int) -> float:
        """Mean sample rate of one vehicle."""
        t = [s.t for s in self.of(sysid)]
        return (len(t) - 1) / (t[-1] - t[0]) if len(t) > 1 and t[-1] > t[0] else 0.0

    def grid(
        self, sysids: list[int], frame: LocalFrame, *, rate_hz: float = 10.0
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Resample every vehicle onto common times where all have data.

        Returns ``times (T,)``, ``positions (T, N, 3)`` metres ENU in ``frame`` (linear
        interpolation) and ``seqs (T, N)``, each vehicle's current mission item (the last
        one reported at or before each time; -1 outside AUTO).
        """
        per = [self.of(s) for s in sysids]
        when = [sample_times(p) for p in per]
        # in the order they were taken (a link may deliver one late)
        order = [np.argsort(w, kind="stable") for w in when]
        per = [[p[k] for k in o] for p, o in zip(per, order)]
        when = [w[o] for w, o in zip(when, order)]
        if any(len(p) < 2 for p in per):
            return np.zeros(0), np.zeros((0, len(sysids), 3)), np.zeros((0, len(sysids)), int)
        start = max(w[0] for w in when)
        stop = min(w[-1] for w in when)
        if stop <= start:
            return np.zeros(0), np.zeros((0, len(sysids), 3)), np.zeros((0, len(sysids)), int)
        times = np.arange(start, stop, 1.0 / rate_hz)
        positions = np.empty((len(times), len(sysids), 3))
        seqs = np.empty((len(times), len(sysids)), int)
        for n, (samples, t) in enumerate(zip(per, when)):
            enu = frame.to_enu(
                lat_deg=[s.lat_deg for s in samples],
                lon_deg=[s.lon_deg for s in samples],
                alt_m=[s.alt_m for s in samples],
            )
            for axis in range(3):
                positions[:, n, axis] = np.interp(times, t, enu[:, axis])
            auto_seq = np.array([s.seq if s.mode == "AUTO" else -1 for s in samples])
            idx = np.clip(np.searchsorted(t, times, side="right") - 1, 0, len(t) - 1)
            seqs[:, n] = auto_seq[idx]
        return times, positions, seqs


def sample_times(samples: list[Sample]) -> np.ndarray:
    """When each sample was taken, on the recorder's clock, ``(len(samples),)`` seconds.

    Arrival times carry the link's jitter (a few to tens of milliseconds: centimetres at
    cruise speed, enough to show as formation error). The vehicle's own time stamps do
    not, so where every sample has one and they increase, arrival time is fitted as
    ``a + b * boot_s`` (``b`` absorbs a simulator running faster than real time) and the
    line is moved down onto the earliest arrivals, the ones least delayed.
    """
    return fitted_times(np.array([s.t for s in samples]), np.array([s.boot_s for s in samples]))


def fitted_times(t: np.ndarray, boot: np.ndarray) -> np.ndarray:
    """Arrival times ``t`` refitted on the vehicle's own stamps ``boot`` (both seconds,
    one per sample), as :func:`sample_times` explains; ``t`` itself when ``boot`` cannot
    be used."""
    t = np.asarray(t, float)
    boot = np.asarray(boot, float)
    # stamps that go back by seconds: a reboot, not one clock (a report delivered late
    # goes back a fraction of a second and is fitted like the others)
    if len(t) < 3 or not np.all(np.isfinite(boot)) or np.any(np.diff(boot) < -1.0) or (
            np.ptp(boot) <= 0):
        return t
    b, _a = np.polyfit(boot, t, 1)
    if not b > 0:
        return t
    a = np.min(t - b * boot)
    return a + b * boot


__all__ = ["FlightRecord", "Photo", "Sample", "fitted_times", "sample_times"]
