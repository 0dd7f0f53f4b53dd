"""Fly the shipped example with three vehicles: the emulator, or ArduPilot SITL when
ARDUPILOT_SITL is set. One test code path: everything is observed over MAVLink."""

from __future__ import annotations

import json
import shutil
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from click.testing import CliRunner
from pymavlink import mavutil

from ftlbo_mav.cli import main
from ftlbo_mav.flight.fly import Fleet, FlyOptions, abort, start_together, take_off
from ftlbo_mav.flight.planned import load_planned_flight
from ftlbo_mav.flight.preflight import preflight
from ftlbo_mav.flight.start import start_gate
from ftlbo_mav.link.discovery import discover
from ftlbo_mav.link.endpoints import open_links
from ftlbo_mav.link.params import read_params, set_params
from ftlbo_mav.link.transfer import Timing
from ftlbo_mav.scenario import load_scenario
from ftlbo_mav.sim.homes import scenario_homes
from ftlbo_mav.sim.vehicle import VehicleOptions

from ..conftest import EXAMPLE
from ..link.ntrip_caster import FakeCaster
from ..link.rtcm_base import base_station
from .fleet import BACKEND, free_udp_port, vehicles

pytestmark = pytest.mark.sitl

SPEEDUP = 4.0
CORNER_CUT_TOLERANCE_M = 0.05
PREDICTED_TOLERANCE_M = 0.1
OPTIONS = VehicleOptions(heartbeat_s=0.25)
HOMES = scenario_homes(load_scenario(EXAMPLE))


@pytest.fixture
def plan_dir(tmp_path) -> Path:
    folder = tmp_path / "plan"
    shutil.copytree(EXAMPLE.with_suffix(""), folder)
    return folder


def free_tcp_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _emulator_options():
    return {} if BACKEND == "sitl" else {"options": OPTIONS}


def _upload(plan_dir: Path, urls: list[str]) -> None:
    result = CliRunner().invoke(main, ["upload", str(plan_dir), "--sysid", "1..3",
                                       "--connect", " ".join(urls)])
    assert result.exit_code == 0, result.output


def test_fly_the_example_all_land_at_the_goal_in_formation(plan_dir):
    # with RTK corrections flowing from an NTRIP caster (a base station's MSM7 stream,
    # ~1 kB/s, at the flight's time scale): the flight is judged as one without
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, **_emulator_options()) as fleet, \
            FakeCaster(lambda: base_station(600), interval_s=1.0 / SPEEDUP) as caster:
        _upload(plan_dir, fleet.urls)
        result = CliRunner().invoke(main, ["fly", str(plan_dir), "--sysid", "1..3",
                                           "--control-port", "0",
                                           "--rtcm", f"ntrip://me:secret@127.0.0.1:"
                                                     f"{caster.port}/BASE1",
                                           "--connect", " ".join(fleet.urls)])
        assert result.exit_code == 0, result.output
        received = (fleet.sim.call(lambda: [list(v.rtcm_frames) for v in fleet.sim.vehicles])
                    if fleet.sim else None)
    assert "all vehicles finished their missions" in result.stdout
    summary = json.loads((plan_dir / "flight" / "summary.json").read_text())
    rtcm = summary["rtcm"]
    assert rtcm["error"] is None and rtcm["dropped"] == 0 and rtcm["frames"] >= 20
    assert 0.5 * 800 * SPEEDUP < rtcm["bytes_per_s"] < 1.5 * 1200 * SPEEDUP
    if received is not None:  # every frame forwarded reached every copter whole
        assert all(len(frames) == rtcm["frames"] for frames in received)
        assert all(sum(map(len, frames)) == rtcm["bytes"] for frames in received)
    assert (plan_dir / "flight" / "report.png").stat().st_size > 20_000
    assert summary["leg_seconds"] > 1.0
    # the clearance the plan promised, less what ArduCopter's S-curve cuts at the tangent
    # waypoints (measured on SITL: 0.03-0.04 m of the 1 m)
    planned = load_planned_flight(plan_dir)
    promised = planned.clearance_m
    assert summary["inside_obstacle"] is False
    assert summary["min_clearance_m"] >= promised - CORNER_CUT_TOLERANCE_M
    # each UAV flies the path the planner predicted for it (ardupilot.flight_path: the
    # emulator flies with the same model; on SITL tests/conformance/test_flown_path.py)
    for flown, predicted in zip(summary["clearance_per_uav_m"], planned.predicted_clearance):
        assert abs(flown - predicted) <= PREDICTED_TOLERANCE_M, (flown, predicted)
    assert summary["predicted_clearance_per_uav_m"] == pytest.approx(
        list(planned.predicted_clearance))
    assert max(summary["final_distance_to_goal_m"]) < 1.0
    assert min(summary["position_rate_hz"].values()) >= 5.0
    csv = (plan_dir / "flight" / "flight.csv").read_text().splitlines()
    assert csv[0].startswith("t,sysid,lat_deg") and len(csv) > 100
    # the same on ArduCopter SITL since AUTO starts at the first real leg (0.05-0.11 m)
    assert summary["formation_error_rms_legs_m"] < 0.2
    assert summary["min_separation_legs_m"] >= summary["planned_min_separation_m"] - 0.5


