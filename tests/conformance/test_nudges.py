"""The formation keeper's two levers, as ArduCopter 4.5.6 SITL answered them
(``tests/data/ardupilot-4.5.6/nudges.json``): a speed set mid-leg, and a short pause."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from ftlbo_mav.ardupilot.navigation import Navigation
from ftlbo_mav.sim.physics import WaypointNav

DATA = json.loads((Path(__file__).parents[1] / "data" / "ardupilot-4.5.6" / "nudges.json")
                  .read_text())
ROWS = DATA["rows"]
T = np.array([r["t"] for r in ROWS])
PROGRESS = np.array([r["progress_m"] for r in ROWS])
SPEED = np.array([r["speed_m_s"] for r in ROWS])
SEQ = np.array([r["seq"] for r in ROWS])
CRUISE = 5.0
PAUSE_S = 0.6


def at(t: float) -> int:
    return int(np.argmin(np.abs(T - t)))


def recorded_pause_loss_m() -> float:
    """How far uav3 fell behind the other two over its pause (uav1's speed command had
    no effect on this leg, see below)."""
    gap = PROGRESS[:, :2].mean(axis=1) - PROGRESS[:, 2]
    return float(gap[at(8.0)] - gap[at(3.6)])


def test_a_speed_set_mid_leg_waits_for_the_next_leg():
    first = np.all(SEQ == 4, axis=1)
    # on the leg it was sent in, uav1 (told 4 m/s) flies as uav2 (not told)
    assert np.max(np.abs(PROGRESS[first, 0] - PROGRESS[first, 1])) < 0.2
    assert SPEED[first & (T > 6.0) & (T < 8.5), 0].mean() > 4.8
    # from the third leg on it holds the speed it was given
    third = np.all(SEQ == 6, axis=1) & (T > 17.0) & (T < 19.5)
    assert SPEED[third, 0].mean() == pytest.approx(4.0, abs=0.1)
    assert SPEED[third, 1].mean() > 4.5


def test_the_model_of_a_pause_costs_what_arducopter_lost():
    recorded = recorded_pause_loss_m()
    assert recorded == pytest.approx(1.79, abs=0.05)  # the measurement itself
    speed = SPEED[at(4.2), 2]  # uav3 as the pause began (still accelerating)
    modelled = speed * Navigation().pause_cost_s(PAUSE_S, CRUISE)
    assert modelled == pytest.approx(recorded, rel=0.15)


def test_the_emulator_loses_to_a_pause_what_arducopter_lost():
    """Two copters of the emulator fly the first leg (37 m, 5 m/s); one is paused 4 s in
    for 0.6 s, as uav3 was."""
    nav = Navigation()
    legs = [WaypointNav(nav, np.zeros(3), CRUISE) for _ in range(2)]
    for leg in legs:
        leg.set_destination(np.array([37.0, 0.0, 0.0]))
    dt = 0.01
    for k in range(int(8.0 / dt)):
        t = k * dt
        if abs(t - 4.0) < dt / 2:
            legs[1].set_pause(True)
        if abs(t - 4.0 - PAUSE_S) < dt / 2:
            legs[1].set_pause(False)
        for leg in legs:
            leg.advance(dt, leg.target)
    lost = float(legs[0].target[0] - legs[1].target[0])
    assert lost == pytest.approx(recorded_pause_loss_m(), rel=0.15)
    assert float(np.linalg.norm(legs[1].target_vel)) == pytest.approx(CRUISE, abs=0.05)
