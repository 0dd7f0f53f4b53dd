"""How ArduCopter 4.5 keeps a mission item: what it accepts, and what it gives back.

ArduPilot does not store a MISSION_ITEM_INT as sent. ``AP_Mission::mavlink_int_to_mission_cmd``
(libraries/AP_Mission/AP_Mission.cpp) packs each command into a 15-byte slot: a 16-bit
``p1`` and, per command, a location (int32 lat/lng, int32 centimetres and flag bits) or a
small packed struct (libraries/AP_Mission/AP_Mission.h). ``mission_cmd_to_mavlink_int``
rebuilds the item from that slot on read-back. So a waypoint's hold time comes back in
whole seconds, its acceptance radius and yaw are gone, NAV_LAND's param4 keeps only its
sign, an altitude of 6.009 m comes back as 6.00 m, and frame 6 comes back as 3.

:func:`check` is the acceptance test of ``mavlink_int_to_mission_cmd`` (with
``sanity_check_params``); :func:`stored` is the round trip through the slot, i.e. what a
read-back returns. Both work on :class:`WireItem`, the item exactly as MISSION_ITEM_INT
carries it (float32 params and z, int32 x and y). The copter build is modelled: no
``APM_BUILD_ArduPlane`` branches; terrain and scripting are compiled in (as in SITL).

C conversions are modelled as the compiler does them on x86-64 and ARM: a float assigned
to an integer field is truncated toward zero and wraps to the field's width; float32
arithmetic is done in float32 (``packet.z * 100.0f``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as R

# --- MAV_FRAME values ArduPilot accepts for an item with a location, and what it keeps
# (the altitude frame only: relative_alt / terrain_alt bits of Location)
_FRAME_KEPT = {
    R.MAV_FRAME_MISSION: R.MAV_FRAME_GLOBAL,
    R.MAV_FRAME_GLOBAL: R.MAV_FRAME_GLOBAL,
    R.MAV_FRAME_GLOBAL_INT: R.MAV_FRAME_GLOBAL,
    R.MAV_FRAME_GLOBAL_RELATIVE_ALT: R.MAV_FRAME_GLOBAL_RELATIVE_ALT,
    R.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT: R.MAV_FRAME_GLOBAL_RELATIVE_ALT,
    R.MAV_FRAME_GLOBAL_TERRAIN_ALT: R.MAV_FRAME_GLOBAL_TERRAIN_ALT,
    R.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT: R.MAV_FRAME_GLOBAL_TERRAIN_ALT,
}

LOCATION_ALT_MAX_M = 83000  # libraries/AP_Common/Location.h
# AP_Mission::num_commands_max on SITL (its storage size over 15 bytes a command): the
# recorded NO_SPACE text says "Only 0 items are supported" while booting, 650 after
SITL_MISSION_CAPACITY = 650


@dataclass(frozen=True)
class WireItem:
    """A mission item as MISSION_ITEM_INT carries it: ``x``/``y`` int32 1e-7 degrees,
    ``z`` and params float32 (held here as Python floats of float32 value)."""

    seq: int
    command: int
    frame: int
    x: int
    y: int
    z: float
    param1: float = 0.0
    param2: float = 0.0
    param3: float = 0.0
    param4: float = 0.0
    current: int = 0
    autocontinue: int = 1

    @property
    def params(self) -> tuple[float, float, float, float]:
        return (self.param1, self.param2, self.param3, self.param4)


def f32(x: float) -> float:
    """``x`` rounded to float32, as it travels in MAVLink."""
    with np.errstate(over="ignore"):
        return float(np.float32(x))


def c_int(x: float, bits: int, *, signed: bool) -> int:
    """A float assigned to a C integer field: truncated toward zero (cvttss2si, to int32),
    then wrapped to ``bits``. NaN and values outside int32 give INT32_MIN's low bits."""
    if math.isnan(x) or not -2**31 <= x < 2**31:
        v = -2**31
    else:
        v = int(x)
    v &= (1 << bits) - 1
    if signed and v >= 1 << (bits - 1):
        v -= 1 << bits
    return v


def u8(x: float) -> int:
    return c_int(x, 8, signed=False)


def i8(x: float) -> int:
    return c_int(x, 8, signed=True)


def u16(x: float) -> int:
    return c_int(x, 16, signed=False)


def i16(x: float) -> int:
    return c_int(x, 16, signed=True)


