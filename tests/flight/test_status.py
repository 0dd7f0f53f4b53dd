"""A vehicle's status figures the keeper reads many times a second, computed once per
report and without numpy's set-up, give numpy's numbers."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from ftlbo_mav.flight.status import GapLog, Status, quantile


@settings(max_examples=300, deadline=None)
@given(values=st.lists(st.floats(-1.0, 5.0, allow_nan=False), min_size=1, max_size=60),
       q=st.sampled_from([0.0, 0.1, 0.5, 0.9, 0.95, 1.0]))
def test_the_quantile_is_numpys_to_the_last_bit(values, q):
    assert quantile(values, q) == float(np.quantile(np.array(values), q))


def test_the_longest_gap_counts_the_window_and_the_silence_going_on():
    s = Status(heard_t=0.0)
    s.position_t = 20.0
    for t, gap in ((5.0, 3.0), (12.0, 1.5), (18.0, 0.4), (20.0, 0.2)):
        s.gaps.append((t, gap))
    assert s.longest_gap_s(20.5, window_s=10.0) == 1.5  # the 3 s gap is older than 10 s
    assert s.longest_gap_s(20.5, window_s=20.0) == 3.0
    assert s.longest_gap_s(24.0, window_s=5.0) == 4.0  # silent for 4 s now
    s.clock_rate = 2.0  # a vehicle whose clock runs twice as fast: its 20 s are our 10
    assert s.longest_gap_s(20.5, window_s=20.0) == 1.5 * 2.0  # in its seconds


@settings(max_examples=200, deadline=None)
@given(gaps=st.lists(st.floats(0.0, 3.0, allow_nan=False), min_size=0, max_size=80),
       keep=st.integers(1, 30), since=st.floats(-1.0, 90.0, allow_nan=False))
def test_the_running_longest_gap_is_the_scan_of_the_kept_reports(gaps, keep, since):
    """GapLog keeps the longest gap as a queue of peaks: the same answer as scanning the
    last ``keep`` reports from the newest back to the window's start."""
    log = GapLog(keep)
    arrivals = [float(k) for k in range(len(gaps))]
    for t, gap in zip(arrivals, gaps):
        log.append((t, gap))
    kept = list(zip(arrivals, gaps))[-keep:]
    scanned = [gap for t, gap in kept if t >= since]
    assert log.longest_since(since) == (max(scanned) if scanned else None)
    assert list(log) == kept and len(log) == len(kept)
