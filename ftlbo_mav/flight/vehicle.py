"""One vehicle seen from the ground: its live status and the commands a flight needs.

A :class:`FlightVehicle` owns a channel of a :class:`~ftlbo_mav.link.endpoints.Link`
and a reader thread that keeps its :class:`~.status.Status` up to date (HEARTBEAT,
GLOBAL_POSITION_INT, MISSION_CURRENT, COMMAND_ACK, STATUSTEXT; on a simulated clock no
thread: whoever reads a message updates the status); it asks the vehicle for those streams on its
link, since ArduPilot sends only HEARTBEAT unasked (:mod:`ftlbo_mav.ardupilot.streams`).
Commands are sent with a timeout and a retry budget and fail with :class:`FlightError`
naming the vehicle and the step.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable

from pymavlink.dialects.v20 import ardupilotmega as R

from .. import clock
from ..ardupilot.modes import CopterMode, mode_name
from ..ardupilot.streams import flight_streams
from ..errors import FtlboError
from ..link.endpoints import LinkError
from ..link.firmware import version_request
from .navigation import jump_vector
from .status import CLOCK_REPORTS, Status

REBOOT_BACK_S = 5.0  # a position report this much older than the last: the vehicle rebooted
CLOCK_RATE_AFTER_S = 2.0  # a vehicle's clock rate is measured over its reports since then


class FlightError(FtlboError):
    """A vehicle refused or did not answer a flight step."""

    def __init__(self, name: str, sysid: int, step: str, problem: str) -> None:
        self.name, self.sysid, self.step = name, sysid, step
        super().__init__(f"{name} (sysid {sysid}): {step}: {problem}")


class LinkLost(FlightError):
    """A command could not be sent: the vehicle's link is down (closed, broken)."""


class FlightAborted(FtlboError):
    """The flight was aborted (Ctrl-C, ``ftlbo-mav abort``): no more commands but the
    abort's own mode change go to the vehicle."""

    def __init__(self, name: str, sysid: int, mode: str) -> None:
        self.name, self.sysid, self.mode = name, sysid, mode
        super().__init__(f"{name} (sysid {sysid}): flight aborted, vehicle sent to {mode}")


POSITION_ONLY = (R.POSITION_TARGET_TYPEMASK_VX_IGNORE | R.POSITION_TARGET_TYPEMASK_VY_IGNORE
                 | R.POSITION_TARGET_TYPEMASK_VZ_IGNORE | R.POSITION_TARGET_TYPEMASK_AX_IGNORE
                 | R.POSITION_TARGET_TYPEMASK_AY_IGNORE | R.POSITION_TARGET_TYPEMASK_AZ_IGNORE
                 | R.POSITION_TARGET_TYPEMASK_YAW_IGNORE
                 | R.POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE)
"""SET_POSITION_TARGET_*'s type_mask for a position alone."""


