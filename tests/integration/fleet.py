"""One test code path, two back ends: the emulator, or ArduPilot SITL when ARDUPILOT_SITL
names an ``arducopter`` binary. Tests ask for vehicles through :func:`vehicles`; the ones
that need fault injection say so and are skipped on SITL.
"""

from __future__ import annotations

import os
import socket
import tempfile
from collections.abc import Callable
from contextlib import contextmanager
from dataclasses import dataclass, field

import pytest
from pymavlink import mavutil

from ftlbo_mav.clock import VirtualClock
from ftlbo_mav.link.addresses import in_process
from ftlbo_mav.sim.faults import Faults
from ftlbo_mav.sim.homes import default_homes
from ftlbo_mav.sim.inprocess import InProcessSimulator
from ftlbo_mav.sim.radio import SharedRadio
from ftlbo_mav.sim.router import RadioRouter
from ftlbo_mav.sim.server import Simulator
from ftlbo_mav.sim.vehicle import VehicleOptions

SITL_BINARY = os.environ.get("ARDUPILOT_SITL")
# a second release's binary for a fleet of two (ArduCopter 4.6.x; the first is 4.5.x)
SITL_BINARY_46 = os.environ.get("ARDUPILOT_SITL_4_6")
BACKEND = "sitl" if SITL_BINARY else "emulator"
FAST = VehicleOptions(heartbeat_s=0.2)  # quicker discovery; protocol timings stay ArduPilot's


@dataclass
class Fleet:
    """Running vehicles: ``urls[i]`` reaches system id i+1, ``serial1_urls[i]`` its
    second port (SITL's SERIAL1: another station, a pilot); ``kill(i)`` ends vehicle i
    as a crash does (its SITL process killed by pid, or the emulator's ``kill``);
    ``sim`` is the emulator, if any; ``time_scale``: the vehicles' seconds per second of
    the test's clock (:mod:`ftlbo_mav.clock`: 1 on a virtual clock)."""

    urls: list[str]
    sim: Simulator | None = None
    udp_url: str | None = None
    extra: dict = field(default_factory=dict)
    serial1_urls: list[str] = field(default_factory=list)
    kill: Callable[[int], None] | None = None
    radio: SharedRadio | None = None  # the shared link's radio, if any
    time_scale: float = 1.0

    def missions(self) -> list[list]:
        """What each emulated vehicle stores (emulator only)."""
        return self.sim.call(lambda: [list(v.missions.items) for v in self.sim.vehicles])


def connect(url: str, *, source_system: int):
    """A pymavlink connection to ``url`` (a TCP port, or an in-process vehicle's ``emu:``
    one) for a test's own station; read it with ``recv_match(blocking=False)`` and
    ``select(timeout)``, which wait on the test's clock."""
    opened = in_process(url)
    if opened is not None:
        return opened(url, source_system=source_system, source_component=0)
    return mavutil.mavlink_connection(url, source_system=source_system,
                                      dialect="ardupilotmega", retries=10)


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@contextmanager
def _behind(fleet: Fleet, radio, *, seed: int, speedup: float):
    """``fleet``'s TCP vehicles behind one :class:`RadioRouter` of ``radio`` (its
    ``udp_url`` and ``radio`` set), or as they are when ``radio`` is None."""
    if radio is None:
        yield
        return
    with RadioRouter(fleet.urls, ("127.0.0.1", free_udp_port()), radio, seed=seed,
                     time_scale=speedup) as r:
        fleet.udp_url, fleet.radio = r.udp_url, r.radio
        yield


@contextmanager
def _in_process(**settings):
    """An :class:`InProcessSimulator` and the virtual clock it runs on (the calling thread
    with it until the block ends)."""
    with VirtualClock(), InProcessSimulator(**settings) as sim:
        yield sim