def _keep(x: float) -> float:
    return f32(x)


def _drop(_x: float) -> float:
    return 0.0


# --- The commands whose location is kept (AP_Mission::stored_in_location)
LOCATION_COMMANDS = frozenset({
    R.MAV_CMD_NAV_WAYPOINT, R.MAV_CMD_NAV_LOITER_UNLIM, R.MAV_CMD_NAV_LOITER_TURNS,
    R.MAV_CMD_NAV_LOITER_TIME, R.MAV_CMD_NAV_LAND, R.MAV_CMD_NAV_TAKEOFF,
    R.MAV_CMD_NAV_CONTINUE_AND_CHANGE_ALT, R.MAV_CMD_NAV_LOITER_TO_ALT,
    R.MAV_CMD_NAV_SPLINE_WAYPOINT, R.MAV_CMD_NAV_GUIDED_ENABLE, R.MAV_CMD_DO_SET_HOME,
    R.MAV_CMD_DO_LAND_START, R.MAV_CMD_DO_GO_AROUND, R.MAV_CMD_DO_SET_ROI,
    R.MAV_CMD_NAV_VTOL_TAKEOFF, R.MAV_CMD_NAV_VTOL_LAND, R.MAV_CMD_NAV_PAYLOAD_PLACE,
})

# sanity_check_params: the one param (index 0..3) each of these may leave NaN
_NAN_ALLOWED = {
    R.MAV_CMD_NAV_WAYPOINT: {3}, R.MAV_CMD_NAV_LAND: {3}, R.MAV_CMD_NAV_TAKEOFF: {3},
    R.MAV_CMD_NAV_VTOL_TAKEOFF: {3}, R.MAV_CMD_NAV_VTOL_LAND: {2, 3},
}

Slot = Callable[[float], float]

