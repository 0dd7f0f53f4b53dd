"""A vehicle leaving the plan, told from what it says: the watch behind ``fly`` and
``monitor``.

:class:`DepartureWatch` is fed a :class:`Seen` per vehicle (a snapshot of its status and
link) a few times a second and returns :class:`Event` s: a departure the first time a
vehicle

- falls silent (no message for ``link_lost_s``) or its link closes: ``link lost``;
- is in a mode this ground station did not ask for (BRAKE, RTL or LAND from a fence
  breach or a failsafe, LOITER or ALT_HOLD from a pilot, GUIDED from another station):
  ``mode``;
- announces a failsafe, a fence breach or a crash (:mod:`ftlbo_mav.ardupilot.failsafes`);
- disarms in the air: ``disarmed in the air``;
- makes no progress along its mission on the legs (no new item and no movement for
  ``stall_s`` plus the item's hold time): ``no progress``;
- lands (disarms) farther than ``landed_away_m`` from where its mission lands:
  ``landed away``;
- has less charge left than the rest of its mission needs with half its reserve
  (:mod:`.battery`: the plan's ``[battery]``, else each copter's own BATT_CAPACITY and
  floor), or announces its own low battery with no failsafe action of its own:
  ``battery``;
- no longer knows well enough where it is (its GPS or EKF past the plan's navigation
  budget, a GPS glitch, ArduCopter's own glitch or EKF variance announcement:
  :mod:`.navigation`): ``navigation``;

and, the formation as a whole on its legs (positions brought to one instant, given only
while every report is fresh):

- a UAV farther from its slot than the plan's bound (``formation_bound`` in plan.json,
  :attr:`~ftlbo_mav.planning.plans.Plan.formation_bound_m`) for ``hold_s``:
  ``formation``, the UAV farthest from its slot the one that left;
- two UAVs closer than ``min_separation`` for ``separation_hold_s``: ``separation``, the
  one of the pair farther from its slot the one that left;

and a ``link back`` event when a lost vehicle is heard from again. Pure: no I/O, the
time is given.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ..ardupilot.failsafes import departure_text
from ..gnss import NavigationBudget
from .battery import BatteryWatch
from .metrics import formation_error, slot_errors
from .navigation import EkfReport, GpsReport, NavigationWatch

LINK_LOST, LINK_BACK, MODE, FAILSAFE, FENCE, CRASH, NAVIGATION, BATTERY = (
    "link lost", "link back", "mode", "failsafe", "fence", "crash", "navigation", "battery")
FORMATION, SEPARATION = "formation", "separation"
DISARMED_AIRBORNE, NO_PROGRESS, LANDED_AWAY = "disarmed in the air", "no progress", "landed away"
# departures the vehicle (its pilot, its failsafe, another station) chose: the flight
# never commands that vehicle against them
VEHICLE_CHOSE = frozenset({MODE, FAILSAFE, FENCE, CRASH, DISARMED_AIRBORNE})


@dataclass(frozen=True)
class WatchOptions:
    """``link_lost_s``: silence that counts as a lost link (ArduPilot sends HEARTBEAT at
    1 Hz and a flight asks for positions at 10 Hz): through a radio on a rough day (10 %
    of frames lost in bursts, a 1 s outage every 15 s: sim/radio.py ROUGH_DAY) a copter's
    longest silence in ten modelled minutes was 1.35 s, and a loss is still seen within
    2 s. ``mode_grace_s``: how long after this station asked for a mode the vehicle may
    still be in the one before. ``stall_s`` / ``stall_m``: no progress. ``airborne_m``:
    above this a disarm is in the air (and below it a vehicle has landed).
    ``landed_away_m``: how far from its mission's landing point a vehicle may land."""

    link_lost_s: float = 1.8
    mode_grace_s: float = 3.0
    stall_s: float = 10.0
    stall_m: float = 0.5
    airborne_m: float = 1.0
    landed_away_m: float = 1.5


DEFAULT_WATCH = WatchOptions()


