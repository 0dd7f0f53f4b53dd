"""Flights that leave the plan: a vehicle lost mid-leg, a mode taken over from a second
port, a fence crossed, a link that drops and comes back. ``fly`` notices within seconds,
answers by its policy and always ends (exit 1, a line per vehicle, the report written).

The emulator, or ArduPilot SITL when ARDUPILOT_SITL is set: one code path, the faults
made as they happen to a real copter (its process killed, a command on its SERIAL1, a
fence parameter set from there, a radio bridge that drops).
"""

from __future__ import annotations

import json
import shutil
import socket
import threading
from pathlib import Path

import pytest
from click.testing import CliRunner
from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav import clock
from ftlbo_mav.ardupilot.modes import CopterMode, mode_name
from ftlbo_mav.cli import main
from ftlbo_mav.flight.fly import Fleet, FlyOptions, abort, start_together, take_off
from ftlbo_mav.flight.planned import load_planned_flight
from ftlbo_mav.scenario import load_scenario
from ftlbo_mav.sim.homes import scenario_homes
from ftlbo_mav.sim.vehicle import VehicleOptions

from ..conftest import EXAMPLE
from .fleet import BACKEND, connect, vehicles

pytestmark = pytest.mark.sitl

SPEEDUP = 1.0 if BACKEND == "sitl" else 6.0
OPTIONS = {} if BACKEND == "sitl" else {"options": VehicleOptions(heartbeat_s=0.25)}
HOMES = scenario_homes(load_scenario(EXAMPLE))
# what a test allows, in the vehicles' seconds (the emulator runs SPEEDUP times faster)
DETECT_S = 1.0
LOST_S = 2.0


