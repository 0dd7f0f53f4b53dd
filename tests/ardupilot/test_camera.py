"""Camera trigger items and distance triggering against ArduCopter 4.5.6 SITL.

``tests/data/ardupilot-4.5.6/camera.json`` (``python -m sitl.record --camera``): the
DO_SET_CAM_TRIGG_DIST items ArduCopter stored and read back, and one survey mission
(``missions/field-survey/uav1.waypoints``) flown with a camera configured (CAM1_TYPE 1),
every CAMERA_FEEDBACK it sent. The storage model must give back what ArduCopter gave
back; the photos predicted from the mission file alone must be ArduPilot's.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav.ardupilot import storage
from ftlbo_mav.ardupilot.camera import DistanceTrigger, track_photos
from ftlbo_mav.mission.files import digest, read_mission_text
from ftlbo_mav.mission.photos import mission_photos
from ftlbo_mav.mission.plan_reader import read_plan
from ftlbo_mav.mission.waypoints import read_waypoints

from .test_storage import _same, wire

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = ROOT / "tests" / "data" / "ardupilot-4.5.6"
DATA = Path(os.environ.get("FTLBO_RECORDINGS", SHIPPED)) / "camera.json"
RECORDING = json.loads(DATA.read_text())
ITEMS = [it for it in RECORDING["camera_items"]["items"]
         if it["sent"]["command"] == R.MAV_CMD_DO_SET_CAM_TRIGG_DIST]
FLIGHT = RECORDING["flight"]


@pytest.mark.parametrize("case", ITEMS, ids=[it["name"] for it in ITEMS])
def test_every_trigger_item_is_stored_as_arducopter_stored_it(case):
    sent, back = wire(case["sent"]), wire(case["read_back"])
    assert storage.check(sent) == R.MAV_MISSION_ACCEPTED
    assert _same(storage.stored(sent), back), (storage.stored(sent), back)


def test_the_recorded_items_show_what_is_lost():
    """Not a tautology: param3 kept as a uint8 (1.7 -> 1, 256 -> 0, -1 -> 255), param2,
    param4 and x, y, z dropped, the frame read back as 0."""
    changed = [it for it in ITEMS if not _same(wire(it["sent"]), wire(it["read_back"]))]
    assert len(ITEMS) >= 6 and len(changed) == len(ITEMS)
    assert {it["read_back"]["param3"] for it in ITEMS} >= {0.0, 1.0, 2.0, 255.0}


@pytest.fixture(scope="module")
def survey():
    path = ROOT / FLIGHT["mission_file"]
    if digest(read_mission_text(path)) != FLIGHT["mission_sha256"]:
        pytest.fail(f"{path} is not the mission flown in {DATA.name}: re-record it "
                    "(python -m sitl.record --camera)")
    plan = read_plan(path.parent)
    sv = plan.scenario.survey
    photos = mission_photos("uav1", read_waypoints(path), frame=plan.scenario.frame,
                            camera=sv.camera, heading_deg=sv.heading_deg,
                            nav=plan.scenario.vehicle)
    fb = FLIGHT["camera_feedback"]
    flown = plan.scenario.frame.to_enu(lat_deg=[f["lat"] * 1e-7 for f in fb],
                                       lon_deg=[f["lng"] * 1e-7 for f in fb])[:, :2]
    return plan, photos, flown


def test_arducopter_takes_the_photos_the_mission_file_predicts(survey):
    plan, photos, flown = survey
    assert FLIGHT["landed"] and FLIGHT["params"]["CAM1_TYPE"] == 1
    assert [f["img_idx"] for f in FLIGHT["camera_feedback"]] == list(range(1, len(flown) + 1))
    assert abs(len(flown) - photos.count) <= 0.05 * photos.count, (len(flown), photos.count)
    # each photo ArduPilot took is within half a metre of one predicted, in the same order
    # (predicted on the planned straight lines they were up to 1.1 m off, in the corners)
    gap = np.hypot(*(flown[:, None, :] - photos.positions[None, :, :2]).transpose(2, 0, 1))
    assert gap.min(axis=1).max() < 0.5
    assert np.array_equal(gap.argmin(axis=1), np.arange(len(flown)))


def test_the_photos_are_on_the_lanes_at_least_the_trigger_distance_apart(survey):
    plan, photos, flown = survey
    sv = plan.scenario.survey
    frame = plan.scenario.frame
    lanes = np.array([frame.to_enu(lat_deg=[a.lat_deg, b.lat_deg], lon_deg=[a.lon_deg, b.lon_deg])
                      [:, :2] for a, b in sv.lanes]) + plan.scenario.offsets_m[0, :2]
    x = lanes[:, 0, 0]  # north-south lanes
    lane = np.abs(flown[:, 0, None] - x[None, :]).argmin(axis=1)
    assert np.abs(flown[:, 0] - x[lane]).max() < 1.0  # on its lane, across
    lo, hi = lanes[lane, :, 1].min(axis=1), lanes[lane, :, 1].max(axis=1)
    assert np.all((flown[:, 1] > lo - 1.0) & (flown[:, 1] < hi + 1.0))  # between its ends
    assert np.array_equal(np.unique(lane), np.arange(len(x)))  # every lane photographed
    same = lane[1:] == lane[:-1]
    step = np.hypot(*np.diff(flown, axis=0).T)[same]
    # AP_Camera never shoots closer than the distance, and (at 5 m/s, 50 Hz) a few cm late
    assert step.min() >= sv.trigger_distance_m - 0.05 and step.max() < sv.trigger_distance_m + 0.3


def test_photos_along_a_sampled_track_and_the_trigger_state():
    times = np.arange(0.0, 4.0, 0.02)
    track = np.column_stack([np.zeros_like(times), 5.0 * times, np.full_like(times, 20.0)])
    # on at once at 0 s (a photo there), 4 m apart, off at 2 s (10 m), on at 3 s, no photo at once
    photos = track_photos(times, track, [(0.0, 4.0, True), (2.0, 0.0, False), (3.0, 4.0, False)])
    assert np.allclose(photos[:, 1], [0.0, 4.0, 8.0, 19.0])  # 15 m remembered, 19 m taken
    assert np.allclose(photos[:, 2], 20.0)
    # at the 50 Hz updates: the first update at least the distance from the last photo
    late = track_photos(times, track, [(0.0, 3.95, True)])
    assert np.allclose(late[:3, 1], [0.0, 4.0, 8.0])
    assert len(track_photos(times, track, [(0.0, 0.0, True)])) == 0
    # the trigger is the emulator's: the same photos update by update
    trigger = DistanceTrigger()
    trigger.set_distance(4.0)
    trigger.take_picture(track[0])
    stepped = [track[0]] + [p for p in track[1:100] if trigger.update(p)
                            and trigger.take_picture(p)]
    assert np.allclose(np.array(stepped), photos[:3])
    trigger = DistanceTrigger()
    trigger.set_distance(4.0)
    assert not trigger.update(np.zeros(3))  # the first update remembers the position
    assert not trigger.update(np.array([0.0, 3.9, 0]))
    assert trigger.update(np.array([0.0, 4.0, 0]))
    assert trigger.take_picture(np.array([0.0, 4.0, 0])) == 1
    trigger.set_distance(0.0)
    assert trigger.last is None and not trigger.update(np.array([0.0, 40.0, 0]))
