"""The ground-station mission protocol: message by message, and against the emulated
vehicle in virtual time (no sockets, no sleeping)."""

from __future__ import annotations

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav.link.codec import mission_differences
from ftlbo_mav.link.mission_protocol import (
    RESULT_TEXT,
    Download,
    MissionTransferError,
    Timing,
    Upload,
    clear_mission,
    describe_result,
    download_mission,
    read_items,
    upload_mission,
    write_items,
)
from ftlbo_mav.link.swarm import upload_and_verify
from ftlbo_mav.sim.faults import Faults
from ftlbo_mav.sim.loopback import LoopbackChannel
from ftlbo_mav.sim.mission_server import MissionServer, MissionServerOptions
from ftlbo_mav.sim.vehicle import Vehicle, VehicleOptions
from tests.link.support import make_mission

ITEMS = make_mission()
N = len(ITEMS)
HOME = (ITEMS[0].lat_deg, ITEMS[0].lon_deg, 12.0)


ONE_BY_ONE = Timing(send_ahead=0)
"""MAVLink's mission protocol as written: an item for each request (PX4's, and the
message-by-message tests of it); ArduPilot's uploads send items ahead (below)."""


def upload_machine(items=ITEMS, timing=None):
    return Upload(items, sysid=1, compid=1, own=(255, 190), timing=timing or ONE_BY_ONE,
                  progress=None)


def request(seq, *, legacy=True):
    cls = R.MAVLink_mission_request_message if legacy else R.MAVLink_mission_request_int_message
    return cls(255, 190, seq, 0)


def ack(result):
    return R.MAVLink_mission_ack_message(255, 190, result, 0)


def sent_seqs(msgs):
    return [m.seq for m in msgs if m.get_type() == "MISSION_ITEM_INT"]


# ----------------------------------------------------------------- message by message


def test_upload_starts_with_count_and_answers_both_request_kinds_with_item_int():
    up = upload_machine()
    (count,) = up.start(0.0)
    assert count.get_type() == "MISSION_COUNT" and count.count == N and count.target_system == 1
    a = up.on_message(request(0, legacy=True), 0.01)
    b = up.on_message(request(1, legacy=False), 0.02)
    assert [m.get_type() for m in a + b] == ["MISSION_ITEM_INT", "MISSION_ITEM_INT"]
    assert sent_seqs(a + b) == [0, 1]
    assert a[0].x == round(ITEMS[0].lat_deg * 1e7) and a[0].y == round(ITEMS[0].lon_deg * 1e7)


def test_duplicate_and_out_of_order_requests_are_answered_and_do_not_end_the_upload():
    up = upload_machine()
    up.start(0.0)
    out = []
    for t, seq in enumerate([0, 1, 1, 0, 2, 1, 3]):
        out += up.on_message(request(seq), 0.01 * (t + 1))
    assert sent_seqs(out) == [0, 1, 1, 0, 2, 1, 3]
    assert not up.finished and up.highest == 3


def test_invalid_sequence_mid_upload_does_not_end_it():
    up = upload_machine()
    up.start(0.0)
    up.on_message(request(0), 0.01)
    assert up.on_message(ack(R.MAV_MISSION_INVALID_SEQUENCE), 0.02) == []
    assert not up.finished and up.error is None
    for seq in range(1, N):
        up.on_message(request(seq), 0.02 + 0.01 * seq)
    up.on_message(ack(R.MAV_MISSION_ACCEPTED), 1.0)
    assert up.finished and up.error is None and up.acknowledged


def test_a_stale_accepted_before_the_last_item_is_ignored():
    up = upload_machine()
    up.start(0.0)
    up.on_message(request(0), 0.01)
    up.on_message(ack(R.MAV_MISSION_ACCEPTED), 0.02)
    assert not up.finished


