"""Whether the link carries what the formation needs, said before take-off.

:mod:`ftlbo_mav.link.budget` judges a radio by the bytes a flight asks of it, before
anything is connected. This module judges it by what came through it: by the time the
pre-flight has read every copter's mission back, each copter's position reports have
crossed the link for seconds, and :class:`~.status.Status` knows how late they came,
how much later than each other (the jitter) and how long the link went silent. The
flight needs three things of them, each one measured on ArduPilot SITL
(docs/flight.md):

- the formation keeper pauses a leader only through a link whose delays vary by at most
  its ``max_jitter_s`` and that has not gone silent for ``max_gap_s`` within
  ``gap_memory_s`` (:class:`~.keeper.KeeperOptions`); through another it pauses nobody,
  and the formation is the copters' own from their synchronized start;
- the start is trimmed for copters whose clocks disagree only through the same link
  (:data:`~.start.TRIM_MAX_JITTER_S`);
- the departure watch takes a silence of ``link_lost_s`` for a lost link
  (:class:`~.departures.WatchOptions`): a link that was that silent on the ground would
  end the flight in the air.

The delays are judged on the reports of a quiet moment after the pre-flight
(:func:`look`): while missions are read back, a radio's queue holds the reports back
behind the items (the emulator's good-day radio, 60 +- 40 ms: 168 ms over the pre-flight,
under 140 ms after it), and a flight's legs are not flown with a mission crossing it.
The silences are judged on every report the pre-flight saw (an outage comes when it
comes). :func:`link_findings` is pure: :class:`LinkSeen` values in, lines out.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from .. import clock
from .departures import WatchOptions
from .keeper import KeeperOptions
from .start import TRIM_MAX_JITTER_S
from .status import Status, quantile

LOST_SHARE = 0.8
"""A silence before take-off of this share of ``link_lost_s`` or more is said: one a
little longer in the air is a lost link, a departure."""
SLOW_SHARE = 0.6
"""Position reports arriving at less than this share of the rate asked are said: the
keeper and the watch then measure on older positions than they were made for."""
LOOK_REPORTS = 30  # the delays of a quiet moment: this many reports from every copter
LOOK_S = 4.0  # waited for at most this long (the ground's seconds)


@dataclass(frozen=True)
class LinkSeen:
    """One copter's link as its reports showed it: ``jitter_s`` the 90th percentile of
    their delays beyond the least delayed (None: too few reports to tell),
    ``longest_gap_s`` the longest silence between them, ``rate_hz`` reports a second,
    over ``seconds`` of reports (the vehicle's seconds)."""

    name: str
    jitter_s: float | None
    longest_gap_s: float
    rate_hz: float
    seconds: float


def seen(name: str, status: Status, now: float, *, since: float) -> LinkSeen:
    """What ``status`` knows of its link at ground time ``now``: the delays of the
    reports that arrived at ``since`` or later (at least 20 of them, else unknown), the
    silences and the rate of every report it keeps (its :class:`~.status.GapLog`, 40 s
    at 10 Hz)."""
    arrivals = [t for t, _gap in status.gaps]
    seconds = (now - arrivals[0]) * status.clock_rate if arrivals else 0.0
    rate = (len(arrivals) - 1) / seconds if len(arrivals) > 1 and seconds > 0 else 0.0
    recent = min(sum(t >= since for t in arrivals), len(status.delays))
    jitter = quantile(list(status.delays)[-recent:], 0.9) if recent >= 20 else None
    return LinkSeen(name, jitter, status.longest_gap_s(now, max(seconds, 1e-9)), rate,
                    seconds)


def look(statuses: Sequence[Status], *, reports: int = LOOK_REPORTS,
         timeout_s: float = LOOK_S) -> float:
    """Wait until every copter's link has brought ``reports`` position reports from now
    (at most ``timeout_s``); returns now, the ``since`` of :func:`seen`."""
    since = clock.monotonic()
    while clock.monotonic() < since + timeout_s and any(
            sum(t >= since for t, _gap in s.gaps) < reports for s in statuses):
        clock.sleep(0.1)
    return since


def link_findings(links: Sequence[LinkSeen], *, keeper: KeeperOptions | None,
                  watch: WatchOptions, position_hz: float) -> list[str]:
    """What the flight cannot count on through these links, a line each (empty: it gets
    what it needs). ``keeper`` None: the flight has no formation keeper."""
    out = []
    slow = [s for s in links if s.seconds >= 2.0 and s.rate_hz < SLOW_SHARE * position_hz]
    if slow:
        out.append("positions arrive at " + ", ".join(f"{s.name} {s.rate_hz:.1f} Hz"
                                                      for s in slow)
                   + f" of the {position_hz:g} Hz asked: the link does not carry them, and "
                   "the keeper and the departure watch see the copters late")
    jittery = [s for s in links if s.jitter_s is not None]
    worst = max(jittery, key=lambda s: s.jitter_s, default=None)
    silent = max(links, key=lambda s: s.longest_gap_s, default=None)
    if keeper is not None and keeper.enabled:
        why = []
        if worst is not None and worst.jitter_s > keeper.max_jitter_s:
            why.append(f"{worst.name}'s reports' delays vary by {_ms(worst.jitter_s)} "
                       f"(it pauses through at most {_ms(keeper.max_jitter_s)})")
        if silent is not None and silent.longest_gap_s > keeper.max_gap_s:
            why.append(f"{silent.name}'s reports stopped for {silent.longest_gap_s:.1f} s "
                       f"(it pauses nobody for {keeper.gap_memory_s:g} s after a silence "
                       f"over {keeper.max_gap_s:g} s)")
        if why:
            out.append("the formation keeper cannot act through this link: "
                       + "; ".join(why) + ": the formation is the copters' own from "
                       "their synchronized start, no leader is paused")
    if worst is not None and worst.jitter_s > TRIM_MAX_JITTER_S:
        out.append(f"{worst.name}'s reports' delays vary by {_ms(worst.jitter_s)}: the "
                   "start is not trimmed for copters whose clocks disagree (it needs "
                   f"at most {_ms(TRIM_MAX_JITTER_S)})")
    if silent is not None and silent.longest_gap_s >= LOST_SHARE * watch.link_lost_s:
        out.append(f"{silent.name}'s link went silent for {silent.longest_gap_s:.1f} s "
                   f"before take-off: in the air {watch.link_lost_s:g} s is a lost link, a "
                   "departure that ends the flight")
    return out


def _ms(seconds: float) -> str:
    """Milliseconds, rounded up: a delay just over a bound does not read as the bound."""
    return f"{math.ceil(1000 * seconds - 1e-9):.0f} ms"


__all__ = ["LOOK_REPORTS", "LOOK_S", "LOST_SHARE", "LinkSeen", "SLOW_SHARE", "link_findings",
           "look", "seen"]