@dataclass(frozen=True, eq=False)
class FormationBound:
    """The formation's own watch: ``offsets`` ``(N, 3)`` the planned offsets, ``bound_m``
    how far from its slot a UAV may be (the plan's ``formation_bound``): for no longer
    than ``hold_s`` (a moment past it, a gust, is the keeper's to answer), and not at
    all ``at_once`` times as far; ``min_separation_m`` how close two may come, for no
    longer than ``separation_hold_s``. Seconds of the vehicles' clock, and in ``looks``
    looks in a row at least (a ground station's timing errors, which a simulator run
    faster than real time multiplies, last one look); ``names`` for the details."""

    offsets: np.ndarray
    bound_m: float
    min_separation_m: float
    hold_s: float = 0.5
    at_once: float = 2.0
    separation_hold_s: float = 0.2
    looks: int = 3
    names: Sequence[str] = ()

    def name(self, i: int) -> str:
        return self.names[i] if i < len(self.names) else f"UAV {i + 1}"


@dataclass(frozen=True)
class Together:
    """Every vehicle's position ``(N, 3)`` ENU brought to one instant ``t`` (seconds of
    the vehicles' clock)."""

    positions: np.ndarray
    t: float


@dataclass(frozen=True)
class Seen:
    """One vehicle as the watch sees it at one instant (times are ``clock.monotonic()``).
    ``position``: ENU metres in the plan's frame, or None; ``seq``: its current item."""

    mode: str
    armed: bool
    alt_m: float
    heard_t: float
    link_up: bool
    asked_mode: str | None
    asked_t: float
    texts: Sequence[tuple[float, int, str]] = ()
    text_count: int = 0
    position: np.ndarray | None = None
    seq: int = -1
    gps: GpsReport | None = None
    ekf: EkfReport | None = None
    gps_jump_m: float = 0.0
    battery_pct: int | None = None
    battery_current_a: float | None = None


@dataclass(frozen=True)
class Event:
    """What happened to vehicle ``index`` at ``t``: ``kind`` (a departure, or ``link
    back``) and a few words of ``detail``."""

    index: int
    kind: str
    detail: str
    t: float

    @property
    def departure(self) -> bool:
        return self.kind != LINK_BACK

    @property
    def vehicle_chose(self) -> bool:
        return self.kind in VEHICLE_CHOSE


FEW_UAVS = 8
"""Up to this many UAVs the formation is judged in plain floats (more: numpy's arrays)."""


@dataclass
class _Track:
    reported: set = field(default_factory=set)
    lost: bool = False
    texts_read: int = 0
    was_armed: bool = False
    flew: bool = False
    last_alt: float = 0.0
    mode_at_ask: str | None = None
    asked_t: float = -1.0
    progress_t: float | None = None
    progress_seq: int = -1
    progress_at: np.ndarray | None = None


