"""The departure watch (pure): each way a vehicle leaves the plan is told once, at the
cycle it shows, and only what ArduCopter says counts (its texts, its modes)."""

from __future__ import annotations

import numpy as np
import pytest

from ftlbo_mav.ardupilot.failsafes import departure_text
from ftlbo_mav.flight.departures import (
    CRASH,
    DISARMED_AIRBORNE,
    FAILSAFE,
    FENCE,
    FORMATION,
    LANDED_AWAY,
    LINK_BACK,
    LINK_LOST,
    MODE,
    NO_PROGRESS,
    SEPARATION,
    DepartureWatch,
    FormationBound,
    Seen,
    Together,
)
from ftlbo_mav.flight.metrics import slot_errors


def seen(**kw) -> Seen:
    base = dict(mode="AUTO", armed=True, alt_m=10.0, heard_t=100.0, link_up=True,
                asked_mode="AUTO", asked_t=50.0, position=np.zeros(3), seq=3)
    base.update(kw)
    return Seen(**base)


@pytest.mark.parametrize(("text", "kind"), [
    ("Fence Breached", FENCE),
    ("Battery Failsafe - Continuing Landing", FAILSAFE),
    ("GCS Failsafe", FAILSAFE),
    ("Radio + Battery Failsafe - Continuing Landing", FAILSAFE),
    ("EKF Failsafe: changed to LAND Mode", FAILSAFE),
    ("Failsafe: Terrain data missing", FAILSAFE),
    ("Crash: Disarming: AngErr=31>30, Accel=0.2<3.0", CRASH),
    ("Potential Thrust Loss (3)", CRASH),
    ("Radio Failsafe Cleared", None),
    ("EKF Failsafe Cleared", None),
    ("Reached command #4", None),
    ("Mission: 5 WP", None),
])
def test_arducopter_texts_that_mean_it_left_its_mission(text, kind):
    assert departure_text(text) == kind


def test_a_silent_vehicle_is_lost_after_the_timeout_and_back_when_heard():
    w = DepartureWatch(1)
    assert w.check([seen(heard_t=100.0)], 101.7) == []
    (e,) = w.check([seen(heard_t=100.0)], 101.9)
    assert (e.kind, e.index) == (LINK_LOST, 0) and "no message for 1.9 s" in e.detail
    assert w.check([seen(heard_t=100.0)], 103.0) == []  # said once
    (back,) = w.check([seen(heard_t=104.0)], 104.1)
    assert back.kind == LINK_BACK and not back.departure
    (again,) = w.check([seen(link_up=False, heard_t=104.0)], 104.2)  # closed: at once
    assert again.kind == LINK_LOST and "closed by the other end" in again.detail


def test_a_mode_not_asked_for_is_a_departure_once_the_grace_is_over():
    w = DepartureWatch(2)
    w.expect(0, "AUTO")
    w.expect(1, "AUTO")
    # vehicle 1 was just asked for AUTO and still shows GUIDED: the switch is under way
    out = w.check([seen(), seen(mode="GUIDED", asked_t=100.0)], 100.2)
    assert out == []
    out = w.check([seen(mode="BRAKE", asked_t=50.0, heard_t=104.0),
                   seen(mode="GUIDED", asked_t=100.0, heard_t=104.0)], 104.0)
    assert [(e.index, e.kind) for e in out] == [(0, MODE), (1, MODE)]
    assert "switched to BRAKE" in out[0].detail and out[0].vehicle_chose
    # a mode this station asked for is no departure; nor any mode without an expectation
    w2 = DepartureWatch(1)
    w2.expect(0, "AUTO")
    assert w2.check([seen(mode="RTL", asked_mode="RTL")], 100.0) == []
    w2.expect(0, None)
    assert w2.check([seen(mode="LOITER")], 100.0) == []


def test_failsafe_texts_are_read_once_in_order():
    w = DepartureWatch(1)
    texts = [(99.0, 6, "Mission: 4 WP"), (99.5, 4, "Battery Failsafe - Continuing RTL"),
             (99.6, 5, "Fence Breached")]
    out = w.check([seen(texts=texts, text_count=3)], 100.0)
    assert [e.kind for e in out] == [FAILSAFE, FENCE]
    assert w.check([seen(texts=texts, text_count=3)], 100.1) == []


