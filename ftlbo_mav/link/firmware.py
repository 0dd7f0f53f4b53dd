"""Which firmware a vehicle runs, asked over its link: AUTOPILOT_VERSION on
MAV_CMD_REQUEST_MESSAGE (GCS_Common.cpp ``handle_command_request_message``: COMMAND_ACK
ACCEPTED, then the message), judged by :mod:`ftlbo_mav.ardupilot.firmware`."""

from __future__ import annotations

import time

from pymavlink.dialects.v20 import ardupilotmega as R

from ..ardupilot.firmware import AUTOPILOT_VERSION_ID, firmware_problem


def request_version(channel, *, timeout_s: float = 1.0, retries: int = 2) -> int | None:
    """The vehicle's AUTOPILOT_VERSION ``flight_sw_version``, or None when it does not
    answer within ``retries + 1`` requests of ``timeout_s`` each."""
    for attempt in range(retries + 1):
        channel.send(R.MAVLink_command_long_message(
            channel.sysid, 1, R.MAV_CMD_REQUEST_MESSAGE, min(attempt, 255),
            AUTOPILOT_VERSION_ID, 0, 0, 0, 0, 0, 0))
        deadline = time.monotonic() + timeout_s
        while (left := deadline - time.monotonic()) > 0:
            msg = channel.recv(left)
            if msg is not None and msg.get_type() == "AUTOPILOT_VERSION":
                return int(msg.flight_sw_version)
    return None


def channel_firmware_problem(channel, heartbeat, *, timeout_s: float = 1.0,
                             retries: int = 2) -> str | None:
    """:func:`~ftlbo_mav.ardupilot.firmware.firmware_problem` for the vehicle on
    ``channel`` whose last HEARTBEAT is ``heartbeat`` (:class:`.endpoints.Heartbeat` or
    None)."""
    version = request_version(channel, timeout_s=timeout_s, retries=retries)
    return firmware_problem(
        vehicle_type=None if heartbeat is None else heartbeat.vehicle_type,
        autopilot=None if heartbeat is None else heartbeat.autopilot, version=version)
