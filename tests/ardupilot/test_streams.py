"""The ground side's stream requests: ask, re-ask until the message arrives, fall back."""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav.ardupilot.streams import READINESS, StreamRequests, flight_streams

GPS, POS = R.MAVLINK_MSG_ID_GPS_RAW_INT, R.MAVLINK_MSG_ID_GLOBAL_POSITION_INT


def kinds(msgs):
    return [(m.get_type(), getattr(m, "param1", getattr(m, "req_stream_id", None)))
            for m in msgs]


def test_each_message_is_asked_for_at_its_interval():
    req = StreamRequests(sysid=2)
    req.want(flight_streams(10.0))
    out = req.due(0.0)
    assert {m.param1 for m in out} == {1, GPS, POS, R.MAVLINK_MSG_ID_MISSION_CURRENT,
                                       R.MAVLINK_MSG_ID_EKF_STATUS_REPORT,
                                       R.MAVLINK_MSG_ID_SYSTEM_TIME}
    pos = next(m for m in out if m.param1 == POS)
    assert pos.command == R.MAV_CMD_SET_MESSAGE_INTERVAL and pos.param2 == 100_000
    assert pos.target_system == 2 and req.due(0.5) == []


def test_an_acknowledged_request_whose_stream_never_starts_is_asked_again():
    """ArduPilot SITL acknowledges an interval set right after connecting, then drops it."""
    req = StreamRequests(sysid=1)
    req.want(READINESS)
    req.due(0.0)
    req.on_ack(None, R.MAV_RESULT_ACCEPTED)
    assert req.due(1.0) == []
    again = req.due(2.0)
    assert sorted(m.param1 for m in again) == sorted(READINESS)
    for t in (2.1, 2.6, 3.1):
        req.seen(GPS, t)
        req.seen(R.MAVLINK_MSG_ID_SYS_STATUS, t)
    assert req.due(4.0) == [] and req.missing(4.0) == []
    # the stream stops: asked again once it is overdue
    assert req.due(8.0) != []


def test_old_firmware_gets_request_data_stream_for_the_group():
    req = StreamRequests(sysid=1)
    req.want({POS: 10.0})
    req.due(0.0)
    req.on_ack(None, R.MAV_RESULT_UNSUPPORTED)
    out = req.due(2.0)
    assert ("REQUEST_DATA_STREAM", R.MAV_DATA_STREAM_POSITION) in kinds(out)
    assert next(m for m in out if m.get_type() == "REQUEST_DATA_STREAM").req_message_rate == 10


def test_silence_alone_also_falls_back_after_a_few_tries():
    req = StreamRequests(sysid=1, legacy_after=3)
    req.want({GPS: 2.0})
    tries = [kinds(req.due(t)) for t in (0.0, 2.0, 4.0)]
    assert all(("REQUEST_DATA_STREAM", R.MAV_DATA_STREAM_EXTENDED_STATUS) not in k
               for k in tries[:2])
    assert ("REQUEST_DATA_STREAM", R.MAV_DATA_STREAM_EXTENDED_STATUS) in tries[2]
    assert req.missing(4.0) == ["GPS_RAW_INT (asked 3x)"]


def test_a_higher_rate_is_asked_for_at_once():
    req = StreamRequests(sysid=1)
    req.want({POS: 2.0})
    req.due(0.0)
    req.seen(POS, 0.4)
    req.want({POS: 10.0})
    assert [m.param2 for m in req.due(0.5)] == [100_000]


def test_a_stream_arriving_at_a_tenth_of_its_rate_is_asked_for_again():
    """On SITL a copter's GLOBAL_POSITION_INT, asked at 10 Hz, once came at 1 Hz for a
    whole flight: arriving is not enough, it must come at half its rate or more."""
    pos = R.MAVLINK_MSG_ID_GLOBAL_POSITION_INT
    req = StreamRequests(1)
    req.want({pos: 10.0})
    assert len(req.due(0.0)) == 1
    for k in range(4):  # 1 Hz
        req.seen(pos, 0.5 + k)
    assert not req.flowing(pos, 3.6)
    asked = req.due(3.6)
    assert [m.param2 for m in asked if m.get_type() == "COMMAND_LONG"] == [1e5]
    assert req.missing(3.6) == ["GLOBAL_POSITION_INT (asked 2x; 1.0/s of 10/s)"]
    for k in range(30):  # 10 Hz from then on
        req.seen(pos, 3.7 + 0.1 * k)
    assert req.flowing(pos, 6.7) and req.due(6.7) == []


def test_streams_asked_for_are_stopped_and_asked_for_no_more():
    req = StreamRequests(sysid=3)
    req.want(READINESS)
    assert len(req.due(0.0)) == 2
    stops = req.stop([*READINESS, R.MAVLINK_MSG_ID_ATTITUDE])  # ATTITUDE was never asked
    # SET_MESSAGE_INTERVAL -1: GCS_Common.cpp, the message no longer sent on that link
    assert sorted((m.target_system, m.command, int(m.param1), m.param2) for m in stops) == [
        (3, R.MAV_CMD_SET_MESSAGE_INTERVAL, msgid, -1.0) for msgid in sorted(READINESS)]
    assert req.due(100.0) == [] and req.missing(100.0) == []


def test_a_streams_recent_count_reads_only_the_old_end_of_its_arrivals():
    """How many arrived within the window is counted from the oldest arrival on (they
    are in order): the same count as looking at every one."""
    import random

    from ftlbo_mav.ardupilot.streams import RATE_WINDOW_S, _Want

    rng = random.Random(4)
    w = _Want(hz=10.0)
    now = 0.0
    for _ in range(400):
        now += rng.choice([0.1, 0.1, 0.1, 0.5, 2.5])
        w.arrived(now)
        for later in (now, now + 0.05, now + 1.0, now + RATE_WINDOW_S, now + 3.0):
            every = sum(1 for t in w.arrivals if later - t <= RATE_WINDOW_S)
            assert w._recent(later) == every
            assert w.rate(later) == every / RATE_WINDOW_S
