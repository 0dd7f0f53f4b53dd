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
  ``handle_command_long_packet``, ``Mode::do_user_takeoff``); the copter leaves the
  ground after the spool-up and throttle slew (recorded ~3 s) and climbs as
  ``_AutoTakeoff::run`` asks (AC_PosControl's jerk-limited vertical shaping).
- AUTO runs the mission from the current item as ArduCopter/mode_auto.cpp does:
  ``do_nav_wp`` / ``wp_start`` / ``set_next_wp`` give AC_WPNav (physics.WaypointNav)
  the destination and, when the next navigation command is a waypoint and there is no
  hold time, the next one, so the S-curve blends through the corner; ``verify_nav_wp``
  reaches a waypoint when AC_WPNav says so, then waits its hold time ("Reached command
  #N", MISSION_ITEM_REACHED). DO_CHANGE_SPEED runs when reached in the mission
  (ModeAuto::do_change_speed -> AC_WPNav::set_speed_xy) or as a command.
  MAV_CMD_MISSION_START switches to AUTO; MISSION_SET_CURRENT moves the current item
  (libraries/AP_Mission/AP_Mission.cpp ``set_current_cmd``).
- NAV_LAND flies to its point at the current altitude, then descends as
  Mode::land_run_vertical_control asks (WPNAV_SPEED_DN above LAND_ALT_LOW, LAND_SPEED
  below) and disarms once the land detector has seen the touchdown (recorded ~2.1 s);
  RTL (ArduCopter/mode_rtl.cpp) climbs to RTL_ALT over its stopping point, returns home,
  waits RTL_LOIT_TIME and lands; LOITER_UNLIM holds at its point.
- A copter armed on the ground that does not take off disarms after DISARM_DELAY, 10 s
  (ArduCopter/motors.cpp ``auto_disarm_check``).
- Parameters (PARAM_REQUEST_READ / PARAM_SET) are ArduCopter's defaults for the
  navigation parameters (:mod:`ftlbo_mav.ardupilot.navigation`); WPNAV_* set in flight
  apply to the next leg, WPNAV_SPEED at once (AC_WPNav::update_wpnav).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as R

from ..ardupilot import fence as ap_fence
from ..ardupilot.camera import CAMERA_PARAM_DEFAULTS, DistanceTrigger, feedback_message
from ..ardupilot.commands import (
    ARMABLE_MODES,
    ARMING_MOTORS,
    DISARM_DELAY_S,
    DISARMING_MOTORS,
    FAILED_TO_PAUSE,
    FAILED_TO_RESUME,
    FORCE_DISARM_MAGIC,
    INSTANT_BOOT,
    MISSING_TAKEOFF,
    NAV_LAST,
    NEEDS_POSITION,
    READY,
    BootTimeline,
    arm_refusals,
    mission_started,
    mode_change_failed,
    mode_not_armable,
    reached_command,
    set_mode_base_ok,
)
from ..ardupilot.modes import CopterMode, mode_name
from ..ardupilot.navigation import (
    BRAKE_DECEL_MAX_M_S2,
    BRAKE_RAMP_S,
    BRAKE_TIME_CONSTANT_S,
    REAL32,
    param_value,
)
from ..ardupilot.navigation import DEFAULTS as NAV_DEFAULTS
from ..mission.items import (
    CMD_DO_CHANGE_SPEED,
    CMD_DO_SET_CAM_TRIGG_DIST,
    CMD_NAV_LAND,
    CMD_NAV_LOITER_UNLIM,
    CMD_NAV_RETURN_TO_LAUNCH,
    CMD_NAV_TAKEOFF,
    CMD_NAV_WAYPOINT,
    MissionItem,
)
from .fence import FenceGuard
from .physics import FlightLimits, VerticalShaper, WaypointNav, landing_rate

PARAM_DEFAULTS = {**NAV_DEFAULTS, **ap_fence.FENCE_PARAM_DEFAULTS, **CAMERA_PARAM_DEFAULTS}
FENCE_CHECK_S = 1.0 / ap_fence.FENCE_CHECK_HZ

STABILIZE, AUTO, GUIDED, LOITER, RTL, LAND, BRAKE = (
    CopterMode.STABILIZE, CopterMode.AUTO, CopterMode.GUIDED, CopterMode.LOITER, CopterMode.RTL,
    CopterMode.LAND, CopterMode.BRAKE)
# the modes the emulator accepts; others are refused as unknown
FLOWN_MODES = frozenset({STABILIZE, CopterMode.ALT_HOLD, AUTO, GUIDED, LOITER, RTL, LAND,
                         CopterMode.POSHOLD, BRAKE})

STEP_S = 0.02
_WGS84_A = 6378137.0
_WGS84_E2 = 6.69437999014e-3
# ModeAuto::set_next_wp: the next commands the copter flies through instead of stopping
_FLY_THROUGH = (CMD_NAV_WAYPOINT, CMD_NAV_LOITER_UNLIM)


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
        self.speed_m_s: float | None = None  # ModeAuto desired_speed_override.xy
        self.params = {name: d.value for name, d in PARAM_DEFAULTS.items()}
        self.params.update(options.limits.nav.to_params())
        self._phase = ""  # what the current mode is doing (see _step)
        self._armed_on_ground_since: float | None = None
        self._announced_ready = False
        self._pending: list = []  # announcements made outside advance()
        self.camera = DistanceTrigger()  # AP_Camera's first instance (with CAM1_TYPE set)
        self.home_alt_m = 0.0  # home above mean sea level (CAMERA_FEEDBACK's alt_msl)
        self._takeoff_at: float | None = None  # spool-up: the climb starts then
        self._takeoff_alt = 0.0
        self._takeoff_done_at: float | None = None
        self._touchdown_at: float | None = None
        self._wait_until: float | None = None  # a hold time, RTL's loiter, a start latency
        self._enter = None  # what a new mode starts once the copter has braked
        self.nav: WaypointNav | None = None  # AC_WPNav, while it is in use
        self.z = VerticalShaper()  # AC_PosControl's vertical target (takeoff, landing)
        self._hold_s = 0
        self._rtl_home = np.zeros(3)
        self._do_done: list[int] = []  # DO commands started, reached at the next update
        self._phase_before_item = ""
        self.fence = FenceGuard(self.tangent.to_en)  # AC_Fence + AP_Rally
        self._brake_since = 0.0  # when the current mode began (BRAKE's deceleration ramp)

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
    def set_fence(self, fence: list, rally: list) -> None:
        """The stored fence and rally points (WireItems, read-back form) changed."""
        self.fence.load(fence, rally)

    def fence_status(self) -> tuple[bool, bool, bool]:
        """SYS_STATUS's GEOFENCE bits: (present, enabled, failed) as AC_Fence::
        sys_status_present (a fence type that needs nothing stored, or a stored
        polygon), sys_status_enabled (FENCE_ENABLE and an action) and sys_status_failed
        (breached)."""
        kind = int(self.params["FENCE_TYPE"])
        present = bool(kind & (ap_fence.TYPE_ALT_MAX | ap_fence.TYPE_CIRCLE)) or bool(
            kind & ap_fence.TYPE_POLYGON and not self.fence.geometry.empty)
        enabled = present and self.fence.enabled(self.params) and int(
            self.params["FENCE_ACTION"]) != ap_fence.ACTION_REPORT_ONLY
        return present, enabled, present and self.fence.breached != 0

    def set_mission(self, items: list[MissionItem]) -> None:
        self.mission = list(items)
        self.current = min(self.current, max(len(self.mission) - 1, 0))

    def _starts_with_takeoff(self) -> bool:
        """AP_Mission::starts_with_takeoff_cmd / is_takeoff_next: the first navigation
        command from the current one is a takeoff."""
        for item in self.mission[max(self.current, 1):]:
            if item.command < NAV_LAST:
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
        if mode == self.mode:
            return True  # Copter::set_mode: already in the desired mode, nothing happens
        refusal = self.mode_refusal(mode, now)
        if refusal is not None:
            self._pending += [_text(t) for t in refusal]
            return False
        self.mode = mode
        self._brake_since = self.time
        self._phase = "hold"
        self.nav = None
        self._wait_until = None
        self._takeoff_at = None
        if not self.armed:
            self._enter = None
            if mode == AUTO:  # ModeAuto::init starts the mission even on the ground
                self.speed_m_s = None
                self.current = max(self.current, 1)
                self._start_item()
                self._phase, self._takeoff_at, self.nav = "", None, None
            return True
        if mode == AUTO:
            self.speed_m_s = None  # ModeAuto::init clears desired_speed_override
            self.current = max(self.current, 1)
            self._enter = self._auto_enter
        elif mode == RTL:
            self._enter = self._rtl_enter
        elif mode == LAND:
            self._enter = self._descend_enter
        else:  # GUIDED, LOITER, BRAKE, ...: stop and hold where the copter stops
            self._enter = self._hold_enter
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
        self._touchdown_at = None
        self._enter = None
        self.nav = None
        self._phase = ""
        self._pending.append(_text(DISARMING_MOTORS))
        # the mission restarts; in AUTO ModeAuto starts its first item again (recorded:
        # "Mission: 1 Takeoff" and MISSION_CURRENT 1 after the landing's disarm)
        if self.mode == AUTO and len(self.mission) > 1:
            self.current = 1
            started = mission_started(1, self.mission[1].command)
            if started:
                self._pending.append(_text(started))
        else:
            self.current = 0

    def takeoff(self, alt_m: float, now: float | None = None) -> bool:
        """MAV_CMD_NAV_TAKEOFF: Mode::do_user_takeoff refuses unless armed, landed
        (``ap.land_complete``) and in a mode that has a user takeoff (GUIDED here)."""
        if not self.armed or self.mode != GUIDED or alt_m <= 0 or not self.landed:
            return False
        self._start_takeoff(alt_m, self.time if now is None else now)
        return True

    def current_nav_index(self) -> int:
        """AP_Mission::get_current_nav_index: set_current_cmd on a DO item loads it with
        the navigation item after it, which is the one reported."""
        seq = self.current
        while 0 < seq < len(self.mission) and self.mission[seq].command >= NAV_LAST:
            seq += 1
        return seq if seq < len(self.mission) else self.current

    def set_current(self, seq: int) -> bool:
        if not 0 <= seq < len(self.mission):
            return False
        self.current = seq
        if self.mode == AUTO and self.armed:
            # AP_Mission::set_current_cmd while running: the new item starts now
            self.current = max(seq, 1)
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
        elif cmd == R.MAV_CMD_DO_PAUSE_CONTINUE:
            result = self._pause_continue(int(p[0]))
        elif cmd == R.MAV_CMD_DO_CHANGE_SPEED:
            if p[1] > 0:  # GCS_MAVLINK handle_MAV_CMD_DO_CHANGE_SPEED -> set_speed_xy
                self.change_speed(float(p[1]))
                result = R.MAV_RESULT_ACCEPTED
        else:
            result = R.MAV_RESULT_UNSUPPORTED
        return result, self._take_pending()


    # -- parameters (GCS_Param.cpp)
    def nav_params(self):
        """The navigation parameters now (the defaults, as set by PARAM_SET)."""
        return self.options.limits.nav.with_params(self.params)

    def get_param(self, name: str) -> tuple[float, int] | None:
        """``(value, MAV_PARAM_TYPE)`` of a parameter the emulator has, else None."""
        if name not in self.params:
            return None
        return self.params[name], PARAM_DEFAULTS[name].type

    def set_param(self, name: str, value: float) -> bool:
        """PARAM_SET: False for an unknown parameter or a non-finite value (ignored, as
        GCS_MAVLINK::handle_param_set does). WPNAV_SPEED applies to the leg being flown
        when no speed was set for it (AC_WPNav::update_wpnav); the others to the next."""
        if name not in self.params or not math.isfinite(value):
            return False
        self.params[name] = param_value(name, value)
        if PARAM_DEFAULTS[name].type != REAL32:  # AP_Param casts to the integer type
            self.params[name] = float(int(value))
        if name == "WPNAV_SPEED" and self.nav is not None:
            self.nav.param_speed_changed(self.params[name] / 100.0)
        return True

    def change_speed(self, speed_m_s: float) -> None:
        """DO_CHANGE_SPEED (ground speed): AC_WPNav::set_speed_xy on the navigation in use;
        in AUTO also kept for the legs to come (ModeAuto desired_speed_override)."""
        if self.mode == AUTO:
            self.speed_m_s = speed_m_s
        if self.nav is not None:
            self.nav.set_speed_xy(speed_m_s)

    def _pause_continue(self, what: int) -> int:
        """GCS_MAVLINK_Copter::handle_command_pause_continue: 0 pauses, 1 resumes, only in
        AUTO flying to a waypoint it has not reached (ModeAuto::pause / resume; other
        modes refuse, "Failed to pause" / "Failed to resume")."""
        if what not in (0, 1):
            return R.MAV_RESULT_DENIED
        flying_wp = (self.mode == AUTO and self._phase == "wp" and self.nav is not None)
        if what == 0 and flying_wp and not self.nav.reached:
            self.nav.set_pause(True)
            return R.MAV_RESULT_ACCEPTED
        if what == 1 and self.mode == AUTO:
            if self.nav is not None:
                self.nav.set_pause(False)
            return R.MAV_RESULT_ACCEPTED
        self._pending.append(_text(FAILED_TO_PAUSE if what == 0 else FAILED_TO_RESUME))
        return R.MAV_RESULT_FAILED

    def goto(self, target: np.ndarray) -> bool:
        """GUIDED: fly to ``target`` (ENU metres) with AC_WPNav (ModeGuided::set_destination)."""
        if self.mode != GUIDED or not self.armed or self.landed:
            return False
        if not self.fence.destination_ok(np.asarray(target, float), self.params):
            return False  # ModeGuided::set_destination: outside the fence, refused
        self._takeoff_at = self._enter = None
        self._start_nav()
        self.nav.set_destination(np.asarray(target, float))
        self._phase = "goto"
        return True

    # -- mission execution
    def _item(self) -> MissionItem | None:
        return self.mission[self.current] if 0 < self.current < len(self.mission) else None

    def _default_point(self) -> np.ndarray:
        """ModeAuto::do_nav_wp's default location: the last destination once reached,
        else where the copter is."""
        if self.nav is not None and self.nav.reached:
            return self.nav.destination.copy()
        return self.position.copy()

    def _item_target(self, item: MissionItem, default: np.ndarray) -> np.ndarray:
        """ModeAuto::loc_from_cmd: zero latitude and longitude, or zero altitude, mean
        the default's."""
        if item.lat_deg == 0 and item.lon_deg == 0:
            east, north = default[0], default[1]
        else:
            east, north = self.tangent.to_en(item.lat_deg, item.lon_deg)
        return np.array([east, north, item.alt_m if item.alt_m != 0 else default[2]])

    def _next_nav(self) -> MissionItem | None:
        for item in self.mission[self.current + 1:]:
            if item.command < NAV_LAST:
                return item
        return None

    def _start_nav(self, stopping_point: np.ndarray | None = None) -> None:
        """AC_WPNav::wp_and_spline_init at the copter's (stopped) position."""
        point = self.position.copy() if stopping_point is None else stopping_point
        self.nav = WaypointNav(self.nav_params(), point, self.speed_m_s)

    def _wp_start(self, target: np.ndarray, stopping_point: np.ndarray | None = None) -> None:
        """ModeAuto::wp_start."""
        if self.nav is None:
            self._start_nav(stopping_point)
        self.nav.set_destination(target)

    def _start_item(self) -> None:
        """AP_Mission::advance_current_nav_cmd: DO commands run as they come (and are
        reached at the next update), then the navigation command starts
        (ModeAuto::start_command, "Mission: N <name>")."""
        self._phase = ""
        self._wait_until = None
        while (item := self._item()) is not None and item.command >= NAV_LAST:
            self._announce_start(item)
            if item.command == CMD_DO_CHANGE_SPEED and item.param2 > 0:
                self.change_speed(float(item.param2))  # ModeAuto::do_change_speed
            elif item.command == CMD_DO_SET_CAM_TRIGG_DIST:
                self._camera_trigger_distance(item.param1, item.param3)
            self._do_done.append(self.current)
            self.current += 1
        if item is None:
            self._phase = "done"  # ModeAuto::exit_mission: hold (or disarm if landed)
            return
        self._announce_start(item)
        default = self._default_point()
        if item.command == CMD_NAV_TAKEOFF:
            self.nav = None
            self._start_takeoff(item.alt_m, self.time)
        elif item.command in (CMD_NAV_WAYPOINT, CMD_NAV_LOITER_UNLIM):
            target = self._item_target(item, default)
            self._wp_start(target, self._takeoff_point())
            nxt = self._next_nav()
            hold = int(item.param1) if item.command == CMD_NAV_WAYPOINT else 0
            if hold <= 0 and nxt is not None and nxt.command in _FLY_THROUGH:
                self.nav.set_destination_next(self._item_target(nxt, target))
            self._hold_s = max(hold, 0)
            self._phase = "wp"
        elif item.command == CMD_NAV_LAND:
            if item.lat_deg == 0 and item.lon_deg == 0:
                self._descend_enter()
            else:  # ModeAuto::do_land: fly there at the current altitude first
                target = self._item_target(item, default)
                target[2] = self.position[2]
                self._wp_start(target, self._takeoff_point())
                self._phase = "land_fly"
        elif item.command == CMD_NAV_RETURN_TO_LAUNCH:
            self._rtl_enter()
        else:  # commands the emulator does not fly are skipped, like unsupported ones
            self.current += 1
            self._start_item()

    def _announce_start(self, item: MissionItem) -> None:
        started = mission_started(self.current, item.command)
        if started:
            self._pending.append(_text(started))

    def _takeoff_point(self) -> np.ndarray | None:
        """ModeAuto::wp_start right after a takeoff: the takeoff's completion point."""
        if self._phase_before_item == "takeoff_done":
            return np.array([self.position[0], self.position[1], self._takeoff_alt])
        return None

    def _reached(self, out: list) -> None:
        """verify_command true: "Reached command #N" (for waypoints) and
        MISSION_ITEM_REACHED, then the next item."""
        item = self._item()
        if item is not None and item.command == CMD_NAV_WAYPOINT:
            out.append(_text(reached_command(self.current)))
        out.append(R.MAVLink_mission_item_reached_message(self.current))
        self.current += 1
        self._start_item()

    # -- mode starts (once the copter has stopped)
    def _hold_enter(self) -> None:
        self.nav = None
        self._phase = "hover" if self._takeoff_done_at is not None else "hold"

    def _auto_enter(self) -> None:
        """ModeAuto::init, then AP_Mission::start_or_resume from the current item (after
        the vehicle's start latency, if it has one)."""
        self.nav = None
        self._phase_before_item = ""
        latency = self.options.limits.start_latency_s
        if latency > 0:
            self._wait_until = self.time + latency
            self._phase = "auto_wait"
        else:
            self._start_item()

    def _rtl_enter(self) -> None:
        """ModeRTL::init / build_path / climb_start: from the stopping point climb to the
        return altitude (RTL_ALT, never lower than now or than the rally point's, but not
        above FENCE_ALT_MAX - FENCE_MARGIN with the altitude fence on), blended into the
        return to home or the nearer rally point (compute_return_target)."""
        nav = self.nav_params()
        self.nav = WaypointNav(nav, self.position.copy(),
                               nav.rtl_speed if nav.rtl_speed > 0 else None)
        target = self.fence.return_target(self.position)
        alt = max(float(self.position[2]), nav.rtl_alt, float(target[2]))
        limit = self.fence.rtl_alt_limit(self.params)
        if limit is not None:
            alt = min(alt, max(limit, 0.0))
        self._rtl_home = np.array([target[0], target[1], alt])
        self.nav.set_destination(np.array([self.position[0], self.position[1], alt]))
        self.nav.set_destination_next(self._rtl_home)
        self._phase = "rtl_climb"

    def _descend_enter(self) -> None:
        """Landing: the vertical target starts where the copter is."""
        self.nav = None
        self.z = VerticalShaper(pos=float(self.position[2]), vel=float(self.velocity[2]))
        self.velocity[:2] = 0.0
        self._phase = "descend"

    def _start_takeoff(self, alt_m: float, now: float) -> None:
        """Mode::do_user_takeoff / ModeAuto::takeoff_start -> _AutoTakeoff::start: from
        the ground the climb starts after the spool-up and throttle slew."""
        self._enter = None
        self._takeoff_alt = alt_m
        self._takeoff_done_at = None
        delay = self.options.limits.takeoff_delay_s if self.landed else 0.0
        self._takeoff_at = now + delay
        self.z = VerticalShaper(pos=float(self.position[2]), vel=float(self.velocity[2]))
        self._phase = "takeoff"

    # -- time
    def advance(self, now: float) -> list:
        """Fly until ``now``; returns announcements (STATUSTEXT, MISSION_ITEM_REACHED)."""
        out: list = self._take_pending()
        if not self._announced_ready and self.since_boot(now) >= self.boot.ready_s:
            # Copter::init_ardupilot ends with set_mode(STABILIZE) and "ArduPilot Ready":
            # a mode set by a GCS before then is lost (boot.json)
            self._announced_ready = True
            if self.mode != STABILIZE and not self.armed:
                self.mode, self._phase = STABILIZE, ""
            out.append(_text(READY))
        while self.time < now - 1e-9:  # fixed steps, the last one shortened to end at now
            dt = min(STEP_S, now - self.time)
            self.time += dt
            self._flush_do(out)
            self._step(dt, out)
            self._camera_step()
            self._fence_step(out)
            out += self._take_pending()
        self._flush_do(out)
        return out + self._take_pending()

    # -- the camera (ardupilot/camera.py: AP_Camera, distance triggering)
    def _camera_trigger_distance(self, distance_m: float, trigger: float) -> None:
        """AP_Mission::start_command_camera for DO_SET_CAM_TRIGG_DIST: no camera, nothing."""
        if int(self.params["CAM1_TYPE"]) == 0:
            return
        self.camera.set_distance(distance_m)
        self.params["CAM1_TRIGG_DIST"] = float(distance_m)
        if int(trigger) == 1:  # cam_trigg_dist.trigger, a uint8
            self._photo()

    def _camera_step(self) -> None:
        """AP_Camera_Backend::update at 50 Hz (one step is 20 ms)."""
        if int(self.params["CAM1_TYPE"]) != 0 and self.camera.update(self.position):
            self._photo()

    def _photo(self) -> None:
        image = self.camera.take_picture(self.position)
        lat, lon = self.latlon()
        alt = float(self.position[2])
        self._pending.append(feedback_message(
            time_usec=int(self.time * 1e6), image=image & 0xFFFF, lat_e7=round(lat * 1e7),
            lon_e7=round(lon * 1e7), alt_msl_m=alt + self.home_alt_m, alt_rel_m=alt))

    def _fence_step(self, out: list) -> None:
        """Copter::fence_check at 25 Hz (ArduCopter/fence.cpp): a new breach while armed
        announces "Fence Breached" (in the air) and takes FENCE_ACTION's mode, the first
        of its modes that is accepted (ardupilot.fence.breach_modes); landed: disarm."""
        if self.time < self.fence.next_check:
            return
        self.fence.next_check = self.time + FENCE_CHECK_S
        new = self.fence.check(position=self.position, params=self.params)
        if not new or not self.armed:
            return
        if not self.landed:
            out.append(_text(ap_fence.FENCE_BREACHED))
        modes = ap_fence.breach_modes(int(self.params["FENCE_ACTION"]), landed=self.landed,
                                      breach_distance_m=self.fence.breach_distance(
                                          self.position, self.params))
        if modes == (-1,):
            self.disarm()
            return
        for mode in modes:
            if mode in FLOWN_MODES and self.set_mode(mode, self.time):
                break

    def _flush_do(self, out: list) -> None:
        """DO commands are reached at the mission's next update (AP_Mission::update)."""
        out += self._take_pending()
        for seq in self._do_done:
            out.append(R.MAVLink_mission_item_reached_message(seq))
        self._do_done = []

    def _brake(self, dt: float) -> bool:
        """Stop before a new mode's navigation starts (AC_PosControl's stopping point,
        reached at WPNAV_ACCEL); True while still moving."""
        speed = float(np.linalg.norm(self.velocity))
        if speed < 1e-3:
            self.velocity[:] = 0.0
            return False
        if self.mode == BRAKE:  # as measured on SITL (ardupilot.navigation BRAKE_*)
            ramp = min(1.0, (self.time - self._brake_since) / BRAKE_RAMP_S)
            accel = min(BRAKE_DECEL_MAX_M_S2, speed / BRAKE_TIME_CONSTANT_S) * ramp
            if speed < 0.02:
                accel = speed / dt
        else:
            accel = self.nav_params().wp_accel
        cut = min(speed, accel * dt)
        new = self.velocity * (1.0 - cut / speed)
        self.position = self.position + (self.velocity + new) / 2 * dt
        self.position[2] = max(self.position[2], 0.0)
        self.velocity = new
        return True

    def _step(self, dt: float, out: list) -> None:
        if not self.armed:
            return
        limits = self.options.limits
        if self._touchdown_at is not None:  # on the ground: the land detector's delay
            if self.time - self._touchdown_at >= limits.disarm_after_touchdown_s:
                self.disarm()
            return
        if self._enter is not None:
            if not self.landed and self._brake(dt):
                return
            enter, self._enter = self._enter, None
            enter()
        phase = self._phase
        if phase == "takeoff":
            self._takeoff_step(dt, out)
        elif phase == "hover":
            self._hover_step(dt)
        elif phase in ("wp", "land_fly", "goto", "rtl_climb", "rtl_return", "rtl_loiter"):
            self._nav_step(dt, out)
        elif phase == "descend":
            self._descend_step(dt)
        elif phase == "auto_wait":
            if self.time >= self._wait_until:
                self._wait_until = None
                self._start_item()
        elif phase == "done" and self.landed:  # ModeAuto::exit_mission on the ground
            self.disarm()
        if self._armed_on_ground_since is not None and self.landed and self.mode != AUTO:
            if (self.time - self._armed_on_ground_since >= DISARM_DELAY_S
                    and self._takeoff_at is None and self._phase != "takeoff"):
                self.disarm()
        if not self.landed:
            self._armed_on_ground_since = None

    def _takeoff_step(self, dt: float, out: list) -> None:
        """_AutoTakeoff::run: shape the altitude to the takeoff altitude at WPNAV_SPEED_UP,
        WPNAV_ACCEL_Z, PSC_JERK_Z; complete when the target is within the stopping distance
        of a tenth of the climb speed and climbs slower than that."""
        if self._takeoff_at is not None:
            if self.time < self._takeoff_at:
                return  # motors spooling up, throttle slewing (still on the ground)
            self._takeoff_at = None
        nav = self.nav_params()
        self.z.to_altitude(self._takeoff_alt, dt, up=nav.wp_speed_up, down=nav.wp_speed_dn,
                           accel_max=nav.wp_accel_z, jerk=nav.psc_jerk_z)
        self.position[2] = max(self.z.pos, 0.0)
        self.velocity[:] = (0.0, 0.0, self.z.vel)
        slow = 0.1 * nav.wp_speed_up
        if (self.z.pos >= self._takeoff_alt - 0.5 * slow * slow / nav.wp_accel_z
                and self.z.vel < slow):
            self._takeoff_done_at = self.time
            if self.mode == AUTO:  # ModeAuto::verify_takeoff
                self._phase_before_item = "takeoff_done"
                self._reached(out)
                self._phase_before_item = ""
            else:  # GUIDED keeps running the takeoff controller: it hovers there
                self._phase = "hover"

    def _hover_step(self, dt: float) -> None:
        """Hovering after a GUIDED takeoff: the altitude target settles on the takeoff
        altitude, the copter ``hover_error_m`` below it (FlightLimits)."""
        nav = self.nav_params()
        self.z.to_altitude(self._takeoff_alt, dt, up=nav.wp_speed_up, down=nav.wp_speed_dn,
                           accel_max=nav.wp_accel_z, jerk=nav.psc_jerk_z)
        settled = min(1.0, (self.time - self._takeoff_done_at) / 1.0)
        self.position[2] = self.z.pos - self.options.limits.hover_error_m * settled
        self.velocity[:] = (0.0, 0.0, self.z.vel)

    def _nav_step(self, dt: float, out: list) -> None:
        nav = self.nav
        nav.advance(dt, self.position)
        self.position = nav.target.copy()
        self.position[2] = max(self.position[2], 0.0)
        self.velocity = nav.target_vel.copy()
        phase = self._phase
        if phase == "wp":
            item = self._item()
            if nav.reached and item is not None and item.command == CMD_NAV_WAYPOINT:
                if self._hold_s > 0 and self._wait_until is None:  # ModeAuto::verify_nav_wp
                    self._wait_until = self.time + self._hold_s
                if self._wait_until is None or self.time >= self._wait_until:
                    self._reached(out)
        elif phase == "land_fly" and nav.reached:
            self._descend_enter()  # ModeAuto::land_run: FlyToLocation -> Descending
        elif phase == "rtl_climb" and nav.reached:
            nav.set_destination(self._rtl_home)  # ModeRTL::return_start
            self._phase = "rtl_return"
        elif phase == "rtl_return" and nav.reached:  # ModeRTL::loiterathome_start
            self._wait_until = self.time + self.nav_params().rtl_loit_time
            self._phase = "rtl_loiter"
        elif phase == "rtl_loiter" and self.time >= self._wait_until:
            self._wait_until = None
            self._descend_enter()  # ModeRTL::land_start (RTL_ALT_FINAL 0)

    def _descend_step(self, dt: float) -> None:
        """Mode::land_run_vertical_control: descend at :func:`physics.landing_rate`
        (the copter achieving ``land_rate_achieved`` of it), shaped by WPNAV_ACCEL_Z and
        PSC_JERK_Z; on the ground the land detector's delay starts."""
        nav = self.nav_params()
        rate = landing_rate(nav, float(self.position[2]), dt)
        rate *= self.options.limits.land_rate_achieved
        self.z.at_rate(rate, dt, accel_max=nav.wp_accel_z, jerk=nav.psc_jerk_z)
        self.position[2] = max(self.z.pos, 0.0)
        self.velocity[:] = (0.0, 0.0, self.z.vel)
        if self.position[2] <= 0.0:
            self.velocity[:] = 0.0
            self._touchdown_at = self.time
