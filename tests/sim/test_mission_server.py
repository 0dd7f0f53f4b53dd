"""The emulator's mission server does what ArduPilot's MissionItemProtocol does."""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav.link.codec import encode_item
from ftlbo_mav.sim.mission_server import MissionServer, MissionServerOptions
from tests.link.support import make_mission

ITEMS = make_mission()
HOME = (-35.363261, 149.165230, 584.0)
GCS = (255, 190)
OTHER_GCS = (254, 190)


def wire(msg, src=GCS):
    """Give a message its sender's ids, as the parser would."""
    packer = R.MAVLink(None, srcSystem=src[0], srcComponent=src[1])
    return R.MAVLink(None).parse_char(bytes(msg.pack(packer)))


def count(n, src=GCS):
    return wire(R.MAVLink_mission_count_message(1, 1, n, 0), src)


def item(seq, src=GCS, frame=None):
    it = ITEMS[seq]
    msg = encode_item(it, target_system=1, target_component=1)
    if frame is not None:
        msg.frame = frame
    return wire(msg, src)


def only(pairs):
    """The one protocol message among ``(link, message)`` replies (STATUSTEXT aside)."""
    (m,) = [m for _, m in pairs if m.get_type() != "STATUSTEXT"]
    return m


def server(**options):
    return MissionServer(sysid=1, home=HOME, options=MissionServerOptions(**options))


def upload_all(s, t=0.0):
    out = s.handle(count(len(ITEMS)), t)
    for k in range(len(ITEMS)):
        out = s.handle(item(k), t + 0.01 * (k + 1))
    return out


def test_asks_with_mission_request_and_acks_accepted_at_the_end():
    s = server()
    req = only(s.handle(count(len(ITEMS)), 0.0))
    assert req.get_type() == "MISSION_REQUEST" and req.seq == 0
    assert (req.target_system, req.target_component) == GCS  # replies to the sender's ids
    done = only(upload_all(server()))
    assert done.get_type() == "MISSION_ACK" and done.type == R.MAV_MISSION_ACCEPTED


def test_wrong_item_gets_invalid_sequence_and_the_upload_goes_on():
    s = server()
    s.handle(count(len(ITEMS)), 0.0)
    s.handle(item(0), 0.01)
    assert only(s.handle(item(0), 0.02)).type == R.MAV_MISSION_INVALID_SEQUENCE
    assert only(s.handle(item(5), 0.03)).type == R.MAV_MISSION_INVALID_SEQUENCE
    assert only(s.handle(item(1), 0.04)).seq == 2


def test_re_asks_after_a_second_and_cancels_a_stalled_upload_after_eight():
    s = server()
    s.handle(count(len(ITEMS)), 0.0)
    assert s.update(0.5) == []
    assert only(s.update(1.01)).seq == 0
    t, asks = 1.01, 1
    while True:
        t += 0.1
        out = s.update(t)
        acks = [m for _, m in out if m.get_type() == "MISSION_ACK"]
        if acks:
            break
        asks += len(out)
    assert acks[0].type == R.MAV_MISSION_OPERATION_CANCELLED and 8.0 < t < 8.2
    assert asks == 7 and not s.receiving


def test_denies_a_second_concurrent_transfer_but_lets_the_uploader_restart():
    s = server()
    s.handle(count(len(ITEMS)), 0.0)
    s.handle(item(0), 0.01)
    assert only(s.handle(count(3, OTHER_GCS), 0.02)).type == R.MAV_MISSION_DENIED
    list_req = wire(R.MAVLink_mission_request_list_message(1, 1, 0), OTHER_GCS)
    assert only(s.handle(list_req, 0.03)).type == R.MAV_MISSION_DENIED
    assert only(s.handle(count(len(ITEMS)), 0.04)).seq == 0  # same sender: restart


def test_no_space_beyond_capacity_and_during_boot():
    assert only(server(capacity=10).handle(count(15), 0.0)).type == R.MAV_MISSION_NO_SPACE
    s = server(boot_no_space_s=2.0)
    assert only(s.handle(count(15), 1.0)).type == R.MAV_MISSION_NO_SPACE
    assert only(s.handle(count(15), 2.5)).get_type() == "MISSION_REQUEST"


def read(s, seq, *, legacy=False, t=1.0):
    cls = R.MAVLink_mission_request_message if legacy else R.MAVLink_mission_request_int_message
    return s.handle(wire(cls(1, 1, seq, 0)), t)


def test_read_back_returns_home_as_item_zero_and_frame_6_as_3():
    s = server()
    s.handle(count(3), 0.0)
    s.handle(item(0), 0.01)
    s.handle(item(1, frame=6), 0.02)
    s.handle(item(2, frame=6), 0.03)
    n = only(s.handle(wire(R.MAVLink_mission_request_list_message(1, 1, 0)), 1.0))
    assert n.get_type() == "MISSION_COUNT" and n.count == 3
    home = only(read(s, 0))
    assert (home.x, home.y, home.z) == (round(HOME[0] * 1e7), round(HOME[1] * 1e7), HOME[2])
    two = only(read(s, 2))
    assert two.get_type() == "MISSION_ITEM_INT" and two.frame == 3
    assert two.x == round(ITEMS[2].lat_deg * 1e7)
    legacy = only(read(s, 2, legacy=True))
    assert legacy.get_type() == "MISSION_ITEM" and abs(legacy.x - ITEMS[2].lat_deg) < 1e-5


def test_reading_past_the_end_educates_with_count_and_error():
    s = server()
    upload_all(s)
    (_, cnt), (_, err) = read(s, 99)
    assert cnt.get_type() == "MISSION_COUNT" and cnt.count == len(ITEMS)
    assert err.type == R.MAV_MISSION_ERROR


def test_a_failed_upload_keeps_the_items_that_arrived_and_clear_removes_them():
    s = server(upload_timeout_s=8.0)
    s.handle(count(15), 0.0)
    for k in range(6):
        s.handle(item(k), 0.01 * (k + 1))
    s.update(9.0)  # cancelled
    assert len(s.items) == 6
    assert only(s.handle(wire(R.MAVLink_mission_clear_all_message(1, 1, 0)), 9.1)).type == 0
    assert s.items == []


def test_items_after_the_upload_get_error():
    s = server()
    upload_all(s)
    assert only(s.handle(item(14), 2.0)).type == R.MAV_MISSION_ERROR


def test_commands_without_a_position_come_back_in_frame_0():
    from ftlbo_mav.mission.items import build_mission

    items = build_mission(home=(12.2, 109.1), takeoff_alt_m=3.0, end_action="rtl",
                          speed_m_s=4.0, path=[(12.2, 109.1, 4.0), (12.2001, 109.1001, 4.0)])
    s = server()
    s.handle(count(len(items)), 0.0)
    for k, it in enumerate(items):
        s.handle(wire(encode_item(it, target_system=1, target_component=1)), 0.01 * (k + 1))
    frames = {it.command: only(read(s, k)).frame for k, it in enumerate(items) if k}
    assert frames == {22: 3, 93: 0, 178: 0, 16: 3, 20: 0}
