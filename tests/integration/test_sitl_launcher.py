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
    from sitl import record, recording

    binary = tmp_path / "arducopter"
    binary.write_text(f"#!/bin/sh\ncd {ROOT}\nexec {sys.executable} {FAKE} \"$@\"\n")
    binary.chmod(0o755)
    assert record.main(["--out", str(tmp_path / "rec"), "--binary", str(binary)]) == 0
    doc = json.loads((tmp_path / "rec" / "mission_items.json").read_text())
    items = doc["main_upload"]["items"]
    assert len(items) == len(record.reference_items()) and "sitl/record.py" in doc["about"]
    for it in items[1:]:
        sent, back = recording.wire_from_json(it["sent"]), recording.wire_from_json(it["read_back"])
        assert storage.stored(sent).params == back.params or any(
            math.isnan(a) for a in back.params)


@pytest.mark.parametrize("args", [["--count", "0"], ["--count", "x"], ["--count", "300"],
                                  ["--speedup", "nan"], ["--speedup", "-1"],
                                  ["--binary", "/nonexistent/arducopter"],
                                  ["--scenario", "/nonexistent.toml", "--binary", sys.executable]])
def test_bad_input_exits_2_in_one_line_before_anything_starts(args):
    """Issue 12: `python -m sitl` exits 2 for bad input (1 is for a SITL that failed)."""
    import subprocess

    proc = subprocess.run([sys.executable, "-m", "sitl", *args], cwd=ROOT, capture_output=True,
                          text=True, timeout=60, env={"PATH": "/usr/bin:/bin"})
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr and "ready" not in proc.stdout
    assert len(proc.stderr.strip().splitlines()[-1:]) == 1


def test_a_sitl_that_has_died_is_named_never_ready(tmp_path):
    """Issue 12: the launcher does not call a swarm ready when a process has exited."""
    import subprocess

    from ftlbo_mav.link.endpoints import LinkError

    swarm = SitlSwarm(binary=sys.executable, homes=default_homes(2), workdir=tmp_path)
    swarm.processes = [subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"]),
                       subprocess.Popen([sys.executable, "-c", "raise SystemExit(3)"])]
    swarm.processes[1].wait()
    procs = list(swarm.processes)
    try:
        with pytest.raises(LinkError, match=r"instance 1 \(sysid 2\) exited with code 3"):
            swarm.check_running()
    finally:
        swarm.__exit__(None, None, None)
    assert all(p.poll() is not None for p in procs)  # every process stopped by __exit__


def test_a_scenario_that_does_not_parse_or_a_missing_defaults_file_exits_2(tmp_path):
    """Issue 21: named in one line, nothing started."""
    import subprocess

    broken = tmp_path / "broken.toml"
    broken.write_text("x = [\n")
    for args in (["--scenario", str(broken), "--binary", sys.executable],
                 ["--defaults", str(tmp_path / "missing.parm"), "--binary", sys.executable]):
        proc = subprocess.run([sys.executable, "-m", "sitl", *args], cwd=ROOT,
                              capture_output=True, text=True, timeout=60,
                              env={"PATH": "/usr/bin:/bin"})
        assert proc.returncode == 2, proc.stderr
        (line,) = proc.stderr.strip().splitlines()
        assert line.startswith("error: ") and ("malformed TOML" in line
                                               or "no such defaults file" in line)


def test_a_binary_that_exits_at_once_is_named_at_once(tmp_path):
    """Issue 21: not after the connect timeout (it waited 30 s, then said "cannot
    connect")."""
    import time

    from ftlbo_mav.link.endpoints import LinkError

    binary = tmp_path / "arducopter"
    binary.write_text("#!/bin/sh\nexit 3\n")
    binary.chmod(0o755)
    t0 = time.monotonic()
    with pytest.raises(LinkError, match=r"instance 0 \(sysid 1\) exited with code 3"):
        with SitlSwarm(binary=binary, homes=default_homes(1), workdir=tmp_path / "run"):
            pass
    assert time.monotonic() - t0 < 10.0


@pytest.mark.parametrize("inside", ["", "run/here"])
def test_a_workdir_that_is_a_file_exits_2_before_anything_starts(tmp_path, inside):
    import subprocess

    marker = tmp_path / "started"
    binary = tmp_path / "arducopter"
    binary.write_text(f"#!/bin/sh\ntouch {marker}\nsleep 30\n")
    binary.chmod(0o755)
    afile = tmp_path / "notes.txt"
    afile.write_text("not a folder\n")
    workdir = afile / inside if inside else afile
    proc = subprocess.run([sys.executable, "-m", "sitl", "--count", "1", "--binary", str(binary),
                           "--workdir", str(workdir)], cwd=ROOT, capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 2, proc.stderr
    (line,) = proc.stderr.strip().splitlines()
    assert line.startswith(f"error: {afile}: is a file, not a directory"), line
    assert not marker.exists()  # no SITL was started
    assert afile.read_text() == "not a folder\n"
