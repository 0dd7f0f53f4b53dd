"""An emulated ArduCopter: what it says about itself and how it answers, as messages.

:class:`Vehicle` takes decoded messages and the time and returns messages (no sockets):
``handle`` for what arrives, ``tick`` for what time brings (HEARTBEAT and telemetry once
a period, the mission server's re-requests, the flight). Mission transfers go to the
:class:`~ftlbo_mav.sim.mission_server.MissionServer`; modes, arming, takeoff and flying
the stored mission to the :class:`~ftlbo_mav.sim.autopilot.Autopilot`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from ..ardupilot.modes import CopterMode
from ..mission.items import MissionItem
from .autopilot import Autopilot, AutopilotOptions
from .mission_server import MissionServer, MissionServerOptions
from .physics import FlightLimits

R = mavlink2


# Modes in which ArduCopter sets MAV_MODE_FLAG_GUIDED_ENABLED (GCS_Mavlink.cpp base_mode())
_GUIDED_MODES = {CopterMode.AUTO, CopterMode.RTL, CopterMode.LOITER, CopterMode.AVOID_ADSB,
                 CopterMode.FOLLOW, CopterMode.GUIDED, CopterMode.CIRCLE, CopterMode.POSHOLD,
                 CopterMode.BRAKE, CopterMode.SMART_RTL}


@dataclass(frozen=True)
class VehicleOptions:
    """``heartbeat_s``: period of HEARTBEAT and status telemetry (ArduPilot: 1 Hz heartbeat).
    ``ready_after_s``: GPS 3D fix and pre-arm checks pass this long after boot.
    ``position_after_s``: the EKF has a position estimate and arming is allowed (default:
    with the pre-arm checks; ArduCopter SITL: about 24 s and 42 s after boot).
    ``position_hz``: GLOBAL_POSITION_INT rate until a client asks for another with
    MAV_CMD_SET_MESSAGE_INTERVAL. ``limits``: the copter's speeds and accelerations."""

    heartbeat_s: float = 1.0
    ready_after_s: float = 0.0
    position_after_s: float | None = None
    position_hz: float = 4.0
    limits: FlightLimits = field(default_factory=FlightLimits)
    mission: MissionServerOptions = field(default_factory=MissionServerOptions)


