"""Which firmware a vehicle runs, asked over its link: AUTOPILOT_VERSION on
MAV_CMD_REQUEST_MESSAGE (GCS_Common.cpp ``handle_command_request_message``: COMMAND_ACK
ACCEPTED, then the message), judged by :mod:`ftlbo_mav.ardupilot.firmware`."""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as R

from .. import clock
from ..ardupilot.firmware import AUTOPILOT_VERSION_ID


def version_request(sysid: int, attempt: int = 0):
    """COMMAND_LONG MAV_CMD_REQUEST_MESSAGE for AUTOPILOT_VERSION, ``attempt`` counting
    resends in its confirmation field."""
    return R.MAVLink_command_long_message(sysid, 1, R.MAV_CMD_REQUEST_MESSAGE,
                                          min(attempt, 255), AUTOPILOT_VERSION_ID,
                                          0, 0, 0, 0, 0, 0)


def request_version(channel, *, timeout_s: float = 1.0, retries: int = 2) -> int | None:
    """The vehicle's AUTOPILOT_VERSION ``flight_sw_version``, or None when it does not
    answer within ``retries + 1`` requests of ``timeout_s`` each. One its link heard
    already (asked when the vehicles were found: :func:`.discovery.discover`) is not
    asked again; one on its way is taken when it comes."""
    known = channel.link.versions
    for attempt in range(retries + 1):
        if channel.sysid in known:
            return known[channel.sysid]
        channel.send(version_request(channel.sysid, attempt))
        deadline = clock.monotonic() + timeout_s
        while (left := deadline - clock.monotonic()) > 0:
            msg = channel.recv(min(left, 0.05))
            if msg is not None and msg.get_type() == "AUTOPILOT_VERSION":
                return int(msg.flight_sw_version)
            if channel.sysid in known:
                return known[channel.sysid]
    return None
