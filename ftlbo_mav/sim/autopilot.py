"""The emulated copter's flight: modes, arming, takeoff, missions, landing.

Kept whole: what every mode shares is one state machine (ArduCopter's mode.cpp, motors.cpp
and the scheduler's battery, fence and camera steps); each mode's own flight is already a
module of :mod:`.modes`.

Pure state machine: :meth:`Autopilot.handle` takes a decoded command and returns replies;
:meth:`Autopilot.advance` moves the copter to a given (emulated) time and returns what
ArduCopter would announce (MISSION_CURRENT, MISSION_ITEM_REACHED, STATUSTEXT). Positions
are ENU metres relative to home.

Modelled on ArduCopter wherever ftlbo-mav looks. Here what every mode shares
(ArduCopter/mode.cpp, motors.cpp, GCS_Mavlink.cpp); each mode's own flight in
:mod:`.modes`, split as ArduCopter splits them (AUTO, GUIDED and its takeoff, RTL, LAND,
BRAKE):

- Arming (MAV_CMD_COMPONENT_ARM_DISARM) is refused until the pre-arm checks pass and
  again until the EKF has a position estimate ("Arm: Need Position Estimate";
  libraries/AP_Arming/AP_Arming.cpp, ArduCopter/AP_Arming.cpp ``mandatory_gps_checks``).
- Modes are switched as ``Copter::set_mode`` does (refusals, nothing when already in the
  mode); a new mode's navigation starts once the copter has stopped (:mod:`.modes.brake`).
- MAV_CMD_MISSION_START switches to AUTO; MAV_CMD_NAV_RETURN_TO_LAUNCH / NAV_LAND to RTL
  and LAND.
- A copter armed on the ground that does not take off disarms after DISARM_DELAY, 10 s
  (ArduCopter/motors.cpp ``auto_disarm_check``).
- The fence is checked at 25 Hz (Copter::fence_check, :mod:`.fence`).
- Parameters (PARAM_REQUEST_READ / PARAM_SET) are ArduCopter's defaults for the
  navigation parameters (:mod:`ftlbo_mav.ardupilot.navigation`); WPNAV_* set in flight
  apply to the next leg, WPNAV_SPEED at once (AC_WPNav::update_wpnav).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as R

from ..ardupilot import battery as ap_battery
from ..ardupilot import fence as ap_fence
from ..ardupilot.battery import BatteryMonitor
from ..ardupilot.camera import CAMERA_PARAM_DEFAULTS, DistanceTrigger, feedback_message
from ..ardupilot.commands import (
    ARMABLE_MODES,
    ARMING_MOTORS,
    DISARM_DELAY_S,
    DISARMING_MOTORS,
    FORCE_DISARM_MAGIC,
    INSTANT_BOOT,
    MISSING_TAKEOFF,
    NEEDS_POSITION,
    READY,
    BootTimeline,
    arm_refusals,
    mission_started,
    mode_change_failed,
    mode_not_armable,
    set_mode_base_ok,
)
from ..ardupilot.modes import mode_name
from ..ardupilot.navigation import DEFAULTS as NAV_DEFAULTS
from ..ardupilot.navigation import (
    NAV_PARAMS,
    REAL32,
    param_value,
)
from ..ardupilot.poscontrol import (
    PositionFollower,
    VerticalFollower,
    stopping_point_xy,
    stopping_point_z,
)
from ..mission.items import (
    MissionItem,
)
from .fence import FenceGuard
from .gps import SIM_GPS_PARAM_DEFAULTS
from .modes import ModeAuto, ModeBrake, ModeGuided, ModeLand, ModeRTL
from .modes.common import AUTO, FLOWN_MODES, LAND, RTL, STABILIZE
from .modes.common import text as _text
from .physics import SETTLING_S, FlightLimits, VerticalShaper, WaypointNav
from .wind import Gusts

PARAM_DEFAULTS = {**NAV_DEFAULTS, **ap_fence.FENCE_PARAM_DEFAULTS, **CAMERA_PARAM_DEFAULTS,
                  **SIM_GPS_PARAM_DEFAULTS, **ap_battery.BATTERY_PARAM_DEFAULTS}
FENCE_CHECK_S = 1.0 / ap_fence.FENCE_CHECK_HZ

STEP_S = 0.02
BATTERY_CHECK_S = 0.1  # AP_BattMonitor::read at 10 Hz (Copter's scheduler table)
_WGS84_A = 6378137.0
_WGS84_E2 = 6.69437999014e-3


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


class Autopilot(ModeAuto, ModeGuided, ModeRTL, ModeLand, ModeBrake):
    """Flight state of one emulated copter; each mode's own steps are in :mod:`.modes`."""

    def __init__(self, *, home: tuple[float, float], boot_time: float,
                 options: AutopilotOptions = AutopilotOptions()) -> None:
        self.tangent = LocalTangent(*home)
        self.options = options
        self.boot = options.boot
        self.boot_time = boot_time
        self.time = boot_time
        # the vehicle's clock (AP_RTC, from its GPS): UTC seconds = time + utc_offset_s;
        # None: no GPS time (set by the vehicle, :class:`~ftlbo_mav.sim.vehicle.Vehicle`)
        self.utc_offset_s: float | None = None
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
        self._nav_params: tuple | None = None  # (the parameters' values, their Navigation)
        self._phase = ""  # what the current mode is doing (see _step)
        self._armed_on_ground_since: float | None = None
        self._announced_ready = False
        self._pending: list = []  # announcements made outside advance()
        self.camera = DistanceTrigger()  # AP_Camera's first instance (with CAM1_TYPE set)
        self.home_alt_m = 0.0  # home above mean sea level (CAMERA_FEEDBACK's alt_msl)
        self._takeoff_at: float | None = None  # spool-up: the climb starts then
        self._takeoff_alt = 0.0
        self._takeoff_from_ground = False  # it lifts off level (ModeGuided._takeoff_step)
        self._takeoff_xy = np.zeros(2)  # the horizontal target a takeoff holds
        self._takeoff_done_at: float | None = None
        self._touchdown_at: float | None = None
        self._wait_until: float | None = None  # a hold time, RTL's loiter, a start latency
        self._enter = None  # what a new mode starts once the copter has braked
        self.nav: WaypointNav | None = None  # AC_WPNav, while it is in use
        self.z = VerticalShaper()  # AC_PosControl's vertical target (takeoff, landing)
        self._hold_s = 0
        self._rtl_home = np.zeros(3)
        # home, east/north of the boot position: moved to where the copter believes it is
        # when it arms (ArduCopter/AP_Arming.cpp AP_Arming_Copter::arm: home not locked is
        # reset to the current location), so RTL returns to the estimate it armed at
        self.home_en = np.zeros(2)
        self._do_done: list[int] = []  # DO commands started, reached at the next update
        self._phase_before_item = ""
        self.fence = FenceGuard(self.tangent.to_en)  # AC_Fence + AP_Rally
        self._brake_since = 0.0  # when the current mode began (BRAKE's deceleration ramp)
        self.gusts: Gusts | None = None  # wind (:mod:`.wind`): the copter is off its target
        self._follower: PositionFollower | None = None  # AC_PosControl, while AC_WPNav flies
        self._followed_until: float | None = None
        self._climber: VerticalFollower | None = None  # AC_PosControl's vertical loops
        self._climbed_until: float | None = None
        self._land_target = np.zeros(3)  # where a landing's descent holds the copter
        self._descend_from = 0.0  # when it starts down (Navigation.land_descent_delay_s)
        self._nav_since = 0.0  # when AC_WPNav was started from a hover
        self.battery = BatteryMonitor()  # AP_BattMonitor's first battery
        # the 400 Hz follower in its compiled loop (ardupilot/compiled.py): the same
        # arithmetic, but loading it stalls the first step by most of a second, which a
        # copter on the wall clock would fly through: on a simulated clock only
        # (sim/inprocess.py)
        self.compiled = False
        self._battery_check = 0.0

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
        self.home_en = self.position[:2].copy()
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
        elif cmd == R.MAV_CMD_BATTERY_RESET:
            result = self.battery_reset(p[0], p[1])
        elif cmd == R.MAV_CMD_DO_CHANGE_SPEED:
            if p[1] > 0:  # GCS_MAVLINK handle_MAV_CMD_DO_CHANGE_SPEED -> set_speed_xy
                self.change_speed(float(p[1]))
                result = R.MAV_RESULT_ACCEPTED
        elif cmd == R.MAV_CMD_DO_SET_CAM_TRIGG_DIST:
            # GCS_Common.cpp handle_command_camera -> AP_Camera::handle_command: the
            # primary camera's trigger distance (none without a camera), a photo at once
            # when param3 is 1, accepted either way
            self._camera_trigger_distance(float(p[0]), 1.0 if p[2] == 1.0 else 0.0)
            result = R.MAV_RESULT_ACCEPTED
        else:
            result = R.MAV_RESULT_UNSUPPORTED
        return result, self._take_pending()


    # -- parameters (GCS_Param.cpp)
    def nav_params(self):
        """The navigation parameters now (the defaults, as set by PARAM_SET), as this
        airframe flies them (FlightLimits.jerk_factor: 1 but with ``--vary``)."""
        key = tuple(map(self.params.get, NAV_PARAMS))  # made again only when one changed
        if self._nav_params is None or self._nav_params[0] != key:
            limits = self.options.limits
            nav = limits.nav.with_params(self.params)
            if limits.jerk_factor != 1.0:
                nav = replace(nav, wp_jerk=nav.wp_jerk * limits.jerk_factor)
            self._nav_params = (key, nav)
        return self._nav_params[1]

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

    def utc_ms(self) -> int | None:
        """AP_RTC::get_utc_usec in ms: the vehicle's UTC clock, None while it has none."""
        if self.utc_offset_s is None:
            return None
        return int((self.time + self.utc_offset_s) * 1000)

    # -- mission execution
    def _start_nav(self, stopping_point: np.ndarray | None = None) -> None:
        """AC_WPNav::wp_and_spline_init from the copter's stopping point: horizontally where
        it is (stopped; in wind, where AC_PosControl::get_stopping_point_xy_cm puts the copter
        following its target), vertically AC_PosControl::get_stopping_point_z_cm (a copter still
        climbing after its takeoff starts its first leg above itself)."""
        if stopping_point is None:
            point = self.position.copy()
            if self._windy():  # the copter following its target is not stopped
                point[:2] = stopping_point_xy(self.position, self.velocity, self.nav_params())
            point[2] = stopping_point_z(float(self.position[2]), float(self.velocity[2]),
                                        self.nav_params())
        else:
            point = stopping_point
        self.nav = WaypointNav(self.nav_params(), point, self.speed_m_s)
        self._nav_since = self.time  # the hover it starts from (FlightLimits: its settling)

    # -- mode starts (once the copter has stopped)
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
            self._battery_step(dt, out)
            self._fence_step(out)
            if self._pending:
                out += self._take_pending()
        self._flush_do(out)
        return out

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

    def _battery_step(self, dt: float, out: list) -> None:
        """AP_BattMonitor::read and check_failsafes at 10 Hz (ardupilot/battery.py): the
        airframe's current in the air (FlightLimits.power), none on the ground; a new
        failsafe while armed says so, and Copter::handle_battery_failsafe takes its
        action: disarm on the ground, else BATT_FS_*_ACT's mode."""
        in_air = self.armed and not self.landed
        v = self.velocity
        amps = (float(self.options.limits.power.current_a(math.hypot(v[0], v[1]), float(v[2])))
                if in_air else 0.0)
        self.battery.draw(amps, dt)
        if self.time < self._battery_check:
            return
        self._battery_check = self.time + BATTERY_CHECK_S
        event = self.battery.check(self.params, self.time, armed=self.armed)
        if event is None:
            return
        words, action = event
        out.append(_text((R.MAV_SEVERITY_WARNING, words)))
        if action < 0:
            return
        out.append(_text((R.MAV_SEVERITY_WARNING, ap_battery.handler_text(landed=self.landed))))
        if self.landed or action == ap_battery.ACTION_TERMINATE:
            self.disarm()
            return
        mode = ap_battery.failsafe_mode(action, rtl=RTL, land=LAND)
        if mode is not None and not self.set_mode(mode, self.time) and mode == RTL:
            self.set_mode(LAND, self.time)  # set_mode_RTL_or_land_with_pause

    def battery_reset(self, mask: float, percent: float) -> int:
        """MAV_CMD_BATTERY_RESET (GCS_Common.cpp handle_command_battery_reset): bit 0 of
        ``mask`` is the first (only) battery."""
        if not int(mask) & 1:
            return R.MAV_RESULT_FAILED
        self.battery.reset(percent, self.params, self.time)
        return R.MAV_RESULT_ACCEPTED

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
        if self._pending:
            out += self._take_pending()
        if self._do_done:
            for seq in self._do_done:
                out.append(R.MAVLink_mission_item_reached_message(seq))
            self._do_done = []

    def _step(self, dt: float, out: list) -> None:
        if not self.armed:
            return
        limits = self.options.limits
        if self._touchdown_at is not None:  # on the ground: the land detector's delay
            if self.time - self._touchdown_at >= limits.disarm_after_touchdown_s:
                self.disarm()
            return
        if self._enter is not None:
            # ModeAuto::init does not stop the copter: AC_WPNav starts from its stopping
            # point (vertically too, _start_nav); other modes' entries brake first here.
            # In wind the copter follows its targets (AC_PosControl, the airframe's drag)
            # and AUTO takes it as it is, moving, horizontally too
            auto = self._enter == self._auto_enter
            if (not self.landed and not (auto and self._windy())
                    and self._brake(dt, vertical=not auto)):
                return
            enter, self._enter = self._enter, None
            enter()
        phase = self._phase
        if phase == "takeoff":
            self._takeoff_step(dt, out)
        elif phase == "hover":
            self._hover_step(dt)
        elif phase in ("wp", "land_fly", "nav_delay", "goto", "rtl_climb", "rtl_return",
                       "rtl_loiter"):
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

    def _follow(self, dt: float, target, target_vel, target_accel, *,
                vertical: bool = True) -> None:
        """AC_PosControl's horizontal loops for ``dt``: the copter follows ``target``
        (ENU) with the airframe's drag, from where it was (a follower is started anew,
        AC_PosControl::init_xy_controller, when the last step did not follow one or
        the parameters changed); vertically too (:meth:`_climb`), unless ``vertical`` is
        False: then it is on its vertical target."""
        nav = self.nav_params()
        follower = self._follower
        if (follower is None or (follower.nav is not nav and follower.nav != nav)
                or self._followed_until is None
                or abs(self._followed_until - (self.time - dt)) > 1e-9):
            follower = self._new_follower()
        follower.step(dt, target, target_vel, target_accel)
        self._followed_until = self.time
        z, vz = (self._climb(dt, target[2], target_vel[2], target_accel[2]) if vertical
                 else (target[2], target_vel[2]))
        self.position = np.array([follower.px, follower.py, z])
        self.velocity = np.array([follower.vx, follower.vy, vz])

    def _new_follower(self, *, airborne: bool = True) -> PositionFollower:
        """AC_PosControl::init_xy_controller: a horizontal follower started where the
        copter is (``airborne`` False: leaving the ground, nothing held against the wind)."""
        wind = (0.0, 0.0, 0.0) if self.gusts is None else self.gusts.wind.velocity_xyz
        kind = PositionFollower
        if self.compiled:
            from ..ardupilot.compiled import CompiledFollower as kind
        self._follower = kind(self.position[:2], self.velocity[:2], nav=self.nav_params(),
                              airframe=self.options.limits.airframe, wind=wind[:2],
                              airborne=airborne)
        return self._follower

    def _climb(self, dt: float, target: float, target_vel: float, target_accel: float
               ) -> tuple[float, float]:
        """AC_PosControl's vertical loops for ``dt``
        (:class:`~ftlbo_mav.ardupilot.poscontrol.VerticalFollower`): the copter's altitude
        and climb rate following ``target`` (m, up), from where it was (started anew,
        AC_PosControl::init_z_controller, when the last step did not follow one)."""
        climber = self._climber
        if (climber is None or self._climbed_until is None
                or abs(self._climbed_until - (self.time - dt)) > 1e-9):
            climber = self._climber = VerticalFollower(
                float(self.position[2]), float(self.velocity[2]), nav=self.nav_params(),
                airframe=self.options.limits.airframe)
        self._climbed_until = self.time
        if target_vel == 0.0 and target_accel == 0.0 and climber.at_rest_on(target):
            return climber.z, climber.v  # hovering on its target: nothing moves
        climber.nav = self.nav_params()
        climber.step(dt, target, target_vel, target_accel)
        if climber.z < 0.0:  # the ground holds it
            climber.z, climber.v = 0.0, max(climber.v, 0.0)
        return climber.z, climber.v

    def _nav_step(self, dt: float, out: list) -> None:
        """AC_WPNav moves the target and the copter follows it (AC_PosControl and the
        airframe's drag, :class:`~ftlbo_mav.ardupilot.poscontrol.PositionFollower`;
        vertically it is on its target); the mode in use then checks whether its leg is
        over (ModeAuto::verify_command, ModeRTL::run)."""
        nav = self.nav
        err = self.options.limits.velocity_estimate_error
        settling = self.time - self._nav_since
        if err != (0.0, 0.0) and settling < 5.0 * SETTLING_S:
            # the hover it started from, still settling (FlightLimits.velocity_estimate_error)
            k = math.exp(-settling / SETTLING_S)
            nav.advance(dt, self.position,
                        self.velocity + np.array([err[0] * k, err[1] * k, 0.0]))
        else:
            nav.advance(dt, self.position, self.velocity)
        self._follow(dt, nav.target, nav.target_vel, nav.target_accel)
        if self.gusts is not None:  # the gusts push it off the path it follows
            (vx, vy, vz), (wx, wy, wz) = self.velocity.tolist(), self.gusts.wind.velocity_xyz
            rx, ry, rz = vx - wx, vy - wy, vz - wz
            airspeed = math.sqrt(rx * rx + ry * ry + rz * rz)
            self.position += self.gusts.step(dt, airspeed)
            self.velocity += self.gusts.error_vel
        self.position[2] = max(self.position[2], 0.0)
        if self._phase in ("wp", "land_fly", "nav_delay"):
            self._verify_auto_nav(out)
        elif self._phase.startswith("rtl_"):
            self._verify_rtl()

