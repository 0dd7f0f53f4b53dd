"""``--rtcm ntrip://``: pygnssutils' client against a fake caster, forwarded to links."""

from __future__ import annotations

import io
import itertools
import socket
import time

import pytest
from pyrtcm import RTCMReader

from ftlbo_mav.link.rtcm import RtcmError, RtcmForwarder, ntrip_frames, parse_source
from tests.link.ntrip_caster import FakeCaster
from tests.link.rtcm_base import base_station
from tests.link.test_rtcm import FakeLink, rtcm_frame


def frames_of(data: bytes) -> list[bytes]:
    return [raw for raw, _ in itertools.takewhile(
        lambda item: item[0] is not None, RTCMReader(io.BytesIO(data), quitonerror=2))]


def url(caster, user="me", password="secret", mount="BASE1"):
    return parse_source(f"ntrip://{user}:{password}@127.0.0.1:{caster.port}/{mount}")


def test_generated_base_station_decodes_at_a_base_stations_rate():
    seconds = list(base_station(10))
    frames = frames_of(b"".join(seconds))
    assert len(frames) == 4 * 10 + 2  # MSM7 of four constellations, 1005 + 1230 once
    assert 800 < sum(map(len, seconds)) / 10 < 1200  # bytes/s, a usual MSM7 base


@pytest.mark.parametrize("version", ["2.0", "1.0"])
def test_stream_from_a_caster_reaches_every_link(version):
    seconds = list(base_station(6))
    # The first read after the head is not forwarded by pygnssutils: lead with a second
    # that may be lost, as a caster's stream always has one before the one that matters.
    with FakeCaster(lambda: seconds, interval_s=0.05, version=version) as caster:
        links = [FakeLink(), FakeLink()]
        fwd = RtcmForwarder(ntrip_frames(url(caster), timeout_s=3), links)
        with fwd:
            fwd._thread.join(timeout=10)
    assert fwd.error is None
    request = caster.requests[0]
    assert request.startswith("GET /BASE1 HTTP/1.1") and "Authorization: Basic " in request
    expected = frames_of(b"".join(seconds[1:]))
    assert links[0].frames[-len(expected):] == expected
    assert links[1].frames == links[0].frames
    assert fwd.frames == len(links[0].frames) and fwd.dropped == 0
    assert fwd.bytes == sum(map(len, links[0].frames))


def test_wrong_password_is_the_casters_401():
    with FakeCaster(lambda: [], interval_s=0.05) as caster:
        with pytest.raises(RtcmError, match="401"):
            list(ntrip_frames(url(caster, password="wrong"), timeout_s=3))


def test_unknown_mountpoint_says_so():
    with FakeCaster(lambda: [], interval_s=0.05) as caster:
        with pytest.raises(RtcmError, match="no such mountpoint"):
            list(ntrip_frames(url(caster, mount="NOPE"), timeout_s=3))


def test_no_caster_cannot_connect():
    with socket.create_server(("127.0.0.1", 0)) as unused:
        port = unused.getsockname()[1]
    with pytest.raises(RtcmError, match="cannot connect"):
        list(ntrip_frames(parse_source(f"ntrip://a:b@127.0.0.1:{port}/BASE1"), timeout_s=3))


def test_silent_caster_times_out_and_the_forwarder_says_why():
    def silent():
        time.sleep(5)
        return []

    with FakeCaster(silent) as caster:
        fwd = RtcmForwarder(ntrip_frames(url(caster), timeout_s=1), [FakeLink()])
        with fwd:
            fwd._thread.join(timeout=6)
    assert fwd.frames == 0 and "nothing received for 1 s" in fwd.error


def test_a_message_pyrtcm_cannot_decode_is_dropped_by_the_client():
    junk = rtcm_frame(1077, 430)  # framed and CRC-valid, not a decodable MSM7
    good = next(iter(base_station(1)))
    with FakeCaster(lambda: [good, junk + good, good], interval_s=0.05) as caster:
        frames = list(ntrip_frames(url(caster), timeout_s=3))
    assert junk not in frames and frames == frames_of(good + good)


def test_a_serial_port_stream_is_cut_into_frames():
    """``--rtcm /dev/ttyUSB0``: a base station's radio on a serial port (a pty here)."""
    import os
    import threading

    from ftlbo_mav.link.rtcm import serial_frames

    master, slave = os.openpty()
    seconds = list(base_station(3))
    got: list[bytes] = []
    reader = threading.Thread(target=lambda: got.extend(
        itertools.islice(serial_frames(parse_source(os.ttyname(slave))), 4 * 3 + 2)),
        daemon=True)
    reader.start()
    time.sleep(0.2)
    for data in seconds:
        os.write(master, data)
    reader.join(timeout=10)
    os.close(master)
    os.close(slave)
    assert got == frames_of(b"".join(seconds))


def test_a_serial_port_that_cannot_be_opened_says_so(tmp_path):
    from ftlbo_mav.link.rtcm import serial_frames

    with pytest.raises(RtcmError, match="cannot open"):
        next(serial_frames(parse_source(str(tmp_path / "ttyNONE"))))
