"""Finding the vehicles on the links: discovery by HEARTBEAT and readiness to arm.

:func:`discover` finds which :class:`~.endpoints.Link` each requested system id speaks on
(asking for a HEARTBEAT and the AUTOPILOT_VERSION instead of waiting for them);
:func:`wait_ready` waits for a GPS fix and passing pre-arm checks; the one-line reasons a
vehicle is missing or cannot be used (:func:`describe_missing`, :func:`mavlink1_problem`).
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterable, Sequence

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from .. import clock
from ..ardupilot.streams import READINESS
from .endpoints import Link, LinkDown, LinkError
from .firmware import version_request

HEARTBEAT_ASK_AGAIN_S = 0.4
""":func:`discover` asks the vehicles not heard yet for a HEARTBEAT at once and once more
after this (a lossy radio may lose the first ask), or as soon as the link first hears a
vehicle when it had heard none (a ``udpin`` link learns where to send from the first
packet it receives). ArduPilot sends HEARTBEAT at 1 Hz, so waiting for the last of three
copters took 0.5-1 s of every upload; asked, it answers at once. Each ask also asks for
AUTOPILOT_VERSION (kept in :attr:`Link.versions`), which every command that found the
vehicles asks next (the firmware check): one round trip fewer."""


def heartbeat_request(sysid: int, attempt: int = 0):
    """COMMAND_LONG MAV_CMD_REQUEST_MESSAGE for HEARTBEAT: ArduPilot answers with
    COMMAND_ACK and one HEARTBEAT (GCS_Common.cpp ``handle_command_request_message``; its
    message map has MAVLINK_MSG_ID_HEARTBEAT -> MSG_HEARTBEAT). ``attempt`` counts resends
    in the confirmation field."""
    return mavlink2.MAVLink_command_long_message(
        sysid, 1, mavlink2.MAV_CMD_REQUEST_MESSAGE, min(attempt, 255),
        mavlink2.MAVLINK_MSG_ID_HEARTBEAT, 0, 0, 0, 0, 0, 0)


def discover(links: Iterable[Link], sysids: Sequence[int], *,
             timeout_s: float = 5.0) -> tuple[dict[int, Link], list[int]]:
    """Which link each requested vehicle speaks on, by its HEARTBEAT system id.

    Returns ``(found, missing)``: ``found[sysid]`` is the first link that heard it;
    ``missing`` lists the ids not heard within ``timeout_s``. The ids not heard yet are
    asked for a HEARTBEAT at :data:`HEARTBEAT_ASKS_S` on every link (a link a vehicle is
    not on ignores a request addressed to it); ids not requested are ignored, so nothing
    is ever sent to them.
    """
    links = list(links)
    deadline = clock.monotonic() + timeout_s
    asks: dict[int, tuple[int, float, bool]] = {}  # id(link): (asks, when, it had heard)
    found: dict[int, Link] = {}
    while True:
        for sysid in sysids:
            if sysid not in found:
                for link in links:
                    if sysid in link.heartbeats:
                        found[sysid] = link
                        break
        missing = [s for s in sysids if s not in found]
        now = clock.monotonic()
        if not missing or now >= deadline:
            return found, missing
        for link in links:
            count, when, heard = asks.get(id(link), (0, 0.0, False))
            due = count == 0 or (count == 1 and (
                now - when >= HEARTBEAT_ASK_AGAIN_S or (link.heartbeats and not heard)))
            if not due:
                continue
            asks[id(link)] = (count + 1, now, bool(link.heartbeats))
            wanted = [(s, s in missing) for s in sysids
                      if s not in link.versions and (s in missing or s in link.heartbeats)]
            try:
                for sysid, unheard in wanted:
                    if unheard:
                        link.send(heartbeat_request(sysid, count))
                    link.send(version_request(sysid, count))
            except LinkDown:
                continue  # that link is gone: its vehicles stay missing
        clock.sleep(0.02)  # the links' reader threads fill in ``heartbeats``


def is_ready(link: Link, sysid: int) -> bool:
    """A 3D GPS fix (GPS_RAW_INT) and passing pre-arm checks (SYS_STATUS health bit)."""
    state = link.readiness.get(sysid, {})
    return state.get("gps_fix", 0) >= mavlink2.GPS_FIX_TYPE_3D_FIX and state.get("prearm", False)


def readiness_problems(link: Link, sysid: int) -> list[str]:
    """Why vehicle ``sysid`` is not ready to arm, as far as its telemetry tells."""
    state = link.readiness.get(sysid, {})
    why = []
    if state.get("gps_fix", 0) < mavlink2.GPS_FIX_TYPE_3D_FIX:
        why.append(f"no 3D GPS fix (fix type {state.get('gps_fix', 'unknown')})")
    if not state.get("prearm", False):
        why.append("pre-arm checks failing" if "prearm" in state else "pre-arm state unknown")
    silent = link.missing_streams(sysid)
    if silent:
        why.append("not receiving " + ", ".join(silent) + " although requested")
    return why


def wait_ready(links: Sequence[Link], sysids: Sequence[int], *, timeout_s: float) -> None:
    """Wait until every vehicle has a GPS fix and is ready to arm; LinkError naming the
    ones that are not after ``timeout_s``. GPS_RAW_INT and SYS_STATUS are requested from
    each vehicle on its link (ArduPilot sends neither unasked) and stopped again at the
    end: the port keeps a rate it was asked for after this link has gone (SITL's SERIAL0
    carried them, 4 messages a second a copter, through the shared radio that came next:
    30 % of 6,000 B/s for ten copters)."""
    found, missing = discover(links, sysids, timeout_s=timeout_s)
    for s, link in found.items():
        link.want(s, READINESS)
    try:
        _wait_ready(found, missing, sysids, timeout_s=timeout_s)
    finally:
        for s, link in found.items():
            with contextlib.suppress(LinkError):
                link.unwant(s, READINESS)


def _wait_ready(found: dict[int, Link], missing: list[int], sysids: Sequence[int], *,
                timeout_s: float) -> None:
    deadline = clock.monotonic() + timeout_s
    while True:
        waiting = [s for s in sysids if s not in missing and not is_ready(found[s], s)]
        if not waiting and not missing:
            return
        if missing or clock.monotonic() >= deadline:
            what = [f"{s} (no HEARTBEAT)" for s in missing] + [
                f"{s} ({'; '.join(readiness_problems(found[s], s))})" for s in waiting]
            raise LinkError(f"not ready after {timeout_s:g} s: system id {', '.join(what)}")
        clock.sleep(0.1)


def mavlink1_problem(sysid: int, url: str) -> str:
    """One line for a vehicle whose link speaks MAVLink 1 only, and what to change."""
    return (f"system id {sysid} speaks MAVLink 1 only on {url} (its HEARTBEATs come as "
            "MAVLink 1 frames): ftlbo-mav needs MAVLink 2 (fence and rally points, "
            "mission types, signing); set SERIALn_PROTOCOL = 2 for the port of this link "
            "(a 3DR Solo on its original firmware: update it to ArduCopter 4, whose "
            "CubeSolo build speaks MAVLink 2); nothing was sent")


def describe_missing(sysid: int, links: Sequence[Link], timeout_s: float) -> str:
    heard = sorted({s for link in links for s in link.heartbeats})
    where = ", ".join(link.url for link in links)
    also = f" (heard: {', '.join(map(str, heard))})" if heard else " (heard no vehicle at all)"
    return (f"system id {sysid}: no HEARTBEAT within {timeout_s:g} s on {where}{also}; "
            "check the id (SYSID_THISMAV) and that the vehicle is on this link")