# Commands whose params round-trip through one field each: param k -> stored as
# SLOTS[cmd][k] (a C type conversion, or dropped). From the two switch statements of
# mavlink_int_to_mission_cmd and mission_cmd_to_mavlink_int, field types from AP_Mission.h.
_P1 = (u16, _drop, _drop, _drop)  # cmd.p1 = packet.param1, nothing else
SLOTS: dict[int, tuple[Slot, Slot, Slot, Slot]] = {
    R.MAV_CMD_NAV_WAYPOINT: _P1,  # Copter: hold time in whole seconds (p1)
    R.MAV_CMD_NAV_RETURN_TO_LAUNCH: (_drop, _drop, _drop, _drop),
    R.MAV_CMD_NAV_TAKEOFF: _P1,
    R.MAV_CMD_NAV_CONTINUE_AND_CHANGE_ALT: _P1,
    R.MAV_CMD_NAV_SPLINE_WAYPOINT: _P1,
    R.MAV_CMD_NAV_GUIDED_ENABLE: _P1,
    R.MAV_CMD_NAV_DELAY: (_keep, i8, i8, i8),
    R.MAV_CMD_CONDITION_DELAY: (_keep, _drop, _drop, _drop),
    R.MAV_CMD_CONDITION_DISTANCE: (_keep, _drop, _drop, _drop),
    R.MAV_CMD_CONDITION_YAW: (_keep, _keep, i8, u8),
    R.MAV_CMD_DO_JUMP: (u16, i16, _drop, _drop),
    R.MAV_CMD_DO_JUMP_TAG: (u16, i16, _drop, _drop),
    R.MAV_CMD_JUMP_TAG: (u16, _drop, _drop, _drop),
    R.MAV_CMD_DO_CHANGE_SPEED: (u8, _keep, _keep, _drop),
    R.MAV_CMD_DO_SET_HOME: _P1,
    R.MAV_CMD_DO_SET_RELAY: (u8, u8, _drop, _drop),
    R.MAV_CMD_DO_REPEAT_RELAY: (u8, i16, _keep, _drop),
    R.MAV_CMD_DO_SET_SERVO: (u8, u16, _drop, _drop),
    R.MAV_CMD_DO_REPEAT_SERVO: (u8, u16, i16, _keep),
    R.MAV_CMD_DO_LAND_START: (_drop, _drop, _drop, _drop),
    R.MAV_CMD_DO_GO_AROUND: (_drop, _drop, _drop, _drop),
    R.MAV_CMD_DO_SET_ROI: _P1,
    R.MAV_CMD_DO_MOUNT_CONTROL: (_keep, _keep, _keep, _drop),
    # Cam_Trigg_Distance: float meters, uint8 trigger (recorded: camera.json)
    R.MAV_CMD_DO_SET_CAM_TRIGG_DIST: (_keep, _drop, u8, _drop),
    R.MAV_CMD_DO_FENCE_ENABLE: _P1,
    R.MAV_CMD_DO_AUX_FUNCTION: (u16, u8, _drop, _drop),
    R.MAV_CMD_DO_PARACHUTE: _P1,
    R.MAV_CMD_DO_INVERTED_FLIGHT: _P1,
    R.MAV_CMD_DO_GRIPPER: (u8, u8, _drop, _drop),
    R.MAV_CMD_DO_GUIDED_LIMITS: (u16, _keep, _keep, _keep),
    R.MAV_CMD_DO_AUTOTUNE_ENABLE: _P1,
    R.MAV_CMD_NAV_ALTITUDE_WAIT: (_keep, _keep, u8, _drop),
    R.MAV_CMD_NAV_VTOL_TAKEOFF: (_drop, _drop, _drop, _drop),
    R.MAV_CMD_NAV_VTOL_LAND: _P1,
    R.MAV_CMD_DO_VTOL_TRANSITION: (u8, _drop, _drop, _drop),
    R.MAV_CMD_DO_SET_REVERSE: _P1,
    R.MAV_CMD_NAV_SET_YAW_SPEED: (_keep, _keep, u8, _drop),
    R.MAV_CMD_DO_WINCH: (u8, u8, _keep, _keep),
    R.MAV_CMD_DO_SET_RESUME_REPEAT_DIST: _P1,
    R.MAV_CMD_DO_SPRAYER: _P1,
    R.MAV_CMD_DO_SEND_SCRIPT_MESSAGE: (u16, _keep, _keep, _keep),
    R.MAV_CMD_DO_PAUSE_CONTINUE: _P1,
    R.MAV_CMD_IMAGE_START_CAPTURE: (u8, _keep, u16, u16),
    R.MAV_CMD_IMAGE_STOP_CAPTURE: _P1,
    R.MAV_CMD_SET_CAMERA_ZOOM: (u8, _keep, _drop, _drop),
    R.MAV_CMD_SET_CAMERA_FOCUS: (u8, _keep, _drop, _drop),
    R.MAV_CMD_SET_CAMERA_SOURCE: (u8, u8, u8, _drop),
    R.MAV_CMD_VIDEO_START_CAPTURE: (u8, _drop, _drop, _drop),
    R.MAV_CMD_VIDEO_STOP_CAPTURE: (u8, _drop, _drop, _drop),
}


def _is_negative(x: float) -> bool:
    """AP_Math's is_negative: below -FLT_EPSILON."""
    return x <= -1.1920928955078125e-07


def _loiter_unlim(p):  # radius |param3| in p1, sign as loiter_ccw
    radius = float(u16(abs(p[2])))
    return (0.0, 0.0, -radius if p[2] < 0 else radius, 0.0)


def _loiter_turns(p):
    turns, small = p[0], False
    if 0 < turns < 1:
        turns, small = f32(turns * 256.0), True
    low = u16(min(255.0, turns))
    radius = abs(p[2])
    big = radius > 255
    radius_m = u8(radius) if not big else u8(min(255.0, f32(radius * 0.1)))
    p1 = (low | (radius_m << 8)) & 0xFFFF
    param1, param3 = float(p1 & 0xFF), float(p1 >> 8)
    if p[2] < 0:
        param3 = -param3
    if big:
        param3 *= 10
    if small:
        param1 = f32(param1 / 256.0)
    return (param1, 0.0, param3, 1.0 if p[3] > 0 else 0.0)


def _loiter_time(p):
    return (float(u16(p[0])), 0.0, -1.0 if p[2] < 0 else 1.0, 1.0 if p[3] > 0 else 0.0)


def _land(p):  # param4 NaN leaves loiter_ccw clear: comes back +1
    ccw = not math.isnan(p[3]) and _is_negative(p[3])
    return (float(u16(p[0])), 0.0, 0.0, -1.0 if ccw else 1.0)


def _loiter_to_alt(p):
    radius = float(u16(abs(p[1])))
    return (0.0, -radius if p[1] < 0 else radius, 0.0, 1.0 if p[3] > 0 else 0.0)