class FlightVehicle:
    """``name`` (uav1...) at ``sysid`` on ``link``; ``on_position(vehicle)`` is called from
    the reader thread (whoever read it, on a simulated clock) after every position
    report (the recorder hooks in there), and
    ``on_photo(vehicle, msg, arrival)`` after every CAMERA_FEEDBACK (``arrival``:
    ``clock.monotonic()``)."""

    def __init__(self, name: str, sysid: int, link, *,
                 on_position: Callable[[FlightVehicle], None] | None = None,
                 on_photo: Callable[[FlightVehicle, object, float], None] | None = None,
                 command_timeout_s: float = 1.5, command_retries: int = 5,
                 position_hz: float = 10.0, status_hz: float = 2.0) -> None:
        self.name, self.sysid, self.link = name, sysid, link
        # found by its HEARTBEAT (Fleet's discovery) just now: heard from at creation
        self.status = Status(heard_t=clock.monotonic())
        self.on_position = on_position
        self.on_photo = on_photo
        self.command_timeout_s = command_timeout_s
        self.command_retries = command_retries
        self._changed = clock.Condition()
        self._requested_mode: str | None = None
        # the mode this ground station last asked for, and when (a mode it did not ask
        # for is the pilot's, a failsafe's or another station's: flight/departures.py)
        self.asked_mode: str | None = None
        self.asked_t = 0.0
        # set by an abort: from then on only this mode may be asked for
        self.aborted_to: str | None = None
        self._stop = clock.Event()
        if clock.virtual() is not None:
            # on a simulated clock the status is updated by whoever read the message:
            # a thread only waiting for them would cost a turn for every few
            self._channel = link.channel(sysid, on_message=self._update)
            self._thread = None
        else:
            self._channel = link.channel(sysid)
            self._thread = clock.Thread(target=self._pump, name=f"{name} status", daemon=True)
            self._thread.start()
        self.request_streams(position_hz, status_hz)

    def close(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
        self._channel.close()

    # -- status
    def _pump(self) -> None:
        while not self._stop.is_set():
            msg = self._channel.recv(0.1)
            if msg is not None:
                self._update(msg)

    def _update(self, msg) -> None:
        kind, s, now = msg.get_type(), self.status, clock.monotonic()
        position, photo = False, None
        with self._changed:
            s.heard_t = now
            if kind == "HEARTBEAT":
                s.mode = mode_name(msg.custom_mode)
                s.armed = bool(msg.base_mode & R.MAV_MODE_FLAG_SAFETY_ARMED)
                s.heartbeat_t = now
                s.vehicle_type, s.autopilot = msg.type, msg.autopilot
            elif kind == "AUTOPILOT_VERSION":
                s.firmware_version = int(msg.flight_sw_version)
            elif kind == "GLOBAL_POSITION_INT":
                boot_s = msg.time_boot_ms / 1000.0
                if (s.clock_offset_s is not None
                        and s.position_boot_s - REBOOT_BACK_S < boot_s <= s.position_boot_s):
                    return  # older than one already had (a link that reorders): no news
                s.lat_deg, s.lon_deg = msg.lat * 1e-7, msg.lon * 1e-7
                s.alt_m = msg.relative_alt / 1000.0
                s.climb_m_s = -msg.vz / 100.0
                s.ground_speed_m_s = (msg.vx ** 2 + msg.vy ** 2) ** 0.5 / 100.0
                s.velocity_enu = (msg.vy / 100.0, msg.vx / 100.0, -msg.vz / 100.0)
                if s.position_t:
                    s.gaps.append((now, now - s.position_t))
                s.position_t = now
                if s.clock_offset_s is None or boot_s < s.position_boot_s:
                    s._rate_since = (now, boot_s)  # first report, or the vehicle rebooted
                    s._clock_pairs.clear()
                elif s._rate_since is not None and now - s._rate_since[0] >= CLOCK_RATE_AFTER_S:
                    s.clock_rate = (boot_s - s._rate_since[1]) / (now - s._rate_since[0])
                # the least delayed of the last few (over seconds the rate's error is nil)
                s._clock_pairs.append((now, boot_s))
                s.clock_offset_s = min(t - b / s.clock_rate for t, b in
                                       itertools.islice(reversed(s._clock_pairs), CLOCK_REPORTS))
                # how much later than the least delayed this one came (its seconds)
                s.delays.append((now - s.clock_offset_s) * s.clock_rate - boot_s)
                s.position_boot_s = boot_s
                position = True
            elif kind == "MISSION_CURRENT":
                s.seq = msg.seq
            elif kind == "GPS_RAW_INT":
                if s.armed:  # a glitch is measured on every report, whoever watches
                    east, north = jump_vector(s.gps_raw, msg, s.velocity_enu)
                    if math.hypot(east, north) > s.gps_jump_m:
                        s.gps_jump_m = math.hypot(east, north)
                        s.gps_jump_enu = (float(east), float(north))
                s.gps_raw = msg
            elif kind == "EKF_STATUS_REPORT":
                s.ekf_raw = msg
            elif kind == "SYSTEM_TIME":
                # its UTC clock (AP_RTC) against its boot clock, sent together: 0 until
                # its GPS gave it a time
                s.utc_offset_s = (msg.time_unix_usec / 1e6 - msg.time_boot_ms / 1000.0
                                  if msg.time_unix_usec else None)
            elif kind == "SYS_STATUS":
                s.battery_pct = None if msg.battery_remaining < 0 else int(msg.battery_remaining)
                s.battery_current_a = max(msg.current_battery, 0) / 100.0
            elif kind == "COMMAND_ACK":
                s.acks[msg.command] = msg.result
                if (msg.command == R.MAV_CMD_DO_SET_MODE and msg.result == R.MAV_RESULT_ACCEPTED
                        and self._requested_mode is not None):
                    # ArduPilot switches before it acknowledges (GCS_Common.cpp
                    # handle_command_do_set_mode): no need to wait for the next HEARTBEAT
                    s.mode = self._requested_mode
            elif kind == "PARAM_VALUE":
                s.params[msg.param_id] = msg.param_value
            elif kind == "CAMERA_FEEDBACK":
                s.photos += 1
                photo = msg
            elif kind == "STATUSTEXT":
                s.text_log.append((now, msg.severity, msg.text))
                del s.text_log[:-50]
                s.text_count += 1
            else:
                return
            self._changed.notify_all()
        if position and self.on_position is not None:
            self.on_position(self)
        if photo is not None and self.on_photo is not None:
            self.on_photo(self, photo, now)

    def wait_for(self, predicate: Callable[[Status], bool], timeout_s: float) -> bool:
        """Wait until ``predicate(status)`` holds, at most ``timeout_s``."""
        deadline = clock.monotonic() + timeout_s
        with self._changed:
            while not predicate(self.status):
                left = deadline - clock.monotonic()
                if left <= 0:
                    return False
                self._changed.wait(min(left, 0.1))
            return True

    @property
    def link_up(self) -> bool:
        """False while the link is closed by the other end (it reconnects by itself)."""
        return self.link.up

    # -- commands
    def send(self, msg, *, step: str = "send") -> None:
        """Send on the vehicle's link; :class:`LinkLost` when the link is down."""
        try:
            self.link.send(msg)
        except LinkError as exc:
            raise LinkLost(self.name, self.sysid, step, str(exc)) from None

    def command(self, command: int, *params: float, step: str,
                timeout_s: float | None = None, retries: int | None = None) -> int:
        """COMMAND_LONG with up to 7 params until acknowledged; returns the MAV_RESULT.

        Resent (with the confirmation field counting up) when no ack arrives within
        ``timeout_s``; FlightError after ``retries`` resends.
        """
        if self.aborted_to is not None:
            raise FlightAborted(self.name, self.sysid, self.aborted_to)
        timeout_s = self.command_timeout_s if timeout_s is None else timeout_s
        retries = self.command_retries if retries is None else retries
        p = list(params) + [0.0] * (7 - len(params))
        for attempt in range(retries + 1):
            with self._changed:
                self.status.acks.pop(command, None)
            self.send(R.MAVLink_command_long_message(self.sysid, 1, command, min(attempt, 255), *p),
                      step=step)
            if self.wait_for(lambda s: command in s.acks, timeout_s):
                return self.status.acks[command]
        raise FlightError(self.name, self.sysid, step,
                          f"no COMMAND_ACK after {retries + 1} tries, {timeout_s:g} s each")

    def request_version(self, *, timeout_s: float = 1.0, retries: int = 2) -> int | None:
        """Ask for AUTOPILOT_VERSION (MAV_CMD_REQUEST_MESSAGE 148); its
        ``flight_sw_version``, or None when it is not answered. One the link heard
        already (asked when the vehicles were found) is not asked again."""
        for attempt in range(retries + 1):
            if self.sysid in self.link.versions:
                with self._changed:
                    self.status.firmware_version = self.link.versions[self.sysid]
                return self.status.firmware_version
            self.send(version_request(self.sysid, attempt), step="firmware")
            if self.wait_for(lambda s: s.firmware_version is not None, timeout_s):
                return self.status.firmware_version
        return None

    def request_streams(self, position_hz: float, status_hz: float = 2.0) -> None:
        """Ask for everything a flight reads (GLOBAL_POSITION_INT at ``position_hz``,
        SYS_STATUS, GPS_RAW_INT, MISSION_CURRENT, EKF_STATUS_REPORT at ``status_hz``);
        the link re-asks until they arrive."""
        self.link.want(self.sysid, flight_streams(position_hz, status_hz))

    def abort_to(self, mode: str) -> None:
        """Mark the flight aborted and ask for ``mode`` at once; confirm with set_mode."""
        self.aborted_to = mode
        self.send_mode(mode)

    def send_mode(self, mode: str) -> None:
        """Ask for ``mode`` without waiting (MAV_CMD_DO_SET_MODE, custom mode). After an
        abort only the abort's mode may be asked for (FlightAborted otherwise)."""
        if self.aborted_to is not None and mode != self.aborted_to:
            raise FlightAborted(self.name, self.sysid, self.aborted_to)
        self._requested_mode = mode
        self.asked_mode, self.asked_t = mode, clock.monotonic()
        self.send(R.MAVLink_command_long_message(
            self.sysid, 1, R.MAV_CMD_DO_SET_MODE, 0, R.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
            CopterMode[mode], 0, 0, 0, 0, 0), step=f"mode {mode}")

    def set_mode(self, mode: str, *, timeout_s: float = 5.0) -> None:
        """Switch to ``mode``; confirmed by its acknowledgement or the HEARTBEAT (resent
        each second until then)."""
        deadline = clock.monotonic() + timeout_s
        while clock.monotonic() < deadline:
            self.send_mode(mode)
            if self.wait_for(lambda s: s.mode == mode, min(1.0, deadline - clock.monotonic())):
                return
        raise FlightError(self.name, self.sysid, f"mode {mode}",
                          f"still in {self.status.mode} after {timeout_s:g} s")

    def arm(self, *, budget_s: float, retry_s: float = 2.0) -> None:
        """Arm, retrying while the autopilot refuses (ArduCopter refuses with "Arm: Need
        Position Estimate" for a while after its pre-arm checks already pass)."""
        deadline = clock.monotonic() + budget_s
        while True:
            result = self.command(R.MAV_CMD_COMPONENT_ARM_DISARM, 1, step="arm")
            if result == R.MAV_RESULT_ACCEPTED and self.wait_for(lambda s: s.armed, 3.0):
                return
            if clock.monotonic() + retry_s > deadline:
                why = self.status.texts[-1] if self.status.texts else f"MAV_RESULT {result}"
                raise FlightError(self.name, self.sysid, "arm",
                                  f"refused for {budget_s:g} s (last: {why})")
            clock.sleep(retry_s)

    def takeoff(self, alt_m: float, *, tries: int = 3, retry_s: float = 0.5) -> None:
        """NAV_TAKEOFF, tried again a few times when refused while still on the ground
        (through a lossy radio the arm or the mode before it can still be on its way)."""
        for attempt in range(tries):
            result = self.command(R.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, alt_m,
                                  step="takeoff")
            # a resend refused because the first try was taken and its ACK lost:
            # ArduCopter refuses a takeoff once off the ground (ArduCopter/takeoff.cpp
            # Mode::do_user_takeoff, ``!copter.ap.land_complete``); climbing, it is taking off
            if result == R.MAV_RESULT_ACCEPTED or self.wait_for(
                    lambda s: s.alt_m > 0.3 or s.climb_m_s > 0.2, 1.0):
                return
            if attempt + 1 < tries:
                clock.sleep(retry_s)
                if not self.status.armed:  # disarmed on the ground meanwhile (DISARM_DELAY)
                    self.arm(budget_s=2.0 * retry_s)
        raise FlightError(self.name, self.sysid, "takeoff", f"refused (MAV_RESULT {result})")

    def read_param(self, name: str, *, timeout_s: float = 1.0, retries: int = 2) -> float | None:
        """A parameter's value (PARAM_REQUEST_READ -> PARAM_VALUE), None if unanswered."""
        with self._changed:
            self.status.params.pop(name, None)
        for _ in range(retries + 1):
            self.send(R.MAVLink_param_request_read_message(self.sysid, 1, name.encode(), -1))
            if self.wait_for(lambda s: name in s.params, timeout_s):
                return self.status.params[name]
        return None

    def goto(self, lat_deg: float, lon_deg: float, alt_m: float) -> None:
        """GUIDED to a position (altitude above home) without waiting:
        SET_POSITION_TARGET_GLOBAL_INT, position only (ArduCopter/GCS_Mavlink.cpp
        handle_message_set_position_target_global_int -> ModeGuided::set_destination;
        never acknowledged)."""
        if self.aborted_to is not None:
            raise FlightAborted(self.name, self.sysid, self.aborted_to)
        self.send(R.MAVLink_set_position_target_global_int_message(
            0, self.sysid, 1, R.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, POSITION_ONLY,
            round(lat_deg * 1e7), round(lon_deg * 1e7), alt_m, 0, 0, 0, 0, 0, 0, 0, 0),
            step="goto")

    def send_pause(self, pause: bool) -> None:
        """MAV_CMD_DO_PAUSE_CONTINUE (param1 0: pause, 1: continue) without waiting; its
        COMMAND_ACK lands in ``status.acks``. The formation keeper's nudge."""
        if self.aborted_to is not None:
            raise FlightAborted(self.name, self.sysid, self.aborted_to)
        self.send(R.MAVLink_command_long_message(
            self.sysid, 1, R.MAV_CMD_DO_PAUSE_CONTINUE, 0, 0 if pause else 1, 0, 0, 0, 0, 0, 0),
            step="pause" if pause else "continue")

    def set_current(self, seq: int, *, timeout_s: float = 5.0) -> None:
        """Make ``seq`` the current mission item.

        MAV_CMD_DO_SET_MISSION_CURRENT, acknowledged; autopilots without it get the older
        MISSION_SET_CURRENT message, confirmed by the MISSION_CURRENT that ArduPilot
        answers it with (libraries/GCS_MAVLink/GCS_Common.cpp handle_mission_set_current).
        """
        try:
            result = self.command(R.MAV_CMD_DO_SET_MISSION_CURRENT, seq, step="set current item",
                                  retries=2)
        except FlightError:
            result = None
        if result == R.MAV_RESULT_ACCEPTED:
            return
        deadline = clock.monotonic() + timeout_s
        while clock.monotonic() < deadline:
            self.send(R.MAVLink_mission_set_current_message(self.sysid, 1, seq))
            if self.wait_for(lambda s: s.seq == seq, min(1.0, deadline - clock.monotonic())):
                return
        raise FlightError(self.name, self.sysid, "set current item",
                          f"vehicle reports item {self.status.seq}, asked for {seq}")
