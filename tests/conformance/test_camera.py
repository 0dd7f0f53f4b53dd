"""The emulator's camera against ArduCopter 4.5.6 SITL's (camera.json): the field
survey's uav1 mission flown with CAM1_TYPE 1 sends as many CAMERA_FEEDBACK as SITL did
(within 5 %), each photo within a metre of the one SITL took."""

from __future__ import annotations

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav.ardupilot.commands import RECORDED_BOOT
from ftlbo_mav.link.codec import to_wire
from ftlbo_mav.mission.waypoints import read_waypoints
from ftlbo_mav.sim.autopilot import LocalTangent
from ftlbo_mav.sim.vehicle import VehicleOptions

from ..conftest import ROOT
from .replay import Bench, load

RECORDING = load("camera.json")["flight"]


def _rows(path):
    return [[w.seq, w.frame, w.command, w.param1, w.param2, w.param3, w.param4, w.x, w.y, w.z]
            for w in map(to_wire, read_waypoints(path))]


def test_the_emulator_takes_the_photos_arducopter_took():
    path = ROOT / RECORDING["mission_file"]
    rows = _rows(path)
    home = (rows[0][7] / 1e7, rows[0][8] / 1e7, 0.0)
    bench = Bench(home=home, options=VehicleOptions(boot=RECORDED_BOOT.scaled(0.05)))
    bench.send(1.0, R.MAVLink_param_set_message(1, 1, b"CAM1_TYPE", 1.0,
                                                R.MAV_PARAM_TYPE_INT8))
    assert bench.upload(1.5, rows) == R.MAV_MISSION_ACCEPTED
    guided, auto = 4, 3
    assert bench.command(2.0, R.MAV_CMD_DO_SET_MODE, [1, guided]).result == 0
    t = 2.5
    while bench.command(t, R.MAV_CMD_COMPONENT_ARM_DISARM, [1]).result != 0 and t < 10:
        t += 0.5  # pre-arm checks pass on the (scaled) recorded timeline
    assert bench.command(t + 0.5, R.MAV_CMD_NAV_TAKEOFF, [0, 0, 0, 0, 0, 0, rows[1][9]]).result == 0
    assert bench.command(t + 20, R.MAV_CMD_DO_SET_MISSION_CURRENT, [2]).result == 0
    t_auto = t + 21
    assert bench.command(t_auto, R.MAV_CMD_DO_SET_MODE, [1, auto]).result == 0
    bench.run(t_auto + RECORDING["mission_item_reached"][-1]["t"] + 10.0)
    photos = [h.msg for h in bench.since(t_auto, {"CAMERA_FEEDBACK"})]
    flown = RECORDING["camera_feedback"]
    assert abs(len(photos) - len(flown)) <= 0.05 * len(flown), (len(photos), len(flown))
    assert [m.img_idx for m in photos] == list(range(1, len(photos) + 1))
    tangent = LocalTangent(*home[:2])
    ours = np.array([tangent.to_en(m.lat / 1e7, m.lng / 1e7) for m in photos])
    sitl = np.array([tangent.to_en(f["lat"] / 1e7, f["lng"] / 1e7) for f in flown])
    gap = np.hypot(*(ours[:, None, :] - sitl[None, :, :]).transpose(2, 0, 1))
    assert gap.min(axis=1).max() < 1.0, gap.min(axis=1)
    assert all(abs(m.alt_rel - f["alt_rel"]) < 0.5 for m, f in zip(photos, flown))
