"""An emulated ArduCopter: what it says about itself and how it answers, as messages.

:class:`Vehicle` takes decoded messages and the time and returns messages (no sockets):
``handle`` for what arrives, ``tick`` for what time brings (HEARTBEAT and telemetry once
a period, the mission server's re-requests). Its state (mode, armed, position) is kept
in one place so that flight modes and physics can be added later beside the mission
server without touching the transport.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from .mission_server import MissionServer, MissionServerOptions

R = mavlink2


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


# Modes in which ArduCopter sets MAV_MODE_FLAG_GUIDED_ENABLED (GCS_Mavlink.cpp base_mode())
_GUIDED_MODES = {CopterMode.AUTO, CopterMode.RTL, CopterMode.LOITER, CopterMode.AVOID_ADSB,
                 CopterMode.FOLLOW, CopterMode.GUIDED, CopterMode.CIRCLE, CopterMode.POSHOLD,
                 CopterMode.BRAKE, CopterMode.SMART_RTL}


@dataclass(frozen=True)
class VehicleOptions:
    """``heartbeat_s``: period of HEARTBEAT and telemetry (ArduPilot: 1 Hz heartbeat).
    ``ready_after_s``: GPS 3D fix and pre-arm checks pass this long after boot."""

    heartbeat_s: float = 1.0
    ready_after_s: float = 0.0
    mission: MissionServerOptions = field(default_factory=MissionServerOptions)


@dataclass
class VehicleState:
    """What a later flight model will move; today the copter sits at home, disarmed."""

    lat_deg: float
    lon_deg: float
    alt_amsl_m: float
    relative_alt_m: float = 0.0
    mode: CopterMode = CopterMode.STABILIZE
    armed: bool = False


class Vehicle:
    """One emulated ArduCopter, system id ``sysid``, component 1 (the autopilot)."""

    compid = R.MAV_COMP_ID_AUTOPILOT1

    def __init__(self, *, sysid: int, home: tuple[float, float, float],
                 options: VehicleOptions = VehicleOptions(), boot_time: float = 0.0):
        self.sysid = sysid
        self.options = options
        self.boot_time = boot_time
        lat, lon, alt = home
        self.state = VehicleState(lat_deg=lat, lon_deg=lon, alt_amsl_m=alt)
        self.missions = MissionServer(sysid=sysid, home=home, options=options.mission,
                                      boot_time=boot_time)
        self._next_beat = boot_time

    def is_for_me(self, msg) -> bool:
        """MAVLink routing: a targeted message is handled only by its target (or broadcast)."""
        target = getattr(msg, "target_system", 0)
        return target in (0, self.sysid)

    def handle(self, msg, now: float) -> list:
        """Replies to one message (already through the link's faults and signing check)."""
        if msg.get_type() == "BAD_DATA" or not self.is_for_me(msg):
            return []
        return self.missions.handle(msg, now)

    def tick(self, now: float) -> tuple[list, list]:
        """``(broadcast, replies)``: periodic telemetry for every client, and the mission
        server's re-requests/cancellations for the client of the transfer."""
        periodic = []
        if now >= self._next_beat:
            self._next_beat = now + self.options.heartbeat_s
            periodic = self.telemetry(now)
        return periodic, self.missions.update(now)

    # -- what ArduCopter streams
    def heartbeat(self):
        s = self.state
        base = R.MAV_MODE_FLAG_STABILIZE_ENABLED | R.MAV_MODE_FLAG_MANUAL_INPUT_ENABLED
        if s.mode in _GUIDED_MODES:
            base |= R.MAV_MODE_FLAG_GUIDED_ENABLED
        if s.armed:
            base |= R.MAV_MODE_FLAG_SAFETY_ARMED
        base |= R.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
        status = R.MAV_STATE_ACTIVE if s.armed else R.MAV_STATE_STANDBY
        # GCS_Common.cpp send_heartbeat: frame type, ARDUPILOTMEGA, base_mode, custom mode
        return R.MAVLink_heartbeat_message(R.MAV_TYPE_QUADROTOR, R.MAV_AUTOPILOT_ARDUPILOTMEGA,
                                           base, int(s.mode), status, 3)

    def ready(self, now: float) -> bool:
        return now - self.boot_time >= self.options.ready_after_s

    def telemetry(self, now: float) -> list:
        s = self.state
        ready = self.ready(now)
        lat, lon = round(s.lat_deg * 1e7), round(s.lon_deg * 1e7)
        boot_ms = int((now - self.boot_time) * 1000) & 0xFFFFFFFF
        sensors = (R.MAV_SYS_STATUS_SENSOR_3D_GYRO | R.MAV_SYS_STATUS_SENSOR_3D_ACCEL
                   | R.MAV_SYS_STATUS_SENSOR_GPS)
        # ArduPilot reports passing pre-arm checks as the PREARM_CHECK health bit
        # (GCS_Common.cpp GCS_MAVLINK::send_sys_status, AP_Arming)
        health = sensors | (R.MAV_SYS_STATUS_PREARM_CHECK if ready else 0)
        return [
            self.heartbeat(),
            R.MAVLink_sys_status_message(sensors | R.MAV_SYS_STATUS_PREARM_CHECK,
                                         sensors | R.MAV_SYS_STATUS_PREARM_CHECK, health,
                                         0, 12600, -1, 100, 0, 0, 0, 0, 0, 0),
            R.MAVLink_gps_raw_int_message(
                boot_ms * 1000, R.GPS_FIX_TYPE_3D_FIX if ready else R.GPS_FIX_TYPE_NO_FIX,
                lat, lon, int(s.alt_amsl_m * 1000), 80, 120, 0, 0, 10 if ready else 0),
            R.MAVLink_global_position_int_message(
                boot_ms, lat, lon, int(s.alt_amsl_m * 1000), int(s.relative_alt_m * 1000),
                0, 0, 0, 0),
        ]