def _payload_place(p):  # max descent, metres -> centimetres in p1 -> metres
    return (f32(u16(f32(p[0] * 100.0)) / 100.0), 0.0, 0.0, 0.0)


def _engine_control(p):
    cm = u16(f32(p[2] * 100.0))
    allow = (u16(p[3]) if not math.isnan(p[3]) else 0) & 1  # ENGINE_CONTROL_OPTIONS bit 0
    return (1.0 if p[0] > 0 else 0.0, 1.0 if p[1] > 0 else 0.0, f32(cm * 0.01), float(allow))


_SPECIAL: dict[int, Callable] = {
    R.MAV_CMD_NAV_LOITER_UNLIM: _loiter_unlim,
    R.MAV_CMD_NAV_LOITER_TURNS: _loiter_turns,
    R.MAV_CMD_NAV_LOITER_TIME: _loiter_time,
    R.MAV_CMD_NAV_LAND: _land,
    R.MAV_CMD_NAV_LOITER_TO_ALT: _loiter_to_alt,
    R.MAV_CMD_NAV_PAYLOAD_PLACE: _payload_place,
    R.MAV_CMD_DO_ENGINE_CONTROL: _engine_control,
}

# Commands that use x/y/z for something other than a location: not modelled (camera
# configuration, gimbal, scripted and attitude-time items). ``check`` accepts them and
# ``stored`` returns them unchanged, which ArduPilot does not; our missions never hold them.
NOT_MODELLED = frozenset({
    R.MAV_CMD_DO_DIGICAM_CONFIGURE, R.MAV_CMD_DO_DIGICAM_CONTROL, R.MAV_CMD_NAV_SCRIPT_TIME,
    R.MAV_CMD_NAV_ATTITUDE_TIME, R.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW,
})

KNOWN_COMMANDS = frozenset(SLOTS) | frozenset(_SPECIAL) | NOT_MODELLED


def check(item: WireItem) -> int:
    """The MAV_MISSION_RESULT ArduCopter answers for this item
    (``mavlink_int_to_mission_cmd`` and ``sanity_check_params``): ACCEPTED, or the
    reason it refuses to store it."""
    allowed = _NAN_ALLOWED.get(item.command, set())
    for k, (value, code) in enumerate(zip(item.params, (
            R.MAV_MISSION_INVALID_PARAM1, R.MAV_MISSION_INVALID_PARAM2,
            R.MAV_MISSION_INVALID_PARAM3, R.MAV_MISSION_INVALID_PARAM4))):
        if math.isinf(value) or (math.isnan(value) and k not in allowed):
            return code
    if item.command in (0, 1):
        return R.MAV_MISSION_INVALID
    if item.command not in KNOWN_COMMANDS:
        return R.MAV_MISSION_UNSUPPORTED
    if item.command in LOCATION_COMMANDS:
        if not -900_000_000 <= item.x <= 900_000_000:  # AP_Math check_lat
            return R.MAV_MISSION_INVALID_PARAM5_X
        if not -1_800_000_000 <= item.y <= 1_800_000_000:  # check_lng
            return R.MAV_MISSION_INVALID_PARAM6_Y
        if math.isnan(item.z) or abs(item.z) >= LOCATION_ALT_MAX_M:
            return R.MAV_MISSION_INVALID_PARAM7
        if item.frame not in _FRAME_KEPT:
            return R.MAV_MISSION_UNSUPPORTED_FRAME
    return R.MAV_MISSION_ACCEPTED


def stored(item: WireItem) -> WireItem:
    """The item as ArduCopter returns it on read-back after storing it.

    ``item`` must pass :func:`check` (ValueError otherwise). ``current`` comes back 0 and
    ``autocontinue`` 1 for every item (mission_cmd_to_mavlink_int sets both). Item 0 is
    the vehicle's own home on read-back whatever was sent: see :func:`home_item`.
    """
    result = check(item)
    if result != R.MAV_MISSION_ACCEPTED:
        raise ValueError(f"ArduCopter refuses this item (MAV_MISSION_RESULT {result})")
    if item.command in NOT_MODELLED:
        return replace(item, current=0, autocontinue=1)
    p = tuple(f32(v) for v in item.params)
    if item.command in _SPECIAL:
        params = _SPECIAL[item.command](p)
    else:
        params = tuple(float(slot(v)) for slot, v in zip(SLOTS[item.command], p))
    frame, x, y, z = R.MAV_FRAME_GLOBAL, 0, 0, 0.0
    if item.command in LOCATION_COMMANDS:
        frame, x, y = _FRAME_KEPT[item.frame], item.x, item.y
        z = altitude_stored(item.z)
    return WireItem(seq=item.seq, command=item.command, frame=frame, x=x, y=y, z=z,
                    param1=params[0], param2=params[1], param3=params[2], param4=params[3],
                    current=0, autocontinue=1)


