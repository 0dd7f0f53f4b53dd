"""The vehicles of a flight on their links, and doing one thing on all of them at once."""

from __future__ import annotations

from collections.abc import Callable, Sequence

from .. import clock
from ..link.discovery import describe_missing, discover, mavlink1_problem
from ..link.endpoints import LinkError, open_links
from .vehicle import FlightVehicle


class Fleet:
    """The vehicles of a flight on their links: open, discover by HEARTBEAT, close.

    ``with Fleet(names, sysids, urls) as fleet:`` gives ``fleet.vehicles``, one
    :class:`FlightVehicle` per requested id, in order.
    """

    def __init__(self, names: Sequence[str], sysids: Sequence[int], urls: Sequence[str], *,
                 signing_key: bytes | None = None, discover_timeout_s: float = 5.0,
                 on_position: Callable | None = None, on_photo: Callable | None = None,
                 position_hz: float = 10.0, status_hz: float = 2.0) -> None:
        self.names, self.sysids, self.urls = list(names), list(sysids), list(urls)
        self.position_hz, self.status_hz = position_hz, status_hz
        self.signing_key, self.discover_timeout_s = signing_key, discover_timeout_s
        self.on_position, self.on_photo = on_position, on_photo
        self.links: list = []
        self.vehicles: list[FlightVehicle] = []

    def __enter__(self) -> Fleet:
        self.links = open_links(self.urls, signing_key=self.signing_key,
                                connect_timeout_s=self.discover_timeout_s)
        try:
            found, missing = discover(self.links, self.sysids, timeout_s=self.discover_timeout_s)
            if missing:
                raise LinkError("; ".join(describe_missing(s, self.links, self.discover_timeout_s)
                                          for s in missing))
            old = [s for s in self.sysids if found[s].heartbeats[s].mavlink1]
            if old:  # said at once, not found out by a time-out later
                raise LinkError("; ".join(mavlink1_problem(s, found[s].url) for s in old))
            self.vehicles = [FlightVehicle(n, s, found[s], on_position=self.on_position,
                                           on_photo=self.on_photo, position_hz=self.position_hz,
                                           status_hz=self.status_hz)
                             for n, s in zip(self.names, self.sysids)]
        except BaseException:
            self.__exit__()
            raise
        return self

    def __exit__(self, *exc) -> None:
        for v in self.vehicles:
            v.close()
        for link in self.links:
            link.close()


def concurrently(fn: Callable, args: Sequence) -> list:
    """``fn(arg)`` for every arg at once (one thread each); after all have finished,
    re-raises the first error."""
    with clock.Executor(max(1, len(args))) as pool:
        futures = [pool.submit(fn, a) for a in args]
        errors = [f.exception() for f in futures]
    for e in errors:
        if e is not None:
            raise e
    return [f.result() for f in futures]
