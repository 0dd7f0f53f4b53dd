"""A second, independent vehicle side: MAVSDK's MissionRawServer (native API, no server).

Our emulator is ours and can share our misreadings of the protocol; MAVSDK asks with
MISSION_REQUEST_INT, keeps item 0 as sent and answers only messages for its own id.
Three MAVSDK vehicles (ids 1..3) take an upload from `ftlbo-mav upload`; what they
received must equal the mission files, and the read-back must verify.
"""

from __future__ import annotations

import threading
from contextlib import ExitStack, contextmanager

import numpy as np
import pytest
from click.testing import CliRunner

from ftlbo_mav.cli import main
from ftlbo_mav.link.codec import encode_item, mission_differences
from ftlbo_mav.mission.waypoints import read_waypoints
from tests.integration.fleet import free_udp_port
from tests.link.support import write_missions

mavsdk = pytest.importorskip("mavsdk")
from mavsdk import Configuration, Mavsdk
from mavsdk.plugins.mission_raw_server import MissionRawServer


class MavsdkVehicle:
    """One MAVSDK autopilot listening on ``udpin://127.0.0.1:port`` with a mission server."""

    def __init__(self, sysid: int):
        self.sysid = sysid
        self.port = free_udp_port()
        self.received: list = []
        self.got = threading.Event()
        self.sdk = Mavsdk(Configuration.create_manual(sysid, 1, True))
        self.sdk.add_any_connection(f"udpin://127.0.0.1:{self.port}")
        self.server = MissionRawServer(self.sdk.server_component())
        self.server.subscribe_incoming_mission(self._incoming)

    def _incoming(self, result, plan, _user_data) -> None:
        self.received.append((result, list(plan.mission_items)))
        self.got.set()

    @property
    def url(self) -> str:
        return f"udpout:127.0.0.1:{self.port}"

    def close(self) -> None:
        self.server.destroy()
        self.sdk.destroy()


@contextmanager
def mavsdk_vehicles(count: int):
    with ExitStack() as stack:
        fleet = []
        for sysid in range(1, count + 1):
            v = MavsdkVehicle(sysid)
            stack.callback(v.close)
            fleet.append(v)
        yield fleet


def fields(msg_or_item):
    """Every MISSION_ITEM_INT field, floats as the float32 they travel as."""
    names = ("seq", "frame", "command", "current", "autocontinue", "x", "y", "z",
             "param1", "param2", "param3", "param4", "mission_type")
    values = (getattr(msg_or_item, n) for n in names)
    return tuple(float(np.float32(v)) if isinstance(v, float) else v for v in values)


def test_three_mavsdk_vehicles_receive_exactly_the_mission_files(tmp_path):
    missions = write_missions(tmp_path, 3)
    with mavsdk_vehicles(3) as fleet:
        # MAVSDK's vehicles are generic, not ArduCopter: uploaded with --any-firmware
        args = ["upload", str(tmp_path), "--sysid", "1..3", "--any-firmware"]
        for v in fleet:
            args += ["--connect", v.url]
        result = CliRunner().invoke(main, args, catch_exceptions=False)
        assert result.exit_code == 0, result.output
        assert result.output.count("verified (16 items)") == 3
        for v, items in zip(fleet, missions):
            assert v.got.wait(5.0)
            (outcome, got), = v.received
            assert outcome.name == "SUCCESS"
            sent = [encode_item(it, target_system=v.sysid, target_component=1) for it in items]
            # MAVSDK stores item 0 as sent, and every field as MISSION_ITEM_INT carried it
            assert [fields(g) for g in got] == [fields(s) for s in sent]
        # and a hand check of one vehicle reads back every item, item 0 included (the
        # mission only: MAVSDK has no ArduPilot fence parameters to read)
        back = tmp_path / "uav2.back.waypoints"
        result = CliRunner().invoke(main, ["download", "--sysid", "2", "--connect", fleet[1].url,
                                           "--no-fence", "-o", str(back)],
                                    catch_exceptions=False)
        assert result.exit_code == 0, result.output
        assert read_waypoints(back)[0].lat_deg == pytest.approx(missions[1][0].lat_deg, abs=1e-7)
        assert mission_differences(missions[1], read_waypoints(back)) == []
