"""What the link cannot carry of a formation flight is said before take-off, from what
its reports showed (flight/linkfit.py)."""

from __future__ import annotations

import pytest

from ftlbo_mav.flight.departures import WatchOptions
from ftlbo_mav.flight.keeper import KeeperOptions
from ftlbo_mav.flight.linkfit import LinkSeen, link_findings, seen
from ftlbo_mav.flight.status import Status

KEEPER = KeeperOptions()
WATCH = WatchOptions()


def links(jitter=0.05, gap=0.2, rate=10.0, n=3):
    return [LinkSeen(f"uav{i + 1}", jitter, gap, rate, 20.0) for i in range(n)]


def findings(seen_links, keeper=KEEPER):
    return link_findings(seen_links, keeper=keeper, watch=WATCH, position_hz=10.0)


def test_a_link_that_carries_the_flight_says_nothing():
    assert findings(links()) == []
    assert findings(links(jitter=None)) == []  # too few reports to judge: nothing made up


def test_delays_that_vary_more_than_the_keeper_can_time_are_said_with_the_copter():
    lines = findings(links()[:2] + [LinkSeen("uav3", 0.19, 0.2, 10.0, 20.0)])
    assert len(lines) == 2
    assert lines[0].startswith("the formation keeper cannot act through this link: uav3's "
                               "reports' delays vary by 190 ms (it pauses through at most "
                               "140 ms)")
    assert lines[1].startswith("uav3's reports' delays vary by 190 ms: the start is not "
                               "trimmed")


def test_a_silence_stops_the_keeper_and_one_near_a_lost_link_is_said_as_such():
    lines = findings(links()[:2] + [LinkSeen("uav3", 0.05, 1.0, 10.0, 20.0)])
    assert lines == ["the formation keeper cannot act through this link: uav3's reports "
                     "stopped for 1.0 s (it pauses nobody for 20 s after a silence over "
                     "0.6 s): the formation is the copters' own from their synchronized "
                     "start, no leader is paused"]
    lines = findings(links()[:2] + [LinkSeen("uav3", 0.05, 1.6, 10.0, 20.0)])
    assert lines[-1] == ("uav3's link went silent for 1.6 s before take-off: in the air "
                         "1.8 s is a lost link, a departure that ends the flight")


def test_without_a_keeper_only_the_start_and_the_watch_are_judged():
    assert findings(links(jitter=0.19, gap=0.9), keeper=None) == [
        "uav1's reports' delays vary by 190 ms: the start is not trimmed for copters whose "
        "clocks disagree (it needs at most 140 ms)"]
    assert findings(links(jitter=0.19), keeper=KeeperOptions(enabled=False))[0].startswith(
        "uav1's reports' delays vary by 190 ms: the start is not trimmed")


def test_positions_slower_than_asked_are_said():
    lines = findings(links(rate=4.2))
    assert lines == ["positions arrive at uav1 4.2 Hz, uav2 4.2 Hz, uav3 4.2 Hz of the "
                     "10 Hz asked: the link does not carry them, and the keeper and the "
                     "departure watch see the copters late"]


def test_what_a_status_saw_judges_its_quiet_moment_and_every_silence():
    s = Status()
    s.clock_rate = 1.0
    arrivals = [0.1 * k for k in range(201)]  # 20 s of reports at 10 Hz
    arrivals = arrivals[:50] + arrivals[62:]  # a 1.3 s silence after 4.9 s
    prev = None
    for t in arrivals:
        s.gaps.append((t, 0.0 if prev is None else t - prev))
        prev = t
    s.position_t = arrivals[-1]
    # the delays: 0.3 s of queue while the missions crossed, then a quiet link
    for k in range(50):
        s.delays.append(0.3 if k < 20 else 0.01 * (k % 5))
    link = seen("uav1", s, now=20.0, since=17.0)  # 30 reports since 17.0
    assert link.jitter_s == pytest.approx(0.04)  # the quiet moment only
    assert link.longest_gap_s == pytest.approx(1.3)
    assert link.rate_hz == pytest.approx((len(arrivals) - 1) / 20.0)
    assert seen("uav1", s, now=20.0, since=19.5).jitter_s is None  # 5 reports: unknown


def test_a_delay_just_over_the_bound_does_not_read_as_the_bound():
    lines = findings(links()[:2] + [LinkSeen("uav3", 0.1404, 0.2, 10.0, 20.0)])
    assert "vary by 141 ms (it pauses through at most 140 ms)" in lines[0]
