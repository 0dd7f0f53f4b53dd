"""Issue 14 on vehicles: the fence uploads and verifies, a stray copter is stopped by its
own fence, and the formation's planned flight never triggers it. The emulator, or
ArduPilot SITL when ARDUPILOT_SITL is set; one code path, everything observed over MAVLink.
"""

from __future__ import annotations

import csv
import math
import time
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav.cli import main
from ftlbo_mav.flight.fly import Fleet
from ftlbo_mav.link.codec import MISSION_TYPE_FENCE, MISSION_TYPE_RALLY, mission_differences
from ftlbo_mav.mission.fence_files import read_fence_set
from ftlbo_mav.mission.waypoints import read_waypoints
from ftlbo_mav.scenario import load_scenario
from ftlbo_mav.sim.homes import scenario_homes
from ftlbo_mav.sim.vehicle import VehicleOptions

from ..conftest import EXAMPLE
from .fleet import BACKEND, vehicles

pytestmark = pytest.mark.sitl

SPEEDUP = 4.0
SCENARIO = load_scenario(EXAMPLE)
HOMES = scenario_homes(SCENARIO)
OPTIONS = {} if BACKEND == "sitl" else {"options": VehicleOptions(heartbeat_s=0.25)}
STOP_TIMEOUT_S = 60.0


def run(*args):
    result = CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)
    return result.exit_code, result.output


@pytest.fixture(scope="module")
def fenced(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("fenced")
    code, out = run("plan", EXAMPLE, "-o", folder, "-q")
    assert code == 0, out
    return folder


def _upload(folder: Path, urls) -> str:
    code, out = run("upload", folder, "--sysid", "1..3", "--connect", " ".join(urls))
    assert code == 0, out
    return out


def test_fence_rally_and_parameters_upload_and_verify(fenced, tmp_path):
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, **OPTIONS) as fleet:
        out = _upload(fenced, fleet.urls)
        assert out.count("fence 11 items, 1 rally point(s), 5 fence parameters)") == 3, out
        assert "3/3 vehicles verified" in out
        back = tmp_path / "back2.waypoints"
        code, out = run("download", "--sysid", 2, "--connect", fleet.urls[1], "-o", back)
        assert code == 0, out
    planned = read_fence_set(fenced, "uav2")
    assert mission_differences(planned.fence, read_waypoints(back.with_suffix(".fence")),
                               mission_type=MISSION_TYPE_FENCE) == []
    assert mission_differences(planned.rally, read_waypoints(back.with_suffix(".rally")),
                               mission_type=MISSION_TYPE_RALLY) == []
    assert "FENCE_ENABLE 1, FENCE_TYPE 5, FENCE_ACTION 4, FENCE_ALT_MAX 8" in out


def _en(lat_deg: float, lon_deg: float) -> np.ndarray:
    return SCENARIO.frame.to_enu(lat_deg=lat_deg, lon_deg=lon_deg).reshape(3)[:2]


def _take_off(v, alt_m: float) -> None:
    v.set_mode("GUIDED", timeout_s=90.0)
    v.arm(budget_s=90.0)
    v.takeoff(alt_m)
    assert v.wait_for(lambda s: abs(s.alt_m - alt_m) < 0.3 and abs(s.climb_m_s) < 0.2, 60.0)


def _go(v, lat_deg: float, lon_deg: float, alt_m: float) -> None:
    """GUIDED: fly to a position (SET_POSITION_TARGET_GLOBAL_INT, altitude above home)."""
    v.send(R.MAVLink_set_position_target_global_int_message(
        0, v.sysid, 1, R.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, 0b110111111000,
        round(lat_deg * 1e7), round(lon_deg * 1e7), alt_m, 0, 0, 0, 0, 0, 0, 0, 0))


def _stopped(v, texts: list[str]):
    """Wait for BRAKE and a standstill; the stop position (east, north) and the texts."""
    deadline = time.monotonic() + STOP_TIMEOUT_S
    while time.monotonic() < deadline:
        texts += [t for t in v.status.texts if t not in texts]
        s = v.status
        if s.mode == "BRAKE" and s.ground_speed_m_s < 0.05:
            return _en(s.lat_deg, s.lon_deg)
        time.sleep(0.05)
    raise AssertionError(f"{v.name} not stopped in BRAKE (mode {v.status.mode}); {texts}")


def test_a_stray_copter_is_stopped_by_its_own_fence(fenced):
    """uav1, GUIDED toward the first tree's centre, brakes at the tree's exclusion circle;
    uav2, GUIDED 30 m south of the area, brakes at the inclusion polygon."""
    tree = SCENARIO.obstacles[0]
    fence_radius = read_fence_set(fenced, "uav1").fence[4].param1
    south = min(SCENARIO.corner_a.lat_deg, SCENARIO.corner_b.lat_deg)
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, **OPTIONS) as fleet:
        _upload(fenced, fleet.urls)
        with Fleet(["uav1", "uav2"], [1, 2], fleet.urls[:2]) as flying:
            uav1, uav2 = flying.vehicles
            for v in flying.vehicles:
                _take_off(v, 4.0)
            _go(uav1, tree.lat_deg, tree.lon_deg, 4.0)
            _go(uav2, south - 30 / 111_000, HOMES[1][1], 4.0)
            texts1, texts2 = [], []
            stop1 = _stopped(uav1, texts1)
            stop2 = _stopped(uav2, texts2)
            for v in flying.vehicles:
                v.send_mode("LAND")
    centre = _en(tree.lat_deg, tree.lon_deg)
    from_axis = float(np.linalg.norm(stop1 - centre))
    south_edge = float(_en(south, HOMES[1][1])[1])
    print(f"\n[{BACKEND}] uav1 stopped {from_axis:.2f} m from the tree's axis (tree radius "
          f"{tree.radius_m:g} m, exclusion circle {fence_radius:g} m); uav2 stopped "
          f"{south_edge - stop2[1]:.2f} m south of the area's edge (polygon "
          f"{0.8:g} m outside it)")
    assert any("Fence Breached" in t for t in texts1), texts1
    assert any("Fence Breached" in t for t in texts2), texts2
    assert from_axis > 0.5 * tree.radius_m  # stopped well before the trunk
    assert stop2[1] > south_edge - 5.0  # within a few metres of the polygon
    assert math.isfinite(from_axis)


def test_the_planned_flight_never_triggers_the_fence(fenced):
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, **OPTIONS) as fleet:
        _upload(fenced, fleet.urls)
        code, out = run("fly", fenced, "--sysid", "1..3", "--control-port", "0",
                        "--connect", " ".join(fleet.urls))
        assert code == 0, out
    assert "all vehicles finished their missions" in out
    with open(fenced / "flight" / "flight.csv", newline="") as f:
        modes = {row["mode"] for row in csv.DictReader(f) if row["armed"] in ("1", "True")}
    assert modes <= {"GUIDED", "AUTO"}, modes  # never BRAKE (FENCE_ACTION), RTL or LAND
