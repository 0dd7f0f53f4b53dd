"""An emulated ArduCopter: what it says about itself and how it answers, as messages.

Kept whole: one vehicle's GCS_MAVLINK (what it answers and what it streams, per link, read
from one state); its flight is :mod:`.autopilot`, its mission protocol :mod:`.mission_server`.

:class:`Vehicle` takes decoded messages, the link they came on and the time, and returns
messages (no sockets): ``handle`` for what arrives (the replies for that link), ``tick``
for what time brings, per link. Mission transfers go to the
:class:`~ftlbo_mav.sim.mission_server.MissionServer`; modes, arming, takeoff and flying
the stored mission to the :class:`~ftlbo_mav.sim.autopilot.Autopilot`.

What each link receives follows ArduPilot's GCS_MAVLINK, one instance per serial port
(libraries/GCS_MAVLink/GCS_Common.cpp): HEARTBEAT (1 Hz) and TIMESYNC (every 10 s)
unconditionally, HOME_POSITION and GPS_GLOBAL_ORIGIN once when home is set, and
nothing else until the link asks with MAV_CMD_SET_MESSAGE_INTERVAL (one message) or
REQUEST_DATA_STREAM (a group, :data:`ftlbo_mav.ardupilot.streams.STREAM_MESSAGES`);
STATUSTEXT only once the link has sent something (GCS_MAVLINK::is_active). Recorded on
ArduCopter 4.5.6 SITL: ``tests/data/ardupilot-4.5.6/boot.json``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Hashable
from dataclasses import dataclass, field, replace

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from ..ardupilot.commands import INSTANT_BOOT, BootTimeline
from ..ardupilot.copters import SITL_CLOCK_BEHIND_S, release_for
from ..ardupilot.fence import (
    FENCE_CAPACITY,
    MISSION_TYPE_FENCE,
    MISSION_TYPE_MISSION,
    MISSION_TYPE_RALLY,
    RALLY_CAPACITY,
)
from ..ardupilot.firmware import (
    RECORDED,
    RECORDED_CAPABILITIES,
    RECORDED_CUSTOM_VERSION,
    Firmware,
)
from ..ardupilot.modes import CopterMode, heartbeat_base_mode
from ..ardupilot.navigation import PARAM_COUNT, with_release
from ..ardupilot.streams import data_stream_messages, radio_slowdown, reschedule_interval_s
from ..link.rtcm import Reassembler
from ..mission.items import MissionItem
from .autopilot import Autopilot, AutopilotOptions
from .gps import GpsError, GpsErrorOptions
from .mission_server import EVERY_LINK, SENDER, MissionServer, MissionServerOptions
from .physics import FlightLimits

R = mavlink2
Link = Hashable

EKF_HEALTHY_FLAGS = (R.EKF_ATTITUDE | R.EKF_VELOCITY_HORIZ | R.EKF_VELOCITY_VERT
                     | R.EKF_POS_HORIZ_REL | R.EKF_POS_HORIZ_ABS | R.EKF_POS_VERT_ABS
                     | R.EKF_PRED_POS_HORIZ_REL | R.EKF_PRED_POS_HORIZ_ABS)
TIMESYNC_S = 10.0  # GCS_MAVLINK::update_send: TIMESYNC every 10 s, asked or not


@dataclass(frozen=True)
class VehicleOptions:
    """``heartbeat_s``: period of HEARTBEAT (ArduPilot: 1 Hz).
    ``boot``: when the vehicle becomes ready, NO_SPACE ends, the GPS has a fix, home is
    set, pre-arm passes and arming is allowed (:class:`BootTimeline`; the recorded one is
    ``RECORDED_BOOT``, ``RECORDED_BOOT.scaled(0.05)`` keeps its order at 1/20 of the
    time). Without it, ``ready_after_s`` (fix, home and pre-arm) and ``position_after_s``
    (arming allowed; default: with the pre-arm checks) give a simpler timeline.
    ``interval_drop_s``: a SET_MESSAGE_INTERVAL received this soon after boot is
    acknowledged and then lost (SITL: the first request, sent as the first client
    connects, is; one 24 ms later is kept). ``limits``: the copter's navigation
    parameters (ArduCopter's defaults, :class:`~ftlbo_mav.sim.physics.FlightLimits`) and
    what its airframe adds; :func:`~ftlbo_mav.sim.physics.varied` makes one copter of a
    real fleet (start latency, WPNAV_JERK). ``gps``: its GPS error and what its GPS
    reports (:mod:`.gps`; default: SITL's, no error, RTK fixed, 0.3 m). ``firmware``: the
    version AUTOPILOT_VERSION reports (default ArduCopter 4.5.6 as recorded); ``autopilot``
    and ``vehicle_type``: what HEARTBEAT says (ArduPilot, a quadrotor)."""

    heartbeat_s: float = 1.0
    ready_after_s: float = 0.0
    position_after_s: float | None = None
    boot: BootTimeline | None = None
    interval_drop_s: float = 0.02
    limits: FlightLimits = field(default_factory=FlightLimits)
    mission: MissionServerOptions = field(default_factory=MissionServerOptions)
    gps: GpsErrorOptions = field(default_factory=GpsErrorOptions)
    firmware: Firmware = RECORDED
    autopilot: int = mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA
    vehicle_type: int = mavlink2.MAV_TYPE_QUADROTOR

    def timeline(self) -> BootTimeline:
        if self.boot is not None:
            return self.boot
        armable = self.ready_after_s if self.position_after_s is None else self.position_after_s
        return BootTimeline(ready_s=INSTANT_BOOT.ready_s, storage_s=0.0,
                            gps_fix_s=self.ready_after_s, home_s=self.ready_after_s,
                            prearm_s=self.ready_after_s, armable_s=armable)


@dataclass
class VehicleState:
    """What the vehicle reports about itself (kept in step with the autopilot)."""

    lat_deg: float
    lon_deg: float
    alt_amsl_m: float
    relative_alt_m: float = 0.0
    mode: CopterMode = CopterMode.STABILIZE
    armed: bool = False


@dataclass
class LinkState:
    """One GCS_MAVLINK instance: which messages it was asked for, at what period."""

    active: bool = False  # has received something (STATUSTEXT goes to active links only)
    periods: dict[int, float] = field(default_factory=dict)  # msgid -> seconds
    due: dict[int, float] = field(default_factory=dict)
    next_beat: float = 0.0
    next_timesync: float = 0.0
    home_sent: bool = False
    home_at: tuple[float, float] = (0.0, 0.0)  # the home (east, north) last sent
    outbox: list = field(default_factory=list)
    slowdown_ms: int = 0  # stream_slowdown_ms: its radio's flow control (RADIO_STATUS)


class Vehicle:
    """One emulated ArduCopter, system id ``sysid``, component 1 (the autopilot)."""

    compid = R.MAV_COMP_ID_AUTOPILOT1

    def __init__(self, *, sysid: int, home: tuple[float, float, float],
                 options: VehicleOptions = VehicleOptions(), boot_time: float = 0.0,
                 utc_offset_s: float | None = None):
        """``utc_offset_s``: the UTC its GPS gives at ``now`` = 0 (its clock: UTC seconds =
        now + offset); default the wall clock at its boot. Vehicles of one simulator share
        one, as GPS receivers share GPS time."""
        self.sysid = sysid
        self.options = options
        self.boot_time = boot_time
        self.boot = options.timeline()
        lat, lon, alt = home
        self.home = (lat, lon, alt)
        self.state = VehicleState(lat_deg=lat, lon_deg=lon, alt_amsl_m=alt)
        mission_options = options.mission
        if self.boot.storage_s > mission_options.boot_no_space_s:
            mission_options = MissionServerOptions(
                capacity=mission_options.capacity, rerequest_s=mission_options.rerequest_s,
                upload_timeout_s=mission_options.upload_timeout_s,
                boot_no_space_s=self.boot.storage_s)
        self.missions = MissionServer(sysid=sysid, home=None, options=mission_options,
                                      boot_time=boot_time)
        # MissionItemProtocol_Fence and _Rally (GCS::get_prot_for_mission_type)
        self.fence = MissionServer(sysid=sysid, home=None, boot_time=boot_time,
                                   mission_type=MISSION_TYPE_FENCE,
                                   options=MissionServerOptions(capacity=FENCE_CAPACITY))
        self.rally = MissionServer(sysid=sysid, home=None, boot_time=boot_time,
                                   mission_type=MISSION_TYPE_RALLY,
                                   options=MissionServerOptions(capacity=RALLY_CAPACITY))
        self._fence_version = -1
        # the navigation of the release it reports (AUTOPILOT_VERSION): ardupilot/navigation.py
        release = release_for(options.firmware.encode())
        limits = replace(options.limits, nav=with_release(options.limits.nav, release))
        self.autopilot = Autopilot(home=(lat, lon), boot_time=boot_time,
                                   options=AutopilotOptions(boot=self.boot, limits=limits))
        self.autopilot.home_alt_m = alt
        self.utc_offset_s = time.time() - boot_time if utc_offset_s is None else utc_offset_s
        # its clock of the day (AP_RTC, from its GPS), as its release's SITL keeps it:
        # start gates and SYSTEM_TIME go by it; flies only after its GPS fix
        self.autopilot.utc_offset_s = self.utc_offset_s - SITL_CLOCK_BEHIND_S.get(release, 0.0)
        self.gps = GpsError(options.gps, self.autopilot.params, lat_deg=lat)
        self._ground_truth: np.ndarray | None = np.zeros(2)  # placed at its home, truly
        self._home_memo: tuple | None = None  # (home_en, current_home()) last converted
        self.links: dict[Link, LinkState] = {}
        self._mission_version = -1
        # GPS_RTCM_DATA reassembled as AP_GPS::handle_gps_rtcm_fragment does (link/rtcm.py)
        self.rtcm = Reassembler()
        self.rtcm_frames: list[bytes] = []

    # -- links
    def link(self, link: Link, now: float | None = None) -> LinkState:
        st = self.links.get(link)
        if st is None:
            t = self.boot_time if now is None else now
            st = self.links[link] = LinkState(next_beat=t, next_timesync=self.boot_time
                                              + TIMESYNC_S)
        return st

    def home_set(self, now: float) -> bool:
        return now - self.boot_time >= self.boot.home_s

    def is_for_me(self, msg) -> bool:
        """MAVLink routing: a targeted message is handled only by its target (or broadcast)."""
        target = getattr(msg, "target_system", 0)
        return target in (0, self.sysid)

    def _route(self, pairs, link: Link) -> list:
        """``(link, msg)`` pairs: the sender's returned, the others queued for their link."""
        mine = []
        for to, msg in pairs:
            if to is SENDER or to == link:
                mine.append(msg)
            elif to == EVERY_LINK:
                for key, st in self.links.items():
                    if key == link:
                        mine.append(msg)
                    elif st.active:
                        st.outbox.append(msg)
            else:
                self.link(to).outbox.append(msg)
        return mine

    def handle(self, msg, now: float, link: Link = 0) -> list:
        """Replies for ``link`` to one message (already through its faults and signing)."""
        if msg.get_type() == "BAD_DATA":
            return []
        st = self.link(link, now)
        kind = msg.get_type()
        if kind == "RADIO_STATUS":  # its radio: no GCS, whoever it is addressed to
            st.slowdown_ms = radio_slowdown(st.slowdown_ms, int(msg.txbuf))
            return []
        st.active = True  # GCS_MAVLINK::packetReceived: the link is a GCS
        if not self.is_for_me(msg):
            return []
        self._sync_mission()
        news = self._announce(self.autopilot.advance(now), link)
        self._stand_still(now)
        if kind in ("COMMAND_LONG", "SET_MODE", "MISSION_SET_CURRENT", "REQUEST_DATA_STREAM"):
            replies = self._command(msg, now, st)
        elif kind in ("PARAM_REQUEST_READ", "PARAM_SET"):
            replies = self._param(msg)
            self.gps.param_changed(now - self.boot_time)  # SIM_GPS_GLITCH_X/Y
        elif kind == "SET_POSITION_TARGET_GLOBAL_INT":
            replies = self._position_target(msg)
        elif kind == "GPS_RTCM_DATA":  # AP_GPS::handle_gps_rtcm_data: injected, no reply
            frame = self.rtcm.add(msg.flags, bytes(msg.data[:msg.len]))
            if frame is not None:
                self.rtcm_frames.append(frame)
            replies = []
        else:
            replies = self.server_for(msg).handle(msg, now, link)
            self.home_for_missions(now)
        self._sync_state()
        return news + self._route(replies, link)

    def server_for(self, msg) -> MissionServer:
        """The mission, fence or rally protocol, by the message's ``mission_type``."""
        kind = getattr(msg, "mission_type", MISSION_TYPE_MISSION)
        return {MISSION_TYPE_FENCE: self.fence, MISSION_TYPE_RALLY: self.rally}.get(
            kind, self.missions)

    def current_home(self) -> tuple[float, float, float]:
        """Home as ArduCopter holds it now: where it booted, then where it believed it
        was when it last armed (:attr:`.autopilot.Autopilot.home_en`)."""
        ap = self.autopilot
        lat, lon = ap.tangent.to_latlon(float(ap.home_en[0]), float(ap.home_en[1]))
        return (lat, lon, self.home[2])

    def home_for_missions(self, now: float) -> None:
        if not self.home_set(now):
            self.missions.home = None
            return
        at = tuple(self.autopilot.home_en.tolist())  # converted again only when it moved
        if self._home_memo is None or self._home_memo[0] != at:
            self._home_memo = (at, self.current_home())
        self.missions.home = self._home_memo[1]

    def _announce(self, texts: list, link: Link | None) -> list:
        """The autopilot's STATUSTEXT and MISSION_ITEM_REACHED for every active link;
        returns those for ``link``."""
        mine = []
        for msg in texts:
            for key, st in self.links.items():
                if not st.active and msg.get_type() == "STATUSTEXT":
                    continue
                (mine if key == link else st.outbox).append(msg)
        return mine

    def tick(self, now: float) -> dict[Link, list]:
        """What time brings, per link: the asked-for telemetry, HEARTBEAT, TIMESYNC,
        home once, announcements, and the mission server's re-requests/cancellations."""
        self._sync_mission()
        self._announce(self.autopilot.advance(now), None)
        self._stand_still(now)
        self._sync_state()
        self.home_for_missions(now)
        for server in (self.missions, self.fence, self.rally):
            self._route(server.update(now), None)
        out: dict[Link, list] = {}
        for key, st in self.links.items():
            msgs, st.outbox = st.outbox, []
            if now >= st.next_beat:
                st.next_beat = max(st.next_beat + self.options.heartbeat_s, now - 1.0)
                msgs.append(self.heartbeat())
            if now >= st.next_timesync:
                st.next_timesync += TIMESYNC_S
                msgs.append(R.MAVLink_timesync_message(0, int((now - self.boot_time) * 1e9)))
            home_at = tuple(self.autopilot.home_en.tolist())
            if not st.home_sent and self.home_set(now):
                st.home_sent = True  # AP_AHRS on setting home: MSG_HOME and MSG_ORIGIN
                st.home_at = home_at
                msgs += self.home_messages(now)
            elif st.home_sent and st.home_at != home_at:  # AP_AHRS::set_home: MSG_HOME
                st.home_at = home_at
                msgs.append(self.home_messages(now)[0])
            for msgid, period in st.periods.items():
                if now >= st.due[msgid]:
                    st.due[msgid] = max(st.due[msgid] + reschedule_interval_s(
                        period, st.slowdown_ms), now - period)
                    m = self.message(msgid, now)
                    if m is not None:
                        msgs.append(m)
            out[key] = msgs
        return out

    # -- flight commands (ArduCopter/GCS_Mavlink.cpp handle_command_long_packet, and
    #    libraries/GCS_MAVLink/GCS_Common.cpp for the commands every vehicle shares)
    def _sync_mission(self) -> None:
        """Give the autopilot the stored mission (and fence, rally points) whenever an
        upload or clear changed them."""
        if self.fence.version + self.rally.version != self._fence_version:
            self._fence_version = self.fence.version + self.rally.version
            self.autopilot.set_fence(list(self.fence.items), list(self.rally.items))
        if self.missions.version == self._mission_version:
            return
        self._mission_version = self.missions.version
        self.autopilot.set_mission([
            MissionItem(seq=i, command=it.command, frame=it.frame, lat_deg=it.x / 1e7,
                        lon_deg=it.y / 1e7, alt_m=it.z, param1=it.param1,
                        param2=it.param2, param3=it.param3, param4=it.param4)
            for i, it in enumerate(self.missions.items)])

    def _stand_still(self, now: float) -> None:
        """On the ground a copter does not move; its estimate does, by the GPS error its
        EKF has fused (ArduCopter 4.5.6 SITL, tests/data/ardupilot-4.5.6/gps.json: a
        SIM_GPS_GLITCH_X step on the ground moves GLOBAL_POSITION_INT, never SIM_STATE).
        So a copter placed at its home believes it is at home plus its GPS error, and
        takes off and starts its mission from there, as one on SITL does. In the air the
        controller holds the estimate and the truth moves instead (:mod:`.gps`)."""
        ap = self.autopilot
        if not ap.landed:
            self._ground_truth = None
            return
        t = now - self.boot_time
        fused = self.gps.error(t) - self.gps.transient(t)
        if self._ground_truth is None:  # just touched down: where it truly stands
            self._ground_truth = ap.position[:2] - fused
        ap.position[:2] = self._ground_truth + fused

    def _sync_state(self) -> None:
        ap, s = self.autopilot, self.state
        s.lat_deg, s.lon_deg = ap.latlon()
        s.relative_alt_m = float(ap.position[2])
        s.alt_amsl_m = self.home[2] + s.relative_alt_m
        if s.mode != ap.mode:  # (an IntEnum: equal to its number)
            s.mode = CopterMode(ap.mode)
        s.armed = ap.armed

    def _set_interval(self, st: LinkState, msgid: int, interval_us: float, now: float) -> int:
        """GCS_MAVLINK::handle_command_set_message_interval / set_message_interval."""
        if now - self.boot_time < self.options.interval_drop_s:
            return R.MAV_RESULT_ACCEPTED  # acknowledged, then lost as SITL's boot resets rates
        if interval_us == -1 or msgid == R.MAVLINK_MSG_ID_HEARTBEAT:
            st.periods.pop(msgid, None)  # -1: stop (HEARTBEAT keeps its 1 Hz here)
            return R.MAV_RESULT_ACCEPTED
        if interval_us == 0:  # 0: the default rate, which is "not sent" with copter.parm
            st.periods.pop(msgid, None)
            return R.MAV_RESULT_ACCEPTED
        if interval_us < 0:
            return R.MAV_RESULT_FAILED
        st.periods[msgid] = interval_us / 1e6
        st.due[msgid] = now
        return R.MAV_RESULT_ACCEPTED

    def _command(self, msg, now: float, st: LinkState) -> list:
        ap = self.autopilot
        kind = msg.get_type()
        sender = (msg.get_srcSystem(), msg.get_srcComponent())
        if kind == "REQUEST_DATA_STREAM":  # GCS_MAVLINK::handle_request_data_stream
            rate = msg.req_message_rate if msg.start_stop else 0
            for msgid in data_stream_messages(msg.req_stream_id):
                if rate > 0:
                    st.periods[msgid] = 1.0 / rate
                    st.due[msgid] = now
                else:
                    st.periods.pop(msgid, None)
            return []
        if kind == "SET_MODE":  # answered with a COMMAND_ACK for "command" 11
            result, texts = ap.command_set_mode(msg.base_mode, int(msg.custom_mode), now)
            return [(SENDER, m) for m in texts] + [
                (SENDER, self._ack(R.MAVLINK_MSG_ID_SET_MODE, result, sender))]
        if kind == "MISSION_SET_CURRENT":  # GCS_Common.cpp handle_mission_set_current
            if ap.set_current(int(msg.seq)):
                return [(EVERY_LINK, self.mission_current())]
            return []
        cmd = msg.command
        if cmd == R.MAV_CMD_SET_MESSAGE_INTERVAL:
            result, texts = self._set_interval(st, int(msg.param1), msg.param2, now), []
        elif cmd == R.MAV_CMD_REQUEST_MESSAGE:
            m = self.message(int(msg.param1), now)
            if m is None:
                result, texts = R.MAV_RESULT_FAILED, []
            else:
                result, texts = R.MAV_RESULT_ACCEPTED, []
                st.outbox.append(m)
        else:
            result, texts = ap.command(cmd, [msg.param1, msg.param2, msg.param3, msg.param4,
                                             msg.param5, msg.param6, msg.param7], now)
        extra = []
        if cmd in (R.MAV_CMD_DO_SET_MISSION_CURRENT,) and result == R.MAV_RESULT_ACCEPTED:
            extra.append((EVERY_LINK, self.mission_current()))
        return ([(EVERY_LINK, m) for m in texts] + [(SENDER, self._ack(cmd, result, sender))]
                + extra)

    def _param(self, msg) -> list:
        """GCS_Param.cpp: PARAM_REQUEST_READ by name is answered with PARAM_VALUE on the
        asking link (param_index -1, as sent for a read by name); an unknown name or a
        read by index of a parameter the emulator lacks gets nothing. PARAM_SET of a known
        parameter sets it and PARAM_VALUE goes to every active link
        (GCS::send_parameter_value); an unknown one or a NaN is ignored."""
        name = msg.param_id if isinstance(msg.param_id, str) else msg.param_id.decode()
        name = name.rstrip("\x00")
        ap = self.autopilot
        if msg.get_type() == "PARAM_SET":
            if not ap.set_param(name, float(msg.param_value)):
                return []
            to = EVERY_LINK
        else:
            if msg.param_index != -1:
                return []  # the emulator keeps no parameter table to index
            to = SENDER
        known = ap.get_param(name)
        if known is None:
            return []
        value, kind = known
        # param_index -1 is 65535 on the wire (uint16), as recorded in flight.json
        return [(to, R.MAVLink_param_value_message(name.encode(), value, kind, PARAM_COUNT,
                                                   0xFFFF))]

    def _position_target(self, msg) -> list:
        """GUIDED's SET_POSITION_TARGET_GLOBAL_INT with a position (ArduCopter/
        GCS_Mavlink.cpp handle_message_set_position_target_global_int ->
        ModeGuided::set_destination), altitude above home (frames 3 / 6): fly there.
        Ignored outside GUIDED or without a position; never acknowledged."""
        ignore_position = msg.type_mask & 0b111 == 0b111
        if ignore_position or msg.coordinate_frame not in (
                R.MAV_FRAME_GLOBAL_RELATIVE_ALT, R.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT):
            return []
        ap = self.autopilot
        east, north = ap.tangent.to_en(msg.lat_int * 1e-7, msg.lon_int * 1e-7)
        ap.goto([east, north, float(msg.alt)])
        return []

    @staticmethod
    def _ack(command: int, result: int, to: tuple[int, int]):
        return R.MAVLink_command_ack_message(command, result, 0, 0, to[0], to[1])

    # -- what ArduCopter sends
    def autopilot_version(self):
        """GCS_Common.cpp send_autopilot_version, as recorded (boot.json ``version``): the
        version as major<<24|minor<<16|patch<<8|type, the git hash's first 8 characters,
        the capabilities; board, vendor, product and OS versions 0 on SITL."""
        custom = RECORDED_CUSTOM_VERSION.encode()
        return R.MAVLink_autopilot_version_message(
            RECORDED_CAPABILITIES, self.options.firmware.encode(), 0, 0, 0, custom, bytes(8),
            bytes(8), 0, 0, 0)

    def heartbeat(self):
        s = self.state
        base = heartbeat_base_mode(s.mode, armed=s.armed)
        status = R.MAV_STATE_ACTIVE if s.armed else R.MAV_STATE_STANDBY
        # GCS_Common.cpp send_heartbeat: frame type, ARDUPILOTMEGA, base_mode, custom mode
        return R.MAVLink_heartbeat_message(self.options.vehicle_type, self.options.autopilot,
                                           base, int(s.mode), status, 3)

    def ready(self, now: float) -> bool:
        """The pre-arm checks pass (SYS_STATUS PREARM_CHECK healthy)."""
        return now - self.boot_time >= self.boot.prearm_s

    def home_messages(self, now: float) -> list:
        """HOME_POSITION (the current home) and GPS_GLOBAL_ORIGIN (the EKF origin: where
        it booted)."""
        usec = int((now - self.boot_time) * 1e6)
        lat, lon, alt = self.current_home()
        olat, olon, _ = self.home
        ialt = int(round(alt * 1000))
        return [R.MAVLink_home_position_message(round(lat * 1e7), round(lon * 1e7), ialt,
                                                0, 0, 0, [float("nan")] * 4, 0, 0, 0, usec),
                R.MAVLink_gps_global_origin_message(round(olat * 1e7), round(olon * 1e7),
                                                    ialt, usec)]

    def mission_current(self):
        """MISSION_CURRENT (GCS_Common.cpp send_mission_current): seq (the current
        *navigation* item, AP_Mission::get_current_nav_index: a DO item made current is
        shown as the navigation item after it), total (the last index), mission_state and
        mission_mode (1 in AUTO)."""
        ap = self.autopilot
        total = max(len(self.missions.items) - 1, 0)
        state = ap.mission_state()
        return R.MAVLink_mission_current_message(ap.current_nav_index(), total, state,
                                                 1 if ap.mode == CopterMode.AUTO else 0)

    def message(self, msgid: int, now: float):
        """The message ``msgid`` as the vehicle would send it now, or None (not emulated)."""
        s = self.state
        fix = now - self.boot_time >= self.boot.gps_fix_s
        if msgid == R.MAVLINK_MSG_ID_HEARTBEAT:
            return self.heartbeat()
        if msgid == R.MAVLINK_MSG_ID_SYS_STATUS:
            sensors = (R.MAV_SYS_STATUS_SENSOR_3D_GYRO | R.MAV_SYS_STATUS_SENSOR_3D_ACCEL
                       | R.MAV_SYS_STATUS_SENSOR_GPS | R.MAV_SYS_STATUS_PREARM_CHECK)
            # passing pre-arm checks is the PREARM_CHECK health bit (send_sys_status)
            health = sensors if self.ready(now) else sensors & ~R.MAV_SYS_STATUS_PREARM_CHECK
            present, enabled = sensors, sensors
            fence = self.autopilot.fence_status()  # AC_Fence::sys_status_present/_enabled/_failed
            if fence[0]:
                present |= R.MAV_SYS_STATUS_GEOFENCE
                enabled |= R.MAV_SYS_STATUS_GEOFENCE if fence[1] else 0
                health |= 0 if fence[2] else R.MAV_SYS_STATUS_GEOFENCE
            b = self.autopilot.battery  # GCS_MAVLINK::send_sys_status: mV, cA, per cent
            return R.MAVLink_sys_status_message(
                present, enabled, health, 0, round(b.voltage * 1000), round(b.current_a * 100),
                b.remaining_pct(self.autopilot.params), 0, 0, 0, 0, 0, 0)
        if msgid == R.MAVLINK_MSG_ID_BATTERY_STATUS:
            return self.battery_status()
        if msgid == R.MAVLINK_MSG_ID_GPS_RAW_INT:
            return self.gps_message(now, fix)
        if msgid == R.MAVLINK_MSG_ID_GLOBAL_POSITION_INT:
            return self.position_message(now)
        if msgid == R.MAVLINK_MSG_ID_EKF_STATUS_REPORT:
            # a healthy EKF3 (AP_NavEKF3_Outputs.cpp send_status_report): attitude,
            # velocities, relative and absolute position, once it uses the GPS
            flags = EKF_HEALTHY_FLAGS if fix else R.EKF_ATTITUDE
            return R.MAVLink_ekf_status_report_message(flags, 0.01, 0.01, 0.01, 0.01, 0.0, 0.0)
        if msgid == R.MAVLINK_MSG_ID_SIM_STATE:
            return self.sim_state(now)
        if msgid == R.MAVLINK_MSG_ID_SYSTEM_TIME:
            # GCS_MAVLINK::send_system_time: AP_RTC's UTC (0 until its GPS gave a time)
            utc_us = int((now + self.autopilot.utc_offset_s) * 1e6) if fix else 0
            return R.MAVLink_system_time_message(
                utc_us, int((now - self.boot_time) * 1000) & 0xFFFFFFFF)
        if msgid == R.MAVLINK_MSG_ID_AUTOPILOT_VERSION:
            return self.autopilot_version()
        if msgid == R.MAVLINK_MSG_ID_MISSION_CURRENT:
            return self.mission_current()
        if msgid == R.MAVLINK_MSG_ID_EXTENDED_SYS_STATE:
            ap = self.autopilot
            landed = (R.MAV_LANDED_STATE_ON_GROUND if ap.landed or not ap.armed
                      else R.MAV_LANDED_STATE_IN_AIR)
            return R.MAVLink_extended_sys_state_message(0, landed)
        if msgid == R.MAVLINK_MSG_ID_HOME_POSITION:
            return self.home_messages(now)[0] if self.home_set(now) else None
        if msgid == R.MAVLINK_MSG_ID_VFR_HUD:
            v = self.autopilot.velocity
            return R.MAVLink_vfr_hud_message(0.0, float((v[0] ** 2 + v[1] ** 2) ** 0.5), 0, 0,
                                             s.alt_amsl_m, float(v[2]))
        return None

    def reading(self, now: float) -> tuple[float, float]:
        """What its GPS reads (lat, lon): the position it flies (its estimate) plus the
        part of a GPS step its EKF has not fused yet (:meth:`.gps.GpsError.transient`)."""
        ap = self.autopilot
        de, dn = self.gps.transient(now - self.boot_time)
        if de == 0 and dn == 0:
            return self.state.lat_deg, self.state.lon_deg
        return ap.tangent.to_latlon(ap.position[0] + de, ap.position[1] + dn)

    def battery_status(self):
        """BATTERY_STATUS as GCS_MAVLINK::send_battery_status fills it for an analog
        monitor without cells (battery.json): voltages[0] the pack's mV, the rest unused;
        no temperature; mAh and hJ consumed; no time remaining."""
        ap = self.autopilot
        b = ap.battery
        volts = [round(b.voltage * 1000)] + [0xFFFF] * 9
        return R.MAVLink_battery_status_message(
            0, R.MAV_BATTERY_FUNCTION_UNKNOWN, R.MAV_BATTERY_TYPE_UNKNOWN, 0x7FFF, volts,
            int(b.current_a * 100), int(b.consumed_mah), int(b.consumed_wh * 36.0),
            b.remaining_pct(ap.params), 0, b.charge_state())

    def true_position(self, now: float) -> tuple[float, float, float]:
        """Where the copter truly is (latitude, longitude degrees, altitude m AMSL): its
        estimate less the fused GPS error (:mod:`.gps`)."""
        ap = self.autopilot
        de, dn = self.gps.unfused(now - self.boot_time)
        east, north = ap.position[:2].tolist()
        lat, lon = ap.tangent.to_latlon(east + de, north + dn)
        return lat, lon, float(self.state.alt_amsl_m)

    def sim_state(self, now: float):
        """SIM_STATE (SITL's true state, libraries/SITL/SITL.cpp ``sim_state_send``): the
        position the copter truly has, its estimate less the fused GPS error (``lat`` and
        ``lon`` as SITL fills them: 1e-7 degrees in a float, as ``lat_int``)."""
        lat, lon, alt = self.true_position(now)
        v = self.autopilot.velocity
        return R.MAVLink_sim_state_message(
            q1=1.0, q2=0.0, q3=0.0, q4=0.0, roll=0.0, pitch=0.0, yaw=0.0, xacc=0.0, yacc=0.0,
            zacc=0.0, xgyro=0.0, ygyro=0.0, zgyro=0.0, lat=lat * 1e7, lon=lon * 1e7,
            alt=alt, std_dev_horz=0.0, std_dev_vert=0.0,
            vn=float(v[1]), ve=float(v[0]), vd=float(-v[2]), lat_int=round(lat * 1e7),
            lon_int=round(lon * 1e7))

    def gps_message(self, now: float, fix: bool):
        """GPS_RAW_INT (GCS_Common.cpp send_gps_raw): the fix type and accuracy its GPS is
        set to report (:class:`.gps.GpsErrorOptions`, SIM_GPS_ACC), the position it
        reads (the copter's estimate), ground speed and course."""
        s, v = self.state, self.autopilot.velocity
        boot_ms = int((now - self.boot_time) * 1000) & 0xFFFFFFFF
        if not fix:
            return R.MAVLink_gps_raw_int_message(boot_ms * 1000, R.GPS_FIX_TYPE_NO_FIX, 0, 0,
                                                 0, 121, 200, 0, 0, 0)
        lat, lon = self.reading(now)
        speed = float(math.hypot(v[0], v[1]))
        course = math.degrees(math.atan2(v[0], v[1])) % 360.0
        acc_mm = int(round(self.gps.accuracy_m() * 1000))
        o = self.options.gps
        return R.MAVLink_gps_raw_int_message(
            boot_ms * 1000, o.fix_type, round(lat * 1e7), round(lon * 1e7),
            int(s.alt_amsl_m * 1000), 121, 200, int(round(speed * 100)),
            int(round(course * 100)) % 36000, o.satellites, int(s.alt_amsl_m * 1000),
            acc_mm, acc_mm, 0, 0, 0)

    def position_message(self, now: float):
        s, v = self.state, self.autopilot.velocity
        boot_ms = int((now - self.boot_time) * 1000) & 0xFFFFFFFF
        lat, lon = s.lat_deg, s.lon_deg
        # GLOBAL_POSITION_INT velocities are NED cm/s; ours are ENU m/s
        return R.MAVLink_global_position_int_message(
            boot_ms, round(lat * 1e7), round(lon * 1e7), int(s.alt_amsl_m * 1000),
            int(round(s.relative_alt_m * 1000)), int(v[1] * 100), int(v[0] * 100),
            int(-v[2] * 100), 0)
