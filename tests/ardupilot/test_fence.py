"""The model of how ArduCopter 4.5 keeps fence and rally items and breaks on its fence
(ftlbo_mav/ardupilot/fence.py), rule by rule as the source says it."""

from __future__ import annotations

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav.ardupilot import fence as F
from ftlbo_mav.ardupilot.storage import WireItem


def vertex(seq, x, y, n=4, frame=R.MAV_FRAME_GLOBAL):
    return WireItem(seq=seq, command=F.FENCE_POLYGON_INCLUSION, frame=frame, x=x, y=y, z=5.0,
                    param1=float(n), param2=7.0, autocontinue=1)


def circle(seq, radius, frame=R.MAV_FRAME_GLOBAL):
    return WireItem(seq=seq, command=F.FENCE_CIRCLE_EXCLUSION, frame=frame, x=122_333_000,
                    y=1_091_148_000, z=3.0, param1=radius, autocontinue=1)


def test_a_fence_item_keeps_its_type_position_and_count_only():
    back = F.stored_fence_item(vertex(0, 122_330_971, 1_091_144_239,
                                      frame=R.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT))
    assert (back.command, back.x, back.y, back.param1) == (5001, 122_330_971, 1_091_144_239, 4)
    # frame, altitude, params 2-4, current and autocontinue come back zero
    assert (back.frame, back.z, back.param2, back.current, back.autocontinue) == (0, 0, 0, 0, 0)


@pytest.mark.parametrize("radius, kept", [(4.0, 4.0), (4.0004, 4.0), (4.2, np.float32(4.2)),
                                          (4.9995, np.float32(4.9995))])
def test_a_circle_radius_is_kept_whole_when_within_a_millimetre_above_a_whole_number(radius, kept):
    # AC_PolyFence_loader::write_fence: store_as_int = radius - int(radius) < 0.001
    assert F.stored_fence_item(circle(0, radius)).param1 == pytest.approx(float(kept), abs=0)


def test_fence_items_are_refused_by_frame_and_command():
    assert F.check_fence_item(vertex(0, 1, 1, frame=R.MAV_FRAME_MISSION)) == \
        R.MAV_MISSION_UNSUPPORTED_FRAME
    wp = WireItem(seq=0, command=R.MAV_CMD_NAV_WAYPOINT, frame=0, x=1, y=1, z=0.0)
    assert F.check_fence_item(wp) == R.MAV_MISSION_UNSUPPORTED
    assert F.check_fence_item(circle(0, 3.0)) == R.MAV_MISSION_ACCEPTED


def test_validate_fence_says_what_write_fence_says():
    square = [vertex(i, 122_330_000 + i, 1_091_140_000) for i in range(4)]
    assert F.validate_fence(square + [circle(4, 2.5)]) is None
    assert F.validate_fence(square[:3]) == "Incorrect item count"
    assert F.validate_fence([vertex(0, 1, 1, n=2)] * 2) == "Invalid vertex count (2)"
    assert F.validate_fence(square + [circle(4, 0.0)]) == "Non-positive circle radius"
    assert F.validate_fence(square[:2] + [circle(2, 3.0)] + square[2:]).startswith(
        "Received incorrect type")


def test_a_rally_point_keeps_whole_metres_and_its_frame():
    sent = WireItem(seq=0, command=F.RALLY_POINT, frame=R.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                    x=122_334_732, y=1_091_151_785, z=6.9, param1=3.0, autocontinue=1)
    back = F.stored_rally_item(sent)
    assert (back.frame, back.z, back.param1, back.autocontinue) == (3, 6.0, 0.0, 0)
    assert F.rally_alt_stored(-2.5) == -2.0  # truncated toward zero (int16 = float)
    assert F.check_rally_item(WireItem(seq=0, command=F.RALLY_POINT, frame=3, x=1, y=1,
                                       z=40000.0)) == R.MAV_MISSION_INVALID_PARAM7
    assert F.check_rally_item(WireItem(seq=0, command=F.RALLY_POINT, frame=2, x=1, y=1,
                                       z=4.0)) == R.MAV_MISSION_UNSUPPORTED_FRAME


def test_breaches_are_outside_the_polygon_inside_a_circle_or_above_the_altitude():
    square = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]])
    geometry = F.FenceGeometry((square,), np.array([[5.0, 5.0, 1.0]]))
    kw = {"fence_type": F.TYPE_ALT_MAX | F.TYPE_POLYGON, "alt_max_m": 8.0}
    assert F.breaches(geometry, east_north=np.array([2.0, 2.0]), alt_m=4.0, **kw) == 0
    assert F.breaches(geometry, east_north=np.array([5.5, 5.0]), alt_m=4.0, **kw) == 4
    assert F.breaches(geometry, east_north=np.array([-0.1, 5.0]), alt_m=4.0, **kw) == 4
    assert F.breaches(geometry, east_north=np.array([2.0, 2.0]), alt_m=8.1, **kw) == 1
    assert F.breaches(geometry, east_north=np.array([2.0, 2.0]), alt_m=8.1,
                      fence_type=F.TYPE_POLYGON, alt_max_m=8.0) == 0


def test_the_breach_action_is_copters():
    assert F.breach_modes(F.ACTION_BRAKE, landed=False, breach_distance_m=1.0) == (17, 9)
    assert F.breach_modes(F.ACTION_RTL_AND_LAND, landed=False, breach_distance_m=1.0) == (6, 9)
    assert F.breach_modes(F.ACTION_BRAKE, landed=False, breach_distance_m=101.0) == (9,)
    assert F.breach_modes(F.ACTION_BRAKE, landed=True, breach_distance_m=0.0) == (-1,)
    assert F.breach_modes(F.ACTION_REPORT_ONLY, landed=False, breach_distance_m=1.0) == ()


def test_parameters_compare_as_ap_param_keeps_them():
    assert F.param_equal("FENCE_ACTION", 4.0, 4.0)
    assert F.param_equal("FENCE_MARGIN", 0.5, float(np.float32(0.5)))
    assert not F.param_equal("FENCE_ALT_MAX", 8.0, 100.0)


def test_the_breach_test_in_plain_floats_agrees_with_arrays():
    """A copter's fence is checked 25 times a second on its corners and circles kept as
    plain floats: the same verdicts as the array arithmetic, near every edge."""
    rng = np.random.default_rng(2)
    square = np.array([[-50.0, -50.0], [50.0, -50.0], [50.0, 50.0], [-50.0, 50.0]])
    circles = np.column_stack([rng.uniform(-40, 40, (12, 2)), rng.uniform(1.0, 4.0, 12)])
    geometry = F.FenceGeometry((square,), circles)
    for p in rng.uniform(-55.0, 55.0, (3000, 2)):
        outside = not (-50.0 < p[0] < 50.0 and -50.0 < p[1] < 50.0)
        in_circle = bool(np.any(np.hypot(circles[:, 0] - p[0], circles[:, 1] - p[1])
                                < circles[:, 2]))
        want = F.TYPE_POLYGON if outside or in_circle else 0
        assert F.breaches(geometry, east_north=p, alt_m=5.0, fence_type=F.TYPE_POLYGON,
                          alt_max_m=100.0) == want