@pytest.fixture(scope="module")
def example(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("example") / "plan"
    shutil.copytree(EXAMPLE.with_suffix(""), folder)
    return folder


@pytest.fixture
def plan_dir(example, tmp_path) -> Path:
    folder = tmp_path / "plan"
    shutil.copytree(example, folder)
    return folder


class SecondPort:
    """Vehicle ``sysid``'s SERIAL1, as a pilot's telemetry or another station: watches
    its HEARTBEAT and sends it commands."""

    def __init__(self, url: str, sysid: int) -> None:
        self.sysid = sysid
        self.conn = connect(url, source_system=246)
        self.mode, self.armed, self.texts = "?", False, []
        self.seq, self._asked = -1, -1e9

    def wait(self, predicate, timeout_s: float) -> bool:
        """Until ``predicate(self)`` holds (True) or ``timeout_s`` of the test's clock pass."""
        deadline = clock.monotonic() + timeout_s
        while clock.monotonic() < deadline:
            if self.seq < 0 and clock.monotonic() - self._asked > 1.0:
                self._asked = clock.monotonic()  # MISSION_CURRENT at 5 Hz on this port
                self.conn.mav.command_long_send(self.sysid, 1, R.MAV_CMD_SET_MESSAGE_INTERVAL,
                                                0, R.MAVLINK_MSG_ID_MISSION_CURRENT, 200_000,
                                                0, 0, 0, 0, 0)
            msg = self.conn.recv_match(blocking=False)
            if msg is None:
                self.conn.select(min(0.1, max(0.0, deadline - clock.monotonic())))
                continue
            if msg.get_srcSystem() != self.sysid:
                continue
            if msg.get_type() == "MISSION_CURRENT":
                self.seq = msg.seq
            elif msg.get_type() == "HEARTBEAT":
                self.mode = mode_name(msg.custom_mode)
                self.armed = bool(msg.base_mode & R.MAV_MODE_FLAG_SAFETY_ARMED)
            elif msg.get_type() == "STATUSTEXT":
                self.texts.append(msg.text)
            if predicate(self):
                return True
        return False

    def set_mode(self, mode: str) -> None:
        self.conn.mav.command_long_send(self.sysid, 1, R.MAV_CMD_DO_SET_MODE, 0,
                                        R.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
                                        CopterMode[mode], 0, 0, 0, 0, 0)

    def pause(self, pause: bool) -> None:
        """MAV_CMD_DO_PAUSE_CONTINUE: another station holds the copter on its track."""
        self.conn.mav.command_long_send(self.sysid, 1, R.MAV_CMD_DO_PAUSE_CONTINUE, 0,
                                        0 if pause else 1, 0, 0, 0, 0, 0, 0)

    def set_param(self, name: str, value: float) -> None:
        self.conn.mav.param_set_send(self.sysid, 1, name.encode(), value,
                                     R.MAV_PARAM_TYPE_REAL32)

    def close(self) -> None:
        self.conn.close()


def _upload(plan_dir: Path, urls) -> None:
    result = CliRunner().invoke(main, ["upload", str(plan_dir), "--sysid", "1..3",
                                       "--connect", " ".join(urls)])
    assert result.exit_code == 0, result.output


def _fly_with(plan_dir: Path, urls, fault, *extra):
    """``fly`` in a thread while ``fault()`` runs here; (result, seconds from the fault's
    return to fly's end)."""
    holder = {}

    def run():
        holder["result"] = CliRunner().invoke(
            main, ["fly", str(plan_dir), "--sysid", "1..3", "--control-port", "0",
                   "--no-keeper", "--connect", " ".join(urls), *extra])
        holder["end"] = clock.monotonic()

    thread = clock.Thread(run, name="fly")
    thread.start()
    try:
        fault_t = fault()
    finally:
        thread.join(timeout=300)
    assert not thread.is_alive(), "fly did not end"
    took = holder["end"] - fault_t
    print(f"[{BACKEND}] fly ended {took:.1f} s after the fault, exit "
          f"{holder['result'].exit_code}:\n{holder['result'].stdout}")
    return holder["result"], took


START_GATE = 3  # the example's start gate: its legs begin after it (fly's timed start)


def _in_auto_for(port: SecondPort, seconds: float, time_scale: float) -> None:
    """``seconds`` (the vehicles') into the legs; ``time_scale``: the vehicles' seconds per
    second of the test's clock (:attr:`Fleet.time_scale <.fleet.Fleet.time_scale>`)."""
    assert port.wait(lambda p: p.armed and p.mode == "AUTO" and p.seq > START_GATE, 120.0)
    port.wait(lambda p: False, seconds / time_scale)


def _summary(plan_dir: Path) -> dict:
    return json.loads((plan_dir / "flight" / "summary.json").read_text())


def test_a_vehicle_lost_mid_leg_stops_the_others_and_the_flight_ends(plan_dir):
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, virtual=True, **OPTIONS) as fleet:
        _upload(plan_dir, fleet.urls)
        watcher = SecondPort(fleet.serial1_urls[0], 1)

        def fault():
            _in_auto_for(watcher, 4.0, fleet.time_scale)
            fleet.kill(1)  # uav2's autopilot dies (SITL: its process, by pid)
            return clock.monotonic()

        try:
            result, took = _fly_with(plan_dir, fleet.urls, fault, "--lost-wait", "3")
            # uav1 (the others too) answered: home on its route (AUTO), RTL or LAND
            answered = watcher.wait(lambda p: p.mode in ("AUTO", "RTL", "LAND")
                                    or not p.armed, 10.0)
        finally:
            watcher.close()
    out = result.output
    assert result.exit_code == 1, out
    assert "Traceback" not in out
    assert "uav2 (sysid 2): link lost" in out
    for name in ("uav1 (sysid 1)", "uav3 (sysid 3)"):
        assert f"{name}: stopped on its track (pause)" in out
    # home on planned routes (tests/integration/test_homeward.py), or RTL / LAND
    assert ("flying home on a planned route" in out or "RTL at" in out
            or "no RTL: the straight line" in out), out
    assert took < 60.0
    assert answered
    summary = _summary(plan_dir)
    assert any(line.startswith("uav2 (sysid 2): link lost") for line in summary["departures"])
    assert len(summary["outcome"]) == 3
    assert (plan_dir / "flight" / "report.png").is_file()


