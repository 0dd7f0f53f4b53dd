"""The keeper's step (flight/watch.py keep_formation): reports brought to one instant."""

from __future__ import annotations

import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from ftlbo_mav.flight.keeper import KeeperOptions
from ftlbo_mav.flight.planned import load_planned_flight
from ftlbo_mav.flight.status import Status
from ftlbo_mav.flight.watch import MAX_REPORT_DELAY_S, keep_formation

ROOT = Path(__file__).resolve().parents[2]
PLANNED = load_planned_flight(ROOT / "missions" / "nha-trang-orchard")


class SeenPositions:
    """A keeper that records what it is given."""

    active, pausing = True, False
    options = KeeperOptions()

    def update(self, positions, speeds, now, ages_s=None, jitter_s=None, gap_s=None):
        self.positions, self.jitter_s, self.gap_s = positions, jitter_s, gap_s
        return {}

    def release(self, now=0.0):
        return {}


def vehicle(i: int, *, clock_offset_s: float, boot_s: float, arrived_ago_s: float):
    enu = np.asarray(PLANNED.paths[i][0]) + [10.0, 0.0, 0.0]
    lat, lon, alt = PLANNED.frame.to_lla(enu)
    s = Status(mode="AUTO", armed=True, lat_deg=float(lat), lon_deg=float(lon),
               alt_m=float(alt), ground_speed_m_s=5.0, velocity_enu=(5.0, 0.0, 0.0), seq=4,
               position_t=time.monotonic() - arrived_ago_s, position_boot_s=boot_s,
               clock_offset_s=clock_offset_s)
    return SimpleNamespace(status=s, send_pause=lambda _p: None)


def test_a_stale_clock_offset_does_not_move_a_copter_along_its_track():
    """uav2's clock has fallen 0.4 s behind ours since its least-delayed report (a SITL
    instance on a loaded machine): its report, just arrived, is not 0.4 s old."""
    now = time.monotonic()
    fresh = [vehicle(i, clock_offset_s=now - 100.0, boot_s=100.0, arrived_ago_s=0.0)
             for i in (0, 2)]
    stale = vehicle(1, clock_offset_s=now - 100.4, boot_s=100.0, arrived_ago_s=0.0)
    keeper = SeenPositions()
    assert keep_formation(PLANNED, [fresh[0], stale, fresh[1]], keeper)
    moved = keeper.positions[:, 0] - (np.asarray(PLANNED.paths)[:, 0, 0] + 10.0)
    assert moved[1] <= 5.0 * (MAX_REPORT_DELAY_S + 0.05)  # not 5 m/s x 0.4 s
    assert abs(moved[0]) < 0.1 and abs(moved[2]) < 0.1


def test_the_links_jitter_is_the_worst_vehicles_once_every_one_has_enough_reports():
    now = time.monotonic()
    copters = [vehicle(i, clock_offset_s=now - 100.0, boot_s=100.0, arrived_ago_s=0.0)
               for i in range(3)]
    keeper = SeenPositions()
    keep_formation(PLANNED, copters, keeper)
    assert keeper.jitter_s is None  # not known yet
    for k, v in enumerate(copters):
        v.status.delays.extend(np.linspace(0.0, 0.05 * (k + 1), 50))
    keep_formation(PLANNED, copters, keeper)
    assert abs(keeper.jitter_s - 0.9 * 0.15) < 0.01  # uav3's: 90 % of its delays below


def test_a_status_measures_each_reports_delay_beyond_the_least_delayed():
    s = Status()
    assert s.jitter_s() is None
    s.delays.extend([0.0] * 18 + [0.3, 0.3])
    assert s.jitter_s() is not None and s.jitter_s() < 0.3


def test_the_longest_silence_of_reports_is_in_the_vehicles_seconds():
    s = Status(clock_rate=2.0)
    s.gaps.extend([(100.0, 0.1), (101.0, 0.45), (108.0, 0.1)])
    s.position_t = 108.0
    assert s.longest_gap_s(108.05, window_s=20.0) == 0.9  # 0.45 s of ground time at 2x
    assert s.longest_gap_s(108.05, window_s=10.0) == 0.2  # the long one is 14 s ago
    assert s.longest_gap_s(109.0, window_s=1.0) == 2.0  # going on now: 1 s


def test_the_positions_at_one_instant_are_worked_out_once_until_a_report_changes():
    """The watch and the keeper both ask at the same instant (a simulated clock): the
    memo answers the second, with its own copy; a new report is worked out again."""
    from ftlbo_mav import clock
    from ftlbo_mav.clock import VirtualClock
    from ftlbo_mav.flight.watch import positions_now

    with VirtualClock(start_s=200.0):
        copters = [vehicle(i, clock_offset_s=100.0, boot_s=99.9, arrived_ago_s=0.0)
                   for i in range(3)]
        st = [v.status for v in copters]
        for s in st:
            s.position_t = clock.monotonic() - 0.05
        memo: dict = {}
        first = positions_now(PLANNED, st, memo=memo)
        first[0][0, 0] += 100.0  # the caller's copy
        again = positions_now(PLANNED, st, memo=memo)
        plain = positions_now(PLANNED, st)
        assert all(np.array_equal(a, b) for a, b in zip(again[:3], plain[:3]))
        assert again[3] == plain[3]
        st[1].lat_deg += 1e-5  # a new report: about 1.1 m north
        moved = positions_now(PLANNED, st, memo=memo)
        assert 1.0 < moved[0][1, 1] - plain[0][1, 1] < 1.2
