"""The emulator's mission store against ArduCopter 4.5.6 SITL's own answers.

Replays ``mission_protocol.json`` (timings and corner cases, on up to three links) and
the bad uploads of ``mission_items.json`` into the emulator's vehicle at the recorded
times, and compares what it answers, on which link, and what it keeps afterwards.
"""

from __future__ import annotations

import math

import pytest
from pymavlink.dialects.v20 import ardupilotmega as R

from .replay import GCS, Bench, item_from_dict, item_int, load, num, rows_of

PROTOCOL = load("mission_protocol.json")
ITEMS = load("mission_items.json")
BASELINE5 = [[0, 0, 16, 0, 0, 0, 0, 122332099, 1091145051, 0.0],
             [1, 3, 22, 0, 0, 0, 0, 0, 0, 6.0],
             [2, 3, 16, 0, 0, 0, 0, 122332997, 1091145051, 6.0],
             [3, 3, 16, 0, 0, 0, 0, 122333896, 1091145511, 6.0],
             [4, 3, 21, 0, 0, 0, 1, 122333896, 1091145051, 0.0]]
PROTOCOL_KINDS = ("MISSION_REQUEST", "MISSION_ACK", "MISSION_COUNT", "MISSION_ITEM_INT")


def _same_rows(a, b) -> bool:
    if len(a) != len(b):
        return False
    for ra, rb in zip(a, b):
        for x, y in zip(ra, rb):
            x, y = num(x), num(y)
            if not ((isinstance(x, float) and math.isnan(x) and math.isnan(y))
                    or abs(x - y) <= 1e-6 * max(1.0, abs(y))):
                return False
    return True


def _key(kind, fields: dict):
    if kind in ("MISSION_REQUEST", "MISSION_ITEM_INT"):
        return (kind, fields["seq"])
    if kind == "MISSION_ACK":
        return (kind, fields["type"], tuple(fields["target"]))
    if kind == "MISSION_COUNT":
        return (kind, fields["count"])
    return (kind,)


def _heard_key(h):
    m = h.msg
    if h.kind == "MISSION_ACK":
        return (h.kind, m.type, (m.target_system, m.target_component))
    if h.kind == "MISSION_COUNT":
        return (h.kind, m.count)
    return (h.kind, m.seq)


def _dedup(seq: list) -> list:
    """A re-request that crossed the recorder's answer (same link, same message as the
    one before) is timing, not protocol: kept once. The re-request timing itself is
    compared by the unanswered-upload tests."""
    return [x for i, x in enumerate(seq) if i == 0 or x[:2] != seq[i - 1][:2]]


def _compare(bench: Bench, events: list, t0: float, t1: float, tolerance_s: float = 0.06):
    """Every recorded protocol message in [t0, t1] and no other: same order per link,
    same content, times within ``tolerance_s``."""
    want = _dedup([(e["link"], _key(e["msg"], e), e["t"]) for e in events
                   if e["msg"] in PROTOCOL_KINDS and t0 <= e["t"] <= t1])
    got = _dedup([(h.link, _heard_key(h), h.t) for h in bench.heard
                  if h.kind in PROTOCOL_KINDS and t0 - 0.01 <= h.t <= t1 + tolerance_s])
    assert [w[:2] for w in want] == [g[:2] for g in got]
    for (_, _, tw), (_, what, tg) in zip(want, got):
        assert abs(tw - tg) <= tolerance_s, (what, tw, tg)


def _generic_item(seq: int, command: int):
    """An item of the recorded command (the recording names only seq and command)."""
    row = {16: [seq, 3, 16, 0, 0, 0, 0, 122332997 + 100 * seq, 1091145051, 6.0],
           22: [seq, 3, 22, 0, 0, 0, 0, 0, 0, 6.0],
           21: [seq, 3, 21, 0, 0, 0, 0, 122333896, 1091145051, 0.0]}[command]
    if seq == 0:
        row = [0, 0, 16, 0, 0, 0, 0, 122332099, 1091145051, 0.0]
    return item_int(row)


