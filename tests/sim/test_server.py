"""The emulator on the network: TCP like SITL (one client at a time), a shared UDP link."""

from __future__ import annotations

import socket
import time

from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav.sim.faults import Faults
from ftlbo_mav.sim.homes import default_homes
from ftlbo_mav.sim.server import Simulator
from ftlbo_mav.sim.vehicle import VehicleOptions

FAST = VehicleOptions(heartbeat_s=0.05)


def heartbeats(sock: socket.socket, want: int, timeout_s: float = 10.0) -> list[int]:
    """System ids of the first ``want`` HEARTBEATs read from ``sock``."""
    parser = R.MAVLink(None)
    parser.robust_parsing = True
    sock.settimeout(timeout_s)
    seen: list[int] = []
    deadline = time.monotonic() + timeout_s
    while len(seen) < want and time.monotonic() < deadline:
        data = sock.recv(4096) if sock.type == socket.SOCK_STREAM else sock.recvfrom(4096)[0]
        for m in parser.parse_buffer(data) or []:
            if m.get_type() == "HEARTBEAT":
                seen.append(m.get_srcSystem())
    return seen


def test_each_vehicle_on_its_own_tcp_port_and_a_new_client_after_the_last_leaves():
    with Simulator(homes=default_homes(2), base_port=0, options=FAST) as sim:
        assert len(set(sim.ports)) == 2 and sim.urls[0].startswith("tcp:127.0.0.1:")
        for sysid, port in ((1, sim.ports[0]), (2, sim.ports[1])):
            with socket.create_connection(("127.0.0.1", port)) as first:
                assert set(heartbeats(first, 2)) == {sysid}
                second = socket.create_connection(("127.0.0.1", port))
            # the first client left: the waiting one is served
            with second:
                assert set(heartbeats(second, 2)) == {sysid}


def test_shared_udp_link_carries_every_vehicle():
    rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    rx.bind(("127.0.0.1", 0))
    port = rx.getsockname()[1]
    with rx, Simulator(homes=default_homes(3), base_port=0, udp_out=("127.0.0.1", port),
                       options=FAST) as sim:
        assert sim.udp_url == f"udpin:127.0.0.1:{port}"
        assert set(heartbeats(rx, 30)) == {1, 2, 3}


def test_a_silent_vehicle_says_nothing_while_the_others_talk():
    rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    rx.bind(("127.0.0.1", 0))
    port = rx.getsockname()[1]
    faults = [Faults(), Faults(silent=True), Faults()]
    with rx, Simulator(homes=default_homes(3), base_port=0, udp_out=("127.0.0.1", port),
                       options=FAST, faults=faults):
        assert set(heartbeats(rx, 40)) == {1, 3}


def test_ports_follow_sitl_layout_from_a_base_port():
    probe = socket.socket()
    probe.bind(("127.0.0.1", 0))
    base = probe.getsockname()[1]
    probe.close()
    with Simulator(homes=default_homes(2), base_port=base, options=FAST) as sim:
        assert sim.ports == [base, base + 10]