def test_a_mode_taken_over_from_a_second_port_is_left_alone(plan_dir):
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, virtual=True, **OPTIONS) as fleet:
        _upload(plan_dir, fleet.urls)
        pilot = SecondPort(fleet.serial1_urls[2], 3)
        times = {}

        def fault():
            _in_auto_for(pilot, 4.0, fleet.time_scale)
            pilot.set_mode("BRAKE")  # uav3's pilot (or a failsafe) takes it over
            times["sent"] = clock.monotonic()
            return times["sent"]

        try:
            result, took = _fly_with(plan_dir, fleet.urls, fault, "--on-departure", "land")
            # uav3 still where its pilot put it: the flight never commanded it
            assert pilot.wait(lambda p: p.mode == "BRAKE", 2.0)
            assert pilot.armed
        finally:
            pilot.set_mode("LAND")
            pilot.close()
    out = result.output
    assert result.exit_code == 1, out
    assert "uav3 (sysid 3): mode: switched to BRAKE" in out
    assert "left to what it chose: not commanded" in out
    assert "uav1 (sysid 1): stopped on its track (pause)" in out and "LAND at" in out
    assert took < 60.0


def test_a_formation_that_falls_apart_is_a_departure_not_a_silent_exit_0(plan_dir):
    """Another station holds uav2 on its track mid-leg (a pause from its SERIAL1): the
    others fly on, uav2 falls behind its slot past the plan's bound (0.77 m for the
    example) and, a second later, the flight counts it a departure and answers it."""
    bound = load_planned_flight(plan_dir).formation_bound_m
    assert 0.5 < bound < 1.0
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, virtual=True, **OPTIONS) as fleet:
        _upload(plan_dir, fleet.urls)
        other = SecondPort(fleet.serial1_urls[1], 2)

        def fault():
            _in_auto_for(other, 6.0, fleet.time_scale)
            other.pause(True)
            return clock.monotonic()

        try:
            result, took = _fly_with(plan_dir, fleet.urls, fault)
        finally:
            other.close()
    out = result.output
    assert result.exit_code == 1, out
    assert "Traceback" not in out
    assert "uav2 (sysid 2): formation: " in out and f"the plan's bound of {bound:.2f} m" in out
    for name in ("uav1 (sysid 1)", "uav3 (sysid 3)"):
        assert f"{name}: stopped on its track (pause)" in out
    assert took < 60.0
    summary = _summary(plan_dir)
    assert any(line.startswith("uav2 (sysid 2): formation") for line in summary["departures"])


def test_a_fence_crossed_in_flight_is_seen_and_answered(plan_dir):
    """Another station lowers uav1's FENCE_ALT_MAX below the flight: ArduCopter says
    "Fence Breached" and takes FENCE_ACTION's mode (brake)."""
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, virtual=True, **OPTIONS) as fleet:
        _upload(plan_dir, fleet.urls)
        station = SecondPort(fleet.serial1_urls[0], 1)

        def fault():
            _in_auto_for(station, 3.0, fleet.time_scale)
            station.set_param("FENCE_ALT_MAX", 5.0)
            return clock.monotonic()

        try:
            result, took = _fly_with(plan_dir, fleet.urls, fault)
        finally:
            station.close()
    out = result.output
    assert result.exit_code == 1, out
    assert 'uav1 (sysid 1): fence: "Fence Breached"' in out
    assert "uav2 (sysid 2): stopped on its track (pause)" in out
    assert took < 60.0


