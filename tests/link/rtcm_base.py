"""A generated RTCM3 stream as a base station sends it, for tests and benchmarks: each
second MSM7 observations of GPS, GLONASS, Galileo and BeiDou (1077, 1087, 1097, 1127),
every ``station_every`` seconds the station's position (1005) and GLONASS biases (1230).

The message layouts are RTCM 10403.3's (MSM header DF002..DF396, MSM7 satellite and
signal fields); the frames are built by pyrtcm (``RTCMMessage(payload).serialize()``:
preamble, length, CRC-24Q) and every one decodes with pyrtcm. The observation values
are plausible, not a real sky: what is carried is the traffic, not a solution."""

from __future__ import annotations

import numpy as np
from pyproj import Transformer
from pyrtcm import RTCMMessage

STATION = 2107
# Satellites in view and signals per constellation: (message, satellites, signals).
SKY = ((1077, 10, 2), (1087, 7, 2), (1097, 8, 2), (1127, 9, 2))


class Bits:
    def __init__(self) -> None:
        self.value, self.n = 0, 0

    def put(self, width: int, value: int) -> Bits:
        self.value = (self.value << width) | (int(value) & ((1 << width) - 1))
        self.n += width
        return self

    def payload(self) -> bytes:
        pad = -self.n % 8
        return (self.value << pad).to_bytes((self.n + pad) // 8, "big")


def frame(bits: Bits) -> bytes:
    return RTCMMessage(payload=bits.payload()).serialize()


def station_1005(lat: float, lon: float, alt: float) -> bytes:
    """Stationary RTK reference station ARP (1005): ECEF in 0.1 mm."""
    x, y, z = Transformer.from_crs("EPSG:4979", "EPSG:4978", always_xy=True).transform(
        lon, lat, alt)
    b = Bits().put(12, 1005).put(12, STATION).put(6, 0)
    b.put(1, 1).put(1, 1).put(1, 1).put(1, 0)  # GPS, GLONASS, Galileo; not a reference
    b.put(38, round(x * 1e4)).put(1, 0).put(1, 0).put(38, round(y * 1e4)).put(2, 0)
    b.put(38, round(z * 1e4))
    return frame(b)


def glonass_biases_1230() -> bytes:
    return frame(Bits().put(12, 1230).put(12, STATION).put(1, 0).put(3, 0).put(4, 0))


def msm7(message: int, n_sat: int, n_sig: int, epoch_ms: int, rng) -> bytes:
    b = Bits().put(12, message).put(12, STATION).put(30, epoch_ms)
    b.put(1, 0).put(3, 0).put(7, 0).put(2, 0).put(2, 0).put(1, 0).put(3, 0)
    sats = sorted(rng.choice(np.arange(1, 33), n_sat, replace=False))
    b.put(64, sum(1 << (64 - s) for s in sats))
    signals = (2, 16)[:n_sig]  # 1C, 2W as GPS numbers them
    b.put(32, sum(1 << (32 - s) for s in signals))
    for _ in range(n_sat * n_sig):
        b.put(1, 1)  # every satellite seen on every signal
    for _ in range(n_sat):
        b.put(8, rng.integers(66, 86))  # DF397 rough range, whole ms
    for _ in range(n_sat):
        b.put(4, 0)  # DF419 extended info
    for _ in range(n_sat):
        b.put(10, rng.integers(0, 1024))  # DF398 rough range mod 1 ms
    for _ in range(n_sat):
        b.put(14, rng.integers(-800, 800))  # DF399 rough phase range rate, m/s
    cells = n_sat * n_sig
    for width, lo, hi in ((20, -1000, 1000), (24, -5000, 5000), (10, 500, 600), (1, 0, 1),
                          (10, 560, 800), (15, -2000, 2000)):
        for _ in range(cells):  # DF405, DF406, DF407, DF420, DF408, DF404
            b.put(width, rng.integers(lo, hi + 1))
    return frame(b)


def base_station(seconds: int, *, lat: float = 12.2329, lon: float = 109.1157,
                 alt: float = 10.0, station_every: int = 10, seed: int = 0):
    """One ``bytes`` per second of a base station's stream, ``seconds`` of them."""
    rng = np.random.default_rng(seed)
    position, biases = station_1005(lat, lon, alt), glonass_biases_1230()
    for t in range(seconds):
        frames = [msm7(m, n, s, (t * 1000) % (7 * 86400 * 1000), rng) for m, n, s in SKY]
        if t % station_every == 0:
            frames = [position, biases, *frames]
        yield b"".join(frames)
