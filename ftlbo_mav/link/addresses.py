"""Where the vehicles are, as a user writes it: connection strings and system id lists.

The kinds of link a connection string names (``tcp:HOST:PORT``, ``udpin:``/``udpout:``, a
serial device with its baud rate, an emulator in this process ``emu:KEY/INDEX``) checked
before anything is opened (:func:`check_url`), SITL's and the emulator's layout of ports
(:func:`default_urls_for`), and ``--sysid`` lists (:func:`parse_sysids`). Pure: nothing
here opens a link (:mod:`.endpoints` does).
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable, Sequence

from ..errors import BadInput

FIRST_TCP_PORT = 5760  # SITL instance i listens on 5760 + 10 * i
MAX_SYSID = 254  # 255 is the ground station's


def parse_sysids(text: str) -> list[int]:
    """``"1..3"`` -> ``[1, 2, 3]``; ``"1,2,5"`` -> ``[1, 2, 5]``; ``"4"`` -> ``[4]``.

    Ids are MAVLink system ids 1..254 (255 is the ground station's), without repeats; each
    number is range-checked before a range is expanded.
    """
    text = text.strip()
    ids: list[int] = []

    def checked(number: str) -> int:
        value = int(number)
        if not 1 <= value <= MAX_SYSID:
            raise BadInput(f"--sysid {text}: system ids are 1..{MAX_SYSID}, got {value}")
        return value

    for part in text.split(","):
        part = part.strip()
        m = re.fullmatch(r"(\d{1,12})\s*\.\.\s*(\d{1,12})", part)
        if m:
            lo, hi = checked(m.group(1)), checked(m.group(2))
            if hi < lo:
                raise BadInput(f"--sysid {text}: range {part} runs backwards")
            ids.extend(range(lo, hi + 1))
        elif re.fullmatch(r"\d{1,12}", part):
            ids.append(checked(part))
        else:
            raise BadInput(f"--sysid {text}: expected a range like 1..3 or a list like 1,2,5")
    if len(set(ids)) != len(ids):
        raise BadInput(f"--sysid {text}: an id is repeated")
    return ids


_NETWORK_URL = re.compile(r"(tcp|tcpin|udp|udpin|udpout|udpbcast|wsserver|ws):(.*):([^:]*)")


def check_url(url: str, *, option: str = "--connect") -> str:
    """A pymavlink connection string whose port (``tcp:HOST:PORT``, ``udpin:...``, ...) is
    a number 0..65535 (1..65535 where it is connected to); :class:`BadInput` otherwise.
    Serial ports and files pass unchanged, as do the connection strings of an emulator
    in this process (``emu:KEY/INDEX``, :mod:`ftlbo_mav.sim.inprocess`)."""
    if in_process(url.strip()) is not None:
        return url.strip()
    m = _NETWORK_URL.fullmatch(url.strip())
    if not m:
        _check_other_url(url, option)
        return url
    kind, host, port = m.groups()
    listens = kind in ("tcpin", "udpin", "udp", "wsserver")
    if not host:
        raise BadInput(f"{option} {url}: no host; expected {kind}:HOST:PORT")
    if not port.isdigit() or not (0 if listens else 1) <= int(port) <= 65535:
        raise BadInput(f"{option} {url}: port {port!r} is not a port number "
                       f"({0 if listens else 1}..65535)")
    return url


_EXAMPLES = ("tcp:HOST:PORT, udpin:0.0.0.0:PORT, udpout:HOST:PORT or a serial device "
             "with its baud rate (/dev/ttyUSB0,57600)")
_SERIAL = re.compile(r"(/dev/[^,:]+|COM\d+)(,\d+)?")


def _check_other_url(url: str, option: str) -> None:
    """What is not ``KIND:HOST:PORT``: a serial device, or what pymavlink would read as
    something else (a bare ``HOST:PORT`` is UDP to it; an existing file is a log to
    replay, or under ``/bin/`` a program to run), named as the mistake it is."""
    text = url.strip()
    if _SERIAL.fullmatch(text):
        return
    scheme, colon, rest = text.partition(":")
    if colon:
        if scheme and ":" not in rest:
            if not rest.isdigit():
                raise BadInput(f"{option} {url}: {scheme!r} is not a kind of link (tcp, "
                               f"udpin, udpout, ...) and {rest!r} not a port; expected "
                               f"{_EXAMPLES}")
            if not 1 <= int(rest) <= 65535:
                raise BadInput(f"{option} {url}: port {rest} is not a port number (1..65535)")
            return  # HOST:PORT, UDP as pymavlink reads it
        raise BadInput(f"{option} {url}: not a connection string; expected {_EXAMPLES}")
    if os.path.exists(text) and not text.startswith("/dev/"):
        raise BadInput(f"{option} {url}: is a file, not a link to a vehicle; expected "
                       f"{_EXAMPLES}")
    if not text.startswith("/dev/") and not re.fullmatch(r"COM\d+", text):
        raise BadInput(f"{option} {url}: not a connection string; expected {_EXAMPLES}")


def default_urls(count: int) -> list[str]:
    """SITL's and the emulator's layout: vehicle i on ``tcp:127.0.0.1:5760 + 10*i``."""
    return [f"tcp:127.0.0.1:{FIRST_TCP_PORT + 10 * i}" for i in range(count)]


def default_urls_for(sysids: Sequence[int]) -> list[str]:
    """Where SITL and the emulator put these system ids: id s (instance s-1) on
    ``tcp:127.0.0.1:5760 + 10*(s-1)``."""
    return [f"tcp:127.0.0.1:{FIRST_TCP_PORT + 10 * (s - 1)}" for s in sysids]


IN_PROCESS: dict[str, Callable] = {}
"""Emulators in this process (:mod:`ftlbo_mav.sim.inprocess`), by the start of their
connection strings (``emu:KEY``): each opens a connection to one of its vehicles."""


def in_process(url: str) -> Callable | None:
    return IN_PROCESS.get(url.split("/", 1)[0]) if url.startswith("emu:") else None