def _replay_sent(bench: Bench, sent: list):
    for s in sent:
        src = (255, 191) if "255/191" in (s.get("note") or "") or s["link"] == "SERIAL2" else GCS
        kind = s["msg"]
        if kind == "MISSION_COUNT":
            msg = R.MAVLink_mission_count_message(1, 1, s["count"], 0)
        elif kind == "MISSION_ITEM_INT":
            msg = _generic_item(s["seq"], s["command"])
        elif kind == "MISSION_REQUEST_LIST":
            msg = R.MAVLink_mission_request_list_message(1, 1, 0)
        elif kind == "MISSION_REQUEST_INT":
            msg = R.MAVLink_mission_request_int_message(1, 1, s["seq"], 0)
        else:
            msg = R.MAVLink_mission_clear_all_message(1, 1, 0)
        bench.send(s["t"], msg, link=s["link"], src=src)


def _bench_with_baseline(t: float, links=("SERIAL0",)) -> Bench:
    bench = Bench(links=links)
    assert bench.upload(t - 1.0, BASELINE5) == R.MAV_MISSION_ACCEPTED
    return bench


@pytest.mark.parametrize("name", ["b_second_count_mid_upload", "f2_read_and_clear_during_upload",
                                  "g1_two_links_same_gcs_ids",
                                  "g2_two_links_different_gcs_component"])
def test_recorded_exchange_is_answered_the_same_on_the_same_links(name):
    case = PROTOCOL[name]
    links = tuple(sorted({s["link"] for s in case["sent"]} | {"SERIAL0"}))
    bench = _bench_with_baseline(case["sent"][0]["t"], links)
    t0 = case["sent"][0]["t"]
    _replay_sent(bench, case["sent"])
    t1 = max(e["t"] for e in case["events"] if e["msg"] in PROTOCOL_KINDS)
    bench.run(t1 + 0.1)
    _compare(bench, case["events"], t0, t1)
    after = case.get("mission_after")
    if after:
        assert [r[:3] for r in rows_of(bench.vehicle)] == [r[:3] for r in after["items"]]


@pytest.mark.parametrize("name,count", [("a_count_15_never_answered", 15),
                                        ("a2_count_3_never_answered_existing_5", 3)])
def test_an_unanswered_count_is_re_asked_every_second_and_cancelled_after_eight(name, count):
    case = PROTOCOL[name]
    t0 = case["t_count_sent"]
    bench = _bench_with_baseline(t0)
    bench.send(t0, R.MAVLink_mission_count_message(1, 1, count, 0))
    bench.run(t0 + 9.0)
    _compare(bench, case["events"], t0, t0 + 9.0)
    asks = [h.t for h in bench.since(t0, ("MISSION_REQUEST",))]
    recorded = [e["t"] for e in case["events"] if e["msg"] == "MISSION_REQUEST"]
    assert len(asks) == len(recorded)
    assert all(abs(a - r) <= 0.06 for a, r in zip(asks, recorded))
    assert _same_rows(rows_of(bench.vehicle), case["mission_after"]["items"])


def test_a_partial_upload_then_silence_leaves_the_items_that_arrived():
    case = PROTOCOL["a3_partial_upload_then_silence"]
    bench = Bench()  # recorded after a2, whose timeout left 3 items
    assert bench.upload(case["answered"][0]["t"] - 1.0, BASELINE5[:3]) == R.MAV_MISSION_ACCEPTED
    t0 = case["answered"][0]["t"] - 0.005
    bench.send(t0, R.MAVLink_mission_count_message(1, 1, 6, 0))
    for a in case["answered"]:
        bench.send(a["t"], item_int(BASELINE5[a["seq"]]))
    bench.run(case["final_ack"]["t"] + 0.5)
    _compare(bench, case["events"], t0, case["final_ack"]["t"] + 0.5)
    assert _same_rows(rows_of(bench.vehicle), case["mission_after"]["items"])


def test_no_space_while_booting_then_accepted():
    case = PROTOCOL["0_upload_during_boot"]
    bench = Bench()
    for attempt in case["attempts"]:
        acks = []
        out = bench.send(attempt["t"], R.MAVLink_mission_count_message(1, 1, 5, 0))
        acks = [m.type for m in out if m.get_type() == "MISSION_ACK"]
        if attempt["result"] == "MAV_MISSION_NO_SPACE":
            assert acks == [R.MAV_MISSION_NO_SPACE]
            assert "Only 0 items are supported" in [m.text for m in out
                                                    if m.get_type() == "STATUSTEXT"]
        else:
            assert acks == [] and out[-1].get_type() == "MISSION_REQUEST"