def test_lost_request_resend_then_invalid_sequence_sends_the_next_item():
    up = upload_machine()
    up.start(0.0)
    up.on_message(request(0), 0.01)
    up.on_message(request(1), 0.02)  # now timed: resends come after a few round trips
    resend = up.on_timeout(up.deadline)
    assert sent_seqs(resend) == [1]
    # the vehicle had item 1 and its request for 2 was lost: it rejects the resent 1
    nxt = up.on_message(ack(R.MAV_MISSION_INVALID_SEQUENCE), up.deadline - 0.1)
    assert sent_seqs(nxt) == [2]
    # a second INVALID_SEQUENCE (a stale one) does not make it jump again
    assert up.on_message(ack(R.MAV_MISSION_INVALID_SEQUENCE), up.deadline - 0.05) == []


# ------------------------------------------------- sending ahead (ArduPilot's uploads)


def test_arducopter_gets_items_ahead_of_its_requests_each_sent_once():
    up = upload_machine(timing=Timing())
    up.start(0.0)
    assert sent_seqs(up.on_message(request(0), 0.10)) == [0, 1, 2, 3]
    # it stored 1-3 as they came, asking for each: one new item each, none twice
    assert sent_seqs(up.on_message(request(1), 0.20)) == [4]
    assert sent_seqs(up.on_message(request(2), 0.21)) == [5]
    assert sent_seqs(up.on_message(request(3), 0.22)) == [6]
    assert up.highest == 3 and not up.finished


def test_an_item_sent_ahead_of_a_lost_one_goes_again_when_asked_for():
    """Item 1 lost: 2 and 3 came out of sequence (INVALID_SEQUENCE, forgotten). The first
    INVALID_SEQUENCE, with no item sent twice lately, says so: item 1 goes again at once
    with the window behind it, in order; the acknowledgements of what was sent twice then
    change nothing, and asked for 2 it sends only what is new."""
    up = upload_machine(timing=Timing())
    up.start(0.0)
    up.on_message(request(0), 0.10)              # 0, 1, 2, 3 go; 1 is lost
    assert sent_seqs(up.on_message(request(1), 0.20)) == [4]  # 1 seems on its way
    again = up.on_message(ack(R.MAV_MISSION_INVALID_SEQUENCE), 0.30)  # 2 forgotten
    assert sent_seqs(again) == [1, 2, 3, 4]      # not after the timer (0.35 s on)
    assert up.on_message(ack(R.MAV_MISSION_INVALID_SEQUENCE), 0.31) == []  # 3 forgotten
    assert sent_seqs(up.on_message(request(2), 0.42)) == [5]
    assert sent_seqs(up.on_message(request(3), 0.43)) == [6]
    assert sent_seqs(up.on_message(request(4), 0.44)) == [7]


def test_a_lost_item_resent_by_the_timer_then_goes_with_the_window_behind_it():
    """Without the INVALID_SEQUENCE (lost as well), item 1 goes again when its request
    seems lost; asked for 2, it sends 2 again with the window behind it, in order."""
    up = upload_machine(timing=Timing())
    up.start(0.0)
    up.on_message(request(0), 0.10)              # 0, 1, 2, 3 go; 1 is lost
    assert sent_seqs(up.on_message(request(1), 0.20)) == [4]  # 1 seems on its way
    assert sent_seqs(up.on_timeout(up.deadline)) == [1]
    t = up.deadline - 0.1
    assert sent_seqs(up.on_message(request(2), t)) == [2, 3, 4, 5]
    assert sent_seqs(up.on_message(request(3), t + 0.01)) == [6]
    assert sent_seqs(up.on_message(request(4), t + 0.02)) == [7]


def test_an_invalid_sequence_soon_after_a_duplicate_is_not_taken_for_a_loss():
    """A stale request answered (every request is): the vehicle had that item, and its
    INVALID_SEQUENCE within 1.5 round trips of the duplicate changes nothing."""
    up = upload_machine(timing=Timing())
    up.start(0.0)
    up.on_message(request(0), 0.10)              # round trips of 0.1 s
    up.on_message(request(1), 0.20)
    assert sent_seqs(up.on_message(request(1), 0.25)) == [1]  # a stale request: item 1 again
    assert up.on_message(ack(R.MAV_MISSION_INVALID_SEQUENCE), 0.30) == []


