"""The firmware the flight model follows: decoding AUTOPILOT_VERSION as ArduCopter 4.5.6
SITL answered it (``tests/data/ardupilot-4.5.6/boot.json`` ``version``) and the refusals."""

from __future__ import annotations

import json
import os
from pathlib import Path

from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav.ardupilot.firmware import (
    RECORDED,
    RECORDED_CAPABILITIES,
    RECORDED_CUSTOM_VERSION,
    Firmware,
    any_firmware_warning,
    firmware_problem,
)

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = ROOT / "tests" / "data" / "ardupilot-4.5.6"
VERSION = json.loads((Path(os.environ.get("FTLBO_RECORDINGS", SHIPPED)) / "boot.json")
                     .read_text())["version"]
RECORDED_AV = VERSION["autopilot_version"]

QUAD, APM = R.MAV_TYPE_QUADROTOR, R.MAV_AUTOPILOT_ARDUPILOTMEGA


def test_recorded_raw_decodes_as_recorded():
    fw = Firmware.decode(RECORDED_AV["flight_sw_version_raw"])
    assert f"{fw.major}.{fw.minor}.{fw.patch}" == RECORDED_AV["flight_sw_version"]
    assert fw.type == RECORDED_AV["flight_sw_version_type"] == R.FIRMWARE_VERSION_TYPE_OFFICIAL
    assert fw == RECORDED and fw.encode() == RECORDED_AV["flight_sw_version_raw"]
    assert fw.describe() == "4.5.6 official" and fw.supported
    assert RECORDED_CUSTOM_VERSION == RECORDED_AV["flight_custom_version"]
    assert RECORDED_CAPABILITIES == RECORDED_AV["capabilities"]
    assert VERSION["version_string"].startswith(f"ArduCopter V{RECORDED_AV['flight_sw_version']}")


def test_the_recorded_copter_has_no_problem():
    assert firmware_problem(vehicle_type=QUAD, autopilot=APM,
                            version=RECORDED_AV["flight_sw_version_raw"]) is None
    rc = Firmware(4, 5, 0, R.FIRMWARE_VERSION_TYPE_RC).encode()
    assert firmware_problem(vehicle_type=R.MAV_TYPE_HEXAROTOR, autopilot=APM, version=rc) is None


def test_both_modelled_releases_are_flown_official_or_rc():
    for fw in (Firmware(4, 6, 3, 255), Firmware(4, 6, 0, R.FIRMWARE_VERSION_TYPE_RC),
               Firmware(4, 5, 7, 255)):
        assert firmware_problem(vehicle_type=QUAD, autopilot=APM, version=fw.encode()) is None


def test_other_versions_are_refused_naming_what_runs_and_what_is_supported():
    tail = ("; the flight model is ArduCopter 4.5.x or 4.6.x (official or rc) on a "
            "multirotor's (--any-firmware to go on anyway)")
    for fw, text in ((Firmware(4, 6, 4, R.FIRMWARE_VERSION_TYPE_BETA), "4.6.4 beta"),
                     (Firmware(4, 5, 7, R.FIRMWARE_VERSION_TYPE_BETA), "4.5.7 beta"),
                     (Firmware(4, 5, 0, R.FIRMWARE_VERSION_TYPE_DEV), "4.5.0 dev")):
        problem = firmware_problem(vehicle_type=QUAD, autopilot=APM, version=fw.encode())
        assert problem == f"firmware: it runs {text}{tail}"
    for fw, text, near in ((Firmware(4, 4, 4, 255), "4.4.4 official", "4.5"),
                           (Firmware(4, 7, 0, 255), "4.7.0 official", "4.6")):
        problem = firmware_problem(vehicle_type=QUAD, autopilot=APM, version=fw.encode())
        assert problem == (f"firmware: it runs {text} (no recordings of {text[:3]} hold the "
                           f"model to it; the nearest modelled release is ArduCopter "
                           f"{near}){tail}")


def test_px4_a_plane_a_heli_and_silence_are_refused():
    px4 = firmware_problem(vehicle_type=QUAD, autopilot=R.MAV_AUTOPILOT_PX4,
                           version=Firmware(1, 14, 0, 255).encode())
    assert "its HEARTBEAT says MAV_AUTOPILOT_PX4" in px4
    plane = firmware_problem(vehicle_type=R.MAV_TYPE_FIXED_WING, autopilot=APM,
                             version=RECORDED.encode())
    assert "MAV_TYPE_FIXED_WING" in plane
    heli = firmware_problem(vehicle_type=R.MAV_TYPE_HELICOPTER, autopilot=APM,
                            version=RECORDED.encode())
    assert "MAV_TYPE_HELICOPTER" in heli
    silent = firmware_problem(vehicle_type=QUAD, autopilot=APM, version=None)
    assert "did not answer AUTOPILOT_VERSION (MAV_CMD_REQUEST_MESSAGE 148)" in silent


def test_the_any_firmware_warning_says_what_is_no_longer_promised():
    problem = firmware_problem(vehicle_type=QUAD, autopilot=APM,
                               version=Firmware(4, 4, 4, 255).encode())
    assert any_firmware_warning(problem) == (
        "firmware: it runs 4.4.4 official (no recordings of 4.4 hold the model to it; the "
        "nearest modelled release is ArduCopter 4.5): the predicted flown path, the "
        "clearance kept on it and its timing are not promised for it (--any-firmware)")
