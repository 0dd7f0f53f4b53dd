"""The emulator's AUTOPILOT_VERSION against ArduCopter 4.5.6 SITL's, as recorded
(boot.json ``version``: asked with MAV_CMD_REQUEST_MESSAGE 148, answered ACCEPTED)."""

from __future__ import annotations

import json
from pathlib import Path

from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav.ardupilot.firmware import RECORDED, Firmware, firmware_problem
from ftlbo_mav.sim.vehicle import Vehicle, VehicleOptions

BOOT = json.loads((Path(__file__).resolve().parents[1] / "data" / "ardupilot-4.5.6"
                   / "boot.json").read_text())
VERSION = BOOT["version"]["autopilot_version"]
HOME = (12.2332099, 109.1145051, 0.0)


def test_the_emulator_answers_autopilot_version_as_sitl_does():
    v = Vehicle(sysid=1, home=HOME)
    m = v.message(R.MAVLINK_MSG_ID_AUTOPILOT_VERSION, 0.0)
    assert m.flight_sw_version == VERSION["flight_sw_version_raw"] == RECORDED.encode()
    assert Firmware.decode(m.flight_sw_version).describe() == "4.5.6 official"
    assert bytes(m.flight_custom_version).decode() == VERSION["flight_custom_version"]
    assert m.capabilities == VERSION["capabilities"]
    for name in ("board_version", "vendor_id", "product_id", "os_sw_version",
                 "middleware_sw_version"):
        assert getattr(m, name) == VERSION[name], name
    beat = v.heartbeat()
    recorded = BOOT["passive_serial0_first_40s"]["first_message_of_each_type"]["HEARTBEAT"]
    assert (beat.type, beat.autopilot) == (recorded["fields"]["type"],
                                           recorded["fields"]["autopilot"])
    assert firmware_problem(vehicle_type=beat.type, autopilot=beat.autopilot,
                            version=m.flight_sw_version) is None


def test_an_emulated_copter_can_run_another_firmware():
    v = Vehicle(sysid=1, home=HOME, options=VehicleOptions(firmware=Firmware(4, 7, 0, 255)))
    m = v.message(R.MAVLINK_MSG_ID_AUTOPILOT_VERSION, 0.0)
    assert "it runs 4.7.0 official" in firmware_problem(
        vehicle_type=R.MAV_TYPE_QUADROTOR, autopilot=R.MAV_AUTOPILOT_ARDUPILOTMEGA,
        version=m.flight_sw_version)