def test_abort_mid_flight_sends_every_vehicle_to_rtl_within_a_second(plan_dir):
    planned = load_planned_flight(plan_dir)
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, **_emulator_options()) as fleet:
        _upload(plan_dir, fleet.urls)
        with Fleet(planned.names, [1, 2, 3], fleet.urls) as flying:
            take_off(planned, flying.vehicles, FlyOptions(), say=lambda _t: None)
            start_together(planned, flying.vehicles)
            assert all(v.wait_for(lambda s: s.seq >= 4, 30.0) for v in flying.vehicles)
            t0 = time.monotonic()
            assert abort(flying.vehicles, mode="RTL") == []
            for v in flying.vehicles:
                assert v.wait_for(lambda s: s.mode == "RTL", 1.0)
            assert time.monotonic() - t0 < 1.0
        # the command line does the same over fresh links (LAND this time)
        result = CliRunner().invoke(main, ["abort", "--sysid", "1..3", "--land",
                                           "--connect", " ".join(fleet.urls)])
        assert result.exit_code == 0, result.output
        assert result.stdout.count("LAND") == 3


def test_fly_refuses_before_arming_when_a_mission_differs(plan_dir, tmp_path):
    wrong = tmp_path / "wrong"
    shutil.copytree(plan_dir, wrong)
    shutil.copy(plan_dir / "uav3.waypoints", wrong / "uav2.waypoints")
    (wrong / "plan.json").unlink()  # upload refuses a plan folder with another's file in it
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, virtual=True, **_emulator_options()) as fleet:
        _upload(wrong, fleet.urls)  # vehicle 2 now holds uav3's mission
        result = CliRunner().invoke(main, ["fly", str(plan_dir), "--sysid", "1..3",
                                           "--control-port", "0",
                                           "--connect", " ".join(fleet.urls)])
        assert result.exit_code == 1
        assert "pre-flight failed, nothing armed" in result.stderr
        assert "uav2 (sysid 2): holds a different mission" in result.stderr
        assert "uav1 (sysid 1)" not in result.stderr
        with Fleet(["uav1", "uav2", "uav3"], [1, 2, 3], fleet.urls) as watching:
            for v in watching.vehicles:
                assert v.wait_for(lambda s: s.heartbeat_t > 0, 5.0)
                assert not v.status.armed and v.status.mode != "GUIDED"


def _set_param(url: str, sysid: int, name: str, value: float) -> None:
    """PARAM_SET on one vehicle and read back, as a user's ground station would."""
    links = open_links([url])
    try:
        found, missing = discover(links, [sysid])
        assert not missing
        with found[sysid].channel(sysid) as channel:
            set_params(channel, {name: value}, timing=Timing())
    finally:
        for link in links:
            link.close()