class DepartureWatch:
    """Watches ``count`` vehicles. ``expect(i, mode)`` says which mode the plan has
    vehicle i in now (GUIDED while it takes off, AUTO on the mission; None: any);
    ``legs(i, hold_s)`` that it flies its legs (no-progress watch on, the current item's
    hold time allowed); ``landing`` (per vehicle, ENU or None) where each mission lands.
    """

    def __init__(self, count: int, *, options: WatchOptions = WatchOptions(),
                 landing: Sequence[np.ndarray | None] | None = None,
                 navigation: NavigationBudget | None = None,
                 battery: BatteryWatch | None = None,
                 formation: FormationBound | None = None) -> None:
        self.options = options
        self.formation = formation
        self._slots: list | None = None  # each slot's offset from the formation's centre
        # FORMATION / SEPARATION: past the bound since (vehicles' clock), looks in a row
        self._past: dict[str, tuple[float, int]] = {}
        self.battery = battery
        self.navigation = None if navigation is None else NavigationWatch(count, navigation)
        self.tracks = [_Track() for _ in range(count)]
        self.expected: list[str | None] = [None] * count
        self.on_legs = [False] * count
        self.hold_s = [0.0] * count
        self.landing = list(landing) if landing is not None else [None] * count
        self.events: list[Event] = []

    def expect(self, index: int, mode: str | None) -> None:
        self.expected[index] = mode

    def legs(self, index: int, on: bool, *, hold_s: float = 0.0) -> None:
        tr = self.tracks[index]
        if on and not self.on_legs[index]:
            tr.progress_t = None
        self.on_legs[index], self.hold_s[index] = on, hold_s

    def stop_landing_check(self, index: int) -> None:
        """After the flight sent the vehicle elsewhere, where it lands is no departure."""
        self.landing[index] = None

    def check(self, seen: Sequence[Seen], now: float,
              together: Together | None = None) -> list[Event]:
        """The new events since the last call. ``together``: every vehicle's position
        brought to one instant, while the formation flies its legs and every report is
        fresh (None: not now; the formation is not judged)."""
        out: list[Event] = []
        for i, s in enumerate(seen):
            out += self._check_one(i, s, now)
        if together is not None and self.formation is not None and all(self.on_legs):
            out += self._formation(np.asarray(together.positions, float), together.t, now)
        self.events += out
        return out

    def _formation(self, positions: np.ndarray, t: float, now: float) -> list[Event]:
        """The formation at ``t`` (the vehicles' clock); events are stamped ``now``."""
        f, out = self.formation, []
        if len(positions) <= FEW_UAVS:
            err, worst, d, i, j = self._formation_few(positions)
        else:
            err = slot_errors(positions, f.offsets)
            worst = int(np.argmax(err))
            d = np.linalg.norm(positions[:, None] - positions[None], axis=-1)
            d[np.diag_indices(len(d))] = np.inf
            i, j = (int(k) for k in np.unravel_index(int(np.argmin(d)), d.shape))
        for kind, past, hold in (
                (FORMATION, err[worst] > f.bound_m,
                 0.0 if err[worst] > f.at_once * f.bound_m else f.hold_s),
                (SEPARATION, d[i, j] < f.min_separation_m, f.separation_hold_s)):
            if not past:
                self._past.pop(kind, None)
                continue
            since, looks = self._past.get(kind, (t, 0))
            self._past[kind] = (since, looks + 1)
            if t - since < hold or looks + 1 < f.looks:
                continue
            if kind == FORMATION:
                detail = (f"{err[worst]:.2f} m from its slot for {t - since:.1f} s, past "
                          f"the plan's bound of {f.bound_m:.2f} m (formation error "
                          f"{float(formation_error(positions, f.offsets)):.2f} m RMS)")
                out += self._once(worst, FORMATION, detail, now)
            else:
                k, other = (i, j) if err[i] >= err[j] else (j, i)
                detail = (f"{d[i, j]:.2f} m from {f.name(other)} for {t - since:.1f} s, "
                          f"closer than min_separation {f.min_separation_m:g} m")
                out += self._once(k, SEPARATION, detail, now)
        return out

    def _formation_few(self, positions: np.ndarray) -> tuple:
        """:meth:`_formation`'s slot errors, the worst, the distances and the closest pair
        of a few UAVs in plain floats (looked at 20 times a second: numpy's per-call cost
        would be most of it), summed in the order numpy sums them."""
        if self._slots is None:
            offsets = np.asarray(self.formation.offsets, float)
            self._slots = (offsets - offsets.mean(axis=0)).tolist()
        p = positions.tolist()
        n = len(p)
        mean = [0.0, 0.0, 0.0]
        for row in p:
            mean = [mean[0] + row[0], mean[1] + row[1], mean[2] + row[2]]
        mean = [m / n for m in mean]
        err = []
        for (x, y, z), (ox, oy, oz) in zip(p, self._slots):
            ex, ey, ez = x - mean[0] - ox, y - mean[1] - oy, z - mean[2] - oz
            err.append(math.sqrt(ex * ex + ey * ey + ez * ez))
        worst = max(range(n), key=err.__getitem__)
        d = [[math.inf] * n for _ in range(n)]
        best, i, j = math.inf, 0, 0
        for a in range(n):
            for b in range(n):
                if a != b:
                    dx, dy, dz = p[a][0] - p[b][0], p[a][1] - p[b][1], p[a][2] - p[b][2]
                    d[a][b] = math.sqrt(dx * dx + dy * dy + dz * dz)
                    if d[a][b] < best:
                        best, i, j = d[a][b], a, b
        return err, worst, np.array(d), i, j

    # -- one vehicle
    def _once(self, i: int, kind: str, detail: str, now: float) -> list[Event]:
        tr = self.tracks[i]
        if kind in tr.reported:
            return []
        tr.reported.add(kind)
        return [Event(i, kind, detail, now)]

    def _check_one(self, i: int, s: Seen, now: float) -> list[Event]:
        o, tr = self.options, self.tracks[i]
        silent = now - s.heard_t if s.heard_t else float("inf")
        if not s.link_up or silent > o.link_lost_s:
            if not tr.lost:
                tr.lost = True
                tr.reported.discard(LINK_LOST)
                why = ("its link was closed by the other end" if not s.link_up
                       else f"no message for {silent:.1f} s")
                return self._once(i, LINK_LOST, why, now)
            return []
        out: list[Event] = []
        if tr.lost:
            tr.lost = False
            tr.progress_t = None
            out.append(Event(i, LINK_BACK, "heard from again", now))
        # what it announces (every STATUSTEXT since the last look, in order)
        new = s.text_count - tr.texts_read
        tr.texts_read = s.text_count
        for _t, _severity, text in (list(s.texts)[-new:] if new > 0 else []):
            kind = departure_text(text)
            if self.battery is not None:
                kind = self.battery.text_kind(i, text, kind)
            if kind is not None:
                out += self._once(i, kind, f'"{text.strip()}"', now)
        # where it is: its GPS and EKF held to the plan's budget, in the air
        if self.navigation is not None and s.armed:
            why = self.navigation.check(i, s.gps, s.ekf, now, jump_m=s.gps_jump_m)
            if why is not None:
                out += self._once(i, NAVIGATION, why, now)
        # its charge against the rest of its mission, in the air
        if self.battery is not None and s.armed and s.alt_m > o.airborne_m:
            why = self.battery.check(i, s.battery_pct, s.seq, current_a=s.battery_current_a,
                                     now=now)
            if why is not None:
                out += self._once(i, BATTERY, why, now)
        # mode
        if s.asked_t != tr.asked_t:  # this station asked for a mode: the one before it
            tr.asked_t, tr.mode_at_ask = s.asked_t, s.mode  # may linger a moment
        expected = self.expected[i]
        if expected is not None and s.armed and s.mode not in (expected, s.asked_mode):
            lingering = s.mode == tr.mode_at_ask and now - s.asked_t <= o.mode_grace_s
            if not lingering:
                out += self._once(i, MODE, f"switched to {s.mode}, not asked for by this "
                                           f"flight", now)
        # arming and landing
        airborne = s.alt_m > o.airborne_m
        if s.armed:
            tr.was_armed = True
            tr.flew = tr.flew or airborne
        elif tr.was_armed:
            tr.was_armed = False
            if tr.last_alt > o.airborne_m and airborne:
                out += self._once(i, DISARMED_AIRBORNE, f"disarmed at {s.alt_m:.1f} m", now)
            elif tr.flew and self.landing[i] is not None and s.position is not None:
                off = float(np.hypot(*(s.position[:2] - self.landing[i][:2])))
                if off > o.landed_away_m:
                    out += self._once(i, LANDED_AWAY, f"landed {off:.1f} m from its mission's "
                                                      "landing point", now)
        tr.last_alt = s.alt_m
        out += self._progress(i, s, now)
        return out

    def _progress(self, i: int, s: Seen, now: float) -> list[Event]:
        o, tr = self.options, self.tracks[i]
        if not (self.on_legs[i] and s.armed and s.mode == "AUTO" and s.position is not None):
            tr.progress_t = None
            return []
        moved = (tr.progress_at is not None
                 and float(np.linalg.norm(s.position - tr.progress_at)) > o.stall_m)
        if tr.progress_t is None or s.seq != tr.progress_seq or moved:
            tr.progress_t, tr.progress_seq, tr.progress_at = now, s.seq, s.position.copy()
            return []
        stalled = now - tr.progress_t
        if stalled > o.stall_s + self.hold_s[i]:
            return self._once(i, NO_PROGRESS, f"still at item {s.seq}, moved less than "
                                              f"{o.stall_m:g} m in {stalled:.0f} s", now)
        return []