def test_disarmed_in_the_air_and_landed_away():
    w = DepartureWatch(2, landing=[np.zeros(3), np.zeros(3)])
    w.check([seen(alt_m=8.0), seen(alt_m=0.5)], 100.0)
    w.check([seen(alt_m=8.0), seen(alt_m=2.0)], 100.1)  # vehicle 1 flew
    out = w.check([seen(armed=False, alt_m=7.9),
                   seen(armed=False, alt_m=0.0, position=np.array([3.0, 0.0, 0.0]))], 100.2)
    assert [(e.index, e.kind) for e in out] == [(0, DISARMED_AIRBORNE), (1, LANDED_AWAY)]
    assert "3.0 m from" in out[1].detail
    # a landing at the planned point is none
    w = DepartureWatch(1, landing=[np.zeros(3)])
    w.check([seen(alt_m=3.0)], 1.0)
    assert w.check([seen(armed=False, alt_m=0.0, position=np.array([0.4, 0.3, 0]))], 2.0) == []


def test_no_progress_on_the_legs_allows_the_items_hold_time():
    w = DepartureWatch(1)
    w.legs(0, True, hold_s=5.0)
    here = np.array([10.0, 5.0, 10.0])
    assert w.check([seen(position=here)], 100.0) == []
    assert w.check([seen(position=here + 0.2, heard_t=114.0)], 114.0) == []  # 10 s + 5 s hold
    (e,) = w.check([seen(position=here + 0.2, heard_t=115.5)], 115.5)
    assert e.kind == NO_PROGRESS and "item 3" in e.detail
    # moving, or a new item, is progress; off the legs nothing is watched
    w = DepartureWatch(1)
    w.legs(0, True)
    w.check([seen(position=here, heard_t=1000.0)], 1000.0)
    for t in range(1001, 1030):
        assert w.check([seen(position=here + [t - 1000.0, 0, 0], heard_t=t)], float(t)) == []
    w.legs(0, False)
    assert w.check([seen(position=here, heard_t=1100.0)], 1100.0) == []


# -- the formation as a whole: the plan's bound and min_separation

OFFSETS = np.array([[0.0, 0.0, 2.0], [3.0, 0.0, -1.0], [-3.0, 0.0, -1.0]])


def formation_watch(**kw) -> DepartureWatch:
    bound = FormationBound(OFFSETS, kw.pop("bound_m", 0.77), kw.pop("min_separation_m", 2.0),
                           names=("uav1", "uav2", "uav3"))
    w = DepartureWatch(3, formation=bound)
    for i in range(3):
        w.legs(i, True)
    return w


def flown(shift=(0.0, 0.0, 0.0), who: int = 1) -> np.ndarray:
    """The formation at (50, 20, 4) with UAV ``who`` moved by ``shift``."""
    p = OFFSETS + np.array([50.0, 20.0, 4.0])
    p[who] += shift
    return p


def look(w: DepartureWatch, t: float, positions, *, clock: float = 1000.0) -> list:
    """The watch at ``t`` on our clock; the vehicles' clock ``clock`` seconds on."""
    together = None if positions is None else Together(positions, t + clock)
    return w.check([seen(heard_t=t)] * 3, t, together)


def test_a_uav_off_its_slot_past_the_bound_for_half_a_second_is_a_formation_departure():
    w = formation_watch()
    assert look(w, 100.0, flown((0.5, 0.0, 0.0))) == []  # 0.33 m from its slot
    off = flown((0.0, 1.5, 0.0))  # uav2 1.5 m behind: 1.0 m from its slot
    assert look(w, 100.1, off) == []
    assert look(w, 100.4, off) == []  # past the bound for 0.3 s: a gust, the keeper's
    events = look(w, 100.6, off)
    assert [(e.index, e.kind, e.t) for e in events] == [(1, FORMATION, 100.6)]
    assert "1.00 m from its slot for 0.5 s" in events[0].detail
    assert "the plan's bound of 0.77 m" in events[0].detail
    assert look(w, 101.0, off) == []  # told once


