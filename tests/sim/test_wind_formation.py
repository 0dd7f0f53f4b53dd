"""The example's legs flown by the emulator's navigation in wind, without MAVLink: three
AC_WPNav S-curves (``WaypointNav``) from the same start, each copter following its
target as AC_PosControl makes it (``PositionFollower``: the airframe's drag in the steady
wind) and off that path by its own gusts (``Gusts``), and the formation keeper pausing
the leaders as ``fly`` does.
A naive start is clearly worse than either way of ``fly``, as SITL measured
(docs/flight.md); the full flights are ``benchmarks/flight.py --wind``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from ftlbo_mav.ardupilot.navigation import Navigation
from ftlbo_mav.ardupilot.poscontrol import PositionFollower
from ftlbo_mav.flight.keeper import FormationKeeper
from ftlbo_mav.flight.metrics import formation_error
from ftlbo_mav.flight.planned import load_planned_flight
from ftlbo_mav.sim.physics import WaypointNav
from ftlbo_mav.sim.wind import Gusts, Wind

ROOT = Path(__file__).resolve().parents[2]
PLANNED = load_planned_flight(ROOT / "missions" / "nha-trang-orchard")
PATHS = np.asarray(PLANNED.paths, float)
OFFSETS = PATHS[:, 0] - PATHS[:, 0].mean(axis=0)
CRUISE = 5.0
DT = 0.02
NAIVE_GAP_S = 0.25  # AUTO sent one by one: each copter starts a little after the last


def fly_legs(wind: Wind, seed: int, **kw) -> np.ndarray:
    """Formation error over the legs, ``(T,)`` metres."""
    return formation_error(fly_legs_positions(wind, seed, **kw)[1], OFFSETS)


def fly_legs_positions(wind: Wind, seed: int, *, starts=(0.0, 0.0, 0.0),
                       keeper: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Times ``(T,)`` and positions ``(T, N, 3)`` over the legs."""
    nav = Navigation()
    navs = [WaypointNav(nav, p[0], CRUISE) for p in PATHS]
    gusts = [Gusts(wind, np.random.default_rng([seed, i])) for i in range(len(PATHS))]
    air = wind.velocity_enu()
    copters = [PositionFollower(p[0], nav=nav, wind=air[:2]) for p in PATHS]
    leg = [0] * len(PATHS)
    keep = FormationKeeper(PATHS, CRUISE) if keeper else None
    positions = PATHS[:, 0].copy()
    t, times, flown = 0.0, [], []
    while t < 60.0 and min(leg) < PATHS.shape[1]:
        for i, (n, path) in enumerate(zip(navs, PATHS)):
            if t < starts[i]:
                continue
            if leg[i] == 0 or (n.reached and leg[i] < path.shape[0] - 1):
                leg[i] += 1
                n.set_destination(path[leg[i]])
                if leg[i] + 1 < path.shape[0]:
                    n.set_destination_next(path[leg[i] + 1])
            elif n.reached:
                leg[i] = path.shape[0]
            c = copters[i]
            velocity = np.array([c.vx, c.vy, n.target_vel[2]]) + gusts[i].error_vel
            n.advance(DT, positions[i], velocity)
            xy = c.step(DT, n.target, n.target_vel, n.target_accel)
            airspeed = float(np.linalg.norm(velocity - air))
            positions[i] = np.array([*xy, n.target[2]]) + gusts[i].step(DT, airspeed)
        if keep is not None:
            speeds = np.array([np.linalg.norm(n.target_vel[:2]) for n in navs])
            for i, pause in keep.update(positions, speeds, t).items():
                navs[i].set_pause(pause)
        times.append(t)
        flown.append(positions.copy())
        t += DT
    return np.array(times), np.array(flown)


@pytest.mark.parametrize("wind", [Wind(5, 315, 2), Wind(8, 315, 3)])
def test_in_wind_the_keeper_beats_no_keeper_and_both_beat_a_naive_start(wind):
    """The ordering SITL shows in wind (docs/flight.md, "In wind"): a naive start far
    worse than either way of ``fly``, and the keeper better than none (the worst of two
    seeds each)."""
    rms = {}
    for way, kw in (("naive", {"starts": (0.0, NAIVE_GAP_S, 2 * NAIVE_GAP_S)}),
                    ("no keeper", {}), ("fly", {"keeper": True})):
        rms[way] = max(float(np.sqrt(np.mean(fly_legs(wind, seed, **kw) ** 2)))
                       for seed in range(2))
    assert rms["naive"] > 2 * rms["no keeper"]
    assert rms["no keeper"] > rms["fly"]
