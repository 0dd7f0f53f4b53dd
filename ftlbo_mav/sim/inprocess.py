"""Emulated copters inside the ground station's process, on its virtual clock.

:class:`InProcessSimulator` is :class:`~ftlbo_mav.sim.server.Simulator` without sockets:
the same vehicles (:class:`~ftlbo_mav.sim.runner.VehicleRunner`: the same faults,
variation, wind, GPS error and truth record), stepped every 20 ms of a
:class:`~ftlbo_mav.clock.VirtualClock` by a call the clock makes in its turn. The ground
station reaches vehicle i at ``emu:KEY/i`` (its SERIAL1 at ``emu:KEY/i/SERIAL1``; all
of them on one shared link, through the telemetry radio if there is one, at
``emu:KEY/link``: :class:`~.server.SharedLink`), a
connection string that :func:`~ftlbo_mav.link.addresses.check_url` and
:class:`~ftlbo_mav.link.endpoints.Link` take like ``tcp:HOST:PORT``: pymavlink's own
parser reads the vehicles' bytes, so ``fly`` and ``upload`` run unchanged. A command is
handled the moment it is written (the copters first stepped up to that instant, as
over TCP to SITL, whose 400 Hz loop answers within 2.5 ms).

A flight on it costs only its computation: ``ftlbo-mav risk`` flies each flight this way.
"""

from __future__ import annotations

import heapq
import itertools
import threading
from collections.abc import Callable, Sequence
from typing import Self

import numpy as np
from pymavlink import mavutil

from .. import clock
from ..ardupilot import flight_path
from ..ardupilot.compiled import follower_ready
from ..link import addresses, endpoints
from .radio import RadioOptions, SharedRadio
from .runner import VehicleRunner
from .server import TICK_S, SharedLink, Simulator

_keys = itertools.count(1)


class _Connection(mavutil.mavfile):
    """The ground station's end of one port of one emulated vehicle (a pymavlink
    connection: the Link reads and writes it as a TCP one)."""

    def __init__(self, sim: InProcessSimulator, url: str, *, source_system: int,
                 source_component: int) -> None:
        super().__init__(None, url, source_system=source_system,
                         source_component=source_component, use_native=False)
        self._sim = sim
        self._buf = bytearray()
        self._data = clock.Event()
        self.closed = False
        # set by the Link that reads this connection: it takes what arrives at once, in
        # the emulator's turn (its reader thread is not woken for every tick's reports)
        self.on_data: Callable[[], None] | None = None
        # the vehicle's side, set by whoever opens it: what the ground station writes
        # goes to ``send``; ``detach`` lets go of the vehicle(s)
        self.send: Callable[[bytes], None] = lambda _data: None
        self.detach: Callable[[], None] = lambda: None
        self.runner: VehicleRunner | None = None  # one vehicle's port (not the shared link)

    # the vehicle's side (the emulator thread, or whoever wrote to it)
    def _incoming(self, data: bytes) -> None:
        self._buf += data
        if self.on_data is not None:  # handed over once the emulator's step is done
            self._sim._pending[self] = None
        else:
            self._data.set()

    def _dropped(self) -> None:
        self.closed = True
        if self.on_data is not None:  # the link reads it (and finds it closed) at once
            self._sim._pending[self] = None
        self._data.set()

    # pymavlink's side
    def pending(self) -> bool:
        """Bytes not yet parsed, here or in pymavlink's parser (a message may be in
        them), or a close not yet noticed."""
        return bool(self._buf) or self.mav.buf_len() > 0 or self.closed

    def select(self, timeout: float) -> bool:
        return self._data.wait(timeout)

    def recv(self, n: int | None = None) -> bytes:
        if not self._buf:
            self._data.clear()
            if self.closed:
                self.handle_disconnect()
            return b""
        out = bytes(self._buf)
        self._buf.clear()
        self._data.clear()
        return out

    def write(self, buf) -> None:
        if self.closed:
            raise ConnectionResetError(f"{self.address}: closed by the vehicle")
        with self._sim.lock:
            self.send(bytes(buf))
            self._sim._hand_over()

    def close(self) -> None:
        if not self.closed:
            self.closed = True
            with self._sim.lock:
                self.detach()


