"""Relay between the vehicles and the ground station the operator already uses.

Every message from the vehicles' links is passed on, unchanged, to the ground station's
endpoint (``udpout:127.0.0.1:14550`` for a Mission Planner or QGroundControl on this
machine); what the ground station sends comes back to the link of the vehicle it is
addressed to, or to every link when it is addressed to everyone. So the operator sees
the swarm and can take over while ftlbo-mav flies it.
"""

from __future__ import annotations

import threading
from collections.abc import Sequence

from pymavlink import mavutil

from ..link.endpoints import LinkError


class Forwarder:
    """``with Forwarder(url, links, sysid_links):`` relays until the block ends.

    ``sysid_links``: the link each vehicle speaks on (from discovery).
    """

    def __init__(self, url: str, links: Sequence, sysid_links: dict[int, object]) -> None:
        self.url = url
        self.links = list(links)
        self.sysid_links = dict(sysid_links)
        self.to_gcs = 0
        self.to_vehicles = 0
        try:
            self._conn = mavutil.mavlink_connection(url, dialect="ardupilotmega")
        except (OSError, ValueError) as exc:
            raise LinkError(f"--forward {url}: cannot open: {exc}") from None
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._from_gcs, name="forward", daemon=True)

    def __enter__(self) -> Forwarder:
        for link in self.links:
            link.taps.append(self._to_gcs)
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        for link in self.links:
            if self._to_gcs in link.taps:
                link.taps.remove(self._to_gcs)
        self._stop.set()
        self._thread.join(timeout=2.0)
        self._conn.close()

    def _to_gcs(self, msg) -> None:
        if msg.get_srcSystem() not in self.sysid_links:
            return  # only the vehicles we fly, not our own link's echo or others
        try:
            with self._lock:
                self._conn.write(msg.get_msgbuf())
            self.to_gcs += 1
        except OSError:
            pass  # no ground station listening yet

    def _from_gcs(self) -> None:
        while not self._stop.is_set():
            try:
                msg = self._conn.recv_match(blocking=True, timeout=0.1)
            except (OSError, ValueError):
                continue
            if msg is None or msg.get_type() == "BAD_DATA":
                continue
            target = getattr(msg, "target_system", 0)
            if target == 0:
                links = self.links
            elif target in self.sysid_links:
                links = [self.sysid_links[target]]
            else:
                continue
            for link in links:
                try:
                    link.write_raw(msg.get_msgbuf())
                    self.to_vehicles += 1
                except OSError:
                    pass