def test_count_beyond_capacity_names_the_capacity_and_keeps_the_mission():
    bench = _bench_with_baseline(51.0)
    out = bench.send(PROTOCOL["f4_count_too_large"]["t_sent"],
                     R.MAVLink_mission_count_message(1, 1, 65000, 0))
    assert [m.type for m in out if m.get_type() == "MISSION_ACK"] == [R.MAV_MISSION_NO_SPACE]
    assert "Only 650 items are supported" in [m.text for m in out if m.get_type() == "STATUSTEXT"]
    assert len(rows_of(bench.vehicle)) == PROTOCOL["f4_count_too_large"]["mission_after"]["count"]


def test_count_0_clears_reads_beyond_the_end_and_unsolicited_items():
    bench = _bench_with_baseline(36.0)
    out = bench.send(35.9, R.MAVLink_mission_count_message(1, 1, 0, 0))
    assert [m.type for m in out if m.get_type() == "MISSION_ACK"] == [R.MAV_MISSION_ACCEPTED]
    assert "Flight plan received" in [m.text for m in out if m.get_type() == "STATUSTEXT"]
    (home,) = bench.send(37.9, R.MAVLink_mission_request_int_message(1, 1, 0, 0))
    rec = PROTOCOL["c_count_0"]["request_int_seq0_events"][0]
    assert (home.x, home.y, home.frame, home.command) == (rec["x"], rec["y"], rec["frame"],
                                                          rec["command"])
    assert abs(home.z - rec["z"]) < 1e-6
    cnt, ack = bench.send(42.4, R.MAVLink_mission_request_int_message(1, 1, 1, 0))
    assert (cnt.get_type(), cnt.count, ack.type) == ("MISSION_COUNT", 0, R.MAV_MISSION_ERROR)
    bench2 = _bench_with_baseline(45.0)
    for case in PROTOCOL["f_request_beyond_count"]["cases"]:
        request = (R.MAVLink_mission_request_int_message if case["sent"] == "MISSION_REQUEST_INT"
                   else R.MAVLink_mission_request_message)
        out = [m for m in bench2.send(case["t_sent"], request(1, 1, case["seq"], 0))
               if m.get_type() != "STATUSTEXT"]
        want = [e for e in case["events"] if e["msg"] in PROTOCOL_KINDS + ("MISSION_ITEM",)]
        assert [m.get_type() for m in out] == [e["msg"] for e in want]
    out = bench2.send(50.0, item_int(BASELINE5[1]))
    assert [(m.get_type(), m.type) for m in out] == [("MISSION_ACK", R.MAV_MISSION_ERROR)]


def _bad_cases():
    return [c for c in ITEMS["bad_uploads"]["cases"] if c.get("items_sent")]


@pytest.mark.parametrize("case", _bad_cases(), ids=[c["name"] for c in _bad_cases()])
def test_a_bad_item_stops_the_upload_with_the_recorded_ack_and_half_overwritten_mission(case):
    bench = Bench()
    assert bench.upload(20.0, ITEMS["bad_uploads"]["baseline"]) == R.MAV_MISSION_ACCEPTED
    out = bench.send(22.0, R.MAVLink_mission_count_message(1, 1, len(case["items_sent"]), 0))
    acks = []
    for _ in range(len(case["items_sent"])):
        acks += [m.type for m in out if m.get_type() == "MISSION_ACK"]
        reqs = [m for m in out if m.get_type() == "MISSION_REQUEST"]
        if not reqs:
            break
        out = bench.send(bench.now + 0.005, item_from_dict(case["items_sent"][reqs[0].seq]))
    else:
        acks += [m.type for m in out if m.get_type() == "MISSION_ACK"]
    assert [R.enums["MAV_MISSION_RESULT"][a].name for a in acks] == [
        a["type_name"] for a in case["acks"]]
    assert _same_rows(rows_of(bench.vehicle), case["mission_after"]["items"])
