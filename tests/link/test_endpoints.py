"""System id lists, connection defaults, mission folders, signing keys."""

from __future__ import annotations

import hashlib

import pytest

from ftlbo_mav.ardupilot.firmware import AUTOPILOT_VERSION_ID
from ftlbo_mav.errors import BadInput
from ftlbo_mav.link.addresses import default_urls, default_urls_for, parse_sysids
from ftlbo_mav.link.commands import mission_files
from ftlbo_mav.link.signing import SigningKeyError, key_from_text, load_key


@pytest.mark.parametrize("text, ids", [
    ("1..3", [1, 2, 3]), ("1,2,5", [1, 2, 5]), ("4", [4]), (" 2 .. 4 ", [2, 3, 4]),
    ("1..2,7", [1, 2, 7]), ("254", [254]),
])
def test_sysid_ranges_and_lists(text, ids):
    assert parse_sysids(text) == ids


@pytest.mark.parametrize("text, problem", [
    ("3..1", "runs backwards"), ("1-3", "expected a range"), ("0..2", "1..254"),
    ("255", "1..254"), ("1,1", "repeated"), ("", "expected a range"),
])
def test_bad_sysids_are_clear_input_errors(text, problem):
    with pytest.raises(BadInput, match=problem) as exc:
        parse_sysids(text)
    assert exc.value.bad_input


def test_default_urls_follow_sitl_ports():
    assert default_urls(3) == ["tcp:127.0.0.1:5760", "tcp:127.0.0.1:5770", "tcp:127.0.0.1:5780"]
    # system id s is SITL's instance s-1
    assert default_urls_for([2, 5]) == ["tcp:127.0.0.1:5770", "tcp:127.0.0.1:5800"]


def test_mission_files_in_uav_order_and_gaps_refused(tmp_path):
    for n in (1, 2, 10):
        (tmp_path / f"uav{n}.waypoints").write_text("QGC WPL 110\n")
    with pytest.raises(BadInput, match="uav3.waypoints is missing"):
        mission_files(tmp_path)
    for n in range(3, 10):
        (tmp_path / f"uav{n}.waypoints").write_text("QGC WPL 110\n")
    assert [p.name for p in mission_files(tmp_path)][-2:] == ["uav9.waypoints", "uav10.waypoints"]
    with pytest.raises(BadInput, match="no uavN.waypoints"):
        mission_files(tmp_path / "..")


def test_signing_key_hex_or_passphrase(tmp_path):
    hexkey = "00" * 31 + "ff"
    assert key_from_text(hexkey + "\n") == bytes.fromhex(hexkey)
    assert key_from_text("orchard swarm\n") == hashlib.sha256(b"orchard swarm").digest()
    (tmp_path / "empty").write_text("  \n")
    with pytest.raises(SigningKeyError, match="empty"):
        load_key(tmp_path / "empty")
    with pytest.raises(SigningKeyError, match="cannot read"):
        load_key(tmp_path / "nope")


class _QuietLink:
    """A link whose vehicles send no HEARTBEAT until asked (as between two of ArduPilot's
    1 Hz ones): ``answers`` the ids that answer a REQUEST_MESSAGE for it."""

    def __init__(self, heard=(), answers=()):
        from ftlbo_mav.link.endpoints import Heartbeat

        self.beat = Heartbeat(sysid=0, compid=1, vehicle_type=2, autopilot=3, custom_mode=0,
                              base_mode=0, system_status=3, received_at=0.0)
        self.heartbeats = {s: self.beat for s in heard}
        self.versions = {}
        self.answers, self.sent = set(answers), []

    def send(self, msg):
        self.sent.append((msg.target_system, msg.command, msg.param1))
        if msg.target_system in self.answers:
            self.heartbeats[msg.target_system] = self.beat


def test_discover_asks_only_the_requested_vehicles_not_heard_yet_for_a_heartbeat():
    from pymavlink.dialects.v20 import ardupilotmega as R

    from ftlbo_mav.link.discovery import discover

    link = _QuietLink(heard=[1], answers=[2, 3])
    found, missing = discover([link], [1, 2], timeout_s=5.0)
    assert found == {1: link, 2: link} and missing == []
    # REQUEST_MESSAGE (GCS_Common.cpp handle_command_request_message) for HEARTBEAT to 2
    # only: 1 was heard, 3 was not asked for; AUTOPILOT_VERSION (the firmware check that
    # follows) to both
    ask = R.MAV_CMD_REQUEST_MESSAGE
    assert link.sent == [(1, ask, AUTOPILOT_VERSION_ID), (2, ask, R.MAVLINK_MSG_ID_HEARTBEAT),
                         (2, ask, AUTOPILOT_VERSION_ID)]


def test_a_version_heard_when_the_vehicles_were_found_is_not_asked_again():
    from ftlbo_mav.link.firmware import request_version

    class Known:
        sysid, link = 2, _QuietLink()

        def send(self, msg):
            raise AssertionError("asked again")

    Known.link.versions[2] = 0x04050600
    assert request_version(Known()) == 0x04050600


def test_discover_asks_a_silent_vehicle_twice_then_waits_for_its_own_heartbeat():
    from ftlbo_mav.link.discovery import discover

    link = _QuietLink()
    found, missing = discover([link], [4], timeout_s=0.6)
    assert found == {} and missing == [4]
    assert [s for s, _c, what in link.sent if what == 0] == [4, 4]  # HEARTBEAT asked twice
