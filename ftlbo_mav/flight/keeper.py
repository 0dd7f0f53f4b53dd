"""Keep the formation while flying: leaders wait, laggards catch up.

Every UAV's planned path is the centroid's path shifted by its offset (the paper's eq. 4),
so all paths have the same length and shape: the formation holds exactly when every UAV
is the same distance along its own path. The keeper measures that distance (*progress*)
from each vehicle's reported position and, a few times a second, slows the ones ahead of
the group with MAV_CMD_DO_CHANGE_SPEED while they lead; a vehicle that no longer leads
gets its planned speed back. ArduCopter applies a new speed at once in AUTO
(ArduCopter/GCS_Mavlink.cpp handle_MAV_CMD_DO_CHANGE_SPEED -> ModeAuto::set_speed_xy ->
AC_WPNav::set_speed_xy, which rescales the S-curve in flight).

The keeper only nudges: each vehicle flies its own uploaded mission, and a leader is
never asked to fly slower than ``min_fraction`` of its own speed.
If the link drops, a vehicle keeps the last speed it was given and still flies its whole
mission; ArduCopter has no speed command that expires by itself.

:class:`FormationKeeper` is pure: positions and speeds in, speed commands out.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

# ArduCopter's WPNAV_SPEED default (AC_WPNav.h WPNAV_WP_SPEED, 1000 cm/s); copter.parm keeps it
ARDUCOPTER_WPNAV_SPEED_M_S = 10.0


@dataclass(frozen=True)
class KeeperOptions:
    """When a vehicle flying at least ``min_speed_m_s`` leads the group by more than
    ``engage_m``, its speed is capped just under its own so that it gives the lead back
    over ``horizon_s`` seconds, never below ``min_fraction`` of its own speed; below
    ``release_m`` it gets its planned speed back.
    Speeds are reconsidered every ``period_s`` and a new command goes out only when it
    differs by ``min_step_m_s``, or every ``refresh_s`` while a vehicle is slowed (a lost
    command is not final).

    The gentleness is measured, not a taste: ArduCopter answers a new speed through its
    jerk-limited S-curve (WPNAV_JERK 1 m/s^3: about 1.5 s to lose 0.6 m/s). On SITL a
    keeper that acted on 5 cm of lead within a quarter of a second overshot into 1.1 m
    RMS formation error where no keeper gave 0.06 m, and one that capped leaders at the
    group's speed (low in corners) made 0.87 m of a flight that flew 0.04 m without it."""

    enabled: bool = False  # off by default until it helps on ArduPilot: docs/flight.md
    engage_m: float = 0.25
    release_m: float = 0.08
    horizon_s: float = 3.0
    min_fraction: float = 0.85
    min_speed_m_s: float = 1.0
    steady_m_s2: float = 0.3  # engage only while no vehicle speeds up or slows faster
    period_s: float = 0.5
    min_step_m_s: float = 0.15
    refresh_s: float = 2.0


@dataclass
class KeeperLog:
    """What the keeper did, per vehicle: commands sent, slowest speed asked, seconds
    spent slowed, and the largest lead it saw."""

    commands: list[int]
    slowest_m_s: list[float | None]
    slowed_s: list[float]
    max_lead_m: list[float]

    def as_dict(self, names) -> dict:
        return {n: {"speed_commands": c, "slowest_speed_m_s": s, "seconds_slowed": round(t, 2),
                    "largest_lead_m": round(m, 3)}
                for n, c, s, t, m in zip(names, self.commands, self.slowest_m_s, self.slowed_s,
                                         self.max_lead_m)}


