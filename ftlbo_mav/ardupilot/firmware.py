"""Which firmware the planner's flight model is ArduCopter's, and how a vehicle says which
firmware it runs.

The flown path the planner predicts (:mod:`.wpnav`, :mod:`.poscontrol`, :mod:`.scurve`)
follows ArduCopter's waypoint navigation and position control: libraries/AC_WPNav/
AC_WPNav.cpp, libraries/AC_AttitudeControl/AC_PosControl.cpp and libraries/AP_Math/
SCurve.cpp as on the Copter-4.5 and Copter-4.6 branches (where they differ, both, chosen
by the copter's release), and is tested against ArduCopter 4.5.6 and 4.6.3 SITL
(``tests/data/ardupilot-4.5.6/``, ``ardupilot-4.6.3/``). Other releases (4.4, 4.7) are
not held to recordings, and other autopilots fly paths of their own, so for them the
predicted path, the clearance kept on it and its timing are not promised; the refusal
names the nearest modelled release.

How a vehicle says it (libraries/GCS_MAVLink/GCS_Common.cpp):

- AUTOPILOT_VERSION, sent on MAV_CMD_REQUEST_MESSAGE param1 148 (``handle_command_request_message``,
  answered COMMAND_ACK ACCEPTED, then the message) or MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES
  param1 1 (``handle_command_request_autopilot_capabilities``); ``send_autopilot_version``
  fills ``flight_sw_version`` as ``major<<24 | minor<<16 | patch<<8 | type``
  (libraries/AP_Common/AP_FWVersion.h, ``FIRMWARE_VERSION_TYPE``), ``flight_custom_version``
  the first 8 characters of the git hash. Recorded in boot.json ``version``.
- HEARTBEAT ``type`` (``gcs().frame_type()``, AP_Motors ``get_frame_mav_type``: QUADROTOR,
  HEXAROTOR, ... for a multirotor, HELICOPTER for a heli) and ``autopilot``
  (MAV_AUTOPILOT_ARDUPILOTMEGA).
"""

from __future__ import annotations

from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as R

from .copters import nearest_release

AUTOPILOT_VERSION_ID = R.MAVLINK_MSG_ID_AUTOPILOT_VERSION  # 148

# FIRMWARE_VERSION_TYPE (libraries/AP_Common/AP_FWVersion.h, MAVLink common.xml)
VERSION_TYPES = {R.FIRMWARE_VERSION_TYPE_DEV: "dev", R.FIRMWARE_VERSION_TYPE_ALPHA: "alpha",
                 R.FIRMWARE_VERSION_TYPE_BETA: "beta", R.FIRMWARE_VERSION_TYPE_RC: "rc",
                 R.FIRMWARE_VERSION_TYPE_OFFICIAL: "official"}

SUPPORTED_SERIES = ((4, 5), (4, 6))
"""ArduCopter 4.5.x and 4.6.x: the branches whose AC_WPNav / AC_PosControl / SCurve the
model follows, each where it differs (:mod:`.copters` ``RELEASES``), each held to
recordings of its SITL (``tests/data/ardupilot-4.5.6``, ``ardupilot-4.6.3``)."""

SUPPORTED_TYPES = frozenset({R.FIRMWARE_VERSION_TYPE_RC, R.FIRMWARE_VERSION_TYPE_OFFICIAL})
"""Releases and release candidates (cut from a Copter-4.x branch, its navigation frozen);
dev, alpha and beta builds may carry navigation changes not in the release."""

# The multirotor frames ArduCopter reports (AP_Motors get_frame_mav_type); the model is a
# multirotor's, so a helicopter (AP_MotorsHeli, its own attitude control) is not one.
COPTER_TYPES = frozenset({
    R.MAV_TYPE_QUADROTOR, R.MAV_TYPE_HEXAROTOR, R.MAV_TYPE_OCTOROTOR, R.MAV_TYPE_TRICOPTER,
    R.MAV_TYPE_COAXIAL, R.MAV_TYPE_DECAROTOR, R.MAV_TYPE_DODECAROTOR,
})

SUPPORTED = "ArduCopter 4.5.x or 4.6.x (official or rc) on a multirotor"
NOT_PROMISED = "the predicted flown path, the clearance kept on it and its timing"
UNANSWERED = "it did not answer AUTOPILOT_VERSION (MAV_CMD_REQUEST_MESSAGE 148)"
ANY_FIRMWARE_HINT = " (--any-firmware to go on anyway)"


