"""RTCM3 from a TCP source through real links into the emulator, reassembled by AP_GPS's rules."""

from __future__ import annotations

import socket
import threading
import time

from ftlbo_mav.link.endpoints import open_links
from ftlbo_mav.link.rtcm import RtcmForwarder, parse_source, tcp_frames
from ftlbo_mav.sim.homes import default_homes
from ftlbo_mav.sim.server import Simulator
from ftlbo_mav.sim.vehicle import VehicleOptions
from tests.link.test_rtcm import rtcm_frame


def test_every_frame_reaches_every_copter_and_the_rate_is_counted():
    epoch = [rtcm_frame(1005, 19), rtcm_frame(1077, 430), rtcm_frame(1087, 360),
             rtcm_frame(1230, 8)]  # a base station's second: ~830 bytes
    seconds = 3
    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]

    def serve():  # a base station at 1 Hz, sped up 5x
        conn, _ = server.accept()
        with conn:
            for _ in range(seconds):
                conn.sendall(b"".join(epoch))
                time.sleep(0.2)

    threading.Thread(target=serve, daemon=True).start()
    with Simulator(homes=default_homes(2), base_port=0,
                   options=VehicleOptions(heartbeat_s=0.05)) as sim:
        links = open_links(sim.urls, connect_timeout_s=5.0)
        try:
            fwd = RtcmForwarder(tcp_frames(parse_source(f"tcp://127.0.0.1:{port}")), links)
            with fwd:
                fwd._thread.join(timeout=10)
                deadline = time.monotonic() + 5
                while time.monotonic() < deadline and any(
                        len(v.rtcm_frames) < 4 * seconds for v in sim.vehicles):
                    time.sleep(0.05)
            rate = fwd.bytes_per_s()
        finally:
            for link in links:
                link.close()
    server.close()
    total = sum(map(len, epoch)) * seconds
    assert fwd.frames == 4 * seconds and fwd.bytes == total and fwd.dropped == 0
    for v in sim.vehicles:
        assert v.rtcm_frames == epoch * seconds
        assert v.rtcm.discarded == 0
    assert 0 < rate <= total / 0.4  # the stream took at least 0.4 s
