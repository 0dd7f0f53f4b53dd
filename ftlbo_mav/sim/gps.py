"""An emulated copter's GPS error: where it believes it is, against where it is.

ArduCopter flies its EKF's position estimate along the mission; the estimate follows the
GPS, so a copter whose GPS is off by ``e`` flies the path with its true position off by
``-e``. The emulator's autopilot flies the estimate (:mod:`.autopilot`); this module
gives the error (:class:`GpsError`):

- a slow wander, independent per copter: per axis a first-order Gauss-Markov process
  (``wander_m`` standard deviation, ``correlation_s``), drawn on a 1 s grid from its seed
  and interpolated, so a flight is the same whatever its message timing;
- steps: ``glitches`` at given times, and SITL's own knobs ``SIM_GPS_GLITCH_X`` /
  ``SIM_GPS_GLITCH_Y`` (an offset of latitude / longitude in degrees,
  libraries/SITL/SIM_GPS.cpp) set by PARAM_SET, as on SITL.

A step of the GPS is no step of the estimate: EKF3 fuses the new GPS position over
seconds (recorded on ArduCopter 4.5.6 SITL, ``tests/data/ardupilot-4.5.6/gps.json``: a
3 m SIM_GPS_GLITCH_X step, the EKF's position moving to it as a first-order lag of
:data:`EKF_FUSE_S`), while AC_PosControl keeps the estimate on the path; the true
position moves away by the fused part of the step. On the ground it is the other way
round: the copter stands where it was placed and its estimate moves by the fused error
(``Vehicle._stand_still``), so it takes off believing it is at home plus its error.
:meth:`GpsError.transient` is the part not yet fused. What the copter reports:
GLOBAL_POSITION_INT the estimate (the position it flies), GPS_RAW_INT the receiver's
reading (the truth plus the error: the estimate plus the unfused part), SIM_STATE the
truth (the estimate less the fused error).

Reported, as SITL does: the fix type (6, RTK fixed, by default: SITL's) and the
accuracy ``SIM_GPS_ACC`` (0.3 m by default) as GPS_RAW_INT's ``h_acc``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ..ardupilot.gps import SITL_GPS_ACCURACY_M
from ..ardupilot.navigation import REAL32, ParamDefault

_SIM = "libraries/SITL/SIM_GPS.cpp"
SIM_GPS_PARAM_DEFAULTS = {
    "SIM_GPS_GLITCH_X": ParamDefault(0.0, REAL32, _SIM + " (latitude offset, degrees)"),
    "SIM_GPS_GLITCH_Y": ParamDefault(0.0, REAL32, _SIM + " (longitude offset, degrees)"),
    "SIM_GPS_ACC": ParamDefault(SITL_GPS_ACCURACY_M, REAL32, _SIM + " (reported accuracy, m)"),
}
"""SITL's GPS parameters the emulator knows (the names ArduCopter 4.5 SITL has)."""

EKF_FUSE_S = 5.0
"""How fast EKF3 takes up a step of the GPS position: a first-order lag of this time
constant (fitted to tests/data/ardupilot-4.5.6/gps.json: 4.7-5.4 s over the step)."""
GRID_S = 1.0
"""The wander is drawn every this many seconds and interpolated between."""
METRES_PER_DEGREE = 111_319.49
"""Metres per degree of latitude (and of longitude at the equator) on SITL's sphere
(libraries/AP_Common/Location.cpp LOCATION_SCALING_FACTOR)."""


@dataclass(frozen=True)
class GpsErrorOptions:
    """``wander_m``: the wander's standard deviation per axis (metres); ``correlation_s``
    its correlation time; ``glitches``: ``(seconds after boot, east m, north m)`` steps
    added to the error; ``fix_type`` and ``satellites`` as reported; ``seed``."""

    wander_m: float = 0.0
    correlation_s: float = 30.0
    glitches: tuple[tuple[float, float, float], ...] = ()
    fix_type: int = 6
    satellites: int = 10
    seed: int = 0

    def __post_init__(self) -> None:
        if not (self.wander_m >= 0 and self.correlation_s > 0):
            raise ValueError("wander_m must be >= 0 and correlation_s > 0")