@dataclass
class VehicleState:
    """What the vehicle reports about itself (kept in step with the autopilot)."""

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
        position_after = (options.ready_after_s if options.position_after_s is None
                          else options.position_after_s)
        self.autopilot = Autopilot(
            home=(lat, lon), boot_time=boot_time,
            options=AutopilotOptions(prearm_after_s=options.ready_after_s,
                                     position_after_s=position_after, limits=options.limits))
        self._home_alt = alt
        self._next_beat = boot_time
        self._position_period = 1.0 / options.position_hz
        self._next_position = boot_time
        self._stored: list = []

    def is_for_me(self, msg) -> bool:
        """MAVLink routing: a targeted message is handled only by its target (or broadcast)."""
        target = getattr(msg, "target_system", 0)
        return target in (0, self.sysid)

    def handle(self, msg, now: float) -> list:
        """Replies to one message (already through the link's faults and signing check)."""
        if msg.get_type() == "BAD_DATA" or not self.is_for_me(msg):
            return []
        kind = msg.get_type()
        if kind in ("COMMAND_LONG", "SET_MODE", "MISSION_SET_CURRENT"):
            self._sync_mission()
            self.autopilot.advance(now)
            replies = self._command(msg, now)
            self._sync_state()
            return replies
        return self.missions.handle(msg, now)

    def tick(self, now: float) -> tuple[list, list]:
        """``(broadcast, replies)``: telemetry and flight announcements for every client,
        and the mission server's re-requests/cancellations for the client of the transfer."""
        self._sync_mission()
        periodic = self.autopilot.advance(now)
        self._sync_state()
        if now >= self._next_beat:
            self._next_beat = now + self.options.heartbeat_s
            periodic += self.telemetry(now)
            # in the extended-status stream, whatever the mode (GCS_Common.cpp
            # send_mission_current)
            periodic.append(R.MAVLink_mission_current_message(self.autopilot.current))
        elif now >= self._next_position:
            periodic.append(self.position_message(now))
        if now >= self._next_position:
            self._next_position = max(self._next_position + self._position_period, now - 1.0)
        return periodic, self.missions.update(now)

    # -- flight commands (ArduCopter/GCS_Mavlink.cpp handle_command_long_packet, and
    #    libraries/GCS_MAVLink/GCS_Common.cpp for the commands every vehicle shares)
    def _sync_mission(self) -> None:
        """Give the autopilot the stored mission whenever an upload or clear changed it."""
        items = self.missions.items
        if items != self._stored:
            self._stored = list(items)
            self.autopilot.set_mission([
                MissionItem(seq=i, command=it.command, frame=it.frame, lat_deg=it.x / 1e7,
                            lon_deg=it.y / 1e7, alt_m=it.z, param1=it.param1,
                            param2=it.param2, param3=it.param3, param4=it.param4)
                for i, it in enumerate(items)])

    def _sync_state(self) -> None:
        ap, s = self.autopilot, self.state
        s.lat_deg, s.lon_deg = ap.latlon()
        s.relative_alt_m = float(ap.position[2])
        s.alt_amsl_m = self._home_alt + s.relative_alt_m
        s.mode = CopterMode(ap.mode)
        s.armed = ap.armed

    def _command(self, msg, now: float) -> list:
        ap = self.autopilot
        kind = msg.get_type()
        sender = (msg.get_srcSystem(), msg.get_srcComponent())
        if kind == "SET_MODE":  # common.xml: deprecated, still honoured by ArduPilot
            ap.set_mode(int(msg.custom_mode), now)
            return []
        if kind == "MISSION_SET_CURRENT":  # GCS_Common.cpp handle_mission_set_current
            if ap.set_current(int(msg.seq)):
                return [R.MAVLink_mission_current_message(ap.current)]
            return []
        cmd = msg.command
        text: list = []
        if cmd == R.MAV_CMD_COMPONENT_ARM_DISARM:
            if msg.param1 >= 0.5:
                reason = ap.arm(now) if not ap.armed else None
                ok = reason is None
                if reason:  # ArduPilot says why as STATUSTEXT beside the FAILED ack
                    text.append(R.MAVLink_statustext_message(R.MAV_SEVERITY_CRITICAL,
                                                             reason.encode()))
            else:
                ok = ap.landed or int(msg.param2) == 21196  # force-disarm magic number
                if ok:
                    ap.disarm()
        elif cmd == R.MAV_CMD_NAV_TAKEOFF:
            ok = ap.takeoff(float(msg.param7))
        elif cmd == R.MAV_CMD_DO_SET_MODE:
            reason = ap.mode_refusal(int(msg.param2), now)
            ok = reason is None and ap.set_mode(int(msg.param2), now)
            if reason:
                text.append(R.MAVLink_statustext_message(R.MAV_SEVERITY_WARNING,
                                                         reason.encode()))
        elif cmd == R.MAV_CMD_MISSION_START:
            ok = ap.set_mode(CopterMode.AUTO, now)
        elif cmd == R.MAV_CMD_DO_SET_MISSION_CURRENT:
            ok = ap.set_current(int(msg.param1))
            if ok:
                text.append(R.MAVLink_mission_current_message(ap.current))
        elif cmd == R.MAV_CMD_NAV_RETURN_TO_LAUNCH:
            ok = ap.set_mode(CopterMode.RTL, now)
        elif cmd == R.MAV_CMD_NAV_LAND:
            ok = ap.set_mode(CopterMode.LAND, now)
        elif cmd == R.MAV_CMD_SET_MESSAGE_INTERVAL:
            ok = int(msg.param1) == R.MAVLINK_MSG_ID_GLOBAL_POSITION_INT and msg.param2 > 0
            if ok:
                self._position_period = float(msg.param2) / 1e6
                self._next_position = now
        else:
            return [self._ack(cmd, R.MAV_RESULT_UNSUPPORTED, sender)]
        result = R.MAV_RESULT_ACCEPTED if ok else R.MAV_RESULT_FAILED
        return text + [self._ack(cmd, result, sender)]

    @staticmethod
    def _ack(command: int, result: int, to: tuple[int, int]):
        return R.MAVLink_command_ack_message(command, result, 0, 0, to[0], to[1])

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
            self.position_message(now),
        ]

    def position_message(self, now: float):
        s, v = self.state, self.autopilot.velocity
        boot_ms = int((now - self.boot_time) * 1000) & 0xFFFFFFFF
        # GLOBAL_POSITION_INT velocities are NED cm/s; ours are ENU m/s
        return R.MAVLink_global_position_int_message(
            boot_ms, round(s.lat_deg * 1e7), round(s.lon_deg * 1e7), int(s.alt_amsl_m * 1000),
            int(round(s.relative_alt_m * 1000)), int(v[1] * 100), int(v[0] * 100),
            int(-v[2] * 100), 0)
