"""The shared radio's model (sim/radio.py): air time for both directions, a buffer per
side that drops when full, latency and jitter in order, losses in bursts, outages."""

from __future__ import annotations

import numpy as np
import pytest

from ftlbo_mav.sim.radio import DOWN, UP, RadioOptions, SharedRadio, split_frames

CLEAN = RadioOptions(bytes_per_s=1000.0, latency_s=0.05, jitter_s=0.0, loss=0.0,
                     buffer_bytes=2048)


def radio(options=CLEAN, seed=0):
    return SharedRadio(options, np.random.default_rng(seed))


def test_a_frame_takes_its_air_time_then_the_latency():
    r = radio()
    assert r.send(DOWN, 100, 1.0) == pytest.approx(1.0 + 0.1 + 0.05)


def test_both_directions_share_one_air_time():
    r = radio()
    first = r.send(DOWN, 500, 0.0)  # on the air 0 .. 0.5 s
    second = r.send(UP, 100, 0.1)  # waits for the air: 0.5 .. 0.6 s
    assert first == pytest.approx(0.55) and second == pytest.approx(0.65)
    assert r.counts.air_s == pytest.approx(0.6)


def test_a_full_buffer_drops_what_does_not_fit():
    r = radio()
    arrivals = [r.send(DOWN, 200, 0.0) for _ in range(15)]  # 3000 bytes at once
    # the first goes on the air at once (out of the buffer), ten more wait (2000 bytes)
    assert sum(a is not None for a in arrivals) == 11
    assert r.counts.full[DOWN] == 4
    assert r.txbuf_pct(DOWN, 0.0) == 2  # 2000 of 2048 bytes waiting
    assert r.buffered(DOWN, 10.0) == 0 and r.txbuf_pct(DOWN, 10.0) == 100
    # the ground's buffer is its own
    assert r.send(UP, 200, 0.0) is not None


def test_jitter_never_reorders_one_direction():
    r = radio(RadioOptions(bytes_per_s=1e6, latency_s=0.06, jitter_s=0.04, loss=0.0))
    arrivals = [r.send(DOWN, 30, t) for t in np.arange(0, 1, 0.001)]
    assert np.all(np.diff(arrivals) >= 0)
    delays = np.array(arrivals) - np.arange(0, 1, 0.001)
    assert 0.02 <= delays.min() and delays.max() <= 0.1 + 1e-3


def test_losses_come_at_the_rate_in_bursts():
    options = RadioOptions(bytes_per_s=1e6, jitter_s=0.0, loss=0.1, burst=4.0)
    r = radio(options, seed=3)
    lost = np.array([r.send(DOWN, 30, t) is None for t in np.arange(0, 200, 0.01)])
    assert lost.mean() == pytest.approx(0.1, abs=0.015)
    starts = np.flatnonzero(np.diff(lost.astype(int)) == 1)
    assert lost.sum() / len(starts) == pytest.approx(4.0, rel=0.2)  # mean burst length


def test_nothing_gets_through_an_outage():
    options = RadioOptions(bytes_per_s=1e6, jitter_s=0.0, loss=0.0, outage_s=1.0,
                           outage_every_s=15.0)
    r = radio(options)
    assert r.send(DOWN, 30, 14.2) is None and r.send(UP, 30, 14.9) is None
    assert r.send(DOWN, 30, 15.1) is not None and r.send(DOWN, 30, 13.9) is not None


def test_figures_a_radio_cannot_have_are_refused():
    for bad in (dict(bytes_per_s=0), dict(loss=1.0), dict(burst=0.5), dict(buffer_bytes=100),
                dict(latency_s=0.01, jitter_s=0.02), dict(outage_s=2.0, outage_every_s=1.0)):
        with pytest.raises(ValueError):
            RadioOptions(**bad)


def _frames() -> list[bytes]:
    from pymavlink.dialects.v10 import ardupilotmega as v1
    from pymavlink.dialects.v20 import ardupilotmega as v2

    one = v1.MAVLink(None, srcSystem=1)
    two = v2.MAVLink(None, srcSystem=2)
    signed = v2.MAVLink(None, srcSystem=3)
    signed.signing.secret_key = bytes(32)
    signed.signing.sign_outgoing = True
    signed.signing.link_id = 0
    hb = (6, 8, 0, 0, 0)
    return [bytes(v1.MAVLink_heartbeat_message(*hb, 3).pack(one)),
            bytes(v2.MAVLink_heartbeat_message(*hb, 3).pack(two)),
            bytes(v2.MAVLink_statustext_message(6, b"Fence Breached").pack(two)),
            bytes(v2.MAVLink_heartbeat_message(*hb, 3).pack(signed))]


def test_a_byte_stream_is_cut_into_whole_frames_of_either_version_signed_or_not():
    frames = _frames()
    assert [len(f) for f in frames][::3] == [17, 34]  # v1 heartbeat; v2, signed (+13)
    stream = b"\x00garbage" + b"".join(frames)
    buffer = bytearray()
    got = []
    for k in range(0, len(stream), 7):  # as a TCP stream arrives: in pieces
        buffer += stream[k:k + 7]
        got += split_frames(buffer)
    assert got == frames and not buffer


def test_a_partial_frame_waits_for_its_rest():
    frame = _frames()[2]
    buffer = bytearray(frame[:-3])
    assert split_frames(buffer) == [] and bytes(buffer) == frame[:-3]
    buffer += frame[-3:]
    assert split_frames(buffer) == [frame]