def _read_param(url: str, sysid: int, name: str) -> float | None:
    links = open_links([url])
    try:
        found, missing = discover(links, [sysid])
        assert not missing
        with found[sysid].channel(sysid) as channel:
            return read_params(channel, [name], timing=Timing())[name]
    finally:
        for link in links:
            link.close()


def test_a_copter_with_its_own_tuning_is_flown_as_it_is_or_refused_never_retuned(plan_dir):
    """The plan fits the copters: a copter whose values are not those the plan was
    predicted with is predicted again with its own; where every promise holds the flight
    goes on saying so, where one is lost fly and upload refuse naming the copter, its
    values and the promise, and neither writes its tuning."""
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, virtual=True, **_emulator_options()) as fleet:
        _upload(plan_dir, fleet.urls)
        _set_param(fleet.urls[1], 2, "WPNAV_ACCEL", 500.0)
        planned = load_planned_flight(plan_dir)
        said = []
        with Fleet(planned.names, [1, 2, 3], fleet.urls) as flying:
            preflight(planned, flying.vehicles, timing=Timing(), ready_timeout_s=60.0,
                      say=said.append)
            assert not any(v.status.armed for v in flying.vehicles)
        assert ("note: uav2 (sysid 2): WPNAV_ACCEL 500 (planned 250): the copter's own "
                "values, kept as they are") in said
        assert any("predicted again with the copters' own values" in t
                   and "every promise holds" in t for t in said), said
        # a copter retuned far from the plan's: the formation cannot be kept
        _set_param(fleet.urls[1], 2, "PSC_VELXY_P", 0.3)
        _set_param(fleet.urls[1], 2, "ANGLE_MAX", 1000.0)
        result = CliRunner().invoke(main, ["fly", str(plan_dir), "--sysid", "1..3",
                                           "--control-port", "0",
                                           "--connect", " ".join(fleet.urls)])
        assert result.exit_code == 1
        assert "pre-flight failed, nothing armed" in result.stderr
        assert ("uav2 (sysid 2) with its WPNAV_ACCEL 500 (planned 250), PSC_VELXY_P 0.3 "
                "(planned 2), ANGLE_MAX 1000 (planned 3000)") in result.stderr
        assert "(min_separation)" in result.stderr
        uploaded = CliRunner().invoke(main, ["upload", str(plan_dir), "--sysid", "1..3",
                                             "--connect", " ".join(fleet.urls)])
        assert uploaded.exit_code == 1, uploaded.output
        assert uploaded.stdout.count("refused, nothing sent to any vehicle") == 3
        assert "0/3 vehicles verified" in uploaded.stdout
        # its tuning is its own: nothing was written
        assert _read_param(fleet.urls[1], 2, "ANGLE_MAX") == 1000.0
        assert _read_param(fleet.urls[1], 2, "PSC_VELXY_P") == pytest.approx(0.3)