def test_an_error_about_an_earlier_transfers_item_does_not_end_a_new_one():
    up = upload_machine(timing=Timing())
    up.start(0.0)
    assert up.on_message(ack(R.MAV_MISSION_ERROR), 0.05) == [] and not up.finished
    up.on_message(request(0), 0.10)
    assert not up.finished


def test_resends_come_sooner_once_a_round_trip_is_timed_but_within_the_same_budget():
    timing = Timing(timeout_s=1.5, retries=5, send_ahead=0)
    up = upload_machine(timing=timing)
    up.start(0.0)
    up.on_message(request(0), 0.010)
    up.on_message(request(1), 0.020)
    first = up.deadline
    assert first - 0.020 == pytest.approx(timing.min_resend_s)
    t, resends = first, 0
    while not up.finished:
        up.on_timeout(t)
        resends += 1
        t = up.deadline
    assert "no answer to item 1" in str(up.error) and "vehicle 1" in str(up.error)
    assert t - 0.020 == pytest.approx(timing.budget_s, abs=timing.min_resend_s + 1e-6)
    assert resends > timing.retries


def test_no_answer_to_count_fails_after_the_budget_naming_vehicle_and_step():
    timing = Timing(timeout_s=0.3, retries=2, first_resend_s=0.3, send_ahead=0)
    up = upload_machine(timing=timing)
    out = up.start(0.0)
    t, counts = 0.0, len(out)
    while not up.finished:
        t = up.deadline
        counts += len(up.on_timeout(t))
    assert counts == timing.retries + 1
    assert t == pytest.approx(timing.budget_s)
    assert isinstance(up.error, MissionTransferError)
    assert str(up.error).startswith("vehicle 1: upload: no answer to MISSION_COUNT")


def test_no_space_at_boot_is_waited_out_then_the_upload_goes_on():
    up = upload_machine(timing=Timing(not_ready_s=5.0, not_ready_poll_s=1.0, send_ahead=0))
    up.start(0.0)
    assert up.on_message(ack(R.MAV_MISSION_NO_SPACE), 0.01) == []
    assert not up.finished
    (again,) = up.on_timeout(up.deadline)
    assert again.get_type() == "MISSION_COUNT"
    assert sent_seqs(up.on_message(request(0), 1.05)) == [0]


def test_no_space_that_persists_is_a_clear_error():
    up = upload_machine(timing=Timing(not_ready_s=2.0, not_ready_poll_s=1.0))
    up.start(0.0)
    t = 0.01
    while not up.finished:
        up.on_message(ack(R.MAV_MISSION_NO_SPACE), t)
        if not up.finished:
            up.on_timeout(up.deadline)
            t = up.deadline - 0.5
    assert up.error.result == R.MAV_MISSION_NO_SPACE
    assert "no space" in str(up.error) and "MAV_MISSION_NO_SPACE" in str(up.error)


def test_a_refusal_mid_upload_ends_it_with_the_item_named():
    up = upload_machine()
    up.start(0.0)
    up.on_message(request(0), 0.01)
    up.on_message(request(1), 0.02)
    up.on_message(ack(R.MAV_MISSION_UNSUPPORTED), 0.03)
    assert up.finished and "not supported" in str(up.error) and "at item 1" in str(up.error)


def test_lost_accepted_after_the_last_item_ends_unconfirmed():
    up = upload_machine()
    up.start(0.0)
    for seq in range(N):
        up.on_message(request(seq), 0.01 * (seq + 1))
    up.on_timeout(up.deadline)  # ACCEPTED lost: the last item is resent
    up.on_message(ack(R.MAV_MISSION_ERROR), up.deadline - 0.1)  # vehicle no longer receiving
    assert up.finished and up.error is None and not up.acknowledged


@pytest.mark.parametrize("code", sorted(R.enums["MAV_MISSION_RESULT"]))
def test_every_mission_result_has_a_sentence(code):
    if code == R.MAV_MISSION_RESULT_ENUM_END:
        return
    assert code in RESULT_TEXT
    text = describe_result(code)
    assert R.enums["MAV_MISSION_RESULT"][code].name in text and len(text) > 25


