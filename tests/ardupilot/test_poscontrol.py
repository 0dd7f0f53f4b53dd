"""AC_PosControl's vertical side in ``ardupilot/poscontrol.py``: the stopping point AUTO
starts from and the copter following its vertical target (held to SITL's own log in
``tests/conformance/test_climb.py``)."""

from __future__ import annotations

from dataclasses import replace

import pytest

from ftlbo_mav.ardupilot.navigation import Navigation
from ftlbo_mav.ardupilot.poscontrol import STEP_S, VerticalFollower, stopping_point_z


def test_the_stopping_point_is_the_climb_over_psc_posz_p_when_slow():
    nav = Navigation()  # PSC_POSZ_P 1, WPNAV_ACCEL_Z 1 m/s/s: linear below 1 m/s
    assert stopping_point_z(6.0, 0.1, nav) == pytest.approx(6.1)
    assert stopping_point_z(6.0, -0.05, nav) == pytest.approx(5.95)
    assert stopping_point_z(6.0, 0.1, replace(nav, psc_posz_p=2.0)) == pytest.approx(6.05)


def test_the_stopping_point_is_the_square_root_controllers_inverse_when_fast_and_clamped():
    nav = Navigation()
    # inv_sqrt_controller: linear_velocity / (2 p) + v^2 / (2 accel) beyond accel / p
    assert stopping_point_z(0.0, 2.0, nav) == pytest.approx(0.5 + 2.0)
    assert stopping_point_z(10.0, 5.0, nav) == pytest.approx(13.0)  # 3 m up at most
    assert stopping_point_z(10.0, -5.0, nav) == pytest.approx(8.0)  # 2 m down at most
    assert stopping_point_z(6.0, 0.3, replace(nav, psc_posz_p=0.0)) == 6.0


def test_the_copter_overshoots_a_target_that_stops_and_settles_on_it():
    copter = VerticalFollower(6.0, 0.3, nav=Navigation())  # on its target as it stops
    peak = trough = 6.0
    for k in range(int(15.0 / STEP_S)):
        copter.step(STEP_S, 6.0)
        peak = max(peak, copter.z)
        if k * STEP_S > 1.0:
            trough = min(trough, copter.z)
    assert 6.02 < peak < 6.3
    assert trough < 6.0  # and comes back below it, as SITL's copters did
    assert copter.z == pytest.approx(6.0, abs=0.005) and abs(copter.v) < 0.005


def test_a_copter_hovering_on_its_target_stays_there():
    copter = VerticalFollower(4.0, nav=Navigation())
    assert copter.at_rest_on(4.0)
    copter.step(1.0, 4.0)
    assert copter.z == pytest.approx(4.0, abs=1e-9) and copter.at_rest_on(4.0)
