"""Keep the formation while flying: leaders wait, so that laggards catch up.

Every UAV's planned path is the centroid's path shifted by its offset (the paper's eq. 4),
so all paths have the same length and shape: the formation holds exactly when every UAV
is the same distance along its own path. The keeper measures that distance (*progress*)
from each vehicle's reported position twenty times a second, and a vehicle ahead of the
group waits: MAV_CMD_DO_PAUSE_CONTINUE, a pause just long enough to lose its lead, then
continue. ArduCopter does not stop dead: a paused AC_WPNav shapes the pace of its
track's clock to zero within WPNAV_ACCEL and PSC_JERK_XY and a continue shapes it back
(libraries/AC_WPNav/AC_WPNav.cpp advance_wp_target_along_track, ``_offset_vel``;
ArduCopter/mode_auto.cpp ModeAuto::pause / resume), so the copter slows along its own
path and speeds up again: on SITL a 0.6 s pause at 5 m/s cost that copter 1.8 m against
the others, its speed dipping to 3.4 m/s and back within 2 s
(:meth:`~ftlbo_mav.ardupilot.navigation.Navigation.pause_cost_s` models it: 1.9 m).

Why not MAV_CMD_DO_CHANGE_SPEED: ArduCopter re-plans the S-curve of a leg that has not
started to a new speed, but the leg being flown only in ways that do not apply here
(libraries/AP_Math/SCurve.cpp set_speed_max: not once cruising unless 12 s of the leg
remain, not on a jerk-limited ramp). On SITL a speed set 4 s into the example's first
leg changed nothing on that leg and held from the leg after: a correction a leg late,
and one that stays after its reason has gone.

The keeper only nudges: each vehicle flies its own uploaded mission at its own speed.
A pause lasts at most ``max_pause_s`` and every continue is sent again over seconds; when a
vehicle's reports stop, the keeper stands aside and keeps sending continue. A copter
whose link is lost for good within a pause (a window of ``max_pause_s``) holds its
position in AUTO, paused, until the link is back or its own failsafe acts.

:class:`FormationKeeper` is pure: positions and speeds in, pauses and continues out.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from ..ardupilot.navigation import Navigation


@dataclass(frozen=True)
class KeeperOptions:
    """Every ``period_s`` (on the vehicles' clock) each vehicle's lead over the group's
    last is measured, in metres and in seconds (metres over the group's speed).
    A vehicle more than ``engage_m`` ahead, or more than ``engage_s`` ahead and at least
    ``floor_m`` (while the group speeds up, a lead shows in time before it shows in
    metres), is paused for as long as makes it lose that lead in metres at the cruise
    speed (ArduCopter's pause and continue, modelled in
    :meth:`~ftlbo_mav.ardupilot.navigation.Navigation.pause_cost_s`; at most
    ``max_pause_s``). Not in seconds at the group's speed: a lead may be one in time (a
    late start) or in space (a copter's estimate moved along its track by its GPS), and
    only the first grows with speed; a pause sized in seconds at 1 m/s costs a copter
    five times a lead in space once cruising at 5 m/s, and the others are paused for that
    in turn (the emulator, GPS wander 1.5 m per axis: leads of 3.5 m; docs/flight.md).
    Sized at cruise a pause never costs more than the lead; a lead in time that is still
    there shows again as the group speeds up and is answered then. A lead that grew with
    the group's speed over the last ``time_lead_window_s`` (the group sped up by at least
    ``time_lead_min_dv_m_s``) is one in time, and is paused for in seconds of track, as
    much as it is at the group's speed now (:meth:`FormationKeeper._time_lead_s`). What
    a pause is still to take (its copter's track clock slows to zero and comes back to
    pace over seconds) counts as taken: each vehicle's progress is measured less what its
    pauses have still to cost it, so a lead that keeps growing is answered again
    ``rest_s`` after the last continue (once the measurement shows that pause), without
    pausing twice for the same lead.
    Nothing happens while the group flies slower than ``min_speed_m_s``. A report older
    than ``late_s`` (positions come at 10 Hz) is not measured on: no new pause while one
    is that late, though a pause under way still ends on time (on SITL with the ground
    station's machine busy, one copter's reports came 1 s late, and a keeper measuring on
    them saw it 1.5 m behind where it was and paused the others in turn: 0.50 m RMS).
    Reports older than ``stale_s`` make the keeper stand aside (continue for everyone).
    No new pause either while the link's delays vary by more than ``max_jitter_s`` (the
    90th percentile of the last 5 s of position reports' delays beyond the least delayed,
    any vehicle): a pause and its continue cross the same link, so a pause meant to take
    back 0.3 m takes back what the difference of their delays makes of it. On SITL behind
    a good-day radio (60 +- 40 ms) that figure was 0.07-0.125 s (four flights) and the
    keeper held 0.05 m RMS; behind the rough day's (120 +- 80 ms, 10 % lost, outages)
    0.148-0.48 s (four flights), and with the keeper pausing each flight's formation came
    apart (1-3 m, a departure), without it 0.12 m RMS.
    Every continue is sent again ``continue_again_s`` after it (the vehicles' seconds),
    until the copter is paused anew: a continue lost leaves its copter stopped, and a
    radio loses frames in bursts (the repeats 50 ms apart lost together) and for a second
    at a time (on SITL behind the rough-day radio, sim/radio.py ROUGH_DAY, a copter held
    0.85 s for a 0.30 s pause and the formation 1.9 m apart: a departure). A continue to a
    copter that is not paused changes nothing (ModeAuto::resume: AC_WPNav::set_resume
    clears its pause flag).
    Nor while any copter's position reports have paused for more than ``max_gap_s``
    within the last ``gap_memory_s`` (the vehicles' seconds): a link that goes silent
    for a second can hold a copter paused that long, its continues lost however often
    they are said (SITL behind the rough-day radio, legs started at one GPS time: the
    keeper paused uav2 just before an outage and it fell 2.1 m behind, a departure;
    without the keeper that flight's formation stayed within 0.27 m).

    The numbers are measured, not a taste: docs/flight.md."""

    enabled: bool = True
    engage_m: float = 0.08
    engage_s: float = 0.08
    floor_m: float = 0.03  # GLOBAL_POSITION_INT's 1e-7 degrees are 1.1 cm
    max_pause_s: float = 0.8
    rest_s: float = 0.5
    min_speed_m_s: float = 0.2
    period_s: float = 0.05
    late_s: float = 0.3
    stale_s: float = 1.0
    continue_again_s: tuple[float, ...] = (0.05, 0.1, 0.4, 1.2, 2.2)
    max_jitter_s: float = 0.14
    max_gap_s: float = 0.6
    gap_memory_s: float = 20.0
    time_lead_window_s: float = 1.0
    time_lead_min_dv_m_s: float = 0.5
    navigation: Navigation = Navigation()  # ArduCopter's defaults (copter.parm keeps them)

    def __post_init__(self) -> None:
        for name in ("engage_m", "engage_s", "floor_m", "max_pause_s", "rest_s",
                     "min_speed_m_s", "period_s", "late_s", "stale_s", "max_gap_s",
                     "gap_memory_s", "time_lead_window_s", "time_lead_min_dv_m_s"):
            value = getattr(self, name)
            if not np.isfinite(value) or value < 0:
                raise ValueError(f"keeper {name} must be a finite number >= 0, got {value!r}")

    def pause_for(self, lead_m: float, speed_m_s: float, cruise_m_s: float) -> float:
        """Seconds to pause a copter flying at ``speed_m_s`` (its navigation set to
        ``cruise_m_s``) so that it loses ``lead_m``: the shortest pause that does, at most
        ``max_pause_s``, in 10 ms steps."""
        costs = _pause_costs(self.navigation, round(cruise_m_s, 1), self.max_pause_s)
        k = int(np.searchsorted(costs, lead_m / max(speed_m_s, 0.1)))
        return round(min(k, len(costs) - 1) * 0.01, 2)


def still_to_lose_s(nav: Navigation, pause_s: float, cruise_m_s: float,
                    since_s: float) -> float:
    """Seconds of track a pause of ``pause_s`` has still to cost its copter ``since_s``
    after it began (:meth:`~ftlbo_mav.ardupilot.navigation.Navigation.pause_loss`)."""
    curve = _pause_curve(nav, round(cruise_m_s, 1), round(pause_s, 2))
    k = int(since_s / 0.01)
    return float(curve[-1] - curve[min(max(k, 0), len(curve) - 1)])


@lru_cache(maxsize=256)
def _pause_curve(nav: Navigation, cruise_m_s: float, pause_s: float) -> list[float]:
    return nav.pause_loss(pause_s, cruise_m_s)


@lru_cache(maxsize=64)
def _pause_costs(nav: Navigation, cruise_m_s: float, max_pause_s: float) -> np.ndarray:
    """Seconds of track lost to pauses of 0, 0.01, ... ``max_pause_s`` seconds."""
    steps = int(round(max_pause_s / 0.01)) + 1
    return np.maximum.accumulate([nav.pause_cost_s(k * 0.01, cruise_m_s)
                                  for k in range(steps)])


@dataclass
class KeeperLog:
    """What the keeper did, per vehicle: pauses and their seconds, and the largest lead
    it saw (metres, + ahead); and how often it stood aside for a link gap."""

    pauses: list[int]
    paused_s: list[float]
    max_lead_m: list[float]
    link_gaps: int = 0
    rough_s: float = 0.0  # seconds without new pauses for the link's varying delays
    worst_jitter_s: float = 0.0
    worst_gap_s: float = 0.0  # the longest silence of reports seen (vehicles' seconds)

    @classmethod
    def empty(cls, n: int) -> KeeperLog:
        return cls([0] * n, [0.0] * n, [0.0] * n)

    def as_dict(self, names) -> dict:
        return {n: {"pauses": p, "seconds_paused": round(t, 2), "largest_lead_m": round(m, 3)}
                for n, p, t, m in zip(names, self.pauses, self.paused_s, self.max_lead_m)}


def _segments(path: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    a, b = path[:-1], path[1:]
    length = np.linalg.norm(b - a, axis=1)
    return a, b, np.concatenate([[0.0], np.cumsum(length)])


def progress_along(path: np.ndarray, point: np.ndarray, *, start_segment: int = 0,
                   window: int = 4, within: tuple[float, float] | None = None,
                   segments: tuple | None = None) -> tuple[float, int]:
    """Distance along ``path`` ``(P, 3)`` of the point nearest ``point`` ``(3,)``, searching
    the segments ``start_segment .. start_segment + window`` (progress never jumps back to
    an earlier leg nor ahead to a far one when a path passes near itself) and, with
    ``within`` ``(lowest, highest)`` metres, among the points of those whose progress lies
    there if any does (where a path comes back along itself, as out to a lane's end and
    back, the nearest point can be on the way back before the copter has turned). Returns
    ``(metres, segment)``. ``segments``: ``_segments(path)``, if known already."""
    a, b, cum = _segments(path) if segments is None else segments
    lo, hi = start_segment, min(len(a), start_segment + window + 1)
    d = b[lo:hi] - a[lo:hi]
    dd = np.einsum("ij,ij->i", d, d)
    t = np.clip(np.einsum("ij,ij->i", point - a[lo:hi], d) / np.where(dd > 0, dd, 1.0), 0, 1)
    nearest = a[lo:hi] + t[:, None] * d
    along = cum[lo:hi] + t * np.sqrt(dd)
    dist = np.linalg.norm(nearest - point, axis=1)
    if within is not None:
        ok = (along >= within[0]) & (along <= within[1])
        if ok.any():
            dist = np.where(ok, dist, np.inf)
    k = int(np.argmin(dist))
    return float(along[k]), lo + k


TIME_LEAD_UNTIL = 0.9
"""Leads are judged as time (:meth:`FormationKeeper._time_lead_s`) until the group first
flies at this share of the cruise speed."""
MAX_AHEAD_M = 3.0  # a progress measured further on than the last one by more is doubted
MAX_BACK_M = 1.0  # ... or further back (a copter overshooting a stop comes back)


@dataclass
class FormationKeeper:
    """``paths``: ``(N, P, 3)`` metres ENU, each UAV's planned points from its start to its
    goal; ``cruise_speed_m_s``: the speed their waypoint navigation is set to (the
    missions' DO_CHANGE_SPEED, else WPNAV_SPEED; None until known, and the keeper stays
    silent): a pause slows the track's clock from it."""

    paths: np.ndarray
    cruise_speed_m_s: float | None = None
    options: KeeperOptions = KeeperOptions()
    off_reason: str | None = None  # why this flight flies without it, if it does
    _segment: list[int] = field(default_factory=list)
    _paused_at: list[float | None] = field(default_factory=list)
    _resume_at: list[float] = field(default_factory=list)
    _rest_until: list[float] = field(default_factory=list)
    _pause: list = field(default_factory=list)  # the last pause: (when, seconds), or None
    _progress: list = field(default_factory=list)  # the last progress measured, per UAV
    _resend: list[list[float]] = field(default_factory=list)  # when to repeat continues
    _resumed_at: list[float] = field(default_factory=list)
    _segments: list = field(default_factory=list)  # _segments of each path, once used
    _last_t: float | None = None
    _standing_aside: bool = False
    # (now, group speed, each UAV's lead over the last) of the last time_lead_window_s,
    # until the group first cruises (at TIME_LEAD_UNTIL of the cruise speed)
    _leads: deque = field(default_factory=deque)
    _cruised: bool = False
    log: KeeperLog | None = None
    # when a list: one row per measurement, (now, progress less what pauses still owe
    # (N,), lead over the mean (N,)), for looking back at what the keeper saw
    # (``benchmarks/flight.py --keep``)
    trace: list | None = None

    def __post_init__(self) -> None:
        n = len(self.paths)
        self._segment = [0] * n
        self._paused_at = [None] * n
        self._resume_at = [0.0] * n
        self._rest_until = [-np.inf] * n
        self._pause = [None] * n
        self._progress = [0.0] * n
        self._resend = [[] for _ in range(n)]
        self._resumed_at = [-np.inf] * n
        self.log = KeeperLog.empty(n)

    @property
    def active(self) -> bool:
        return (self.options.enabled and self.off_reason is None
                and self.cruise_speed_m_s is not None)

    @property
    def pausing(self) -> bool:
        """A pause is under way: its continue is due within ``max_pause_s``."""
        return any(t is not None for t in self._paused_at)

    def progress(self, positions: np.ndarray) -> np.ndarray:
        """``(N,)`` metres along each UAV's own path, from ``positions`` ``(N, 3)``."""
        out = np.empty(len(self.paths))
        for i, (path, p) in enumerate(zip(self.paths, positions)):
            # from one measurement to the next (20 Hz) a copter moves a metre at most; the
            # first is at the start (fly starts AUTO there)
            last = self._progress[i]
            within = (last - MAX_BACK_M, last + MAX_AHEAD_M)
            if len(self._segments) != len(self.paths):  # each path's segments, once
                self._segments = [_segments(np.asarray(q)) for q in self.paths]
            out[i], self._segment[i] = progress_along(path, p, start_segment=self._segment[i],
                                                      within=within,
                                                      segments=self._segments[i])
        self._progress = out.tolist()
        return out

    def update(self, positions: np.ndarray, speeds_m_s: np.ndarray, now: float,
               ages_s: np.ndarray | None = None, jitter_s: float | None = None,
               gap_s: float | None = None) -> dict[int, bool]:
        """What to send now, ``{uav index: True to pause, False to continue}`` (empty most
        of the time).

        ``positions`` ``(N, 3)`` metres ENU, ``speeds_m_s`` ``(N,)`` ground speeds, ``now``
        seconds (any clock, the same for all), ``ages_s`` ``(N,)`` how old each vehicle's
        report is (None: fresh), ``jitter_s`` how much the link's delays vary (None: not
        known yet), ``gap_s`` the longest silence of any copter's reports lately (the
        vehicles' seconds; None: not known)."""
        if not self.active:
            return {}
        o, log = self.options, self.log
        dt = 0.0 if self._last_t is None else now - self._last_t
        if self._last_t is not None and dt < o.period_s:
            return {}
        self._last_t = now
        if ages_s is not None and float(np.max(ages_s)) > o.stale_s:
            if not self._standing_aside:
                log.link_gaps += 1
            self._standing_aside = True
            out = self.release(now)
            for i, resumed in enumerate(self._resumed_at):  # a lost continue is not final
                if i not in out and now - resumed < 10.0:
                    out[i] = False
            return out
        self._standing_aside = False
        late = ages_s is not None and float(np.max(ages_s)) > o.late_s
        jittery = jitter_s is not None and jitter_s > o.max_jitter_s
        silent = gap_s is not None and gap_s > o.max_gap_s
        rough = jittery or silent
        if rough:
            log.rough_s += dt
        if jittery:
            log.worst_jitter_s = max(log.worst_jitter_s, jitter_s)
        if gap_s is not None:
            log.worst_gap_s = max(log.worst_gap_s, gap_s)
        s = self.progress(positions)
        lead = s - s.mean()  # what the formation error sees (logged)
        group_speed = float(np.mean(speeds_m_s))
        # what the pauses under way have still to take, taken
        owed = np.array([0.0 if p is None else group_speed * still_to_lose_s(
            o.navigation, p[1], self.cruise_speed_m_s, now - p[0]) for p in self._pause])
        s = s - owed
        # what a pause can take back: a copter cannot be made to catch up, so every other
        # one loses its whole lead over the last (against the mean a laggard's two
        # leaders would each lose only a third of the gap a round, and the formation stay
        # out for rounds: SITL in 5 m/s wind, a copter 0.5 m behind for 8 s)
        ahead = s - s.min()
        self._cruised |= group_speed >= TIME_LEAD_UNTIL * self.cruise_speed_m_s
        if not self._cruised:
            self._leads.append((now, group_speed, ahead))
            while self._leads and self._leads[0][0] < now - o.time_lead_window_s:
                self._leads.popleft()
        if self.trace is not None:
            self.trace.append((now, s.tolist(), lead.tolist()))
        flying = group_speed >= o.min_speed_m_s
        # a lead in time shows before a lead in metres while the group speeds up
        ahead_s = ahead / max(group_speed, o.min_speed_m_s)
        out: dict[int, bool] = {}
        for i in range(len(s)):
            if not late:
                log.max_lead_m[i] = max(log.max_lead_m[i], float(lead[i]), key=abs)
            if self._paused_at[i] is not None:
                if now >= self._resume_at[i] or not flying:
                    log.paused_s[i] += now - self._paused_at[i]
                    self._cut_short(i, now)
                    self._paused_at[i], self._resumed_at[i] = None, now
                    self._resend[i] = [now + t for t in o.continue_again_s]
                    out[i] = False
            elif (flying and not late and not rough and now >= self._rest_until[i]
                  and (ahead[i] > o.engage_m
                       or (ahead[i] > o.floor_m and ahead_s[i] > o.engage_s))
                  and self._start_pause(i, float(ahead[i]), group_speed, now,
                                        self._time_lead_s(i, group_speed))):
                out[i] = True
            elif self._resend[i] and now >= self._resend[i][0]:
                while self._resend[i] and now >= self._resend[i][0]:
                    self._resend[i].pop(0)
                out[i] = False
        return out

    def _time_lead_s(self, i: int, group_speed: float) -> float:
        """Seconds of track vehicle i is ahead of the last by a lead shown to be one in
        time: while the group sped up by ``time_lead_min_dv_m_s`` or more over the last
        ``time_lead_window_s``, the slope of its lead against the group's speed (a lead in
        time grows with the speed, one in space does not), at most its lead over the
        group's speed now (a lead still growing is not answered ahead of time). 0 when
        the group did not speed up enough to tell, and once it has first cruised: the
        legs' first speed-up, from a hover, is where a track clock stalls (a target
        speed of centimetres a second against a copter's hover residual); at a corner
        the leads measured along paths that cut it differently grow and shrink with the
        speed too, and are not answered as time."""
        o = self.options
        if self._cruised or len(self._leads) < 5 or group_speed < o.min_speed_m_s:
            return 0.0
        v = np.array([x[1] for x in self._leads])
        if float(v.max() - v.min()) < o.time_lead_min_dv_m_s:
            return 0.0
        lead = np.array([x[2][i] for x in self._leads])
        dv = v - v.mean()
        slope = float(np.dot(dv, lead - lead.mean()) / np.dot(dv, dv))
        return max(0.0, min(slope, float(lead[-1]) / group_speed))

    def _start_pause(self, i: int, lead_m: float, group_speed: float, now: float,
                     time_lead_s: float = 0.0) -> bool:
        """Pause vehicle i for a lead of ``lead_m``, sized as a lead in metres at the
        cruise speed: never more than the lead needs, whichever kind it is (see
        :class:`KeeperOptions`), or for ``time_lead_s`` seconds of track where more
        (:meth:`_time_lead_s`: a lead that grew with the group's speed is one in time,
        and sized in metres at cruise while the group is still slow it was answered a
        fifth at a time: SITL in 5 m/s wind, a copter whose track clock stalled at the
        start fell 0.69 m behind over 2.5 s with the others paused ten times). False when
        no pause of 10 ms or more would do."""
        o = self.options
        cruise = self.cruise_speed_m_s
        lead_m = max(lead_m, time_lead_s * cruise)
        d = o.pause_for(lead_m, max(group_speed, cruise), cruise)
        if d <= 0:
            return False
        # the continues still to repeat were sent before: they arrive first
        self._resend[i] = []
        self._paused_at[i], self._resume_at[i] = now, now + d
        self._rest_until[i] = now + d + o.rest_s
        self._pause[i] = (now, d)
        self.log.pauses[i] += 1
        return True

    def _cut_short(self, i: int, now: float) -> None:
        """A pause continued before its time owes what a pause that long does."""
        if self._pause[i] is not None and now < self._resume_at[i]:
            began = self._pause[i][0]
            self._pause[i] = (began, max(now - began, 0.0))

    def release(self, now: float = 0.0) -> dict[int, bool]:
        """Continue for every vehicle paused (the legs are over, or the reports stopped)."""
        out = {}
        for i in range(len(self.paths)):
            if self._paused_at[i] is not None or self._resend[i]:
                if self._paused_at[i] is not None:
                    self.log.paused_s[i] += max(now - self._paused_at[i], 0.0)
                    self._cut_short(i, now)
                    self._paused_at[i], self._resumed_at[i] = None, now
                self._resend[i] = []
                out[i] = False
        return out


def planned_speed(missions) -> float | None:
    """The speed the missions set with their first DO_CHANGE_SPEED (None: none does, the
    vehicles fly at their own WPNAV_SPEED)."""
    for items in missions:
        for it in items:
            if it.command == 178 and it.param2 > 0:  # MAV_CMD_DO_CHANGE_SPEED
                return float(it.param2)
    return None