class Bridge:
    """A TCP relay between ``fly`` and one vehicle, as a telemetry radio bridge: it can
    drop (close both sides, refuse) for a while and come back."""

    def __init__(self, target_url: str) -> None:
        host, port = target_url.split(":")[1:]
        self.target = (host, int(port))
        self.server = socket.create_server(("127.0.0.1", 0))
        self.port = self.server.getsockname()[1]
        self.url = f"tcp:127.0.0.1:{self.port}"
        self.up = threading.Event()
        self.up.set()
        self.stop = threading.Event()
        self.pairs: list[tuple[socket.socket, socket.socket]] = []
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self) -> None:
        self.server.settimeout(0.1)
        while not self.stop.is_set():
            try:
                client, _ = self.server.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            if not self.up.is_set():
                client.close()
                continue
            vehicle = socket.create_connection(self.target)
            self.pairs.append((client, vehicle))
            for a, b in ((client, vehicle), (vehicle, client)):
                threading.Thread(target=self._pipe, args=(a, b), daemon=True).start()

    @staticmethod
    def _pipe(a: socket.socket, b: socket.socket) -> None:
        try:
            while data := a.recv(4096):
                b.sendall(data)
        except OSError:
            pass
        for s in (a, b):
            try:
                s.close()
            except OSError:
                pass

    def drop(self) -> None:
        self.up.clear()
        for a, b in self.pairs:
            for s in (a, b):
                try:
                    s.shutdown(socket.SHUT_RDWR)
                except OSError:
                    pass
        self.pairs.clear()

    def restore(self) -> None:
        self.up.set()

    def close(self) -> None:
        self.stop.set()
        self.drop()
        self.server.close()


def test_a_link_that_drops_and_returns_is_picked_up_again(plan_dir):
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, **OPTIONS) as fleet:
        _upload(plan_dir, fleet.urls)
        bridge = Bridge(fleet.urls[1])
        watcher = SecondPort(fleet.serial1_urls[1], 2)
        urls = [fleet.urls[0], bridge.url, fleet.urls[2]]

        def fault():
            _in_auto_for(watcher, 3.0, fleet.time_scale)
            bridge.drop()
            t = clock.monotonic()
            clock.sleep(3.0)  # the radio is out of range for 3 s (wall clock)
            bridge.restore()
            return t

        try:
            result, took = _fly_with(plan_dir, urls, fault)
            assert watcher.wait(lambda p: p.mode in ("RTL", "LAND") or not p.armed, 5.0)
        finally:
            watcher.close()
            bridge.close()
    out = result.output
    assert result.exit_code == 1, out
    assert "uav2 (sysid 2): link lost" in out
    assert "uav2 (sysid 2): link back: heard from again" in out
    # the vehicle itself chose nothing: once back it is answered as the others are. (Its
    # line may begin with another departure: on a loaded machine its AUTO can come late,
    # and a copter started late is flagged for formation before its link drops.)
    summary = [line for line in out.splitlines() if line.startswith("  uav2 (sysid 2): ")]
    assert len(summary) == 1, out
    assert "link lost at" in summary[0] and "link back at" in summary[0], out
    assert took < 60.0


def test_abort_with_a_dead_link_answers_per_vehicle_within_two_seconds(plan_dir):
    planned = load_planned_flight(plan_dir)
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, **OPTIONS) as fleet:
        _upload(plan_dir, fleet.urls)
        with Fleet(planned.names, [1, 2, 3], fleet.urls) as flying:
            take_off(planned, flying.vehicles, FlyOptions(), say=lambda _t: None)
            start_together(planned, flying.vehicles)
            fleet.kill(2)
            assert flying.vehicles[2].wait_for(lambda s: False, 0.5) is False
            t0 = clock.monotonic()
            late = abort(flying.vehicles, mode="LAND")
            took = clock.monotonic() - t0
        assert late == ["uav3"]
        assert took < 2.0
        # the command line, on links of its own: a line per vehicle, the dead one named
        t0 = clock.monotonic()
        result = CliRunner().invoke(main, ["abort", "--sysid", "1..3", "--land",
                                           "--control-port", "0",
                                           "--connect", " ".join(fleet.urls)])
        took = clock.monotonic() - t0
    assert result.exit_code == 1, result.output
    assert "Traceback" not in result.output
    assert "sysid 1: LAND" in result.stdout and "sysid 2: LAND" in result.stdout
    assert "sysid 3: NOT REACHED" in result.stdout
    assert took < 2.0  # 1.5 s to give up on the dead one, the rest at once


