"""ArduCopter's flight modes as MAVLink carries them (HEARTBEAT ``custom_mode``,
MAV_CMD_DO_SET_MODE ``param2``): one table for the ground side and the emulator."""

from __future__ import annotations

import enum

from pymavlink.dialects.v20 import ardupilotmega as R


class CopterMode(enum.IntEnum):
    """ArduCopter's custom modes (ArduCopter/mode.h, ``enum class Number``)."""

    STABILIZE = 0
    ACRO = 1
    ALT_HOLD = 2
    AUTO = 3
    GUIDED = 4
    LOITER = 5
    RTL = 6
    CIRCLE = 7
    LAND = 9
    DRIFT = 11
    SPORT = 13
    FLIP = 14
    AUTOTUNE = 15
    POSHOLD = 16
    BRAKE = 17
    THROW = 18
    AVOID_ADSB = 19
    GUIDED_NOGPS = 20
    SMART_RTL = 21
    FLOWHOLD = 22
    FOLLOW = 23
    ZIGZAG = 24
    SYSTEMID = 25
    AUTOROTATE = 26
    AUTO_RTL = 27
    TURTLE = 28


def mode_name(number: int) -> str:
    """``4`` -> ``"GUIDED"``; an unknown number as its digits."""
    try:
        return CopterMode(number).name
    except ValueError:
        return str(number)


# Modes in which ArduCopter sets MAV_MODE_FLAG_GUIDED_ENABLED
# (ArduCopter/GCS_Mavlink.cpp GCS_MAVLINK_Copter::base_mode)
GUIDED_ENABLED_MODES = frozenset({
    CopterMode.AUTO, CopterMode.RTL, CopterMode.LOITER, CopterMode.AVOID_ADSB,
    CopterMode.FOLLOW, CopterMode.GUIDED, CopterMode.CIRCLE, CopterMode.POSHOLD,
    CopterMode.BRAKE, CopterMode.SMART_RTL,
})


def heartbeat_base_mode(mode: int, *, armed: bool) -> int:
    """HEARTBEAT ``base_mode`` as ArduCopter sends it in ``mode`` (GCS_MAVLINK_Copter::
    base_mode): stabilize and manual input always, guided in :data:`GUIDED_ENABLED_MODES`,
    safety-armed when armed, and custom mode enabled."""
    base = R.MAV_MODE_FLAG_STABILIZE_ENABLED | R.MAV_MODE_FLAG_MANUAL_INPUT_ENABLED
    if mode in GUIDED_ENABLED_MODES:
        base |= R.MAV_MODE_FLAG_GUIDED_ENABLED
    if armed:
        base |= R.MAV_MODE_FLAG_SAFETY_ARMED
    base |= R.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
    return base