def _item(seq):
    return R.MAVLink_mission_item_int_message(
        255, 190, seq, 3, 16, 0, 1, 0, 0, 0, 0, 122332099, 1091145051, 5.0, 0)


def test_download_ignores_duplicates_and_stale_acks_and_acks_at_the_end():
    dl = Download(sysid=1, compid=1, own=(255, 190), timing=Timing(), progress=None)
    (first,) = dl.start(0.0)
    assert first.get_type() == "MISSION_REQUEST_LIST"
    reqs = dl.on_message(R.MAVLink_mission_count_message(255, 190, 2, 0), 0.01)
    # the window: every item asked for at once (ArduPilot answers each on its own)
    assert [(r.get_type(), r.seq) for r in reqs] == [("MISSION_REQUEST_INT", 0),
                                                     ("MISSION_REQUEST_INT", 1)]
    assert dl.on_message(_item(0), 0.02) == []  # nothing more to ask
    assert dl.on_message(_item(0), 0.03) == []  # duplicate
    assert dl.on_message(ack(R.MAV_MISSION_ERROR), 0.035) == []  # stale, from an upload
    assert dl.on_message(R.MAVLink_mission_count_message(255, 190, 2, 0), 0.04) == []
    (done,) = dl.on_message(_item(1), 0.05)
    assert done.get_type() == "MISSION_ACK" and done.type == R.MAV_MISSION_ACCEPTED
    assert dl.finished and [i.seq for i in dl.items] == [0, 1]
    assert dl.items[1].lat_deg == pytest.approx(12.2332099)


def test_download_asks_a_window_at_a_time_and_again_for_what_was_lost():
    from ftlbo_mav.link.mission_protocol import READ_WINDOW

    count = READ_WINDOW + 3
    dl = Download(sysid=1, compid=1, own=(255, 190), timing=Timing(), progress=None)
    dl.start(0.0)
    reqs = dl.on_message(R.MAVLink_mission_count_message(255, 190, count, 0), 0.1)
    assert [r.seq for r in reqs] == list(range(READ_WINDOW))
    # answers in order, one lost (seq 2): each answer lets one more be asked, and the
    # answer that overtook the lost one has it asked again at once, not after the timer
    more = []
    for seq in (0, 1, 3):
        more += dl.on_message(_item(seq), 0.2)
    assert [r.seq for r in more] == [READ_WINDOW, READ_WINDOW + 1, READ_WINDOW + 2, 2]
    for seq in [2, *range(4, count - 1)]:  # the last one lost: nothing overtakes it
        assert dl.on_message(_item(seq), 0.25) == []
    assert not dl.finished and len(dl.items) == count - 1
    again = dl.on_timeout(dl.deadline)
    assert [r.seq for r in again] == [count - 1]  # only the one not answered
    (done,) = dl.on_message(_item(count - 1), dl.deadline + 0.1)
    assert done.type == R.MAV_MISSION_ACCEPTED and len(dl.items) == count


def test_a_read_backs_last_request_lost_is_asked_again_sooner_than_one_with_others_behind():
    """Once every item has been asked for, nothing can overtake a lost one: the timer is
    TAIL_RTTS round trips from the last answer, not RESEND_RTTS."""
    from ftlbo_mav.link.transfer import RESEND_RTTS, TAIL_RTTS

    dl = Download(sysid=1, compid=1, own=(255, 190), timing=Timing(), progress=None,
                  srtt=0.2)
    dl.start(0.0)
    dl.on_message(R.MAVLink_mission_count_message(255, 190, 3, 0), 0.1)
    assert dl.deadline == pytest.approx(0.1 + TAIL_RTTS * dl.srtt)  # all three asked
    dl.on_message(_item(0), 0.3)
    dl.on_message(_item(1), 0.31)  # item 2's request (or answer) lost
    assert dl.deadline == pytest.approx(0.31 + TAIL_RTTS * dl.srtt)
    assert dl.deadline < 0.31 + RESEND_RTTS * dl.srtt - 0.1
    (again,) = dl.on_timeout(dl.deadline)
    assert again.seq == 2