def test_monitor_records_and_forwards_to_a_ground_station(plan_dir):
    port = free_udp_port()
    gcs = mavutil.mavlink_connection(f"udpin:127.0.0.1:{port}", source_system=250,
                                     dialect="ardupilotmega")
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, **_emulator_options()) as fleet:
        runner = CliRunner()
        holder = {}
        thread = threading.Thread(target=lambda: holder.setdefault("result", runner.invoke(
            main, ["monitor", str(plan_dir), "--sysid", "1..3", "--duration", "4",
                   "--forward", f"udpout:127.0.0.1:{port}", "--connect", " ".join(fleet.urls)])))
        thread.start()
        heard, acked = set(), False
        deadline = time.monotonic() + 3.5
        while time.monotonic() < deadline and not (heard == {1, 2, 3} and acked):
            msg = gcs.recv_match(blocking=True, timeout=0.2)
            if msg is None:
                continue
            if msg.get_type() == "HEARTBEAT":
                heard.add(msg.get_srcSystem())
                if msg.get_srcSystem() == 2 and not acked:
                    # the ground station asks vehicle 2, and only it, to switch to GUIDED
                    gcs.mav.command_long_send(2, 1, mavutil.mavlink.MAV_CMD_DO_SET_MODE, 0,
                                              1, 4, 0, 0, 0, 0, 0)
            elif (msg.get_type() == "COMMAND_ACK" and msg.get_srcSystem() == 2
                  and msg.command == mavutil.mavlink.MAV_CMD_DO_SET_MODE):
                acked = msg.result == mavutil.mavlink.MAV_RESULT_ACCEPTED
        thread.join(timeout=15)
        gcs.close()
        assert heard == {1, 2, 3}
        assert acked
        with Fleet(["uav1", "uav2", "uav3"], [1, 2, 3], fleet.urls) as watching:
            modes = []
            for v in watching.vehicles:
                assert v.wait_for(lambda s: s.heartbeat_t > 0, 5.0)
                modes.append(v.status.mode)
        assert modes[1] == "GUIDED" and modes[0] != "GUIDED" and modes[2] != "GUIDED"
    result = holder["result"]
    assert result.exit_code == 0, result.output
    lines = (plan_dir / "monitor" / "flight.csv").read_text().splitlines()
    per_vehicle = sum(1 for line in lines[1:] if line.split(",")[1] == "1")
    assert per_vehicle >= 5 * 3  # at least 5 Hz over the monitored seconds


@pytest.mark.skipif(BACKEND == "sitl", reason="SITL's own boot decides when arming works")
def test_takeoff_retries_arming_until_the_position_estimate_is_ready(plan_dir):
    """ArduCopter passes its pre-arm checks well before it will arm ("Arm: Need Position
    Estimate"): the takeoff retries within its budget instead of failing."""
    planned = load_planned_flight(plan_dir)
    late = VehicleOptions(heartbeat_s=0.25, ready_after_s=0.0, position_after_s=10.0)
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, virtual=True, options=late) as fleet:
        with Fleet(planned.names, [1, 2, 3], fleet.urls) as flying:
            take_off(planned, flying.vehicles, FlyOptions(arm_budget_s=20.0),
                     say=lambda _t: None)
            assert all(v.status.armed and v.status.alt_m > 2.5 for v in flying.vehicles)
            # disarmed, ArduCopter accepts GUIDED without a position (Copter::set_mode
            # skips its checks; recorded in commands.json): it is arming that waits
            assert all("Arm: Need Position Estimate" in v.status.texts
                       for v in flying.vehicles)
            abort(flying.vehicles, mode="LAND")


def test_a_mission_ending_in_loiter_finishes_when_every_vehicle_holds_there(tmp_path):
    scenario = tmp_path / "loiter.toml"
    scenario.write_text(EXAMPLE.read_text().replace('end_action = "land"',
                                                    'end_action = "loiter"'))
    plan_dir = tmp_path / "plan"
    assert CliRunner().invoke(main, ["plan", str(scenario), "-o", str(plan_dir), "-q"]
                              ).exit_code == 0
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, virtual=True, **_emulator_options()) as fleet:
        _upload(plan_dir, fleet.urls)
        result = CliRunner().invoke(main, ["fly", str(plan_dir), "--sysid", "1..3",
                                           "--control-port", "0",
                                           "--connect", " ".join(fleet.urls),
                                           "--flight-timeout", "60"])
        assert result.exit_code == 0, result.output
        with Fleet(["uav1", "uav2", "uav3"], [1, 2, 3], fleet.urls) as watching:
            for v in watching.vehicles:
                assert v.wait_for(lambda s: s.heartbeat_t > 0, 5.0)
                assert v.status.armed and v.status.mode == "AUTO"  # still holding
            abort(watching.vehicles, mode="LAND")
    summary = json.loads((plan_dir / "flight" / "summary.json").read_text())
    assert max(summary["final_distance_to_goal_m"]) < 2.0