def test_departures_are_seen_within_their_deadlines(plan_dir):
    """A mode taken over is seen within 1 s of the HEARTBEAT that shows it (ArduPilot
    sends one a second), a vehicle that dies within 2 s."""
    from ftlbo_mav.flight.policy import FaultPolicy
    from ftlbo_mav.flight.watch import FlightWatch

    planned = load_planned_flight(plan_dir)
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, **OPTIONS) as fleet:
        _upload(plan_dir, fleet.urls)
        pilot = SecondPort(fleet.serial1_urls[2], 3)
        try:
            with Fleet(planned.names, [1, 2, 3], fleet.urls) as flying:
                take_off(planned, flying.vehicles, FlyOptions(), say=lambda _t: None)
                start_together(planned, flying.vehicles)
                fw = FlightWatch(planned, flying.vehicles, policy=FaultPolicy.CONTINUE)
                fw.started = True
                fw.expect("AUTO")

                def seen_after(kind: str, t0: float) -> float:
                    while clock.monotonic() - t0 < 10.0:
                        if any(e.kind == kind for e in fw.poll()):
                            return clock.monotonic() - t0
                        clock.sleep(0.05)
                    return float("inf")

                t0 = clock.monotonic()
                pilot.set_mode("LOITER")
                mode_s = seen_after("mode", t0)
                t0 = clock.monotonic()
                fleet.kill(1)
                lost_s = seen_after("link lost", t0)
                abort([flying.vehicles[0]], mode="LAND")
        finally:
            pilot.set_mode("LAND")
            pilot.close()
    print(f"[{BACKEND}] mode seen after {mode_s:.2f} s, link lost after {lost_s:.2f} s")
    assert mode_s <= 1.0 + 0.2  # one HEARTBEAT period, one watch cycle
    assert lost_s <= 2.0


def test_monitor_lists_a_vehicle_that_leaves_its_mission(plan_dir):
    """``monitor`` on the vehicles' SERIAL1 ports while they fly on SERIAL0: a switch to
    LOITER in the middle of the mission is listed, and monitor exits 1."""
    planned = load_planned_flight(plan_dir)
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, virtual=True, **OPTIONS) as fleet:
        _upload(plan_dir, fleet.urls)
        holder = {}
        with Fleet(planned.names, [1, 2, 3], fleet.urls) as flying:
            take_off(planned, flying.vehicles, FlyOptions(), say=lambda _t: None)
            thread = clock.Thread(lambda: holder.setdefault(
                "result", CliRunner().invoke(main, [
                    "monitor", str(plan_dir), "--sysid", "1..3", "--duration", "10",
                    "--log-dir", str(plan_dir / "watched"),
                    "--connect", " ".join(fleet.serial1_urls)])), name="monitor")
            thread.start()
            start_together(planned, flying.vehicles)
            flying.vehicles[0].wait_for(lambda s: False, 2.0 / fleet.time_scale + 1.0)
            flying.vehicles[0].set_mode("LOITER")  # as a pilot would
            thread.join(timeout=60)
            abort(flying.vehicles, mode="LAND")
    result = holder["result"]
    assert result.exit_code == 1, result.output
    assert "departure(s) from the plan" in result.stdout
    assert "uav1 (sysid 1): mode: switched to LOITER" in result.stdout
    summary = json.loads((plan_dir / "watched" / "summary.json").read_text())
    assert any("switched to LOITER" in line for line in summary["departures"])
