"""The emulator's wind (ftlbo_mav/sim/wind.py) against what SITL's update_wind does."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ftlbo_mav.sim.wind import IIR_COEF, SITL_RATE_HZ, TURB_STD, Gusts, Wind


def sitl_turbulence(turb: float, steps: int, rng: np.random.Generator) -> np.ndarray:
    """SIM_Aircraft.cpp Aircraft::update_wind's turbulence, step by step at 1200 Hz."""
    h = v = 0.0
    out = np.empty((steps, 3))
    for k in range(steps):
        azimuth = rng.uniform(0, 2 * math.pi)
        h = h * IIR_COEF + 10 * turb * rng.normal() * (1 - IIR_COEF)
        v = v * IIR_COEF + 10 * turb * rng.normal() * (1 - IIR_COEF)
        out[k] = (math.cos(azimuth) * h, math.sin(azimuth) * h, v)
    return out


def test_steady_wind_blows_from_its_direction():
    # SIM_WIND_DIR is where the wind comes from: 315 (north-west) blows to the south-east
    v = Wind(5.0, 315.0, 0.0).velocity_enu()
    assert v[0] == pytest.approx(5 / math.sqrt(2)) and v[1] == pytest.approx(-5 / math.sqrt(2))
    assert Wind().calm and not Wind(0, 0, 1).calm


@pytest.mark.parametrize("bad", [(-1, 0, 0), (1, 0, -2), (float("nan"), 0, 0)])
def test_bad_wind_is_refused(bad):
    with pytest.raises(ValueError):
        Wind(*bad)


def test_gusts_average_over_a_step_as_sitl_s_steps_do():
    """The turbulence drawn over 20 ms steps has the spread of SITL's 24 steps of 1200 Hz
    averaged (vertical: correlated over 41 ms; horizontal: a new azimuth every step)."""
    dt, steps = 0.02, int(0.02 * SITL_RATE_HZ)
    sitl = sitl_turbulence(2.0, steps * 4000, np.random.default_rng(1))
    means = sitl.reshape(-1, steps, 3).mean(axis=1)
    gusts = Gusts(Wind(5, 315, 2.0), np.random.default_rng(2))
    ours = np.array([gusts._draw(dt).copy() for _ in range(4000)])
    assert np.std(sitl[:, 2]) == pytest.approx(2.0 * TURB_STD, rel=0.1)
    for axis in range(3):
        assert np.std(ours[:, axis]) == pytest.approx(np.std(means[:, axis]), rel=0.15)


def test_each_copter_meets_its_own_gusts_and_the_error_stays_bounded():
    wind = Wind(5, 315, 2.0)
    a, b = (Gusts(wind, np.random.default_rng(k)) for k in (1, 2))
    ea = np.array([a.step(0.02, 5.0).copy() for _ in range(3000)])
    eb = np.array([b.step(0.02, 5.0).copy() for _ in range(3000)])
    assert not np.allclose(ea, eb)
    assert 0 < np.abs(ea).max() < 2.0  # the position controller holds it near its target
    calm = Gusts(Wind(5, 315, 0.0), np.random.default_rng(1))
    assert np.all([calm.step(0.02, 5.0) == 0 for _ in range(10)])
