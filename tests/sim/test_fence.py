"""The emulated copter's fence and rally protocols and its fence enforcement, without
sockets: the loopback channel (virtual time) and the autopilot itself."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav.ardupilot.storage import WireItem
from ftlbo_mav.link.codec import MISSION_TYPE_FENCE, MISSION_TYPE_RALLY, mission_differences
from ftlbo_mav.link.geofence import fence_differences, upload_fence_set
from ftlbo_mav.link.mission_protocol import (
    Timing,
    download_mission,
    upload_mission,
)
from ftlbo_mav.mission.fence import plan_fences
from ftlbo_mav.mission.fence_files import FenceSet
from ftlbo_mav.mission.plan_reader import read_plan
from ftlbo_mav.scenario import load_scenario
from ftlbo_mav.sim.autopilot import Autopilot, LocalTangent
from ftlbo_mav.sim.homes import scenario_homes
from ftlbo_mav.sim.loopback import LoopbackChannel
from ftlbo_mav.sim.modes.common import BRAKE, GUIDED, RTL
from ftlbo_mav.sim.vehicle import Vehicle, VehicleOptions

from ..conftest import EXAMPLE
from ..mission.test_outputs import STORED

PLAN = read_plan(STORED)
FENCES = plan_fences(PLAN)
HOME = scenario_homes(load_scenario(EXAMPLE))[0]
TIMING = Timing()


def fence_set(n: int = 0) -> FenceSet:
    f = FENCES[n]
    return FenceSet(f.fence, f.rally, f.params)


def channel() -> LoopbackChannel:
    return LoopbackChannel(Vehicle(sysid=1, home=HOME, options=VehicleOptions()))


def test_fence_and_rally_upload_read_back_as_the_model_says():
    ch = channel()
    ok, message = upload_fence_set(ch, fence_set(), timing=TIMING)
    assert ok, message
    assert message == "fence 11 items, 1 rally point(s), 5 fence parameters"
    assert fence_differences(ch, fence_set(), timing=TIMING) == []
    back = download_mission(ch, timing=TIMING, mission_type=MISSION_TYPE_FENCE)
    assert [it.autocontinue for it in back] == [0] * 11  # zeroed as in ArduPilot
    assert [it.frame for it in back] == [0] * 11
    # the mission is untouched by the other protocols
    assert len(download_mission(ch, timing=TIMING)) <= 1


def test_a_fence_refused_by_validate_fence_leaves_the_stored_one():
    ch = channel()
    upload_mission(ch, fence_set().fence, timing=TIMING, mission_type=MISSION_TYPE_FENCE)
    kept = list(fence_set().fence[:3]) + list(fence_set().fence[4:])  # 3 of 4 vertices
    broken = [replace(it, seq=i) for i, it in enumerate(kept)]
    # the last item is ACKed ERROR (MissionItemProtocol_Fence::complete): the uploader
    # cannot tell that from a lost ACCEPTED and leaves it to the read-back
    assert upload_mission(ch, broken, timing=TIMING, mission_type=MISSION_TYPE_FENCE) is False
    back = download_mission(ch, timing=TIMING, mission_type=MISSION_TYPE_FENCE)
    assert mission_differences(fence_set().fence, back, mission_type=MISSION_TYPE_FENCE) == []


def test_a_rally_point_keeps_whole_metres():
    ch = channel()
    point = replace(fence_set().rally[0], alt_m=5.7)
    upload_mission(ch, [point], timing=TIMING, mission_type=MISSION_TYPE_RALLY)
    (back,) = download_mission(ch, timing=TIMING, mission_type=MISSION_TYPE_RALLY)
    assert back.alt_m == 5.0 and back.frame == R.MAV_FRAME_GLOBAL_RELATIVE_ALT
    assert mission_differences([point], [back], mission_type=MISSION_TYPE_RALLY) == []


def test_differences_name_a_wrong_fence_parameter():
    ch = channel()
    upload_fence_set(ch, fence_set(), timing=TIMING)
    wanted = FenceSet(fence_set().fence, fence_set().rally,
                      {**fence_set().params, "FENCE_ALT_MAX": 9.0})
    assert fence_differences(ch, wanted, timing=TIMING) == [
        "parameter FENCE_ALT_MAX is 8, expected 9"]


# --- enforcement (Autopilot, virtual time)

def _wire(items):
    from ftlbo_mav.ardupilot.fence import stored_item
    from ftlbo_mav.link.codec import to_wire

    return [stored_item(to_wire(it), kind) for it, kind in items]


def flying(fence: bool = True) -> tuple[Autopilot, float]:
    ap = Autopilot(home=HOME[:2], boot_time=-100.0)
    if fence:
        fs = fence_set()
        ap.set_fence(_wire([(it, MISSION_TYPE_FENCE) for it in fs.fence]),
                     _wire([(it, MISSION_TYPE_RALLY) for it in fs.rally]))
        for name, value in fs.params.items():
            ap.set_param(name, value)
    ap.set_mode(GUIDED, 0.0)
    ap.arm(0.0)
    ap.takeoff(4.0, 0.0)
    t = 0.0
    while t < 20.0:
        t += 0.1
        ap.advance(t)
    return ap, t


def _fly(ap, t, seconds, step=0.05):
    texts = []
    for _ in range(int(seconds / step)):
        t += step
        texts += [m.text for m in ap.advance(t) if m.get_type() == "STATUSTEXT"]
    return t, texts


def _tree_en():
    c = PLAN.scenario.obstacles[0]
    return np.array(LocalTangent(*HOME[:2]).to_en(c.lat_deg, c.lon_deg))


def test_guided_refuses_a_target_inside_the_fence():
    ap, _t = flying()
    assert ap.goto([*_tree_en(), 4.0]) is False
    assert ap.goto([0.0, -40.0, 4.0]) is False  # south of the area
    assert ap.goto([0.0, 0.0, 12.0]) is False   # above FENCE_ALT_MAX
    assert ap.goto([0.0, 2.0, 4.0]) is True


def test_crossing_an_exclusion_circle_breaks_with_fence_breached_and_brake():
    ap, t = flying()
    tree = _tree_en()
    ahead = tree / np.linalg.norm(tree)
    assert ap.goto([*(tree + ahead * 8.0), 4.0])
    t, texts = _fly(ap, t, 30.0)
    assert "Fence Breached" in texts and ap.mode == BRAKE
    assert np.linalg.norm(ap.velocity) < 0.05


def test_without_the_fence_the_same_flight_goes_on_through():
    ap, t = flying(fence=False)
    tree = _tree_en()
    ahead = tree / np.linalg.norm(tree)
    assert ap.goto([*(tree + ahead * 8.0), 4.0])
    t, texts = _fly(ap, t, 30.0)
    assert "Fence Breached" not in texts and ap.mode == GUIDED


def test_rtl_goes_to_the_nearer_rally_point_below_the_fence_altitude():
    ap, t = flying()
    rally = fence_set().rally[0]
    east, north = LocalTangent(*HOME[:2]).to_en(rally.lat_deg, rally.lon_deg)
    ap.position[:2] = (east - 3.0, north)  # hovering near its rally point (near its goal)
    ap.set_mode(RTL, t)
    heights = []
    for _ in range(1200):
        t += 0.05
        ap.advance(t)
        heights.append(float(ap.position[2]))
        if not ap.armed:
            break
    assert not ap.armed
    assert np.hypot(ap.position[0] - east, ap.position[1] - north) < 0.5  # landed there
    # RTL_ALT clamped; the copter overshoots its target a few cm (as after a takeoff)
    assert max(heights) <= fence_set().params["FENCE_ALT_MAX"] - 0.5 + 0.05


def test_wire_items_are_what_the_autopilot_reads():
    w = _wire([(fence_set().fence[4], MISSION_TYPE_FENCE)])[0]
    assert isinstance(w, WireItem) and w.command == 5004
