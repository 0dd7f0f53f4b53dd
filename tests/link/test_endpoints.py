"""System id lists, connection defaults, mission folders, signing keys."""

from __future__ import annotations

import hashlib

import pytest

from ftlbo_mav.link.commands import mission_files
from ftlbo_mav.link.endpoints import BadInput, default_urls, default_urls_for, parse_sysids
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