class InProcessSimulator:
    """N emulated copters in this process, on the current :class:`VirtualClock`.

    Takes :class:`~ftlbo_mav.sim.server.Simulator`'s vehicle settings (``homes``,
    ``faults``, ``options``, ``seed``, ``vary``, ``wind``, ``first_sysid``); with
    ``shared_link`` or a ``radio`` (:class:`~.radio.RadioOptions`, its frames timed on
    the virtual clock to the instant) all of them also speak on one connection,
    :attr:`link_url`, as :class:`~.server.Simulator`'s UDP link; ``radio.counts`` says
    what went over it. Use inside
    ``with VirtualClock():`` as ``with InProcessSimulator(...) as sim:``; ``urls`` and
    ``serial1_urls`` are its connection strings, :meth:`kill` ends a vehicle as a killed
    SITL process ends."""

    def __init__(self, *, homes: Sequence[tuple[float, float, float]],
                 shared_link: bool = False, radio: RadioOptions | None = None,
                 **settings) -> None:
        self.config = Simulator(homes=homes, base_port=0, **settings)
        self.radio_options = radio
        self.radio: SharedRadio | None = None
        self._want_shared = shared_link or radio is not None
        self._shared: SharedLink | None = None
        self._shared_to: _Connection | None = None
        self.key = f"emu:{next(_keys)}"
        self.lock = threading.Lock()  # the vehicles: stepped by one thread, written by others
        self._later: list = []
        self._order = itertools.count()
        self._running = False
        self._connections: list[_Connection] = []
        # connections with bytes to hand over, in the order they came (a tick's messages
        # are read at once, not one by one)
        self._pending: dict[_Connection, None] = {}

    @property
    def runners(self) -> list[VehicleRunner]:
        return self.config.runners

    @property
    def vehicles(self):
        return [r.vehicle for r in self.runners]

    @property
    def urls(self) -> list[str]:
        return [f"{self.key}/{i}" for i in range(len(self.runners))]

    @property
    def serial1_urls(self) -> list[str]:
        return [f"{self.key}/{i}/SERIAL1" for i in range(len(self.runners))]

    @property
    def link_url(self) -> str | None:
        """The shared link's connection string (with ``shared_link`` or a ``radio``)."""
        return f"{self.key}/link" if self._want_shared else None

    # -- lifetime
    def __enter__(self) -> Self:
        vc = clock.virtual()
        if vc is None:
            raise RuntimeError("InProcessSimulator runs on a virtual clock: use it inside "
                               "`with VirtualClock():`")
        self.config.make_runners(self, clock.monotonic, clock.monotonic(),
                                 utc_offset_s=vc.utc_offset)
        # the simulated clock waits for the compiled follower's loading; while its machine
        # code is not cached (a first run after an install) it is compiled in the
        # background and the copters follow stepwise meanwhile (the same arithmetic)
        compiled = follower_ready() or not flight_path.compile_in_background()
        for v in self.vehicles:
            v.autopilot.compiled = compiled
        if self._want_shared:
            if self.radio_options is not None:
                self.radio = SharedRadio(self.radio_options,
                                         np.random.default_rng([self.config.seed, 0x52]))
            self._shared = SharedLink(self.runners, self._to_ground, radio=self.radio,
                                      clock=clock.monotonic, later=self._later_exactly)
        addresses.IN_PROCESS[self.key] = self._connect
        self._running = True
        vc.call_later(0.0, self._tick, name=f"{self.key} emulator")
        return self

    def __exit__(self, *exc) -> None:
        addresses.IN_PROCESS.pop(self.key, None)
        self._running = False
        for c in list(self._connections):
            c._dropped()
        self._pending.clear()

    def _tick(self) -> None:
        """One step of every vehicle, then the next in :data:`TICK_S`: a call the clock
        makes in its turn (no thread of its own: the step costs no thread switch)."""
        if not self._running:
            return
        now = clock.monotonic()
        with self.lock:
            while self._later and self._later[0][0] <= now:
                _t, _o, fn, args = heapq.heappop(self._later)
                fn(*args)
            for r in self.runners:
                r.tick()
            if self._shared is not None:
                self._shared.tick()
            self._hand_over()
        clock.call_later(TICK_S, self._tick, name=f"{self.key} emulator")

    def _later_exactly(self, delay: float, fn: Callable, *args) -> None:
        """``fn(*args)`` ``delay`` from now, at that instant (a frame's arrival), not at the
        next step: a scheduled call of the clock's, with the vehicles still."""
        def call() -> None:
            if self._running:
                with self.lock:
                    fn(*args)
                    self._hand_over()

        clock.call_later(delay, call, name=f"{self.key} shared link")

    def _hand_over(self) -> None:
        """What the vehicles wrote, read by the links now (still the same instant)."""
        while self._pending:
            conn = next(iter(self._pending))
            del self._pending[conn]
            if conn.on_data is not None:
                conn.on_data()

    def call(self, fn: Callable[[], object]):
        """``fn()`` with the vehicles still (between two steps) and its result: inspection,
        as :meth:`Simulator.call <ftlbo_mav.sim.server.Simulator.call>`."""
        with self.lock:
            return fn()

    # -- the runners' loop (VehicleRunner: what a fault delays)
    def call_later(self, delay: float, fn: Callable, *args) -> None:
        heapq.heappush(self._later, (clock.monotonic() + delay, next(self._order), fn, args))

    # -- the ground station's side
    def _connect(self, url: str, *, source_system: int, source_component: int) -> _Connection:
        parts = url[len(self.key) + 1:].split("/")
        if parts == ["link"]:
            return self._connect_link(url, source_system=source_system,
                                      source_component=source_component)
        try:
            index = int(parts[0])
            runner = self.runners[index]
        except (ValueError, IndexError):
            raise endpoints.LinkError(f"{url}: no such emulated vehicle "
                                      f"({len(self.runners)} in {self.key})") from None
        link = parts[1] if len(parts) > 1 else "SERIAL0"
        if link not in ("SERIAL0", "SERIAL1") or len(parts) > 2:
            raise endpoints.LinkError(f"{url}: expected {self.key}/INDEX[/SERIAL1] "
                                      f"or {self.key}/link")
        if runner.dead:
            raise ConnectionRefusedError(f"{url}: the vehicle is gone")
        with self.lock:
            conn = _Connection(self, url, source_system=source_system,
                               source_component=source_component)
            att = runner.attach(conn._incoming, link, close=conn._dropped)
            conn.runner = runner
            conn.send = lambda data: runner.feed(att, data)
            conn.detach = lambda: runner.detach(att)
            self._hand_over()
        self._connections.append(conn)
        return conn

    def _connect_link(self, url: str, *, source_system: int,
                      source_component: int) -> _Connection:
        """The shared link (:class:`~.server.SharedLink`, through the radio if there is
        one): every vehicle's frames on one connection, one at a time."""
        if self._shared is None:
            raise endpoints.LinkError(f"{url}: this emulator has no shared link "
                                      "(shared_link or radio)")
        if self._shared_to is not None and not self._shared_to.closed:
            raise ConnectionRefusedError(f"{url}: the shared link is in use")
        with self.lock:
            conn = _Connection(self, url, source_system=source_system,
                               source_component=source_component)
            conn.send = self._shared.from_ground
            self._shared_to = conn
            self._hand_over()
        self._connections.append(conn)
        return conn

    def _to_ground(self, data: bytes) -> None:
        """A frame from the shared link to the ground station's connection, if one is
        open (a link nobody listens to, as a UDP output)."""
        conn = self._shared_to
        if conn is not None and not conn.closed:
            conn._incoming(data)

    # -- faults
    def drop(self, index: int) -> None:
        """Vehicle ``index``'s connections drop (a TCP bridge that restarts): it flies on
        and takes new ones."""
        with self.lock:
            runner = self.runners[index]
            for c in self._connections:
                if c.runner is runner and not c.closed:
                    c.detach()
                    c._dropped()
            self._hand_over()

    def kill(self, index: int) -> None:
        """Vehicle ``index`` dies as a killed SITL process does: its connections close, it
        refuses new ones, it neither flies nor says anything again."""
        with self.lock:
            self.runners[index].dead = True
            for c in self._connections:
                if c.runner is self.runners[index]:
                    c._dropped()
            self._hand_over()