def test_the_hold_is_on_the_vehicles_clock_and_twice_the_bound_is_at_once():
    w = formation_watch()
    off = flown((0.0, 1.5, 0.0))
    # an emulator six times faster: 0.05 s of ours is 0.3 s of theirs
    assert look(w, 100.0, off, clock=0.0) == []
    assert look(w, 100.05, off, clock=0.25) == []
    assert [e.kind for e in look(w, 100.1, off, clock=0.5)] == [FORMATION]
    w = formation_watch()
    far = flown((0.0, 2.4, 0.0))  # 1.6 m from its slot: more than twice 0.77 m
    assert look(w, 100.0, far) == [] and look(w, 100.05, far) == []
    assert [e.kind for e in look(w, 100.1, far)] == [FORMATION]


def test_one_look_past_the_bound_is_not_enough_however_long_the_clock_says():
    """A ground station's timing errors (a simulator run twenty times faster makes 10 ms
    of ours 0.2 s of its) show in one look: three in a row are needed."""
    w = formation_watch()
    far = flown((0.0, 2.4, 0.0))
    assert look(w, 100.0, far, clock=0.0) == []
    assert look(w, 100.05, flown(), clock=20.0) == []
    assert look(w, 100.1, far, clock=40.0) == [] and look(w, 100.15, far, clock=60.0) == []
    assert [e.kind for e in look(w, 100.2, far, clock=80.0)] == [FORMATION]


def test_back_within_the_bound_starts_the_count_again():
    w = formation_watch()
    off = flown((0.0, 1.5, 0.0))
    assert look(w, 100.0, off) == []
    assert look(w, 100.4, flown()) == []
    assert look(w, 100.5, off) == [] and look(w, 100.9, off) == []
    assert [e.kind for e in look(w, 101.0, off)] == [FORMATION]


def test_the_formation_is_not_judged_without_positions_together_or_off_the_legs():
    w = formation_watch()
    off = flown((0.0, 3.0, 0.0))
    w.legs(2, False)  # one still taking off
    assert look(w, 100.0, off) == []
    w.legs(2, True)
    assert look(w, 102.0, None) == []  # stale reports: no judgement
    assert DepartureWatch(3).check([seen(heard_t=104.0)] * 3, 104.0,
                                   Together(off, 104.0)) == []  # a plan without a bound


def test_two_uavs_closer_than_min_separation_is_a_separation_departure():
    # uav2 moves 2.5 m towards uav3: 3.04 m below-beside uav1 (4.24 m apart as planned)
    w = formation_watch(bound_m=5.0, min_separation_m=3.2)
    close = flown((-2.5, 0.0, 0.0), who=1)
    assert look(w, 100.0, close) == [] and look(w, 100.1, close) == []
    events = look(w, 100.25, close)
    assert [(e.index, e.kind) for e in events] == [(1, SEPARATION)]
    assert "3.04 m from uav1" in events[0].detail
    assert "min_separation 3.2 m" in events[0].detail


@pytest.mark.parametrize("n", [2, 3, 5, 8])
def test_a_few_uavs_are_judged_in_plain_floats_to_numpys_last_bit(n):
    """Up to FEW_UAVS the watch computes the slot errors and distances itself (20 looks
    a second): the same numbers, the same worst UAV and the same closest pair as numpy."""
    rng = np.random.default_rng(n)
    offsets = rng.normal(0.0, 3.0, (n, 3))
    w = DepartureWatch(n, formation=FormationBound(offsets, 0.77, 2.0))
    for _ in range(50):
        positions = offsets + rng.normal(0.0, 0.5, (n, 3)) + rng.normal(0.0, 100.0, 3)
        err, worst, d, i, j = w._formation_few(positions)
        assert err == slot_errors(positions, offsets).tolist()
        assert worst == int(np.argmax(slot_errors(positions, offsets)))
        ours = np.linalg.norm(positions[:, None] - positions[None], axis=-1)
        ours[np.diag_indices(n)] = np.inf
        assert np.array_equal(d, ours)
        assert (i, j) == tuple(int(k) for k in np.unravel_index(int(np.argmin(ours)), ours.shape))