def test_download_on_a_link_that_reorders_asks_once_more_and_keeps_one_copy():
    dl = Download(sysid=1, compid=1, own=(255, 190), timing=Timing(), progress=None)
    dl.start(0.0)
    dl.on_message(R.MAVLink_mission_count_message(255, 190, 3, 0), 0.1)
    (again,) = dl.on_message(_item(1), 0.2)  # 1 before 0: 0 taken for lost
    assert again.get_type() == "MISSION_REQUEST_INT" and again.seq == 0
    assert dl.on_message(_item(0), 0.21) == []  # it was late, not lost
    assert dl.on_message(_item(0), 0.3) == []  # the answer to the second request
    (done,) = dl.on_message(_item(2), 0.31)
    assert done.type == R.MAV_MISSION_ACCEPTED and [i.seq for i in dl.items] == [0, 1, 2]


def test_a_read_back_of_what_was_sent_asks_for_its_first_items_with_the_count():
    dl = Download(sysid=1, compid=1, own=(255, 190), timing=Timing(), progress=None, expect=3)
    first = dl.start(0.0)
    assert [(m.get_type(), getattr(m, "seq", None)) for m in first] == [
        ("MISSION_REQUEST_LIST", None), ("MISSION_REQUEST_INT", 0),
        ("MISSION_REQUEST_INT", 1), ("MISSION_REQUEST_INT", 2)]
    assert dl.on_message(_item(0), 0.1) == [] and not dl.finished  # kept, the count to come
    assert dl.on_message(R.MAVLink_mission_count_message(255, 190, 3, 0), 0.11) == []
    dl.on_message(_item(1), 0.12)
    (done,) = dl.on_message(_item(2), 0.13)
    assert done.type == R.MAV_MISSION_ACCEPTED and [i.seq for i in dl.items] == [0, 1, 2]


def test_a_read_back_that_finds_fewer_items_than_sent_reads_what_is_there():
    dl = Download(sysid=1, compid=1, own=(255, 190), timing=Timing(), progress=None, expect=3)
    dl.start(0.0)
    dl.on_message(_item(0), 0.1)
    dl.on_message(_item(1), 0.1)
    (done,) = dl.on_message(R.MAVLink_mission_count_message(255, 190, 1, 0), 0.11)
    assert done.type == R.MAV_MISSION_ACCEPTED and [i.seq for i in dl.items] == [0]


# ----------------------------------------------------------------- against the emulator


def vehicle(**mission_options):
    return Vehicle(sysid=1, home=HOME,
                   options=VehicleOptions(mission=MissionServerOptions(**mission_options)))


def test_upload_then_read_back_over_a_clean_link():
    ch = LoopbackChannel(vehicle())
    assert upload_mission(ch, ITEMS) is True
    back = download_mission(ch)
    assert mission_differences(ITEMS, back) == []
    assert back[0].lat_deg == pytest.approx(HOME[0]) and back[0].alt_m == HOME[2]  # home
    # the vehicle asked with MISSION_REQUEST, as ArduPilot does
    assert {m.get_type() for m in ch.received} >= {"MISSION_REQUEST"}
    assert "MISSION_REQUEST_INT" not in {m.get_type() for m in ch.received}


def test_one_item_is_replaced_in_place_and_read_back_alone():
    """MISSION_WRITE_PARTIAL_LIST (MissionItemProtocol::handle_mission_write_partial_list):
    the vehicle asks for just that item; the rest of the mission stays as it was."""
    from dataclasses import replace

    ch = LoopbackChannel(vehicle())
    assert upload_mission(ch, ITEMS) is True
    changed = replace(ITEMS[4], alt_m=ITEMS[4].alt_m + 3.0)
    before = len(ch.received)
    assert write_items(ch, [changed]) is True
    asked = [m.seq for m in ch.received[before:] if m.get_type() == "MISSION_REQUEST"]
    assert asked == [4]
    (back,) = read_items(ch, [4])
    assert back.alt_m == pytest.approx(changed.alt_m)
    assert mission_differences([*ITEMS[:4], changed, *ITEMS[5:]], download_mission(ch)) == []


