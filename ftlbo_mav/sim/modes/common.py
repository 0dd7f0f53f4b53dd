"""What every emulated mode shares: ArduCopter's mode numbers as the emulator uses
them, and STATUSTEXT from a (severity, text) pair."""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as R

from ...ardupilot.modes import CopterMode
from ...mission.items import CMD_NAV_LOITER_UNLIM, CMD_NAV_WAYPOINT

STABILIZE, AUTO, GUIDED, LOITER, RTL, LAND, BRAKE = (
    CopterMode.STABILIZE, CopterMode.AUTO, CopterMode.GUIDED, CopterMode.LOITER, CopterMode.RTL,
    CopterMode.LAND, CopterMode.BRAKE)
# the modes the emulator accepts; others are refused as unknown
FLOWN_MODES = frozenset({STABILIZE, CopterMode.ALT_HOLD, AUTO, GUIDED, LOITER, RTL, LAND,
                         CopterMode.POSHOLD, BRAKE})
# ModeAuto::set_next_wp: the next commands the copter flies through instead of stopping
FLY_THROUGH = (CMD_NAV_WAYPOINT, CMD_NAV_LOITER_UNLIM)


def text(severity_text: tuple[int, str]):
    severity, words = severity_text
    return R.MAVLink_statustext_message(severity, words.encode())
