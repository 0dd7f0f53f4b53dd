"""One emulated vehicle between bytes and messages: :class:`VehicleRunner`.

It parses what each client sends (each :class:`Attachment` with its own stream state and
signature check), hands the messages to the :class:`~.vehicle.Vehicle`, applies the
faults (:mod:`.faults`: lost, delayed, muted replies) and writes what the vehicle says
to each client of each link, on whatever clock and transport runs it: the sockets of
:class:`~.server.Simulator` or the in-process links of :mod:`.inprocess`.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable, Hashable

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from .faults import Faults, FaultyPipe
from .vehicle import Vehicle

# replies to a request, which a muted vehicle (Faults.mute) does not send
_ANSWERS = frozenset({"MISSION_REQUEST", "MISSION_ACK", "MISSION_COUNT", "MISSION_ITEM",
                      "MISSION_ITEM_INT", "COMMAND_ACK"})


def _signing_timestamp() -> int:
    """MAVLink signing time: 10 microsecond units since 2015-01-01 (as pymavlink's)."""
    return int((time.time() - 1420070400) * 100_000)


class Attachment:
    """One client of one vehicle: its own parser (stream state, signature check) and writer."""

    def __init__(self, write: Callable[[bytes], None], *, sysid: int, key: bytes | None,
                 link: Hashable, close: Callable[[], None] | None = None):
        self.write = write
        self.close = close  # drops the client (a TCP one), for Faults.close_after_items
        self.link = link  # the vehicle's serial port: its stream rates outlive a client
        self.parser = mavlink2.MAVLink(None, srcSystem=sysid, srcComponent=1)
        self.parser.robust_parsing = True  # bad CRC or signature -> BAD_DATA, not an exception
        if key is not None:
            # a vehicle that requires signing drops unsigned or wrongly signed messages
            # (GCS_Signing.cpp GCS_MAVLINK::signature_check / accept_unsigned_callback)
            self.parser.signing.secret_key = key
            self.parser.signing.timestamp = _signing_timestamp()


class VehicleRunner:
    """One vehicle between its clients: faults each way, signing, periodic telemetry."""

    def __init__(self, vehicle: Vehicle, *, faults: Faults, signing_key: bytes | None,
                 rng: np.random.Generator, loop: asyncio.AbstractEventLoop,
                 clock: Callable[[], float] | None = None):
        self.vehicle = vehicle
        self.clock = clock or loop.time
        self.faults = faults
        self.key = signing_key
        self.loop = loop
        self.up = FaultyPipe.up(faults, rng)
        self.down = FaultyPipe.down(faults, rng)
        self.packer = mavlink2.MAVLink(None, srcSystem=vehicle.sysid, srcComponent=vehicle.compid)
        if signing_key is not None:
            self.packer.signing.secret_key = signing_key
            self.packer.signing.sign_outgoing = True
            self.packer.signing.timestamp = _signing_timestamp()
        self.attachments: list[Attachment] = []
        self.items_received = 0  # MISSION_ITEM_INTs, for Faults.close_after_items
        self.dead = False  # killed (Simulator.kill): no more flying, sending or answering
        self.truth: list | None = None  # (t, lat, lon, alt AMSL) each tick, when recorded

    def attach(self, write: Callable[[bytes], None], link: Hashable = "SERIAL0", *,
               close: Callable[[], None] | None = None) -> Attachment:
        att = Attachment(write, sysid=self.vehicle.sysid, key=self.key, link=link,
                          close=close)
        self.vehicle.link(link, self.clock())
        self.attachments.append(att)
        return att

    def detach(self, att: Attachment) -> None:
        if att in self.attachments:
            self.attachments.remove(att)

    def _later(self, delay: float, fn, *args) -> None:
        if delay > 0:
            self.loop.call_later(delay, fn, *args)
        else:
            fn(*args)

    def feed(self, att: Attachment, data: bytes) -> None:
        """Bytes from a client: parse, then each message through the uplink's faults."""
        if self.faults.silent or self.dead:
            return
        for msg in att.parser.parse_buffer(data) or []:
            if msg.get_type() == "BAD_DATA":
                continue
            routes = self.up.route(msg)
            if self.key is not None:
                # a duplicated signed frame repeats its timestamp: the signature check
                # rejects the replay (MAVLink signing, libraries/GCS_MAVLink/GCS_Signing.cpp)
                routes = routes[:1]
            for delay, m in routes:
                self._later(delay, self._handle, att, m)

    def _handle(self, att: Attachment, msg) -> None:
        if att not in self.attachments or self.faults.mute:
            return
        limit = self.faults.close_after_items
        if limit is not None and msg.get_type() == "MISSION_ITEM_INT":
            self.items_received += 1
            if self.items_received > limit and att.close is not None:
                self.detach(att)
                att.close()  # the link drops mid-upload
                return
        # the flight stepped up to now first, so that a command takes effect when it
        # arrives and not at the last tick: with a time scale a tick (20 ms of ours) is
        # a long time of the copters' (0.4 s at 20x), and three AUTOs of one burst that
        # straddled a tick started 0.4 s apart, a copter 0.8 m off its slot
        self.tick()
        self._send(att, self.vehicle.handle(msg, self.clock(), att.link))

    def _send(self, att: Attachment, msgs: list) -> None:
        # a port set to MAVLink 1 (SERIALn_PROTOCOL 1, read at boot as ArduPilot does)
        v1 = self.faults.mavlink1 or self.vehicle.autopilot.params.get(
            f"{att.link}_PROTOCOL") == 1
        for msg in msgs:
            if v1 and msg.get_msgId() > 255:
                continue  # MAVLink 1 cannot carry it
            buf = bytes(msg.pack(self.packer, force_mavlink1=v1))
            self.packer.seq = (self.packer.seq + 1) % 256
            for delay, b in self.down.route(buf):
                self._later(delay, self._write, att, b)

    def _write(self, att: Attachment, data: bytes) -> None:
        if att in self.attachments:
            try:
                att.write(data)
            except (OSError, RuntimeError):
                self.detach(att)

    def tick(self) -> None:
        if self.dead:
            return
        now = self.clock()
        out = self.vehicle.tick(now)
        if self.truth is not None:
            self.truth.append((now, *self.vehicle.true_position(now)))
        if self.faults.silent:
            return
        for att in list(self.attachments):
            msgs = out.get(att.link, [])
            if self.faults.mute:  # a muted vehicle still streams, but answers nothing
                msgs = [m for m in msgs if m.get_type() not in _ANSWERS]
            self._send(att, msgs)