def test_a_partial_write_past_the_end_is_refused():
    from dataclasses import replace

    ch = LoopbackChannel(vehicle())
    assert upload_mission(ch, ITEMS) is True
    with pytest.raises(MissionTransferError):
        write_items(ch, [replace(ITEMS[1], seq=N + 1)])


@pytest.mark.parametrize("seed", range(10))
def test_a_partial_write_gets_through_loss(seed):
    from dataclasses import replace

    faults = Faults(loss_up=0.3, loss_down=0.3, duplicate=0.05, reorder=0.05)
    ch = LoopbackChannel(vehicle(), faults=faults, rng=np.random.default_rng(seed))
    assert upload_mission(ch, ITEMS) is not None
    changed = replace(ITEMS[2], param1=3.0)
    write_items(ch, [changed])
    (back,) = read_items(ch, [2])
    assert back.param1 == 3.0


@pytest.mark.parametrize("seed", range(40))
def test_thirty_percent_loss_duplicates_and_reordering_still_verify(seed):
    faults = Faults(loss_up=0.3, loss_down=0.3, duplicate=0.05, reorder=0.05)
    ch = LoopbackChannel(vehicle(), faults=faults, rng=np.random.default_rng(seed))
    ok, message = upload_and_verify(ch, ITEMS, timing=Timing())
    assert ok, message


@pytest.mark.parametrize("seed", range(10))
def test_duplicated_frames_alone_never_break_an_upload(seed):
    ch = LoopbackChannel(vehicle(), faults=Faults(duplicate=0.3),
                         rng=np.random.default_rng(seed))
    ok, message = upload_and_verify(ch, ITEMS, timing=Timing())
    assert ok, message
    acks = [m.type for m in ch.received if m.get_type() == "MISSION_ACK"]
    assert R.MAV_MISSION_ACCEPTED in acks


def test_boot_no_space_is_waited_for():
    ch = LoopbackChannel(vehicle(boot_no_space_s=3.0))
    assert upload_mission(ch, ITEMS, timing=Timing(not_ready_s=10.0)) is True
    assert ch.now >= 3.0
    acks = [m.type for m in ch.received if m.get_type() == "MISSION_ACK"]
    assert acks[0] == R.MAV_MISSION_NO_SPACE


def test_capacity_no_space_is_an_error_and_nothing_is_stored():
    ch = LoopbackChannel(vehicle(capacity=10))
    with pytest.raises(MissionTransferError, match="no space for this many items") as exc:
        upload_mission(ch, ITEMS, timing=Timing(not_ready_s=2.0))
    assert exc.value.sysid == 1 and exc.value.step == "upload"
    assert ch.vehicle.missions.items == []


class RefusesItem(MissionServer):
    """A vehicle whose storage fails at one item, as AP_Mission::add_cmd can."""

    fail_at = 7

    def _item(self, msg, sender, now):
        if self.receiving and msg.seq == self.request_i == self.fail_at:
            self.receiving = False
            return self._ack(sender, R.MAV_MISSION_ERROR)
        return super()._item(msg, sender, now)


def test_failed_upload_leaves_no_partial_mission_and_says_so():
    v = vehicle()
    v.missions = RefusesItem(sysid=1, home=HOME)
    ch = LoopbackChannel(v)
    ok, message = upload_and_verify(ch, ITEMS, timing=Timing())
    assert not ok
    assert "upload failed" in message and "at item 7" in message
    assert "now has no mission" in message
    assert v.missions.items == []  # the 7 items that arrived were cleared


def test_a_read_back_that_differs_is_never_ok():
    v = vehicle()
    ch = LoopbackChannel(v)
    upload_mission(ch, ITEMS)
    back = download_mission(ch)
    assert mission_differences(ITEMS, back[:-1]) == [f"read back {N - 1} items, sent {N}"]
    changed = list(ITEMS)
    changed[5] = type(ITEMS[5])(**{**ITEMS[5].__dict__, "lat_deg": ITEMS[5].lat_deg + 2e-7})
    (problem,) = mission_differences(changed, back)
    assert problem.startswith("item 5: lat")