def test_abort_from_another_terminal_reaches_a_running_flight(plan_dir):
    """`fly` holds the vehicles' links (SITL serves one client per port); `abort` typed
    elsewhere goes through fly's control endpoint and every vehicle confirms RTL."""
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, **_emulator_options()) as fleet:
        _upload(plan_dir, fleet.urls)
        # a port free when asked can be taken before fly binds it (the other tests' own
        # ports, chosen by the system meanwhile): a fly refused for that goes again
        for _attempt in range(3):
            control = free_tcp_port()
            flying = subprocess.Popen(
                [sys.executable, "-m", "ftlbo_mav", "fly", str(plan_dir), "--sysid", "1..3",
                 "--control-port", str(control), "--connect", " ".join(fleet.urls)],
                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            said = []
            for line in flying.stderr:
                said.append(line)
                if "starting the missions together" in line:
                    break
            else:
                rest = flying.communicate()
                if any("Address already in use" in line for line in said):
                    continue
                pytest.fail(f"fly ended before the start: {''.join(said)}{rest}")
            break
        else:
            pytest.fail("fly found its control port taken three times")
        try:
            time.sleep(2.0)
            result = CliRunner().invoke(main, ["abort", "--sysid", "1..3",
                                               "--control-port", str(control)])
            out, _err = flying.communicate(timeout=300)
        finally:
            if flying.poll() is None:
                flying.kill()
        assert result.exit_code == 0, result.output
        assert "through the running flight" in result.stderr
        assert [line for line in result.stdout.splitlines()] == [
            "sysid 1: RTL", "sysid 2: RTL", "sysid 3: RTL"]
    assert flying.returncode == 1
    assert "flight aborted: every vehicle sent to RTL" in out
    assert (plan_dir / "flight" / "summary.json").exists()


def test_abort_with_no_flight_running_opens_the_links_itself(plan_dir):
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, virtual=True, **_emulator_options()) as fleet:
        result = CliRunner().invoke(main, ["abort", "--sysid", "1..3", "--land",
                                           "--control-port", str(free_tcp_port()),
                                           "--connect", " ".join(fleet.urls)])
    assert result.exit_code == 0, result.output
    assert "through the running flight" not in result.stderr
    assert result.stdout.count("LAND") == 3


def test_a_46_copter_among_45_ones_begins_its_legs_with_them(plan_dir):
    """ArduCopter 4.6.3 SITL's clock of the day is 0.17 s behind 4.5.6's
    (ardupilot/copters.py SITL_CLOCK_BEHIND_S), so its start gate opened 0.17 s after
    theirs: the start trimmed for it, all three leave their gates in the same 20 ms step
    of the emulator (untrimmed: 0.16-0.18 s apart)."""
    planned = load_planned_flight(plan_dir)
    fleet_of = [("4.5.6", {}), ("4.6.3", {}), ("4.5.6", {})]
    with vehicles(3, homes=HOMES, virtual=True, copters=fleet_of) as fleet:
        if fleet.sim is None:
            pytest.skip("the emulator's clocks")
        left: dict[int, float] = {}
        gate = start_gate(planned.missions[0], planned.frame)  # the trim's place
        for i, r in enumerate(fleet.sim.runners):
            def tick(r=r, i=i, step=r.tick):
                out = step()
                if i not in left and r.vehicle.mission_current().seq > gate:
                    left[i] = r.clock()
                return out
            r.tick = tick
        _upload(plan_dir, fleet.urls)
        result = CliRunner().invoke(main, ["fly", str(plan_dir), "--sysid", "1..3",
                                           "--control-port", "0", "--no-keeper",
                                           "--connect", " ".join(fleet.urls)])
        assert result.exit_code == 0, result.output
    assert "held for their clocks: uav1 170 ms, uav3 170 ms" in result.output
    assert len(left) == 3 and max(left.values()) - min(left.values()) <= 0.021, left
