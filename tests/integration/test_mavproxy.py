"""``--forward`` with MAVProxy as the operator's ground station (the ``mavproxy`` package,
run headless as its own process, commands typed on its stdin): it sees every vehicle, a
mode change it sends for one vehicle reaches that vehicle only, and ftlbo-mav's own
commands keep working through the same links meanwhile. The forwarder is the one ``fly``
and ``monitor`` start for ``--forward`` (flight/commands.py)."""

from __future__ import annotations

import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from pymavlink import mavutil

from ftlbo_mav.flight.fly import Fleet
from ftlbo_mav.flight.forward import Forwarder
from ftlbo_mav.scenario import load_scenario
from ftlbo_mav.sim.homes import scenario_homes
from ftlbo_mav.sim.vehicle import VehicleOptions

from ..conftest import EXAMPLE
from .fleet import BACKEND, free_udp_port, vehicles

pytestmark = pytest.mark.sitl

HOMES = scenario_homes(load_scenario(EXAMPLE))
OPTIONS = {} if BACKEND == "sitl" else {"options": VehicleOptions(heartbeat_s=0.25)}


class MavProxy:
    """``mavproxy.py --master udpin:...`` as a child process; ``say`` types a command."""

    def __init__(self, port: int, state: Path) -> None:
        self.lines: list[str] = []
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "MAVProxy.mavproxy", f"--master=udpin:127.0.0.1:{port}",
             f"--state-basedir={state}", f"--logfile={state / 'mav.tlog'}",
             "--default-modules=link,mode,cmdlong,fence,rally,wp,param",
             "--cmd=set flushlogs 1"],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
            text=True, bufsize=1, cwd=state)
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self) -> None:
        for line in self.proc.stdout:
            self.lines.append(line.rstrip())

    def say(self, command: str) -> None:
        self.proc.stdin.write(command + "\n")
        self.proc.stdin.flush()

    def wait_for(self, text: str, timeout_s: float) -> bool:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if any(text in line for line in self.lines):
                return True
            time.sleep(0.05)
        return False

    def close(self) -> None:
        """End of input: MAVProxy exits as on Ctrl-D, flushing its telemetry log."""
        self.proc.stdin.close()
        try:
            self.proc.wait(timeout=15)
            return
        except subprocess.TimeoutExpired:
            self.proc.terminate()
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait(timeout=5)


def test_mavproxy_sees_every_vehicle_and_commands_only_the_one_it_means(tmp_path):
    port = free_udp_port()
    with vehicles(3, homes=HOMES, **OPTIONS) as fleet:
        with Fleet(["uav1", "uav2", "uav3"], [1, 2, 3], fleet.urls) as ours:
            relay = Forwarder(f"udpout:127.0.0.1:{port}", ours.links,
                              {v.sysid: v.link for v in ours.vehicles})
            with relay:
                gcs = MavProxy(port, tmp_path)
                try:
                    for sysid in (1, 2, 3):
                        assert gcs.wait_for(f"Detected vehicle {sysid}:1", 30.0), gcs.lines
                    gcs.say("vehicle 2")
                    assert gcs.wait_for("Set vehicle 2", 10.0), gcs.lines
                    gcs.say("mode GUIDED")
                    assert gcs.wait_for("DO_SET_MODE: ACCEPTED", 10.0), gcs.lines
                    uav1, uav2, uav3 = ours.vehicles
                    assert uav2.wait_for(lambda s: s.mode == "GUIDED", 10.0)
                    # our own command, on the same links, while MAVProxy is attached
                    uav3.set_mode("LOITER", timeout_s=10.0)
                    assert uav3.wait_for(lambda s: s.mode == "LOITER", 5.0)
                    time.sleep(1.0)
                    assert uav1.status.mode not in ("GUIDED", "LOITER")
                    assert uav2.status.mode == "GUIDED" and uav3.status.mode == "LOITER"
                    assert gcs.proc.poll() is None  # MAVProxy still running
                finally:
                    gcs.close()
            assert relay.to_gcs > 0 and relay.to_vehicles > 0
    heard = set()
    log = mavutil.mavlink_connection(str(tmp_path / "mav.tlog"), dialect="ardupilotmega")
    while (msg := log.recv_match(type="HEARTBEAT")) is not None:
        heard.add(msg.get_srcSystem())
    assert {1, 2, 3} <= heard  # MAVProxy's own telemetry log holds every vehicle
