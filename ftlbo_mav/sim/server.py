"""Emulated ArduCopters on the network: TCP like SITL, or one shared UDP link.

:class:`Simulator` runs N :class:`~ftlbo_mav.sim.vehicle.Vehicle` s in an asyncio loop
(in a background thread when used as a context manager; in the foreground for
``ftlbo-mav sim``). Vehicle i (system id i+1) listens on TCP ``127.0.0.1:5760 + 10*i``
like SITL's instance i, serves one client at a time and takes the next one after it
disconnects. With ``udp_out`` all vehicles also speak on one UDP socket that sends to
that address, as a telemetry radio or a router's UDP output does. Each vehicle's bytes
go through its :class:`~.runner.VehicleRunner` (parsing, signing, faults).
"""

from __future__ import annotations

import asyncio
import signal
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Self

import numpy as np

from .faults import Faults
from .physics import hovering, varied
from .radio import DOWN, RADIO_STATUS_S, UP, RadioOptions, SharedRadio, StatusSender
from .runner import Attachment, VehicleRunner
from .vehicle import Vehicle, VehicleOptions
from .wind import Gusts, Wind

TICK_S = 0.02
MAX_TIME_SCALE = 100.0
"""The fastest the vehicles' clock may run: every tick steps each vehicle's flight in
20 ms steps (sim/autopilot.py), so 100x is 100 steps per vehicle and tick; far faster
and a tick never ends, and nothing (not even SIGTERM) is handled."""
class SharedLink:
    """Every vehicle on one link to the ground station; what comes from the ground goes to
    all (as a multipoint radio's or a router's UDP output). Transport-free: ``to_ground``
    sends one frame to the ground station, ``later(delay_s, fn, *args)`` calls ``fn``
    ``delay_s`` of the vehicles' seconds from now, ``clock()`` is the vehicles' clock; the
    UDP socket (:class:`_SharedUdp`) and the in-process emulator
    (:mod:`.inprocess`) give them.

    With a ``radio`` (:class:`~ftlbo_mav.sim.radio.SharedRadio`) every frame each way
    goes through its air time, buffers, latency and losses; each radio reports
    RADIO_STATUS once a second to its own end, as SiK radios do (system id 51 '3',
    component 68 'D'): the ground's to the ground station, each copter's to its
    autopilot, whose streams slow down by ArduPilot's flow control."""

    def __init__(self, runners: Sequence[VehicleRunner], to_ground: Callable[[bytes], None], *,
                 radio: SharedRadio | None, clock: Callable[[], float],
                 later: Callable[..., None]) -> None:
        self.runners, self.to_ground = runners, to_ground
        self.radio, self.clock, self.later = radio, clock, later
        self._next_status = 0.0
        self._status = None if radio is None else StatusSender(radio)
        self.atts: list[tuple[VehicleRunner, Attachment]] = [
            (r, r.attach(lambda d, s=r.vehicle.sysid: self._down(d, s), link="UDP"))
            for r in runners]

    def _after(self, arrival: float | None, fn, *args) -> None:
        """``fn(*args)`` when a frame sent now arrives (the vehicles' clock), if it does."""
        if arrival is not None:
            self.later(max(0.0, arrival - self.clock()), fn, *args)

    def _down(self, data: bytes, sysid: int) -> None:
        if self.radio is None:
            self.to_ground(data)
        else:
            self._after(self.radio.send(DOWN, len(data), self.clock(), sysid),
                        self.to_ground, data)

    def from_ground(self, data: bytes) -> None:
        if self.radio is None:
            self._feed(data)
        else:
            self._after(self.radio.send(UP, len(data), self.clock()), self._feed, data)

    def _feed(self, data: bytes) -> None:
        for r, att in self.atts:
            r.feed(att, data)

    def tick(self) -> None:
        """Each radio's RADIO_STATUS, once a second."""
        if self.radio is None:
            return
        now = self.clock()
        if now < self._next_status:
            return
        self._next_status = now + RADIO_STATUS_S
        self.to_ground(self._status.frame(self.radio.txbuf_pct(UP, now)))
        for r, att in self.atts:
            r.feed(att, self._status.frame(self.radio.txbuf_pct(DOWN, now, r.vehicle.sysid)))