def test_clear_then_read_back_shows_no_items():
    ch = LoopbackChannel(vehicle())
    upload_mission(ch, ITEMS)
    clear_mission(ch)
    assert download_mission(ch) == []


def test_a_mute_vehicle_fails_within_the_budget():
    timing = Timing(timeout_s=0.5, retries=3)
    ch = LoopbackChannel(vehicle(), faults=Faults(mute=True))
    with pytest.raises(MissionTransferError, match="no answer to MISSION_COUNT"):
        upload_mission(ch, ITEMS, timing=timing)
    assert ch.now == pytest.approx(timing.budget_s, abs=0.05)


def test_a_stalled_upload_is_cancelled_by_the_vehicle_and_reported():
    """The link dies mid-upload for the vehicle's 8 s: it sends OPERATION_CANCELLED."""
    v = vehicle(upload_timeout_s=8.0)
    ch = LoopbackChannel(v)
    up = Upload(ITEMS, sysid=1, compid=1, own=(255, 190), timing=Timing(timeout_s=20.0),
                progress=None)
    for m in up.start(ch.now):
        ch.send(m)
    msg = ch.recv(1.0)
    assert msg.get_type() == "MISSION_REQUEST" and msg.seq == 0
    # we never answer: the vehicle re-asks about every second, then cancels
    seen = []
    while (m := ch.recv(10.0)) is not None:
        seen.append((round(ch.now, 1), m.get_type(), getattr(m, "seq", getattr(m, "type", None))))
        if m.get_type() == "MISSION_ACK":
            break
    requests = [s for s in seen if s[1] == "MISSION_REQUEST"]
    assert 6 <= len(requests) <= 8
    assert seen[-1][1:] == ("MISSION_ACK", R.MAV_MISSION_OPERATION_CANCELLED)
    assert up.on_message(ch.received[-1], ch.now) == [] and up.finished
    assert "cancelled" in str(up.error)


def test_early_resends_only_for_autopilots_that_check_item_sequence():
    from ftlbo_mav.link.endpoints import Heartbeat
    from ftlbo_mav.link.swarm import timing_for

    def hb(autopilot):
        return Heartbeat(sysid=1, compid=1, vehicle_type=2, autopilot=autopilot, custom_mode=0,
                         base_mode=0, system_status=3, received_at=0.0)

    timing = Timing()
    assert timing_for(hb(R.MAV_AUTOPILOT_ARDUPILOTMEGA), timing) is timing
    generic = timing_for(hb(R.MAV_AUTOPILOT_GENERIC), timing)  # e.g. MAVSDK's server
    up = upload_machine(timing=generic)
    up.start(0.0)
    up.on_message(request(0), 0.01)
    up.on_message(request(1), 0.02)
    assert up.deadline == pytest.approx(0.02 + timing.timeout_s)


def test_upload_and_verify_sends_ahead_only_its_share_of_a_shared_link():
    """Three vehicles heard on one radio: each upload sends one item ahead of the one asked
    for, not three (a whole burst of three per copter overflowed the good-day radio's
    buffer on SITL, and items sent ahead were lost: INVALID_SEQUENCE, resends)."""
    from ftlbo_mav.link.mission_protocol import SEND_AHEAD_ON_LINK

    class Shared(LoopbackChannel):
        sharing = 3

    ch = Shared(vehicle(), faults=Faults(latency_s=0.1))
    sent = []
    send = ch.send
    ch.send = lambda msg: (sent.append((ch.clock(), msg.get_type())), send(msg))[1]
    ok, why = upload_and_verify(ch, ITEMS, timing=Timing())
    assert ok, why
    first = next(t for t, kind in sent if kind == "MISSION_ITEM_INT")
    burst = [kind for t, kind in sent if t == first and kind == "MISSION_ITEM_INT"]
    assert len(burst) == 1 + SEND_AHEAD_ON_LINK // 3 == 2