@dataclass(frozen=True)
class Firmware:
    """``flight_sw_version`` decoded: ``4.5.6`` of type 255 (official)."""

    major: int
    minor: int
    patch: int
    type: int

    @classmethod
    def decode(cls, raw: int) -> Firmware:
        raw = int(raw) & 0xFFFFFFFF
        return cls(major=raw >> 24, minor=(raw >> 16) & 0xFF, patch=(raw >> 8) & 0xFF,
                   type=raw & 0xFF)

    def encode(self) -> int:
        return self.major << 24 | self.minor << 16 | self.patch << 8 | self.type

    def describe(self) -> str:
        kind = VERSION_TYPES.get(self.type, f"type {self.type}")
        return f"{self.major}.{self.minor}.{self.patch} {kind}"

    @property
    def supported(self) -> bool:
        return (self.major, self.minor) in SUPPORTED_SERIES and self.type in SUPPORTED_TYPES


RECORDED = Firmware(major=4, minor=5, patch=6, type=R.FIRMWARE_VERSION_TYPE_OFFICIAL)
"""ArduCopter 4.5.6 SITL as recorded (boot.json ``version``: raw 67438335)."""
RECORDED_CUSTOM_VERSION = "bbf0b066"
RECORDED_RELEASES = {"4.5": RECORDED,
                     "4.6": Firmware(major=4, minor=6, patch=3,
                                     type=R.FIRMWARE_VERSION_TYPE_OFFICIAL)}
"""The recorded release of each modelled series (tests/data/ardupilot-<release>/): what an
emulated copter of that series reports."""
RECORDED_CAPABILITIES = 64495


def _type_name(prefix: str, value: int) -> str:
    enum = R.enums["MAV_TYPE" if prefix == "type" else "MAV_AUTOPILOT"]
    entry = enum.get(value)
    return entry.name if entry is not None else f"{prefix} {value}"


def heartbeat_findings(*, vehicle_type: int | None, autopilot: int | None) -> list[str]:
    """What a vehicle's HEARTBEAT says against the flight model (empty: an ArduPilot
    multirotor, or not heard)."""
    found = []
    if autopilot is not None and autopilot != R.MAV_AUTOPILOT_ARDUPILOTMEGA:
        found.append(f"its HEARTBEAT says {_type_name('autopilot', autopilot)}")
    if vehicle_type is not None and vehicle_type not in COPTER_TYPES:
        found.append(f"its HEARTBEAT says {_type_name('type', vehicle_type)}")
    return found


def firmware_problem(*, vehicle_type: int | None, autopilot: int | None,
                     version: int | None) -> str | None:
    """Why a vehicle's firmware is not one the flight model follows, or None when it is.
    ``vehicle_type``/``autopilot`` from its HEARTBEAT (None: not heard), ``version`` its
    AUTOPILOT_VERSION ``flight_sw_version`` (None: not answered)."""
    found = heartbeat_findings(vehicle_type=vehicle_type, autopilot=autopilot)
    if version is None:
        found.append(UNANSWERED)
    elif not found:
        fw = Firmware.decode(version)
        if not fw.supported:
            series = (fw.major, fw.minor)
            near = nearest_release(fw.major, fw.minor)
            found.append(f"it runs {fw.describe()}" + (
                "" if series in SUPPORTED_SERIES else
                f" (no recordings of {fw.major}.{fw.minor} hold the model to it; the "
                f"nearest modelled release is ArduCopter {near})"))
    if not found:
        return None
    return f"firmware: {'; '.join(found)}; the flight model is {SUPPORTED}'s{ANY_FIRMWARE_HINT}"


def firmware_entry(*, vehicle_type: int | None, autopilot: int | None,
                   version: int | None) -> dict:
    """What summary.json says of one vehicle's firmware: its version as decoded (None:
    AUTOPILOT_VERSION not answered), its HEARTBEAT's type and autopilot names, and
    :func:`firmware_problem` (None: the flight model's firmware)."""
    return {"version": Firmware.decode(version).describe() if version is not None else None,
            "vehicle_type": (_type_name("type", vehicle_type) if vehicle_type is not None
                             else None),
            "autopilot": _type_name("autopilot", autopilot) if autopilot is not None else None,
            "problem": firmware_problem(vehicle_type=vehicle_type, autopilot=autopilot,
                                        version=version)}


def any_firmware_warning(problem: str) -> str:
    """The warning line for a vehicle flown with ``--any-firmware`` despite ``problem``."""
    reason = problem.removeprefix("firmware: ").split("; the flight model is ")[0]
    return f"firmware: {reason}: {NOT_PROMISED} are not promised for it (--any-firmware)"