def _segments(path: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    a, b = path[:-1], path[1:]
    length = np.linalg.norm(b - a, axis=1)
    return a, b, np.concatenate([[0.0], np.cumsum(length)])


def progress_along(path: np.ndarray, point: np.ndarray, *, start_segment: int = 0,
                   window: int = 4) -> tuple[float, int]:
    """Distance along ``path`` ``(P, 3)`` of the point nearest ``point`` ``(3,)``, searching
    the segments ``start_segment .. start_segment + window`` (progress never jumps back to
    an earlier leg nor ahead to a far one when a path passes near itself). Returns
    ``(metres, segment)``."""
    a, b, cum = _segments(path)
    lo, hi = start_segment, min(len(a), start_segment + window + 1)
    d = b[lo:hi] - a[lo:hi]
    dd = np.einsum("ij,ij->i", d, d)
    t = np.clip(np.einsum("ij,ij->i", point - a[lo:hi], d) / np.where(dd > 0, dd, 1.0), 0, 1)
    nearest = a[lo:hi] + t[:, None] * d
    k = int(np.argmin(np.linalg.norm(nearest - point, axis=1)))
    seg = lo + k
    return float(cum[seg] + t[k] * np.sqrt(dd[k])), seg


@dataclass
class FormationKeeper:
    """``paths``: ``(N, P, 3)`` metres ENU, each UAV's planned points from its start to its
    goal; ``planned_speed_m_s``: the speed each flies when not slowed (its mission's
    DO_CHANGE_SPEED, else the vehicles' WPNAV_SPEED; None until known, and the keeper
    stays silent)."""

    paths: np.ndarray
    planned_speed_m_s: float | None = ARDUCOPTER_WPNAV_SPEED_M_S
    options: KeeperOptions = KeeperOptions()
    off_reason: str | None = None  # why this flight flies without it, if it does
    _segment: list[int] = field(default_factory=list)
    _sent: list[float | None] = field(default_factory=list)
    _sent_t: list[float] = field(default_factory=list)
    _last_t: float | None = None
    _last_speeds: np.ndarray | None = None
    log: KeeperLog | None = None

    def __post_init__(self) -> None:
        n = len(self.paths)
        self._segment = [0] * n
        self._sent = [None] * n
        self._sent_t = [0.0] * n
        self.log = KeeperLog([0] * n, [None] * n, [0.0] * n, [0.0] * n)

    @property
    def active(self) -> bool:
        return (self.options.enabled and self.off_reason is None
                and self.planned_speed_m_s is not None)

    def progress(self, positions: np.ndarray) -> np.ndarray:
        """``(N,)`` metres along each UAV's own path, from ``positions`` ``(N, 3)``."""
        out = np.empty(len(self.paths))
        for i, (path, p) in enumerate(zip(self.paths, positions)):
            out[i], self._segment[i] = progress_along(path, p, start_segment=self._segment[i])
        return out

    def update(self, positions: np.ndarray, speeds_m_s: np.ndarray,
               now: float) -> dict[int, float]:
        """The speed commands to send now: ``{uav index: m/s}`` (empty most of the time).

        ``positions`` ``(N, 3)`` metres ENU, ``speeds_m_s`` ``(N,)`` ground speeds, ``now``
        seconds (any clock)."""
        if not self.active:
            return {}
        o, log = self.options, self.log
        dt = 0.0 if self._last_t is None else now - self._last_t
        if self._last_t is not None and dt < o.period_s:
            return {}
        self._last_t = now
        s = self.progress(positions)
        lead = s - s.mean()
        speeds_m_s = np.asarray(speeds_m_s, float)
        # a cap set while the group accelerates out of a corner freezes the leader at that
        # speed while the others go on accelerating (SITL: 0.04 -> 0.88 m RMS on long legs)
        steady = (self._last_speeds is not None and dt > 0 and float(
            np.max(np.abs(speeds_m_s - self._last_speeds))) / dt <= o.steady_m_s2)
        self._last_speeds = speeds_m_s
        out = {}
        for i, e in enumerate(lead):
            log.max_lead_m[i] = max(log.max_lead_m[i], float(abs(e)))
            last = self._sent[i]
            slowed = last is not None and last != self.planned_speed_m_s
            if (slowed and e < o.release_m) or (not slowed and e <= o.engage_m):
                if slowed:
                    out[i] = self.planned_speed_m_s  # the lead is given back
                    self._sent[i], self._sent_t[i] = out[i], now
                    log.commands[i] += 1
                continue
            own = float(speeds_m_s[i])
            if not slowed and (own < o.min_speed_m_s or not steady):
                continue  # starting, turning or stopping: not the moment to nudge
            log.slowed_s[i] += dt if slowed else 0.0
            give_back = max(e - o.release_m, 0.0) / o.horizon_s
            # a cap just under its own speed: ArduCopter re-plans the S-curve below it, and
            # a cap far below (a corner's low group speed) made SITL copters brake hard
            base = max(own, o.min_speed_m_s)
            want = max(base - give_back, o.min_fraction * base, 0.5)
            want = round(min(want, self.planned_speed_m_s), 2)
            if not slowed or abs(want - last) >= o.min_step_m_s or \
                    now - self._sent_t[i] >= o.refresh_s:
                out[i] = want if not slowed or abs(want - last) >= o.min_step_m_s else last
                self._sent[i], self._sent_t[i] = out[i], now
                log.commands[i] += 1
                log.slowest_m_s[i] = min(log.slowest_m_s[i] or out[i], out[i])
        return out

    def release(self) -> dict[int, float]:
        """Planned speed back for every vehicle that was slowed (the legs are over)."""
        out = {}
        for i, last in enumerate(self._sent):
            if last is not None and last != self.planned_speed_m_s:
                out[i] = self.planned_speed_m_s
                self._sent[i] = self.planned_speed_m_s
                self.log.commands[i] += 1
        return out


def planned_speed(missions) -> float | None:
    """The speed the missions set with their first DO_CHANGE_SPEED (None: none does, the
    vehicles fly at their own WPNAV_SPEED)."""
    for items in missions:
        for it in items:
            if it.command == 178 and it.param2 > 0:  # MAV_CMD_DO_CHANGE_SPEED
                return float(it.param2)
    return None
