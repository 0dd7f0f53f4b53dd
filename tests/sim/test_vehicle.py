"""The emulated copter introduces itself as ArduCopter does."""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav.sim.vehicle import CopterMode, Vehicle, VehicleOptions

HOME = (12.2332099, 109.1145051, 3.0)


def test_heartbeat_is_an_ardupilot_quadrotor_in_a_copter_mode():
    v = Vehicle(sysid=4, home=HOME)
    hb = v.heartbeat()
    assert hb.type == R.MAV_TYPE_QUADROTOR and hb.autopilot == R.MAV_AUTOPILOT_ARDUPILOTMEGA
    assert hb.custom_mode == CopterMode.STABILIZE and hb.system_status == R.MAV_STATE_STANDBY
    assert hb.base_mode & R.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
    assert not hb.base_mode & R.MAV_MODE_FLAG_SAFETY_ARMED
    v.state.mode, v.state.armed = CopterMode.AUTO, True
    hb = v.heartbeat()
    assert hb.custom_mode == 3 and hb.base_mode & R.MAV_MODE_FLAG_GUIDED_ENABLED
    assert hb.base_mode & R.MAV_MODE_FLAG_SAFETY_ARMED


def test_telemetry_reports_fix_and_prearm_once_ready():
    v = Vehicle(sysid=1, home=HOME, options=VehicleOptions(ready_after_s=2.0))
    periodic, _ = v.tick(0.0)
    kinds = [m.get_type() for m in periodic]
    assert kinds == ["HEARTBEAT", "SYS_STATUS", "GPS_RAW_INT", "GLOBAL_POSITION_INT",
                     "MISSION_CURRENT"]
    assert periodic[2].fix_type < 3
    assert not periodic[1].onboard_control_sensors_health & R.MAV_SYS_STATUS_PREARM_CHECK
    # status once a heartbeat period; the position between, at position_hz (4 Hz)
    periodic, replies = v.tick(0.3)
    assert [m.get_type() for m in periodic] == ["GLOBAL_POSITION_INT"] and replies == []
    assert v.tick(0.4) == ([], [])
    periodic, _ = v.tick(2.0)
    assert periodic[2].fix_type == 3 and periodic[2].lat == round(HOME[0] * 1e7)
    assert periodic[1].onboard_control_sensors_health & R.MAV_SYS_STATUS_PREARM_CHECK


def test_only_messages_for_this_vehicle_are_handled():
    v = Vehicle(sysid=2, home=HOME)
    packer = R.MAVLink(None, srcSystem=255, srcComponent=190)
    parse = R.MAVLink(None).parse_char
    for_other = parse(bytes(R.MAVLink_mission_request_list_message(3, 1, 0).pack(packer)))
    for_me = parse(bytes(R.MAVLink_mission_request_list_message(2, 1, 0).pack(packer)))
    assert v.handle(for_other, 0.0) == []
    (reply,) = v.handle(for_me, 0.0)
    assert reply.get_type() == "MISSION_COUNT" and reply.target_system == 255
