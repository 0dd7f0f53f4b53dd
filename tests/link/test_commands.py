"""The `sim` command as a user runs it, and `upload`/`download` input errors."""

from __future__ import annotations

import re
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from ftlbo_mav.cli import main
from ftlbo_mav.mission.waypoints import read_waypoints
from ftlbo_mav.scenario import load_scenario
from ftlbo_mav.sim.homes import scenario_homes
from tests.link.support import write_missions

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "missions" / "nha-trang-orchard.toml"


def test_sim_puts_homes_at_the_uav_starts_and_takes_uploads(tmp_path):
    cmd = [sys.executable, "-c", "from ftlbo_mav.cli import main; main()", "sim",
           "--scenario", str(EXAMPLE), "--base-port", "0"]
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True)
    try:
        lines = []
        while "emulating" not in (line := proc.stdout.readline()):
            assert line, "".join(lines)  # the process ended before it was ready
            lines.append(line)
        urls = [re.search(r"(tcp:\S+)", x).group(1) for x in lines if x.startswith("vehicle")]
        assert len(urls) == 3
        write_missions(tmp_path, 3)
        args = ["upload", str(tmp_path), "--sysid", "1..3"]
        for u in urls:
            args += ["--connect", u]
        result = CliRunner().invoke(main, args, catch_exceptions=False)
        assert result.exit_code == 0, result.output
        out = tmp_path / "back.waypoints"
        result = CliRunner().invoke(main, ["download", "--sysid", "3", "--connect", urls[2],
                                           "-o", str(out)], catch_exceptions=False)
        assert result.exit_code == 0, result.output
        home = read_waypoints(out)[0]
        lat, lon, _alt = scenario_homes(load_scenario(EXAMPLE))[2]
        assert (round(home.lat_deg * 1e7), round(home.lon_deg * 1e7)) == (
            round(lat * 1e7), round(lon * 1e7))
    finally:
        proc.send_signal(signal.SIGINT)
        assert proc.wait(timeout=10) == 0


@pytest.mark.parametrize("args, problem", [
    (["--sysid", "3..1"], "runs backwards"),
    (["--sysid", "1..3", "--signing-key", "/nonexistent/key"], "cannot read the signing key"),
])
def test_upload_input_errors_exit_2_with_one_line(tmp_path, args, problem):
    write_missions(tmp_path, 3)
    result = CliRunner().invoke(main, ["upload", str(tmp_path), *args,
                                       "--connect", "tcp:127.0.0.1:9"])
    assert result.exit_code == 2
    assert result.output.startswith("error:") and problem in result.output
    assert len(result.output.strip().splitlines()) == 1


@pytest.mark.parametrize("name", ["uav0.waypoints", "uav01.waypoints"])
def test_upload_of_a_folder_with_a_uav0_mission_is_refused_naming_it(tmp_path, name):
    write_missions(tmp_path, 3)
    (tmp_path / name).write_bytes((tmp_path / "uav1.waypoints").read_bytes())
    result = CliRunner().invoke(main, ["upload", str(tmp_path), "--sysid", "1..3",
                                       "--connect", "tcp:127.0.0.1:9"])
    assert result.exit_code == 2, result.output
    assert result.exception is None or isinstance(result.exception, SystemExit)
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error:"), result.output
    assert name in lines[0] and "start at 1" in lines[0]


def test_download_from_nobody_is_a_clear_error(tmp_path):
    result = CliRunner().invoke(main, ["download", "--sysid", "4", "--connect",
                                       "tcp:127.0.0.1:9", "--discover-timeout", "0.3",
                                       "-o", str(tmp_path / "x.waypoints")])
    assert result.exit_code == 1
    assert "cannot connect" in result.output and "tcp:127.0.0.1:9" in result.output
    assert not (tmp_path / "x.waypoints").exists()


class FakeTerminal:
    def __init__(self, tty: bool):
        self.tty, self.text = tty, ""

    def isatty(self) -> bool:
        return self.tty

    def write(self, s: str) -> None:
        self.text += s

    def flush(self) -> None:
        pass


def test_progress_is_one_line_per_vehicle_redrawn_in_place_on_a_terminal():
    from ftlbo_mav.link.commands import ProgressBoard
    from ftlbo_mav.link.swarm import ProgressEvent

    term = FakeTerminal(tty=True)
    board = ProgressBoard([("uav1", 1), ("uav2", 2)], stream=term)
    board(ProgressEvent("uav2", 2, "upload", 5, 15))
    board(ProgressEvent("uav1", 1, "failed", message="x"))
    last = term.text.split("\x1b[2F")[-1]  # cursor up two lines, then both lines again
    assert last == ("\x1b[2Kuav1 -> sysid 1: FAILED\n"
                    "\x1b[2Kuav2 -> sysid 2: upload    [######              ] 5/15\n")
    log = FakeTerminal(tty=False)
    board = ProgressBoard([("uav1", 1)], stream=log)
    for done in range(3):
        board(ProgressEvent("uav1", 1, "upload", done, 15))
    board(ProgressEvent("uav1", 1, "verified"))
    assert log.text.splitlines() == ["uav1 -> sysid 1: upload    [                    ] 0/15",
                                     "uav1 -> sysid 1: verified"]
