"""What a link receives, against ArduCopter 4.5.6 SITL (boot.json)."""

from __future__ import annotations

from collections import Counter

from pymavlink.dialects.v20 import ardupilotmega as R

from .replay import Bench, load

BOOT = load("boot.json")


def test_a_silent_link_gets_only_heartbeat_timesync_and_home_once():
    rec = BOOT["passive_serial0_first_40s"]
    bench = Bench()
    bench.run(rec["window_s"][1])
    got = Counter(h.kind for h in bench.heard if h.t < rec["window_s"][1])
    want = {t["type"]: t["count"] for t in rec["types"]}
    assert set(got) == set(want) and rec["statustext"] == []
    for kind in ("TIMESYNC", "HOME_POSITION", "GPS_GLOBAL_ORIGIN"):
        assert got[kind] == want[kind], kind
    assert abs(got["HEARTBEAT"] - want["HEARTBEAT"]) <= 2
    (home,) = [h for h in bench.heard if h.kind == "HOME_POSITION"]
    assert abs(home.t - rec["first_message_of_each_type"]["HOME_POSITION"]["t"]) < 0.2


def test_set_message_interval_on_a_second_link_brings_the_asked_rates_there_only():
    rec = BOOT["serial1_set_message_interval_5hz"]
    bench = Bench(links=("SERIAL0", "SERIAL1"))
    for a in rec["acks"]:
        ack = bench.command(a["t_send"], R.MAV_CMD_SET_MESSAGE_INTERVAL,
                            [a["msgid"], a["param2_interval_us"]], link="SERIAL1")
        assert R.enums["MAV_RESULT"][ack.result].name == a["result_name"]
    t0, t1 = rec["windows"][1]["window_s"]
    bench.run(t1)
    window = [h for h in bench.heard if t0 <= h.t < t1]
    one = Counter(h.kind for h in window if h.link == "SERIAL1")
    for kind, hz in rec["windows"][1]["rates_hz"].items():
        if kind in ("GPS_RAW_INT", "GLOBAL_POSITION_INT", "SYS_STATUS", "MISSION_CURRENT",
                    "EXTENDED_SYS_STATE", "HEARTBEAT"):
            assert abs(one[kind] / (t1 - t0) - hz) <= 0.2, kind
    zero = Counter(h.kind for h in window if h.link == "SERIAL0")
    assert set(zero) <= {"HEARTBEAT", "TIMESYNC"}


def test_request_data_stream_all_brings_every_emulated_message_at_the_rate():
    rec = BOOT["request_data_stream_all_4hz_serial0"]
    bench = Bench()
    bench.send(rec["t_request"], R.MAVLink_request_data_stream_message(
        1, 1, R.MAV_DATA_STREAM_ALL, 4, 1))
    t0, t1 = rec["windows"][1]["window_s"]
    bench.run(t1)
    got = Counter(h.kind for h in bench.heard if t0 <= h.t < t1)
    for kind in ("GLOBAL_POSITION_INT", "GPS_RAW_INT", "SYS_STATUS", "MISSION_CURRENT",
                 "VFR_HUD"):
        assert abs(got[kind] / (t1 - t0) - rec["windows"][1]["rates_hz"][kind]) <= 0.2, kind
