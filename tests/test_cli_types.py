"""Issue 12: option values are checked where they enter (ftlbo_mav/cli_types.py): ports
outside 0-65535 in every connection string and port option, system id lists (range-checked
before a range is expanded), numbers that are not finite. One line, exit 2, at once."""

from __future__ import annotations

import time

import pytest
from click.testing import CliRunner

from ftlbo_mav.cli import main

from .conftest import ROOT

PLANNED = str(ROOT / "missions" / "nha-trang-orchard")
# every command that opens links, with what it needs besides the option under test
LINKED = {
    "upload": ["upload", PLANNED, "--sysid", "1..3"],
    "download": ["download", "--sysid", "1", "-o", "/nonexistent/x.waypoints"],
    "fly": ["fly", PLANNED, "--sysid", "1..3"],
    "monitor": ["monitor", "--sysid", "1"],
    "abort": ["abort", "--sysid", "1", "--control-port", "0"],
}
BAD_URLS = ["tcp:127.0.0.1:70000", "tcp:127.0.0.1:-1", "udpin:0.0.0.0:99999",
            "udpout:127.0.0.1:65536", "udpout:127.0.0.1:0", "tcp:127.0.0.1:abc", "tcp::5760"]
BAD_SYSIDS = ["1..99999999999", "0..3", "1..255", "3..1", "1,1", "a", "", "1..3..5", "-1",
              "99999999999999999999999"]


def one_line_exit_2(argv: list[str]) -> str:
    started = time.monotonic()
    result = CliRunner().invoke(main, argv)
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error:"), lines
    assert time.monotonic() - started < 5  # refused at once: nothing expanded, nothing opened
    return lines[0]


@pytest.mark.parametrize("url", BAD_URLS)
@pytest.mark.parametrize("command", list(LINKED))
def test_a_port_outside_0_65535_in_connect_is_bad_input(command, url):
    line = one_line_exit_2(LINKED[command] + ["--connect", url])
    assert "--connect" in line


@pytest.mark.parametrize("url", BAD_URLS[:4])
@pytest.mark.parametrize("command", ["fly", "monitor"])
def test_a_port_outside_0_65535_in_forward_is_bad_input(command, url):
    line = one_line_exit_2(LINKED[command] + ["--forward", url])
    assert "--forward" in line


@pytest.mark.parametrize("sysids", BAD_SYSIDS)
@pytest.mark.parametrize("command", ["upload", "fly", "monitor", "abort"])
def test_system_id_lists_are_checked_before_they_are_expanded(command, sysids):
    argv = [a if a != "1..3" and a != "1" else sysids for a in LINKED[command]]
    line = one_line_exit_2(argv)
    assert "--sysid" in line


@pytest.mark.parametrize("option, value", [
    ("--base-port", "70000"), ("--base-port", "-1"), ("--udp-out", "127.0.0.1:70000"),
    ("--udp-out", "127.0.0.1:0"), ("--udp-out", "127.0.0.1:"), ("--udp-out", "nohost"),
    ("--time-scale", "1e9"), ("--time-scale", "nan"), ("--time-scale", "inf"),
    ("--latency-ms", "inf"), ("--speed", "nan"), ("--loss", "nan"), ("--capacity", "1e11"),
    ("--silent", "70000"), ("--count", "1000000000"), ("--seed", "-1"),
])
def test_sim_options_are_bad_input(option, value):
    line = one_line_exit_2(["sim", "--base-port", "0", option, value])
    assert option in line


@pytest.mark.parametrize("address", ["nowhere.invalid:14550", "a..b:14550"])
def test_sim_refuses_a_udp_out_host_that_does_not_resolve(address):
    # .invalid never resolves (RFC 6761): no lookup of anything real is needed
    line = one_line_exit_2(["sim", "--base-port", "0", "--count", "1", "--udp-out", address])
    assert "--udp-out" in line and address in line and "does not resolve" in line


def test_sim_refuses_a_silent_vehicle_it_does_not_run():
    assert "1..3" in one_line_exit_2(["sim", "--base-port", "0", "--silent", "7"])


@pytest.mark.parametrize("argv", [
    LINKED["upload"] + ["--timeout", "nan"], LINKED["upload"] + ["--timeout", "1e300"],
    LINKED["upload"] + ["--discover-timeout", "inf"], LINKED["monitor"] + ["--duration", "nan"],
    LINKED["fly"] + ["--flight-timeout", "inf"], LINKED["abort"] + ["--control-port", "70000"],
    LINKED["monitor"] + ["--rate", "nan"],
], ids=lambda a: " ".join(a[-2:]))
def test_seconds_and_rates_are_finite(argv):
    one_line_exit_2(argv)
