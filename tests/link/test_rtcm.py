"""GPS_RTCM_DATA fragmentation and AP_GPS's reassembly rules; a TCP RTCM3 stream forwarded."""

from __future__ import annotations

import socket
import threading

import pytest

from ftlbo_mav.errors import BadInput
from ftlbo_mav.link.rtcm import (
    DATA_LEN,
    Reassembler,
    RtcmForwarder,
    Sequencer,
    TooLong,
    fragment,
    parse_source,
    tcp_frames,
)


def crc24q(data: bytes) -> int:
    crc = 0
    for b in data:
        crc ^= b << 16
        for _ in range(8):
            crc <<= 1
            if crc & 0x1000000:
                crc ^= 0x1864CFB
    return crc & 0xFFFFFF


def rtcm_frame(msg_type: int, size: int) -> bytes:
    """A valid RTCM3 frame: preamble, 10-bit length, payload starting with the 12-bit
    message type, CRC-24Q."""
    payload = bytes([msg_type >> 4, (msg_type & 0xF) << 4]) + bytes(
        (i * 7) & 0xFF for i in range(size - 2))
    head = bytes([0xD3, (size >> 8) & 0x03, size & 0xFF]) + payload
    return head + crc24q(head).to_bytes(3, "big")


@pytest.mark.parametrize("n, lengths", [
    (0, [0]), (1, [1]), (180, [180]), (181, [180, 1]), (360, [180, 180, 0]),
    (540, [180, 180, 180, 0]), (720, [180, 180, 180, 180]), (719, [180, 180, 180, 179])])
def test_fragment_lengths(n, lengths):
    parts = fragment(bytes(range(256)) * 3 and bytes(i & 0xFF for i in range(n)), 5)
    assert [p[1] for p in parts] == lengths
    if len(lengths) == 1:
        assert parts[0][0] == 0
    else:
        assert [(f & 1, (f >> 1) & 3, f >> 3) for f, _, _ in parts] == [
            (1, i, 5) for i in range(len(lengths))]
    assert b"".join(p[2] for p in parts) == bytes(i & 0xFF for i in range(n))


def test_longer_than_720_cannot_be_sent():
    with pytest.raises(TooLong):
        fragment(bytes(721), 0)


def test_sequence_wraps_at_32():
    seq = Sequencer()
    ids = [seq.messages(bytes(200))[0][0] >> 3 for _ in range(33)]
    assert ids == list(range(32)) + [0]
    assert seq.messages(bytes(10))[0][0] == 0 and seq.next == 1  # short: no sequence used


@pytest.mark.parametrize("n", [0, 1, 180, 181, 360, 500, 540, 719, 720])
def test_round_trip(n):
    frame = bytes((i * 13) & 0xFF for i in range(n))
    r, out = Reassembler(), []
    for flags, _length, data in fragment(frame, 3):
        out.append(r.add(flags, data))
    assert out[-1] == frame and all(o is None for o in out[:-1])


def test_lost_fragment_is_discarded_by_the_next_sequence():
    r = Reassembler()
    first = fragment(bytes(400), 1)
    second = fragment(bytes(range(200)), 2)
    assert r.add(first[0][0], first[0][2]) is None  # fragment 1 of the first is lost
    assert r.add(second[0][0], second[0][2]) is None
    assert r.discarded == 1
    assert r.add(second[1][0], second[1][2]) == bytes(range(200))


def test_out_of_order_fragments_of_one_sequence_complete():
    frame = bytes((i * 3) & 0xFF for i in range(400))
    parts = fragment(frame, 7)
    r = Reassembler()
    assert r.add(parts[2][0], parts[2][2]) is None
    assert r.add(parts[0][0], parts[0][2]) is None
    assert r.add(parts[1][0], parts[1][2]) == frame


def test_repeated_fragment_id_restarts():
    parts = fragment(bytes(400), 4)
    r = Reassembler()
    r.add(parts[0][0], parts[0][2])
    r.add(parts[0][0], parts[0][2])
    assert r.discarded == 1


@pytest.mark.parametrize("text", ["", "udp://x:1", "tcp://host", "tcp://h:99999",
                                  "ntrip://u:p@h:2101"])
def test_bad_source(text):
    with pytest.raises(BadInput):
        parse_source(text)


def test_sources():
    assert parse_source("/dev/ttyUSB0").kind == "serial"
    assert parse_source("tcp://127.0.0.1:2101").port == 2101
    s = parse_source("ntrip://me:secret@caster:2101/BASE1")
    assert (s.user, s.password, s.mountpoint) == ("me", "secret", "BASE1")


class FakeLink:
    def __init__(self):
        self.r, self.frames = Reassembler(), []

    def send(self, msg):
        out = self.r.add(msg.flags, bytes(msg.data[:msg.len]))
        if out is not None:
            self.frames.append(out)


def test_tcp_stream_forwarded_to_every_link():
    epoch = [rtcm_frame(1005, 19), rtcm_frame(1077, 430), rtcm_frame(1087, 360),
             rtcm_frame(1230, 8)]
    stream = b"".join(epoch * 3)
    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]

    def serve():
        conn, _ = server.accept()
        with conn:
            conn.sendall(b"\x00garbage" + stream)

    threading.Thread(target=serve, daemon=True).start()
    links = [FakeLink(), FakeLink()]
    fwd = RtcmForwarder(tcp_frames(parse_source(f"tcp://127.0.0.1:{port}")), links)
    with fwd:
        fwd._thread.join(timeout=5)
    server.close()
    assert fwd.frames == 12 and fwd.dropped == 0 and fwd.bytes == len(stream)
    for link in links:
        assert link.frames == epoch * 3
    assert DATA_LEN == 180


def test_cli_bad_rtcm_source_exits_2():
    from click.testing import CliRunner

    from ftlbo_mav.cli import main

    result = CliRunner().invoke(main, ["monitor", "--sysid", "1", "--rtcm", "udp://x:1"])
    assert result.exit_code == 2 and "--rtcm udp://x:1" in result.output