class _SharedUdp(asyncio.DatagramProtocol):
    """The :class:`SharedLink` on one UDP socket, sending to ``target``."""

    def __init__(self, runners: Sequence[VehicleRunner], target: tuple[str, int], *,
                 radio: SharedRadio | None, clock: Callable[[], float], scale: float) -> None:
        self.runners, self.target = runners, target
        self.radio, self.clock, self.scale = radio, clock, scale
        self.transport = None
        self.link: SharedLink | None = None

    def connection_made(self, transport) -> None:
        self.transport = transport
        loop = asyncio.get_running_loop()
        self.link = SharedLink(
            self.runners, self._send, radio=self.radio, clock=self.clock,
            later=lambda delay, fn, *args: loop.call_later(delay / self.scale, fn, *args))

    def _send(self, data: bytes) -> None:
        if not self.transport.is_closing():
            self.transport.sendto(data, self.target)

    def datagram_received(self, data: bytes, addr) -> None:
        self.link.from_ground(data)

    def tick(self) -> None:
        if self.link is not None:
            self.link.tick()

    def error_received(self, exc) -> None:  # nobody listening yet: ICMP port unreachable
        pass


class Simulator:
    """N emulated ArduCopters, system ids ``first_sysid``.., two TCP ports each.

    ``homes``: ``(lat_deg, lon_deg, alt_m AMSL)`` per vehicle. ``base_port``: vehicle i
    listens on ``base_port + 10*i`` (SERIAL0) and, as SITL's second serial port does,
    ``base_port + 10*i + 2`` (SERIAL1: another ground station, a pilot's telemetry);
    ``0`` lets the system choose free ports (tests). Faults in flight, for tests:
    :meth:`kill` (the vehicle's process dies), :meth:`drop_link` (its SERIAL0 link drops
    and comes back).
    ``faults`` / ``options``: one for all vehicles, or one per vehicle. ``seed``: seeds
    the fault decisions. ``time_scale``: the vehicles' clock runs this many times faster
    than the wall clock (flights in tests; link latency stays real). ``vary``: each
    vehicle's flight differs a little, as in a real fleet (a start latency, WPNAV_JERK;
    :func:`~ftlbo_mav.sim.physics.varied`), drawn from ``seed``; off by default. ``wind``:
    a :class:`~ftlbo_mav.sim.wind.Wind` or ``(speed, direction, turbulence)`` as SITL's
    SIM_WIND_SPD/DIR/TURB, each vehicle meeting its own gusts (drawn from ``seed``). Use
    ``with Simulator(...) as sim:`` (background thread) or
    :meth:`run` (foreground, until interrupted). ``urls`` gives the client connection
    strings; ``udp_url`` the shared link's, when ``udp_out`` is set. ``radio``: the shared
    link is one telemetry radio (:mod:`.radio`: air time, buffers, latency, losses);
    ``radio.counts`` says what went over it.
    """

    def __init__(self, *, homes: Sequence[tuple[float, float, float]], base_port: int = 5760,
                 host: str = "127.0.0.1", udp_out: tuple[str, int] | None = None,
                 faults: Faults | Sequence[Faults] | None = None,
                 options: VehicleOptions | Sequence[VehicleOptions] | None = None,
                 signing_key: bytes | None = None, seed: int = 0, first_sysid: int = 1,
                 time_scale: float = 1.0, vary: bool = False, wind=None,
                 radio: RadioOptions | None = None):
        n = len(homes)
        if radio is not None and udp_out is None:
            raise ValueError("a radio is the shared link's: give udp_out too")
        self.radio_options = radio
        self.radio: SharedRadio | None = None
        if not 0 < time_scale <= MAX_TIME_SCALE:
            raise ValueError(f"time_scale must be within (0, {MAX_TIME_SCALE:g}], "
                             f"got {time_scale}")
        self.time_scale = time_scale
        if n < 1:
            raise ValueError("at least one vehicle")
        self.homes = [tuple(h) for h in homes]
        self.host, self.base_port, self.udp_out = host, base_port, udp_out
        faults = Faults() if faults is None else faults
        options = VehicleOptions() if options is None else options
        self.faults = list(faults) if not isinstance(faults, Faults) else [faults] * n
        self.options = list(options) if not isinstance(options, VehicleOptions) else [options] * n
        if len(self.faults) != n or len(self.options) != n:
            raise ValueError("faults and options: one for all vehicles, or one per vehicle")
        if vary:
            self.options = [replace(o, limits=varied(o.limits, np.random.default_rng(
                [seed, 0x7A, i]))) for i, o in enumerate(self.options)]
        # how every ArduCopter hovers where its legs start (physics.hovering)
        self.options = [replace(o, limits=hovering(o.limits, np.random.default_rng(
            [seed, 0x48, i]))) for i, o in enumerate(self.options)]
        self.signing_key, self.seed, self.first_sysid = signing_key, seed, first_sysid
        self.wind = None if wind is None else Wind.parse(wind)
        self.ports: list[int] = []
        self.serial1_ports: list[int] = []
        self.runners: list[VehicleRunner] = []
        self._servers: list[dict] = []  # per vehicle: link -> asyncio server
        self._writers: list[dict] = []  # per vehicle: link -> set of client writers
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None
        self._stopping: asyncio.Event | None = None
        self._clients: dict[asyncio.Task, asyncio.StreamWriter] = {}

    @property
    def urls(self) -> list[str]:
        return [f"tcp:{self.host}:{p}" for p in self.ports]

    @property
    def serial1_urls(self) -> list[str]:
        """Each vehicle's second port (SITL's SERIAL1, TCP 5762 + 10*i)."""
        return [f"tcp:{self.host}:{p}" for p in self.serial1_ports]

    @property
    def udp_url(self) -> str | None:
        return f"udpin:{self.udp_out[0]}:{self.udp_out[1]}" if self.udp_out else None

    @property
    def vehicles(self) -> list[Vehicle]:
        return [r.vehicle for r in self.runners]

    async def _main(self, ready: Callable[[], None]) -> None:
        loop = asyncio.get_running_loop()
        self._stopping = asyncio.Event()
        start, scale = loop.time(), self.time_scale

        def clock() -> float:
            return start + (loop.time() - start) * scale

        # one GPS time for all: the wall clock at start
        self.make_runners(loop, clock, start, utc_offset_s=time.time() - start)
        servers = []
        try:
            for i in range(len(self.runners)):
                self._servers.append({})
                self._writers.append({"SERIAL0": set(), "SERIAL1": set()})
                for link, ports, offset in (("SERIAL0", self.ports, 0),
                                            ("SERIAL1", self.serial1_ports, 2)):
                    port = self.base_port + 10 * i + offset if self.base_port else 0
                    server = await self._listen(i, link, port)
                    servers.append(server)
                    ports.append(server.sockets[0].getsockname()[1])
            udp = shared = None
            if self.udp_out:
                if self.radio_options is not None:
                    self.radio = SharedRadio(self.radio_options,
                                             np.random.default_rng([self.seed, 0x52]))
                shared = _SharedUdp(self.runners, self.udp_out, radio=self.radio, clock=clock,
                                    scale=scale)
                udp, _ = await loop.create_datagram_endpoint(lambda: shared,
                                                             local_addr=(self.host, 0))
            ready()
            while not self._stopping.is_set():
                for r in self.runners:
                    r.tick()
                if shared is not None:
                    shared.tick()
                try:
                    await asyncio.wait_for(self._stopping.wait(), TICK_S)
                except TimeoutError:
                    pass
            if udp is not None:
                udp.close()
        finally:
            for server in [s for d in self._servers for s in d.values()]:
                server.close()
            for writer in self._clients.values():  # clients are dropped, as SITL exiting does
                writer.close()
            await asyncio.gather(*self._clients, return_exceptions=True)
            for s in servers:
                await s.wait_closed()

    def make_runners(self, loop, clock: Callable[[], float], start: float, *,
                     utc_offset_s: float) -> None:
        """The vehicles, booted at ``start`` of ``clock`` (GPS time ``utc_offset_s`` ahead of
        it), each behind its :class:`VehicleRunner`; ``loop.call_later`` runs what a
        fault delays."""
        rngs = [np.random.default_rng([self.seed, i]) for i in range(len(self.homes))]
        for i, home in enumerate(self.homes):
            v = Vehicle(sysid=self.first_sysid + i, home=home, options=self.options[i],
                        boot_time=start, utc_offset_s=utc_offset_s)
            if self.wind is not None and not self.wind.calm:
                v.autopilot.gusts = Gusts(self.wind, np.random.default_rng([self.seed, 0x57, i]),
                                          nav=v.autopilot.nav_params())
            self.runners.append(VehicleRunner(v, faults=self.faults[i], rng=rngs[i], loop=loop,
                                              signing_key=self.signing_key, clock=clock))

    async def _listen(self, i: int, link: str, port: int):
        server = await asyncio.start_server(self._client_handler(self.runners[i], link, i),
                                            self.host, port)
        self._servers[i][link] = server
        return server

    def _client_handler(self, runner: VehicleRunner, link: str, index: int):
        one_at_a_time = asyncio.Lock()

        async def serve(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
            task = asyncio.current_task()
            self._clients[task] = writer
            self._writers[index][link].add(writer)
            try:
                await self._serve(runner, one_at_a_time, reader, writer, link)
            finally:
                del self._clients[task]
                self._writers[index][link].discard(writer)

        return serve

    async def _serve(self, runner: VehicleRunner, one_at_a_time: asyncio.Lock,
                     reader: asyncio.StreamReader, writer: asyncio.StreamWriter,
                     link: str = "SERIAL0") -> None:
        try:
            async with one_at_a_time:  # the next client is served after this one leaves
                if runner.dead:
                    return
                att = runner.attach(writer.write, link, close=writer.close)
                try:
                    while data := await reader.read(4096):
                        runner.feed(att, data)
                except (ConnectionError, OSError):
                    pass
                finally:
                    runner.detach(att)
        finally:
            writer.close()

    # -- background thread (tests, benchmarks)
    def __enter__(self) -> Self:
        started = threading.Event()
        errors: list[BaseException] = []

        def run() -> None:
            loop = asyncio.new_event_loop()
            self._loop = loop
            try:
                loop.run_until_complete(self._main(started.set))
            except Exception as exc:  # noqa: BLE001 - re-raised in the thread that started us
                errors.append(exc)
                started.set()
            finally:
                loop.close()

        self._thread = threading.Thread(target=run, name="ftlbo-mav sim", daemon=True)
        self._thread.start()
        started.wait()
        if errors:
            self._thread.join()
            raise errors[0]
        return self

    def __exit__(self, *exc) -> None:
        if self._loop is not None and self._stopping is not None and self._thread.is_alive():
            self._loop.call_soon_threadsafe(self._stopping.set)
        if self._thread is not None:
            self._thread.join(timeout=5.0)

    def call(self, fn: Callable[[], object]):
        """Run ``fn`` in the simulator's loop thread and return its result (inspection)."""
        fut = asyncio.run_coroutine_threadsafe(_call(fn), self._loop)
        return fut.result(timeout=5.0)

    # -- faults in flight (from another thread: tests)
    def kill(self, index: int) -> None:
        """Vehicle ``index`` dies as a killed SITL process does: its connections close,
        its ports refuse, it neither flies nor says anything again."""

        async def die() -> None:
            self.runners[index].dead = True
            self._close(index, ("SERIAL0", "SERIAL1"))

        asyncio.run_coroutine_threadsafe(die(), self._loop).result(timeout=5.0)

    def drop_link(self, index: int, down_s: float) -> None:
        """Vehicle ``index``'s SERIAL0 link drops (its client is disconnected, the port
        refuses) for ``down_s`` wall seconds, then listens again; the vehicle flies on."""
        port = self.ports[index]

        async def drop() -> None:
            self._close(index, ("SERIAL0",))
            await asyncio.sleep(down_s)
            if not self._stopping.is_set():
                await self._listen(index, "SERIAL0", port)

        asyncio.run_coroutine_threadsafe(drop(), self._loop)

    def _close(self, index: int, links) -> None:
        for link in links:
            server = self._servers[index].pop(link, None)
            if server is not None:
                server.close()
            for writer in list(self._writers[index][link]):
                writer.close()

    # -- foreground (the CLI)
    def run(self, ready: Callable[[], None] = lambda: None) -> None:
        """Serve until interrupted (Ctrl-C) or terminated (SIGTERM), then stop cleanly."""

        def started() -> None:
            loop = asyncio.get_running_loop()
            # Ctrl-C and kill stop the same clean way (a KeyboardInterrupt raised inside
            # the loop could land in a busy step and leave the process hanging)
            loop.add_signal_handler(signal.SIGTERM, self._stopping.set)
            loop.add_signal_handler(signal.SIGINT, self._stopping.set)
            ready()

        try:
            asyncio.run(self._main(started))
        except KeyboardInterrupt:
            pass


async def _call(fn):
    return fn()
