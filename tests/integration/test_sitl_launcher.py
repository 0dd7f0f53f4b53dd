"""The SITL launcher's process handling, with a stand-in binary (the emulator) when no
ArduPilot build is configured."""

from __future__ import annotations

import json
import math
import socket
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from ftlbo_mav.cli import main
from ftlbo_mav.sim.homes import default_homes
from sitl import SitlSwarm, sitl_command
from tests.link.support import write_missions

FAKE = Path(__file__).with_name("fake_arducopter.py")
ROOT = Path(__file__).resolve().parents[2]


def ports_free(count: int) -> bool:
    for i in range(count):
        with socket.socket() as s:
            try:
                s.bind(("127.0.0.1", 5760 + 10 * i))
            except OSError:
                return False
    return True


def test_command_line_has_instance_home_and_defaults(tmp_path):
    cmd = sitl_command("/opt/arducopter", instance=2, home=(-35.1, 149.2, 584.0),
                       defaults=[tmp_path / "copter.parm", tmp_path / "id.parm"])
    assert cmd[:1] == ["/opt/arducopter"]
    assert cmd[cmd.index("--instance") + 1] == "2"
    assert "--home=-35.1000000,149.2000000,584.00,0" in cmd  # '=': a negative latitude
    assert cmd[cmd.index("--defaults") + 1] == f"{tmp_path}/copter.parm,{tmp_path}/id.parm"


def test_swarm_starts_waits_until_ready_and_stops_every_process(tmp_path):
    if not ports_free(2):
        pytest.skip("TCP 5760/5770 in use (SITL or `ftlbo-mav sim` running)")
    binary = tmp_path / "arducopter"
    binary.write_text(f"#!/bin/sh\ncd {ROOT}\nexec {sys.executable} {FAKE} \"$@\"\n")
    binary.chmod(0o755)
    write_missions(tmp_path, 2)
    with SitlSwarm(binary=binary, homes=default_homes(2), workdir=tmp_path / "run",
                   ready_timeout_s=30) as swarm:
        assert swarm.urls == ["tcp:127.0.0.1:5760", "tcp:127.0.0.1:5770"]
        assert (tmp_path / "run/instance1/identity.parm").read_text().startswith(
            "SYSID_THISMAV 2")
        procs = list(swarm.processes)
        result = CliRunner().invoke(main, ["upload", str(tmp_path), "--sysid", "1..2"],
                                    catch_exceptions=False)
        assert result.exit_code == 0, result.output
    assert all(p.poll() is not None for p in procs)


def test_the_recorder_writes_a_recording_the_storage_tests_read(tmp_path):
    """`python -m sitl.record` with the stand-in binary: the plumbing, not ArduPilot (the
    stand-in stores items with our own model; on SITL the same run checks ArduPilot)."""
    if not ports_free(1):
        pytest.skip("TCP 5760 in use (SITL or `ftlbo-mav sim` running)")
    from ftlbo_mav.ardupilot import storage
    from sitl import record

    binary = tmp_path / "arducopter"
    binary.write_text(f"#!/bin/sh\ncd {ROOT}\nexec {sys.executable} {FAKE} \"$@\"\n")
    binary.chmod(0o755)
    assert record.main(["--out", str(tmp_path / "rec"), "--binary", str(binary)]) == 0
    doc = json.loads((tmp_path / "rec" / "mission_items.json").read_text())
    items = doc["main_upload"]["items"]
    assert len(items) == len(record.reference_items()) and "sitl/record.py" in doc["about"]
    for it in items[1:]:
        sent, back = record.wire_from_json(it["sent"]), record.wire_from_json(it["read_back"])
        assert storage.stored(sent).params == back.params or any(
            math.isnan(a) for a in back.params)
