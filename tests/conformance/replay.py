"""Replaying a recording's messages into the emulator at the recorded times.

A :class:`Bench` is one emulated vehicle on named links (``"SERIAL0"``, ``"SERIAL1"``, ...
as in the recordings), booted at t = 0 (SITL boots when its first client connects, which
is the recordings' t = 0), with ArduCopter's recorded boot timeline. ``send`` hands it a
message from the recorder's ground station (255/190 unless told) at a time; ``run``
ticks it every 10 ms; what it says is kept per link with its time.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav.ardupilot.commands import RECORDED_BOOT
from ftlbo_mav.ardupilot.firmware import Firmware
from ftlbo_mav.sim.vehicle import Vehicle, VehicleOptions

DATA = Path(__file__).parents[1] / "data" / "ardupilot-4.5.6"
RELEASES = ("4.5.6", "4.6.3")  # the recorded releases, tests/data/ardupilot-<release>/
# the recordings' --home 12.2332099,109.1145051,0 (SITL's home item reads back 0.1 m)
HOME = (12.2332099, 109.1145051, 0.1)
GCS = (255, 190)
TICK_S = 0.01


def load(name: str, release: str = "4.5.6") -> dict:
    return json.loads((DATA.parent / f"ardupilot-{release}" / name).read_text())


def firmware(release: str) -> Firmware:
    """The AUTOPILOT_VERSION of a recorded release (official, as recorded)."""
    major, minor, patch = map(int, release.split("."))
    return Firmware(major, minor, patch, R.FIRMWARE_VERSION_TYPE_OFFICIAL)


def num(v):
    return float(v) if isinstance(v, str) else v  # "nan", "inf" as the recorder wrote them


def wire(msg, src=GCS):
    """``msg`` packed and parsed, so it carries its sender's ids as on a real link."""
    packer = R.MAVLink(None, srcSystem=src[0], srcComponent=src[1])
    return R.MAVLink(None).parse_char(bytes(msg.pack(packer)))


@dataclass
class Heard:
    t: float
    link: str
    msg: object

    @property
    def kind(self) -> str:
        return self.msg.get_type()


@dataclass
class Bench:
    options: VehicleOptions = field(default_factory=lambda: VehicleOptions(boot=RECORDED_BOOT))
    links: tuple[str, ...] = ("SERIAL0",)
    home: tuple[float, float, float] = HOME

    def __post_init__(self):
        self.vehicle = Vehicle(sysid=1, home=self.home, options=self.options, boot_time=0.0)
        self.now = 0.0
        self.heard: list[Heard] = []
        for link in self.links:
            self.vehicle.link(link, 0.0)

    def run(self, until: float) -> None:
        """Tick every TICK_S, and at ``until`` itself (ArduPilot's loop runs at 400 Hz)."""
        while self.now < until - 1e-9:
            self.now = min(round(self.now + TICK_S, 6), until)
            for link, msgs in self.vehicle.tick(self.now).items():
                self.heard += [Heard(self.now, link, m) for m in msgs]

    def send(self, t: float, msg, *, link: str = "SERIAL0", src=GCS) -> list:
        """Run to ``t``, deliver ``msg``; returns the replies on ``link`` (also kept)."""
        self.run(t)
        replies = self.vehicle.handle(wire(msg, src), self.now, link)
        self.heard += [Heard(self.now, link, m) for m in replies]
        return replies

    def since(self, t: float, kinds=None) -> list[Heard]:
        return [h for h in self.heard if h.t >= t - 1e-9 and (kinds is None or h.kind in kinds)]

    def texts(self, t0: float, t1: float) -> list[str]:
        return [h.msg.text for h in self.heard
                if h.kind == "STATUSTEXT" and t0 - 1e-9 <= h.t <= t1]

    def command(self, t: float, command: int, params, *, link: str = "SERIAL0"):
        """A COMMAND_LONG; returns its COMMAND_ACK."""
        p = [float(x) for x in params] + [0.0] * (7 - len(params))
        replies = self.send(t, R.MAVLink_command_long_message(1, 1, command, 0, *p), link=link)
        (ack,) = [m for m in replies if m.get_type() == "COMMAND_ACK"]
        return ack

    def upload(self, t: float, rows: list, *, link: str = "SERIAL0") -> int:
        """Upload compact rows (seq, frame, command, p1..p4, x, y, z) answering each
        request at once; returns the final MISSION_ACK type."""
        out = self.send(t, R.MAVLink_mission_count_message(1, 1, len(rows), 0), link=link)
        while True:
            for m in out:
                if m.get_type() == "MISSION_ACK":
                    return m.type
            (req,) = [m for m in out if m.get_type() == "MISSION_REQUEST"]
            out = self.send(self.now + 0.005, item_int(rows[req.seq]), link=link)


def item_int(row, *, seq=None):
    seq_, frame, command, p1, p2, p3, p4, x, y, z = row
    return R.MAVLink_mission_item_int_message(
        1, 1, seq_ if seq is None else seq, frame, command, 0, 1, num(p1), num(p2), num(p3),
        num(p4), x, y, num(z), 0)


def item_from_dict(d: dict):
    return R.MAVLink_mission_item_int_message(
        1, 1, d["seq"], d["frame"], d["command"], d["current"], d["autocontinue"],
        num(d["param1"]), num(d["param2"]), num(d["param3"]), num(d["param4"]), d["x"], d["y"],
        num(d["z"]), 0)


def rows_of(vehicle: Vehicle) -> list:
    """The stored mission as compact rows, item 0 as read back (the vehicle's home)."""
    ms = vehicle.missions
    items = [ms.home_item()] + list(ms.items[1:]) if ms.items else []
    return [[i, it.frame, it.command, it.param1, it.param2, it.param3,
             it.param4, it.x, it.y, it.z] for i, it in enumerate(items)]