@contextmanager
def vehicles(count: int = 3, *, faults=None, options=None, signing_key: bytes | None = None,
             shared_link: bool = False, seed: int = 0, homes=None, speedup: float = 1.0,
             params: dict[str, float] | None = None, radio=None, router: bool = False,
             copters: list[tuple[str, dict[str, float]]] | None = None,
             virtual: bool = False):
    """``count`` vehicles, system ids 1..count, ready for uploads; ``homes`` (default a
    row at SITL's default location) and ``speedup`` (the emulator's time scale, SITL's
    --speedup) for flights; ``params``: parameters every vehicle boots with (SITL: a
    defaults file after its own; CAM1_TYPE, for one, is read at boot); ``radio``: the
    shared link is one telemetry radio (:mod:`ftlbo_mav.sim.radio`): the emulator's own,
    or with ``router`` (always on SITL) a :class:`~ftlbo_mav.sim.router.RadioRouter`
    between the vehicles' TCP ports and the ground station. ``copters``: per vehicle its
    release (``"4.5.6"`` or ``"4.6.3"``) and the parameters it boots with (a fleet of
    different copters; on SITL a 4.6 copter needs ARDUPILOT_SITL_4_6). ``virtual``: on the
    emulator, the copters inside this process and the test with them on a virtual clock
    (:mod:`ftlbo_mav.sim.inprocess`, ``emu:`` URLs; ``speedup`` unused, ``time_scale``
    1): the flight costs only its computation, for a test whose wall time is not what it
    tests; the test's waits go through :mod:`ftlbo_mav.clock` (no sockets, threads or
    sleeps of its own; :func:`connect` for a station of its own). SITL ignores it."""
    homes = default_homes(count) if homes is None else homes
    emulator_only = faults is not None or options is not None or signing_key or shared_link
    if BACKEND == "sitl":
        if emulator_only:
            pytest.skip("needs the emulator's fault injection")
        from sitl import SitlSwarm

        extra = tempfile.NamedTemporaryFile("w", suffix=".parm", delete=False)
        with extra:
            extra.write("".join(f"{k} {v:g}\n" for k, v in (params or {}).items()))
        binaries, own = None, None
        if copters is not None:
            if any(r.startswith("4.6") for r, _p in copters) and not SITL_BINARY_46:
                pytest.skip("a 4.6 copter on SITL needs ARDUPILOT_SITL_4_6")
            binaries = [SITL_BINARY_46 if r.startswith("4.6") else None for r, _p in copters]
            own = [values for _r, values in copters]
        try:
            with SitlSwarm(binary=SITL_BINARY, homes=homes, speedup=speedup,
                           defaults=[extra.name] if params else (), binaries=binaries,
                           instance_params=own) as swarm:
                serial1 = [f"tcp:127.0.0.1:{int(u.rsplit(':', 1)[1]) + 2}" for u in swarm.urls]
                fleet = Fleet(urls=swarm.urls, serial1_urls=serial1,
                              kill=lambda i: swarm.processes[i].kill(), time_scale=speedup)
                with _behind(fleet, radio, seed=seed, speedup=speedup):
                    yield fleet
        finally:
            os.unlink(extra.name)
        return
    own_radio = radio is not None and not router
    udp_out = ("127.0.0.1", free_udp_port()) if shared_link or own_radio else None
    if copters is not None:
        from ftlbo_mav.sim.commands import fleet_options

        base = options if options is not None else FAST
        options = [fleet_options(base, 1, firmware=[release])[0] for release, _p in copters]
    if virtual:
        if router:
            raise ValueError("a virtual clock's copters have no TCP ports for a router")
        with _in_process(homes=homes, faults=faults if faults is not None else Faults(),
                         options=options if options is not None else FAST,
                         signing_key=signing_key, seed=seed, shared_link=shared_link,
                         radio=radio) as sim:
            if params:
                sim.call(lambda: [v.autopilot.params.update(params) for v in sim.vehicles])
            for v, (_r, values) in zip(sim.vehicles if copters else (), copters or ()):
                sim.call(lambda v=v, values=values: v.autopilot.params.update(values))
            yield Fleet(urls=sim.urls, sim=sim, serial1_urls=sim.serial1_urls, kill=sim.kill,
                        udp_url=sim.link_url, radio=sim.radio)
        return
    with Simulator(homes=homes, base_port=0, udp_out=udp_out, time_scale=speedup,
                   faults=faults if faults is not None else Faults(),
                   options=options if options is not None else FAST,
                   signing_key=signing_key, seed=seed,
                   radio=radio if own_radio else None) as sim:
        if params:
            sim.call(lambda: [v.autopilot.params.update(params) for v in sim.vehicles])
        for v, (_r, values) in zip(sim.vehicles if copters else (), copters or ()):
            sim.call(lambda v=v, values=values: v.autopilot.params.update(values))
        fleet = Fleet(urls=sim.urls, sim=sim, udp_url=sim.udp_url,
                      serial1_urls=sim.serial1_urls, kill=sim.kill, radio=sim.radio,
                      time_scale=speedup)
        with _behind(fleet, None if own_radio else radio, seed=seed, speedup=speedup):
            yield fleet
