"""``fly`` and ``upload`` against a copter whose firmware is not the one the planner's
flight model follows (ArduCopter 4.5.x or 4.6.x, ardupilot/firmware.py): refused at pre-flight,
one line naming the vehicle and its version, unless ``--any-firmware``, which flies and
says what is not promised. The emulator only: SITL reports the version it was built as
(4.5.6, tests/conformance/test_firmware_version.py holds the emulator to it)."""

from __future__ import annotations

import json
from dataclasses import replace

from click.testing import CliRunner

from ftlbo_mav import clock
from ftlbo_mav.ardupilot.firmware import Firmware
from ftlbo_mav.cli import main
from ftlbo_mav.sim.vehicle import VehicleOptions

from .fleet import vehicles
from .test_departures import HOMES, _fly_with, example, plan_dir  # noqa: F401 (fixtures)

SPEEDUP = 12.0  # SITL's; the emulator flies these on a virtual clock
OLD = replace(VehicleOptions(heartbeat_s=0.25), firmware=Firmware(4, 4, 4, 255))
FLEET = [VehicleOptions(heartbeat_s=0.25), OLD, VehicleOptions(heartbeat_s=0.25)]


def _upload_anyway(folder, urls) -> str:
    result = CliRunner().invoke(main, ["upload", str(folder), "--sysid", "1..3",
                                       "--any-firmware", "--connect", " ".join(urls)])
    assert result.exit_code == 0, result.output
    return result.output


def test_fly_refuses_a_copter_on_another_firmware_before_arming(plan_dir):  # noqa: F811
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, virtual=True, options=FLEET) as fleet:
        assert "uav2 (sysid 2): firmware: it runs 4.4.4 official" in _upload_anyway(
            plan_dir, fleet.urls)
        result, _took = _fly_with(plan_dir, fleet.urls, clock.monotonic)
        armed = fleet.sim.call(lambda: [v.state.armed for v in fleet.sim.vehicles])
    out = result.output
    assert result.exit_code != 0, out
    assert "pre-flight failed, nothing armed" in out
    line = next(x for x in out.splitlines() if "uav2 (sysid 2):" in x and "firmware" in x)
    assert "it runs 4.4.4 official" in line and "--any-firmware" in line
    assert not any("firmware" in x for x in out.splitlines() if "uav1 (sysid 1)" in x)
    assert armed == [False, False, False]


def test_any_firmware_flies_and_says_what_is_not_promised(plan_dir):  # noqa: F811
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, virtual=True, options=FLEET) as fleet:
        _upload_anyway(plan_dir, fleet.urls)
        result, _took = _fly_with(plan_dir, fleet.urls, clock.monotonic, "--any-firmware")
    out = result.output
    assert result.exit_code == 0, out
    assert ("warning: uav2 (sysid 2): firmware: it runs 4.4.4 official (no recordings of 4.4 "
            "hold the model to it; the nearest modelled release is ArduCopter 4.5): the "
            "predicted flown path, the clearance kept on it and its timing are not "
            "promised") in out
    assert "pre-flight failed" not in out
    firmware = json.loads((plan_dir / "flight" / "summary.json").read_text())["firmware"]
    assert firmware["uav2"]["version"] == "4.4.4 official"
    assert "it runs 4.4.4 official" in firmware["uav2"]["problem"]
    assert firmware["uav1"] == {"version": "4.5.6 official", "vehicle_type": "MAV_TYPE_QUADROTOR",
                                "autopilot": "MAV_AUTOPILOT_ARDUPILOTMEGA", "problem": None,
                                "sysid": 1}
