"""The emulated copter's flight: modes, arming, takeoff, missions, landing.

Pure state machine: :meth:`Autopilot.handle` takes a decoded command and returns replies;
:meth:`Autopilot.advance` moves the copter to a given (emulated) time and returns what
ArduCopter would announce (MISSION_CURRENT, MISSION_ITEM_REACHED, STATUSTEXT). Positions
are ENU metres relative to home.

Modelled on ArduCopter wherever ftlbo-mav looks:

- Arming (MAV_CMD_COMPONENT_ARM_DISARM) is refused until the pre-arm checks pass and
  again until the EKF has a position estimate ("Arm: Need Position Estimate";
  libraries/AP_Arming/AP_Arming.cpp, ArduCopter/AP_Arming.cpp ``mandatory_gps_checks``).
- MAV_CMD_NAV_TAKEOFF is accepted in GUIDED when armed (ArduCopter/GCS_Mavlink.cpp
  ``handle_command_long_packet``, ``Mode::do_user_takeoff``).
- AUTO runs the mission from the current item; MAV_CMD_MISSION_START switches to AUTO
  and starts it (ArduCopter/GCS_Mavlink.cpp); MISSION_SET_CURRENT moves the current
  item (libraries/AP_Mission/AP_Mission.cpp ``set_current_cmd``).
- Waypoints count as reached inside WPNAV_RADIUS; NAV_LAND flies to the point, descends
  at LAND_SPEED and disarms on the ground (ArduCopter/mode_land.cpp,
  ArduCopter/mode_auto.cpp); RTL climbs to RTL_ALT (15 m), returns home and lands
  (ArduCopter/mode_rtl.cpp); LOITER_UNLIM holds at its point.
- A copter armed on the ground that does not take off disarms after DISARM_DELAY, 10 s
  (ArduCopter/motors.cpp ``auto_disarm_check``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as R

from ..ardupilot.commands import (
    ARMABLE_MODES,
    ARMING_MOTORS,
    DISARM_DELAY_S,
    DISARMING_MOTORS,
    FORCE_DISARM_MAGIC,
    INSTANT_BOOT,
    LAND_COMPLETE,
    MISSING_TAKEOFF,
    NEEDS_POSITION,
    READY,
    BootTimeline,
    arm_refusals,
    mode_change_failed,
    mode_not_armable,
    set_mode_base_ok,
)
from ..ardupilot.modes import CopterMode, mode_name
from ..mission.items import (
    CMD_DO_CHANGE_SPEED,
    CMD_NAV_LAND,
    CMD_NAV_LOITER_UNLIM,
    CMD_NAV_RETURN_TO_LAUNCH,
    CMD_NAV_TAKEOFF,
    CMD_NAV_WAYPOINT,
    MissionItem,
)
from .physics import FlightLimits, reached, step_towards

STABILIZE, AUTO, GUIDED, LOITER, RTL, LAND, BRAKE = (
    CopterMode.STABILIZE, CopterMode.AUTO, CopterMode.GUIDED, CopterMode.LOITER, CopterMode.RTL,
    CopterMode.LAND, CopterMode.BRAKE)
# the modes the emulator accepts; others are refused as unknown
FLOWN_MODES = frozenset({STABILIZE, CopterMode.ALT_HOLD, AUTO, GUIDED, LOITER, RTL, LAND,
                         CopterMode.POSHOLD, BRAKE})

RTL_ALT_M = 15.0
STEP_S = 0.02
_WGS84_A = 6378137.0
_WGS84_E2 = 6.69437999014e-3
_NAV_LAST = 95  # MAV_CMD_NAV_LAST: commands below are navigation commands (AP_Mission)
_MISSION_TEXT = {CMD_NAV_TAKEOFF: "Takeoff", CMD_NAV_WAYPOINT: "WP", CMD_NAV_LAND: "Land",
                 CMD_NAV_RETURN_TO_LAUNCH: "RTL", CMD_NAV_LOITER_UNLIM: "LoitUnlim"}


def _text(severity_text: tuple[int, str]):
    severity, text = severity_text
    return R.MAVLink_statustext_message(severity, text.encode())


@dataclass(frozen=True)
class AutopilotOptions:
    """``boot``: when the vehicle is ready, has home, passes pre-arm and may arm.
    ``limits``: its navigation parameters."""

    boot: BootTimeline = INSTANT_BOOT
    limits: FlightLimits = field(default_factory=FlightLimits)


class LocalTangent:
    """Home-centred conversion between lat/lon and east/north metres.

    Uses WGS84's meridian and prime-vertical radii of curvature at home: over a few
    hundred metres this agrees with a full geodetic transform to millimetres.
    """

    def __init__(self, lat_deg: float, lon_deg: float) -> None:
        self.lat0, self.lon0 = lat_deg, lon_deg
        s = math.sin(math.radians(lat_deg))
        w = math.sqrt(1.0 - _WGS84_E2 * s * s)
        self.m_per_rad_lat = _WGS84_A * (1.0 - _WGS84_E2) / w**3
        self.m_per_rad_lon = _WGS84_A / w * math.cos(math.radians(lat_deg))

    def to_en(self, lat_deg: float, lon_deg: float) -> tuple[float, float]:
        return (math.radians(lon_deg - self.lon0) * self.m_per_rad_lon,
                math.radians(lat_deg - self.lat0) * self.m_per_rad_lat)

    def to_latlon(self, east: float, north: float) -> tuple[float, float]:
        return (self.lat0 + math.degrees(north / self.m_per_rad_lat),
                self.lon0 + math.degrees(east / self.m_per_rad_lon))


class Autopilot:
    """Flight state of one emulated copter."""

    def __init__(self, *, home: tuple[float, float], boot_time: float,
                 options: AutopilotOptions = AutopilotOptions()) -> None:
        self.tangent = LocalTangent(*home)
        self.options = options
        self.boot = options.boot
        self.boot_time = boot_time
        self.time = boot_time
        self.position = np.zeros(3)
        self.velocity = np.zeros(3)
        self.mode = STABILIZE
        self.armed = False
        self.mission: list[MissionItem] = []
        self.current = 0
        self.mission_started = False
        self.speed_m_s: float | None = None
        self._target: np.ndarray | None = None  # GUIDED / LOITER / mission hold point
        self._phase = ""  # within a mode: "climb", "return", "descend", "hold"
        self._armed_on_ground_since: float | None = None
        self._announced_ready = False
        self._pending: list = []  # announcements made outside advance()
        self._takeoff_at: float | None = None  # spool-up: the climb starts then
        self.nav = None  # the S-curve navigator of the current mission leg (physics)

    # -- what the vehicle knows about itself
    @property
    def landed(self) -> bool:
        return self.position[2] <= 0.05 and abs(self.velocity[2]) < 0.1

    def since_boot(self, now: float) -> float:
        return now - self.boot_time

    def prearm_ok(self, now: float) -> bool:
        return self.since_boot(now) >= self.boot.prearm_s

    def position_ok(self, now: float) -> bool:
        return self.since_boot(now) >= self.boot.armable_s

    def latlon(self) -> tuple[float, float]:
        return self.tangent.to_latlon(self.position[0], self.position[1])

    def mode_name(self) -> str:
        return mode_name(self.mode)

    def mission_state(self) -> int:
        """MISSION_CURRENT mission_state (AP_Mission::state)."""
        if len(self.mission) <= 1:
            return R.MISSION_STATE_NO_MISSION
        if self.mode == AUTO and self.armed:
            return R.MISSION_STATE_ACTIVE
        if self.mode == AUTO:
            return R.MISSION_STATE_ACTIVE
        return R.MISSION_STATE_NOT_STARTED

    # -- commands
    def set_mission(self, items: list[MissionItem]) -> None:
        self.mission = list(items)
        self.current = min(self.current, max(len(self.mission) - 1, 0))

    def _starts_with_takeoff(self) -> bool:
        """AP_Mission::starts_with_takeoff_cmd / is_takeoff_next: the first navigation
        command from the current one is a takeoff."""
        for item in self.mission[max(self.current, 1):]:
            if item.command < _NAV_LAST:
                return item.command == CMD_NAV_TAKEOFF
        return False

    def mode_refusal(self, mode: int, now: float) -> list[tuple[int, str]] | None:
        """Why ArduCopter would refuse ``mode`` now (its STATUSTEXTs), or None
        (ArduCopter/mode.cpp ``Copter::set_mode``: disarmed, every check is skipped
        (``ignore_checks``); ModeAuto::init)."""
        if mode not in FLOWN_MODES:
            return [(R.MAV_SEVERITY_WARNING, f"No such mode {mode}")]
        if not self.armed:
            return None
        if mode in NEEDS_POSITION and not self.position_ok(now):
            return [mode_change_failed(mode, "requires position")]
        if mode == AUTO:
            if len(self.mission) <= 1:
                return [mode_change_failed(mode, "init failed")]
            if self.landed and not self._starts_with_takeoff():
                return [MISSING_TAKEOFF, mode_change_failed(mode, "init failed")]
        return None

    def set_mode(self, mode: int, now: float) -> bool:
        """Switch mode; False when ArduCopter would refuse (see :meth:`mode_refusal`)."""
        refusal = self.mode_refusal(mode, now)
        if refusal is not None:
            self._pending += [_text(t) for t in refusal]
            return False
        self.mode = mode
        self._phase = ""
        self.nav = None
        self.speed_m_s = self.speed_m_s if mode == AUTO else None
        if mode in (GUIDED, LOITER, BRAKE):
            self._target = self.position.copy()
        elif mode == AUTO:
            self.current = max(self.current, 1)
            self._start_item()
        elif mode == RTL:
            self._phase, self._target = "climb", None
        return True

    def command_set_mode(self, base_mode: float, custom_mode: int, now: float):
        """DO_SET_MODE / SET_MODE: ``(MAV_RESULT, STATUSTEXTs)`` (GCS_MAVLINK::
        _set_mode_common: DENIED without the custom-mode flag, FAILED when refused)."""
        if not set_mode_base_ok(base_mode):
            return R.MAV_RESULT_DENIED, []
        ok = self.set_mode(custom_mode, now)
        return (R.MAV_RESULT_ACCEPTED if ok else R.MAV_RESULT_FAILED), self._take_pending()

    def _take_pending(self) -> list:
        out, self._pending = self._pending, []
        return out

    def arm(self, now: float) -> list[tuple[int, str]] | None:
        """Arm; returns the refusal texts when refused (AP_Arming::arm: pre-arm checks,
        then ArduCopter/AP_Arming.cpp arm_checks' mode check)."""
        if not self.position_ok(now):
            return arm_refusals(self.since_boot(now), self.boot)
        if self.mode not in ARMABLE_MODES:
            return [mode_not_armable(self.mode)]
        self.armed = True
        self._armed_on_ground_since = now
        return None

    def disarm(self) -> None:
        """AP_Arming::disarm; Copter::init_disarm_motors resets the mission to its start."""
        self.armed = False
        self.velocity[:] = 0.0
        self._armed_on_ground_since = None
        self._takeoff_at = None
        self.current = 0
        self.nav = None
        self._pending.append(_text(DISARMING_MOTORS))

    def takeoff(self, alt_m: float, now: float | None = None) -> bool:
        """MAV_CMD_NAV_TAKEOFF: Mode::do_user_takeoff refuses unless armed, landed
        (``ap.land_complete``) and in a mode that has a user takeoff (GUIDED here)."""
        if not self.armed or self.mode != GUIDED or alt_m <= 0 or not self.landed:
            return False
        self._target = np.array([self.position[0], self.position[1], alt_m])
        self._takeoff_at = (self.time if now is None else now) + self.options.limits.spool_up_s
        return True

    def set_current(self, seq: int) -> bool:
        if not 0 <= seq < len(self.mission):
            return False
        self.current = seq
        if self.mode == AUTO:
            self.current = max(seq, 1)
            self.nav = None
            self._start_item()
        return True

    def command(self, cmd: int, p: list[float], now: float):
        """A COMMAND_LONG: ``(MAV_RESULT, STATUSTEXTs)`` (ArduCopter/GCS_Mavlink.cpp
        handle_command_long_packet and GCS_Common.cpp)."""
        result = R.MAV_RESULT_FAILED
        if cmd == R.MAV_CMD_COMPONENT_ARM_DISARM:
            if p[0] >= 0.5:
                if self.armed:
                    result = R.MAV_RESULT_ACCEPTED
                else:
                    refusal = self.arm(now)
                    if refusal:
                        self._pending += [_text(t) for t in refusal]
                    else:
                        self._pending.append(_text(ARMING_MOTORS))
                        result = R.MAV_RESULT_ACCEPTED
            elif int(p[1]) == FORCE_DISARM_MAGIC or self.landed or not self.armed:
                if self.armed:
                    self.disarm()
                    self.position[2] = 0.0  # a forced disarm in flight falls
                result = R.MAV_RESULT_ACCEPTED
        elif cmd == R.MAV_CMD_NAV_TAKEOFF:
            result = R.MAV_RESULT_ACCEPTED if self.takeoff(float(p[6]), now) else result
        elif cmd == R.MAV_CMD_DO_SET_MODE:
            return self.command_set_mode(p[0], int(p[1]), now)
        elif cmd == R.MAV_CMD_MISSION_START:
            # ArduCopter/GCS_Mavlink.cpp: set_mode(AUTO); when already in AUTO, accepted
            if self.mode == AUTO or self.set_mode(AUTO, now):
                result = R.MAV_RESULT_ACCEPTED
        elif cmd == R.MAV_CMD_DO_SET_MISSION_CURRENT:
            seq = int(p[0])
            if not 0 <= seq < len(self.mission):
                result = R.MAV_RESULT_DENIED  # AP_Mission::is_valid_index
            elif self.set_current(seq):
                result = R.MAV_RESULT_ACCEPTED
        elif cmd == R.MAV_CMD_NAV_RETURN_TO_LAUNCH:
            result = R.MAV_RESULT_ACCEPTED if self.set_mode(RTL, now) else result
        elif cmd == R.MAV_CMD_NAV_LAND:
            result = R.MAV_RESULT_ACCEPTED if self.set_mode(LAND, now) else result
        elif cmd == R.MAV_CMD_DO_CHANGE_SPEED:
            if p[1] > 0:  # Copter::set_desired_speed via ModeAuto / ModeGuided
                self.speed_m_s = float(p[1])
                if self.nav is not None:
                    self.nav.set_speed(float(p[1]))
                result = R.MAV_RESULT_ACCEPTED
        else:
            result = R.MAV_RESULT_UNSUPPORTED
        return result, self._take_pending()

    # -- mission execution
    def _item(self) -> MissionItem | None:
        return self.mission[self.current] if 0 < self.current < len(self.mission) else None

    def _item_target(self, item: MissionItem) -> np.ndarray:
        if item.lat_deg == 0 and item.lon_deg == 0:
            east, north = self.position[0], self.position[1]
        else:
            east, north = self.tangent.to_en(item.lat_deg, item.lon_deg)
        return np.array([east, north, item.alt_m])

    def _start_item(self) -> None:
        """Begin the current item; DO_ commands run at once and move on."""
        self._phase = ""
        while (item := self._item()) is not None and item.command == CMD_DO_CHANGE_SPEED:
            self.speed_m_s = item.param2 if item.param2 > 0 else None
            self.current += 1
        item = self._item()
        if item is None:
            self._target = self.position.copy()
            self._phase = "done"
            return
        if item.command in _MISSION_TEXT:  # ModeAuto::start_command
            self._pending.append(_text((R.MAV_SEVERITY_INFO,
                                        f"Mission: {self.current} {_MISSION_TEXT[item.command]}")))
        if item.command == CMD_NAV_TAKEOFF:
            self._target = np.array([self.position[0], self.position[1], item.alt_m])
        elif item.command in (CMD_NAV_WAYPOINT, CMD_NAV_LOITER_UNLIM):
            self._target = self._item_target(item)
        elif item.command == CMD_NAV_LAND:
            target = self._item_target(item)
            target[2] = self.position[2]
            self._target, self._phase = target, "return"
        elif item.command == CMD_NAV_RETURN_TO_LAUNCH:
            self._phase, self._target = "climb", None
        else:  # commands the emulator does not fly are skipped, like unsupported ones
            self.current += 1
            self._start_item()

    def _next_item(self, out: list) -> None:
        out.append(R.MAVLink_mission_item_reached_message(self.current))
        self.current += 1
        self._start_item()

    # -- time
    def advance(self, now: float) -> list:
        """Fly until ``now``; returns announcements (STATUSTEXT, MISSION_ITEM_REACHED)."""
        out: list = self._take_pending()
        if not self._announced_ready and self.since_boot(now) >= self.boot.ready_s:
            # Copter::init_ardupilot ends with set_mode(STABILIZE) and "ArduPilot Ready":
            # a mode set by a GCS before then is lost (boot.json)
            self._announced_ready = True
            if self.mode != STABILIZE and not self.armed:
                self.mode, self._target, self._phase = STABILIZE, None, ""
            out.append(_text(READY))
        while self.time < now - 1e-9:  # fixed steps, the last one shortened to end at now
            dt = min(STEP_S, now - self.time)
            self.time += dt
            self._step(dt, out)
        return out + self._take_pending()

    def _fly(self, target: np.ndarray, dt: float, *, stop: bool = True, speed=None) -> None:
        self.position, self.velocity = step_towards(
            self.position, self.velocity, target, dt, self.options.limits, stop=stop,
            speed_m_s=speed if speed is not None else self.speed_m_s)
        self.position[2] = max(self.position[2], 0.0)

    def _step(self, dt: float, out: list) -> None:
        if not self.armed:
            return
        limits = self.options.limits
        if self._takeoff_at is not None:
            if self.time < self._takeoff_at:  # motors spooling up (Mode::_TakeOff::start)
                return
            self._takeoff_at = None
        if self.mode in (GUIDED, LOITER, BRAKE) and self._target is not None:
            self._fly(self._target, dt)
        elif self.mode == LAND or (self.mode in (RTL, AUTO) and self._phase == "descend"):
            self._descend(dt, out)
        elif self.mode == RTL or (self.mode == AUTO and self._phase in ("climb", "home")):
            self._rtl(dt)
        elif self.mode == AUTO:
            self._auto(dt, out, limits)
        if self._armed_on_ground_since is not None and self.landed and self.mode != AUTO:
            if self.time - self._armed_on_ground_since >= DISARM_DELAY_S and (
                self._target is None or self._target[2] <= 0.05
            ):
                self.disarm()
        if not self.landed:
            self._armed_on_ground_since = None

    def _auto(self, dt: float, out: list, limits: FlightLimits) -> None:
        item = self._item()
        if item is None or self._target is None:
            return
        if item.command == CMD_NAV_TAKEOFF:
            self._fly(self._target, dt)
            if abs(self.position[2] - self._target[2]) < 0.1:
                self._next_item(out)
        elif item.command == CMD_NAV_WAYPOINT:
            nxt = self.mission[self.current + 1] if self.current + 1 < len(self.mission) else None
            through = nxt is not None and nxt.command == CMD_NAV_WAYPOINT
            self._fly(self._target, dt, stop=not through)
            if reached(self.position, self._target, limits) if through else (
                np.linalg.norm(self._target - self.position) < 0.1
            ):
                self._next_item(out)
        elif item.command == CMD_NAV_LOITER_UNLIM:
            self._fly(self._target, dt)
        elif item.command == CMD_NAV_LAND and self._phase == "return":
            self._fly(self._target, dt)
            if np.linalg.norm(self._target[:2] - self.position[:2]) < 0.1:
                self._phase = "descend"

    def _rtl(self, dt: float) -> None:
        if self._phase == "climb":
            if self._target is None or self._target[2] < RTL_ALT_M - 1e-9:
                alt = max(self.position[2], RTL_ALT_M)
                self._target = np.array([self.position[0], self.position[1], alt])
            self._fly(self._target, dt)
            if abs(self.position[2] - self._target[2]) < 0.1 and abs(self.velocity[2]) < 0.2:
                self._phase = "home"
                self._target = np.array([0.0, 0.0, self._target[2]])
        elif self._phase == "home":
            self._fly(self._target, dt)
            if np.linalg.norm(self._target[:2] - self.position[:2]) < 0.1:
                self._phase = "descend"
        else:
            self._phase = "climb"

    def _descend(self, dt: float, out: list) -> None:
        land = self.options.limits.land_m_s
        self.velocity[:2] = 0.0
        self.velocity[2] = -land
        self.position[2] = max(self.position[2] - land * dt, 0.0)
        if self.position[2] <= 0.0:
            self.velocity[:] = 0.0
            if self.mode == AUTO and self._item() is not None:
                out.append(R.MAVLink_mission_item_reached_message(self.current))
            out.append(_text(LAND_COMPLETE))
            self.disarm()
            self._phase = "landed"
