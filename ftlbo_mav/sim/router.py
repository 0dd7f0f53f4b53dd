"""One telemetry radio between a ground station and copters that speak TCP: ArduPilot SITL
behind the swarm's shared link.

Each SITL instance serves its SERIAL0 on TCP (5760 + 10 i); a field swarm's ground station
reaches all of its copters through one radio. :class:`RadioRouter` is that radio: it is
the one client of every copter's TCP port, cuts their byte streams into MAVLink frames
and carries every frame through one :class:`~ftlbo_mav.sim.radio.SharedRadio` (its air
time, buffers, latency, losses, outages) to one UDP address, the ground station's
(``fly --connect udpin:HOST:PORT``); what the ground station sends goes through the same
radio to every copter, as a multipoint radio broadcasts it. Each radio reports
RADIO_STATUS once a second to its own end, as SiK radios do: the ground's to the ground
station, each copter's to its autopilot, whose streams then slow down by ArduPilot's own
flow control (GCS_Common.cpp, ``GCS_MAVLINK::handle_radio_status``).

The same radio model as the emulator's (``ftlbo-mav sim --radio``), so that a flight
through it can be compared on both. ``time_scale``: SITL's ``--speedup`` (the radio is as
fast as the copters' clock). ``python -m sitl --radio good --udp-out HOST:PORT`` runs one.
"""

from __future__ import annotations

import asyncio
import contextlib
import threading
import time
from collections.abc import Sequence
from typing import Self

import numpy as np

from .radio import DOWN, RADIO_STATUS_S, UP, RadioOptions, SharedRadio, StatusSender, split_frames

CONNECT_TIMEOUT_S = 30.0


class RouterError(OSError):
    """A copter's TCP port could not be reached, or the router's UDP socket opened."""


def _address(url: str) -> tuple[str, int]:
    """``tcp:HOST:PORT`` (or ``HOST:PORT``) -> (host, port)."""
    rest = url.removeprefix("tcp:")
    host, _, port = rest.rpartition(":")
    if not host or not port.isdigit():
        raise ValueError(f"{url!r}: a copter's TCP port as tcp:HOST:PORT")
    return host, int(port)


class _Ground(asyncio.DatagramProtocol):
    def __init__(self, router: RadioRouter) -> None:
        self.router = router

    def datagram_received(self, data: bytes, addr) -> None:
        self.router._from_ground(data)

    def error_received(self, exc) -> None:  # nobody listening yet: ICMP port unreachable
        pass


class RadioRouter:
    """Copters at ``vehicle_urls`` (``tcp:HOST:PORT`` each, radio ``i + 1``) behind one
    radio to the ground station at ``udp_out`` ``(host, port)``. Use as a context manager
    (a background thread); :attr:`counts` says what went over the radio."""

    def __init__(self, vehicle_urls: Sequence[str], udp_out: tuple[str, int],
                 options: RadioOptions | None = None, *, seed: int = 0,
                 time_scale: float = 1.0) -> None:
        if not vehicle_urls:
            raise ValueError("no copters to route")
        if not time_scale > 0:
            raise ValueError(f"time_scale must be > 0, got {time_scale!r}")
        self.addresses = [_address(u) for u in vehicle_urls]
        self.udp_out = udp_out
        self.radio = SharedRadio(options or RadioOptions(), np.random.default_rng(seed))
        self.scale = time_scale
        self._status = StatusSender(self.radio)
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._loop.run_forever, name="radio router",
                                        daemon=True)
        self._writers: list[asyncio.StreamWriter] = []
        self._udp = None
        self._tasks: list[asyncio.Task] = []

    @property
    def counts(self):
        return self.radio.counts

    @property
    def udp_url(self) -> str:
        """What the ground station connects with."""
        return f"udpin:{self.udp_out[0]}:{self.udp_out[1]}"

    def clock(self) -> float:
        """The radio's time: the copters' seconds."""
        return time.monotonic() * self.scale

    def __enter__(self) -> Self:
        self._thread.start()
        try:
            asyncio.run_coroutine_threadsafe(self._start(), self._loop).result(
                CONNECT_TIMEOUT_S + 5.0)
        except BaseException:
            self.__exit__(None, None, None)
            raise
        return self

    def __exit__(self, *exc) -> None:
        if self._thread.is_alive():
            with contextlib.suppress(Exception):
                asyncio.run_coroutine_threadsafe(self._stop(), self._loop).result(5.0)
            self._loop.call_soon_threadsafe(self._loop.stop)
            self._thread.join(timeout=5.0)
        self._loop.close()

    async def _start(self) -> None:
        loop = asyncio.get_running_loop()
        for i, (host, port) in enumerate(self.addresses):
            deadline = time.monotonic() + CONNECT_TIMEOUT_S
            while True:
                try:
                    reader, writer = await asyncio.open_connection(host, port)
                    break
                except OSError as exc:
                    if time.monotonic() > deadline:
                        raise RouterError(f"copter {i + 1} at tcp:{host}:{port}: {exc}") \
                            from None
                    await asyncio.sleep(0.2)
            self._writers.append(writer)
            self._tasks.append(loop.create_task(self._from_vehicle(i, reader)))
        self._udp, _ = await loop.create_datagram_endpoint(
            lambda: _Ground(self), local_addr=("127.0.0.1", 0))
        self._tasks.append(loop.create_task(self._report()))

    async def _stop(self) -> None:
        for task in self._tasks:
            task.cancel()
        for writer in self._writers:
            writer.close()
        if self._udp is not None:
            self._udp.close()

    def _after(self, arrival: float | None, fn, *args) -> None:
        """``fn(*args)`` when a frame handed to the radio now arrives, if it does: at that
        instant of the loop's clock (time.monotonic, as :meth:`clock` is), in the radio's
        order. A delay from "now" instead was off by the microseconds between reading the
        clock and the loop's reading it, and frames the radio delivers a microsecond apart
        (in order, each way) went out swapped: on SITL an item sent ahead reached the
        copter before the one it followed (INVALID_SEQUENCE, a resend)."""
        if arrival is not None:
            self._loop.call_at(arrival / self.scale, fn, *args)

    async def _from_vehicle(self, i: int, reader: asyncio.StreamReader) -> None:
        buffer = bytearray()
        while True:
            data = await reader.read(4096)
            if not data:
                return  # the copter's process ended: nothing more from its radio
            buffer += data
            for frame in split_frames(buffer):
                self._after(self.radio.send(DOWN, len(frame), self.clock(), i + 1),
                            self._to_ground, frame)

    def _to_ground(self, frame: bytes) -> None:
        if self._udp is not None and not self._udp.is_closing():
            self._udp.sendto(frame, self.udp_out)

    def _from_ground(self, data: bytes) -> None:
        for frame in split_frames(bytearray(data)):
            self._after(self.radio.send(UP, len(frame), self.clock()), self._to_vehicles, frame)

    def _to_vehicles(self, frame: bytes) -> None:
        for writer in self._writers:
            if not writer.is_closing():
                writer.write(frame)

    async def _report(self) -> None:
        """Each radio's RADIO_STATUS, once a second of the copters' clock."""
        while True:
            now = self.clock()
            self._to_ground(self._status.frame(self.radio.txbuf_pct(UP, now)))
            for i, writer in enumerate(self._writers):
                if not writer.is_closing():
                    writer.write(self._status.frame(self.radio.txbuf_pct(DOWN, now, i + 1)))
            await asyncio.sleep(RADIO_STATUS_S / self.scale)


__all__ = ["RadioRouter", "RouterError"]