@dataclass
class GpsError:
    """One copter's GPS error (ENU metres east/north) over time since boot; ``params``
    is the autopilot's parameter table (SIM_GPS_GLITCH_X/Y are read from it)."""

    options: GpsErrorOptions
    params: dict
    lat_deg: float = 0.0
    response_s: float = EKF_FUSE_S
    _grid: list = field(default_factory=list)
    _rng: np.random.Generator | None = None
    _steps: list = field(default_factory=list)  # (t, east, north) of parameter steps
    _param_offset: tuple[float, float] = (0.0, 0.0)
    _memo: dict = field(default_factory=dict)  # error and transient at the last time asked

    def __post_init__(self) -> None:
        self._rng = np.random.default_rng([self.options.seed, 0x6E55])
        self._grid = [np.zeros(2) if self.options.wander_m == 0 else
                      self._rng.normal(0.0, self.options.wander_m, 2)]

    def _wander(self, t: float) -> np.ndarray:
        return np.array(self._wander_xy(t))

    def _wander_xy(self, t: float) -> tuple[float, float]:
        """The wander at ``t``, east and north as floats (the same arithmetic, element by
        element, as on the grid's arrays)."""
        o = self.options
        if o.wander_m == 0 or t <= 0:
            return tuple(self._grid[0].tolist()) if t <= 0 else (0.0, 0.0)
        k = int(t // GRID_S)
        a = math.exp(-GRID_S / o.correlation_s)
        while len(self._grid) <= k + 1:
            self._grid.append(a * self._grid[-1]
                              + o.wander_m * math.sqrt(1 - a * a) * self._rng.normal(0, 1, 2))
        f = t / GRID_S - k
        (g0, g1), (h0, h1) = self._grid[k].tolist(), self._grid[k + 1].tolist()
        return (1 - f) * g0 + f * h0, (1 - f) * g1 + f * h1

    def param_changed(self, t: float) -> None:
        """SIM_GPS_GLITCH_X/Y may have changed at ``t``: a step of the difference."""
        north = float(self.params.get("SIM_GPS_GLITCH_X", 0.0)) * METRES_PER_DEGREE
        east = (float(self.params.get("SIM_GPS_GLITCH_Y", 0.0)) * METRES_PER_DEGREE
                * math.cos(math.radians(self.lat_deg)))
        de, dn = east - self._param_offset[0], north - self._param_offset[1]
        if de or dn:
            self._steps.append((t, de, dn))
            self._param_offset = (east, north)

    def _all_steps(self) -> Sequence[tuple[float, float, float]]:
        return [*self.options.glitches, *self._steps]

    def error(self, t: float) -> np.ndarray:
        """The GPS error at ``t`` seconds after boot, ``(2,)`` east/north metres."""
        key = ("error", t, len(self._steps))  # asked several times per step: once
        if self._memo.get("error", (None,))[0] != key:
            out = self._wander(t)
            for t0, east, north in self._all_steps():
                if t >= t0:
                    out = out + (east, north)
            self._memo["error"] = (key, out)
        return self._memo["error"][1].copy()

    def transient(self, t: float) -> np.ndarray:
        """The part of the steps so far the EKF has not yet fused (each step decaying
        with ``response_s``), ``(2,)``: the GPS reads this much beyond the estimate."""
        key = ("transient", t, len(self._steps))
        if self._memo.get("transient", (None,))[0] != key:
            out = np.zeros(2)
            for t0, east, north in self._all_steps():
                if t >= t0:
                    out += np.array([east, north]) * math.exp(-(t - t0) / self.response_s)
            self._memo["transient"] = (key, out)
        return self._memo["transient"][1].copy()

    def unfused(self, t: float) -> tuple[float, float]:
        """``transient(t) - error(t)`` as two floats: from the estimate to the truth
        (east, north; the truth is recorded at every step)."""
        if not self._steps and not self.options.glitches:  # no step: the wander's alone
            east, north = self._wander_xy(t)
            return 0.0 - east, 0.0 - north
        key = ("unfused", t, len(self._steps))
        if self._memo.get("unfused", (None,))[0] != key:
            self._memo["unfused"] = (key, tuple((self.transient(t) - self.error(t)).tolist()))
        return self._memo["unfused"][1]

    def accuracy_m(self) -> float:
        return float(self.params.get("SIM_GPS_ACC", SITL_GPS_ACCURACY_M))
