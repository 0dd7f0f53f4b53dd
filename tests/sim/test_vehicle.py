"""The emulated copter introduces itself as ArduCopter does."""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav.ardupilot.commands import RECORDED_BOOT
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


def _kinds(msgs):
    return [m.get_type() for m in msgs]


def test_a_link_that_asked_nothing_gets_heartbeat_timesync_and_home_once():
    boot = RECORDED_BOOT.scaled(0.1)  # home at 1.98 s
    v = Vehicle(sysid=1, home=HOME, options=VehicleOptions(boot=boot))
    v.link("A", 0.0)
    seen = []
    for k in range(0, 2100):  # 21 s at 100 Hz
        seen += v.tick(k * 0.01)["A"]
    kinds = _kinds(seen)
    assert set(kinds) == {"HEARTBEAT", "TIMESYNC", "HOME_POSITION", "GPS_GLOBAL_ORIGIN"}
    assert kinds.count("HEARTBEAT") == 21 and kinds.count("TIMESYNC") == 2
    assert kinds.count("HOME_POSITION") == 1 and "STATUSTEXT" not in kinds


def test_set_message_interval_and_request_data_stream_are_per_link():
    v = Vehicle(sysid=1, home=HOME)
    packer = R.MAVLink(None, srcSystem=255, srcComponent=190)
    parse = R.MAVLink(None).parse_char

    def wire(m):
        return parse(bytes(m.pack(packer)))

    ask = wire(R.MAVLink_command_long_message(1, 1, R.MAV_CMD_SET_MESSAGE_INTERVAL, 0,
                                              R.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, 200000,
                                              0, 0, 0, 0, 0))
    (ack,) = [m for m in v.handle(ask, 1.0, "A") if m.get_type() == "COMMAND_ACK"]
    assert ack.result == R.MAV_RESULT_ACCEPTED
    v.handle(wire(R.MAVLink_request_data_stream_message(
        1, 1, R.MAV_DATA_STREAM_EXTENDED_STATUS, 2, 1)), 1.0, "B")
    got = {"A": [], "B": []}
    for k in range(101, 301):  # 2 s
        for link, msgs in v.tick(k * 0.01).items():
            got[link] += _kinds(msgs)
    assert got["A"].count("GLOBAL_POSITION_INT") in (10, 11) and "SYS_STATUS" not in got["A"]
    assert got["B"].count("SYS_STATUS") in (4, 5) and "GLOBAL_POSITION_INT" not in got["B"]
    assert got["B"].count("GPS_RAW_INT") in (4, 5)


def test_an_interval_set_right_at_boot_is_acknowledged_and_lost():
    v = Vehicle(sysid=1, home=HOME)
    packer = R.MAVLink(None, srcSystem=255, srcComponent=190)
    ask = R.MAVLink(None).parse_char(bytes(R.MAVLink_command_long_message(
        1, 1, R.MAV_CMD_SET_MESSAGE_INTERVAL, 0, R.MAVLINK_MSG_ID_GPS_RAW_INT, 200000,
        0, 0, 0, 0, 0).pack(packer)))
    (ack,) = [m for m in v.handle(ask, 0.0, "A") if m.get_type() == "COMMAND_ACK"]
    assert ack.result == R.MAV_RESULT_ACCEPTED
    assert "GPS_RAW_INT" not in _kinds(v.tick(0.5)["A"] + v.tick(1.0)["A"])


def test_only_messages_for_this_vehicle_are_handled():
    v = Vehicle(sysid=2, home=HOME)
    packer = R.MAVLink(None, srcSystem=255, srcComponent=190)
    parse = R.MAVLink(None).parse_char
    for_other = parse(bytes(R.MAVLink_mission_request_list_message(3, 1, 0).pack(packer)))
    for_me = parse(bytes(R.MAVLink_mission_request_list_message(2, 1, 0).pack(packer)))
    assert [m for m in v.handle(for_other, 0.0) if m.get_type() != "STATUSTEXT"] == []
    (reply,) = [m for m in v.handle(for_me, 0.0) if m.get_type() != "STATUSTEXT"]
    assert reply.get_type() == "MISSION_COUNT" and reply.target_system == 255


def test_param_request_read_and_param_set_are_answered_as_gcs_param_does():
    v = Vehicle(sysid=1, home=HOME)
    v.link("B", 0.0)
    packer = R.MAVLink(None, srcSystem=255, srcComponent=190)
    parse = R.MAVLink(None).parse_char

    def wire(m):
        return parse(bytes(m.pack(packer)))

    def values(msgs):
        return [m for m in msgs if m.get_type() == "PARAM_VALUE"]

    (pv,) = values(v.handle(wire(R.MAVLink_param_request_read_message(
        1, 1, b"WPNAV_SPEED", -1)), 1.0, "A"))
    assert (pv.param_id, pv.param_value, pv.param_type) == ("WPNAV_SPEED", 1000.0, 9)
    assert pv.param_count == 1390 and pv.param_index == 65535  # as flight.json recorded
    assert values(v.handle(wire(R.MAVLink_param_request_read_message(1, 1, b"NO_SUCH", -1)),
                           1.0, "A")) == []
    (pv,) = values(v.handle(wire(R.MAVLink_param_set_message(1, 1, b"WPNAV_SPEED", 500.0, 9)),
                            1.0, "A"))
    assert pv.param_value == 500.0
    assert v.autopilot.nav_params().wp_speed == 5.0
    v.handle(wire(R.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3)), 1.0, "B")  # B is active
    v.handle(wire(R.MAVLink_param_set_message(1, 1, b"LAND_SPEED", 30.0, 4)), 1.0, "A")
    assert any(m.get_type() == "PARAM_VALUE" for m in v.tick(1.01)["B"])
