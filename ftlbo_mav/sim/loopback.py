"""An emulated vehicle inside the process, in virtual time: a channel for fast, exact tests.

:class:`LoopbackChannel` has the interface the mission protocol talks through (``send``,
``recv``, ``clock``) and, at its other end, a :class:`~ftlbo_mav.sim.vehicle.Vehicle`
behind the same :class:`~ftlbo_mav.sim.faults.FaultyPipe` s as on the network. Time only
moves when the protocol waits, so a run at 30% loss with ArduPilot's 1 s re-requests and
8 s cancellations takes milliseconds and is repeatable from its seed. Messages are packed
and parsed as on a real link (so they carry their sender's ids).
"""

from __future__ import annotations

import heapq
import itertools
from typing import Self

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from .faults import Faults, FaultyPipe
from .vehicle import Vehicle

ONE_WAY_S = 0.005  # the link's own delay, each way
TICK_S = 0.02      # how often the vehicle's timers run


class LoopbackChannel:
    """The ground station's end of an in-memory link to ``vehicle``."""

    def __init__(self, vehicle: Vehicle, *, faults: Faults | None = None,
                 rng: np.random.Generator | None = None, own_sysid: int = 255,
                 own_compid: int = 190):
        rng = rng if rng is not None else np.random.default_rng(0)
        self.vehicle = vehicle
        self.sysid = vehicle.sysid
        self.own_sysid, self.own_compid = own_sysid, own_compid
        self.srtt: float | None = None
        faults = faults if faults is not None else Faults()
        self.faults = faults
        self.up = FaultyPipe.up(faults, rng)
        self.down = FaultyPipe.down(faults, rng)
        self.now = vehicle.boot_time
        self._events: list = []
        self._order = itertools.count()
        self._next_tick = self.now
        self._gcs = mavlink2.MAVLink(None, srcSystem=own_sysid, srcComponent=own_compid)
        self._veh = mavlink2.MAVLink(None, srcSystem=vehicle.sysid, srcComponent=vehicle.compid)
        self._gcs_parser = mavlink2.MAVLink(None)
        self._veh_parser = mavlink2.MAVLink(None)
        self.received: list = []  # every message the ground station was handed, in order
        self.link = "loopback"
        vehicle.link(self.link, self.now)

    def clock(self) -> float:
        return self.now

    @staticmethod
    def _wire(msg, packer, parser):
        buf = msg.pack(packer)
        packer.seq = (packer.seq + 1) % 256
        return parser.parse_char(bytes(buf))

    def _push(self, t: float, where: str, msg) -> None:
        heapq.heappush(self._events, (t, next(self._order), where, msg))

    def send(self, msg) -> None:
        wire = self._wire(msg, self._gcs, self._veh_parser)
        for delay, m in self.up.route(wire):
            self._push(self.now + ONE_WAY_S + delay, "vehicle", m)

    def _from_vehicle(self, msgs) -> None:
        for msg in msgs:
            if not msg.get_type().startswith(("MISSION_", "COMMAND_", "PARAM_")):
                continue  # the channel carries the protocols, not the link's telemetry
            wire = self._wire(msg, self._veh, self._gcs_parser)
            for delay, m in self.down.route(wire):
                self._push(self.now + ONE_WAY_S + delay, "gcs", m)

    def recv(self, timeout_s: float):
        """Run the vehicle until a message for us arrives, or ``timeout_s`` passes."""
        deadline = self.now + max(0.0, timeout_s)
        while True:
            t_event = self._events[0][0] if self._events else float("inf")
            t = min(t_event, self._next_tick)
            if t > deadline:
                self.now = deadline
                return None
            self.now = max(self.now, t)
            if t == self._next_tick and t < t_event:
                self._next_tick += TICK_S
                out = self.vehicle.tick(self.now).get(self.link, [])
                if not (self.faults.silent or self.faults.mute):
                    self._from_vehicle(out)
                continue
            _, _, where, msg = heapq.heappop(self._events)
            if where == "vehicle":
                if not (self.faults.silent or self.faults.mute):
                    self._from_vehicle(self.vehicle.handle(msg, self.now, self.link))
            elif getattr(msg, "target_system", 0) in (0, self.own_sysid):
                self.received.append(msg)
                return msg

    def close(self) -> None:
        pass

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc) -> None:
        pass
