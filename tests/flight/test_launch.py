"""The settle before AUTO (``flight.launch.settle``): each copter's climb still for a
while, bounded, on a virtual clock with stand-in vehicles whose climb is a function of
time."""

from __future__ import annotations

import math
from types import SimpleNamespace

import pytest

from ftlbo_mav import clock
from ftlbo_mav.clock import VirtualClock
from ftlbo_mav.flight.fly import FlyOptions
from ftlbo_mav.flight.launch import settle


class Climbing:
    """A vehicle whose reported climb is ``climb(t)`` (m/s, t since the wait began)."""

    def __init__(self, name: str, climb, t0: float) -> None:
        self.name, self.sysid, self.aborted_to = name, 1, None
        self._climb, self._t0 = climb, t0

    @property
    def status(self):
        return SimpleNamespace(climb_m_s=self._climb(clock.monotonic() - self._t0))

    def wait_for(self, predicate, timeout_s: float) -> bool:
        clock.sleep(timeout_s)
        return predicate(self.status)


def _settle(*climbs, **options) -> tuple[float, list[str]]:
    said: list[str] = []
    with VirtualClock(start_s=0.0):
        vehicles = [Climbing(f"uav{i + 1}", c, 0.0) for i, c in enumerate(climbs)]
        settle(vehicles, FlyOptions(**{"settle_budget_s": 4.0, **options}), said.append)
        return clock.monotonic(), said


def test_it_waits_until_every_climb_has_been_still_for_the_hold():
    # one copter overshooting and coming back as SITL's do (0.1 m/s, fading over 2 s)
    waited, said = _settle(lambda t: 0.0, lambda t: 0.1 * math.exp(-t / 1.0) * math.cos(t))
    # within 0.05 m/s from 0.6 s on, then held 1 s
    assert waited == pytest.approx(1.6, abs=0.15)
    assert said == []


def test_the_wait_is_bounded_and_says_who_was_still_moving():
    waited, said = _settle(lambda t: 0.0, lambda t: 0.2, settle_budget_s=2.0)
    assert waited == pytest.approx(2.0, abs=0.11)
    assert len(said) == 1 and "uav2 climbing +0.20 m/s" in said[0]


def test_no_budget_no_wait_which_is_the_default():
    assert FlyOptions().settle_budget_s == 0.0
    waited, said = _settle(lambda t: 0.3, settle_budget_s=0.0)
    assert waited == 0.0 and said == []