def altitude_cm(z_m: float) -> int:
    """``Location::alt = packet.z * 100.0f``: float32 product truncated to int32 cm."""
    return c_int(f32(f32(z_m) * np.float32(100.0)), 32, signed=True)


def altitude_stored(z_m: float) -> float:
    """The altitude a read-back returns: ``alt * 0.01f`` in float32."""
    return f32(np.float32(altitude_cm(z_m)) * np.float32(0.01))


def home_item(*, lat_e7: int, lon_e7: int, alt_cm: int) -> WireItem:
    """Item 0 on read-back: the vehicle's home (AP_Mission::write_home_to_storage), a
    NAV_WAYPOINT in frame GLOBAL with its altitude above mean sea level."""
    return WireItem(seq=0, command=R.MAV_CMD_NAV_WAYPOINT, frame=R.MAV_FRAME_GLOBAL,
                    x=lat_e7, y=lon_e7, z=f32(np.float32(alt_cm) * np.float32(0.01)))


def check_jump(item: WireItem, *, stored_count: int, last_seq: int) -> int:
    """MissionItemProtocol_Waypoints::append_item / replace_item
    (libraries/GCS_MAVLink/MissionItemProtocol_Waypoints.cpp): a DO_JUMP to item 0, or
    beyond both the stored mission and the upload, is refused with MAV_MISSION_ERROR."""
    if item.command != R.MAV_CMD_DO_JUMP:
        return R.MAV_MISSION_ACCEPTED
    target = u16(f32(item.param1))
    if target == 0 or (target >= stored_count and target > last_seq):
        return R.MAV_MISSION_ERROR
    return R.MAV_MISSION_ACCEPTED


# Differences between an item as sent and as stored that change nothing in a copter's
# flight: (command, param index 1..4). NAV_LAND's param4 (yaw direction, Plane's deep stall
# only) comes back as +1/-1; NaN in a param that allows it ("use the default") comes back 0.
_HARMLESS = {(R.MAV_CMD_NAV_LAND, 4)}


# Short names where MAVLink's own description is a sentence
_LABELS = {(R.MAV_CMD_NAV_WAYPOINT, 3): "pass radius", (R.MAV_CMD_NAV_WAYPOINT, 4): "yaw"}


def _label(command: int, k: int) -> str:
    if (command, k) in _LABELS:
        return f"param{k} ({_LABELS[command, k]})"
    entry = R.enums["MAV_CMD"].get(command)
    text = (entry.param.get(k, "") if entry is not None else "") or ""
    text = text.split(". ")[0].split(" (")[0].rstrip(".").strip()
    return f"param{k} ({text.lower()})" if text else f"param{k}"


def storage_notes(item: WireItem) -> list[str]:
    """What ArduCopter will not keep of this item that a person may have meant: a hold
    time of 2.5 s stored as 2 s, an acceptance radius or yaw it drops, ``autocontinue``
    0 (it always continues). Empty when nothing that matters changes. Altitudes lose at
    most the part below one centimetre, frames only their *_INT spelling: not named."""
    if check(item) != R.MAV_MISSION_ACCEPTED or item.command in NOT_MODELLED:
        return []
    kept = stored(item)
    notes = []
    allowed = _NAN_ALLOWED.get(item.command, set())
    for k, (sent, back) in enumerate(zip(item.params, kept.params), start=1):
        sent = f32(sent)
        if (item.command, k) in _HARMLESS or (math.isnan(sent) and k - 1 in allowed):
            continue
        if sent != back:
            notes.append(f"{_label(item.command, k)} {sent:g} is stored as {back:g}")
    if item.autocontinue == 0:
        notes.append("autocontinue 0 is ignored: ArduCopter always continues to the next item")
    return notes
