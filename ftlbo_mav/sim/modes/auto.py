"""AUTO (ArduCopter/mode_auto.cpp): the stored mission from the current item.

``do_nav_wp`` / ``wp_start`` / ``set_next_wp`` give AC_WPNav the destination and, when
the next navigation command is a waypoint and there is no hold time, the next one, so
the S-curve blends through the corner; ``verify_nav_wp`` reaches a waypoint when AC_WPNav
says so, then waits its hold time ("Reached command #N", MISSION_ITEM_REACHED).
DO_CHANGE_SPEED runs when reached in the mission (ModeAuto::do_change_speed ->
AC_WPNav::set_speed_xy) or as a command; MAV_CMD_DO_PAUSE_CONTINUE pauses and resumes a
leg (ModeAuto::pause / resume); MISSION_SET_CURRENT moves the current item
(libraries/AP_Mission/AP_Mission.cpp ``set_current_cmd``). NAV_LAND flies to its point
at the current altitude, then descends (:mod:`.land`). NAV_DELAY holds where the copter
is until its time (ModeAuto::do_nav_delay / verify_nav_delay; the time by the vehicle's
GPS clock, :func:`~ftlbo_mav.ardupilot.commands.nav_delay_ms`).
"""

from __future__ import annotations

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as R

from ...ardupilot.commands import (
    FAILED_TO_PAUSE,
    FAILED_TO_RESUME,
    NAV_LAST,
    delaying,
    mission_started,
    nav_delay_ms,
    reached_command,
)
from ...mission.items import (
    CMD_DO_CHANGE_SPEED,
    CMD_DO_SET_CAM_TRIGG_DIST,
    CMD_NAV_DELAY,
    CMD_NAV_LAND,
    CMD_NAV_LOITER_UNLIM,
    CMD_NAV_RETURN_TO_LAUNCH,
    CMD_NAV_TAKEOFF,
    CMD_NAV_WAYPOINT,
    MissionItem,
)
from .common import AUTO, FLY_THROUGH, text


class ModeAuto:
    """The AUTO part of :class:`~ftlbo_mav.sim.autopilot.Autopilot`."""

    def _starts_with_takeoff(self) -> bool:
        """AP_Mission::starts_with_takeoff_cmd / is_takeoff_next: the first navigation
        command from the current one is a takeoff."""
        for item in self.mission[max(self.current, 1):]:
            if item.command < NAV_LAST and item.command != CMD_NAV_DELAY:  # skippable
                return item.command == CMD_NAV_TAKEOFF
        return False

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
        self._pending.append(text(FAILED_TO_PAUSE if what == 0 else FAILED_TO_RESUME))
        return R.MAV_RESULT_FAILED

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
            elif item.command == CMD_DO_SET_CAM_TRIGG_DIST:  # AP_Mission, AP_Camera
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
            if hold <= 0 and nxt is not None and nxt.command in FLY_THROUGH:
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
        elif item.command == CMD_NAV_DELAY:
            # ModeAuto::do_nav_delay: the submode is left as it was (ModeAuto::init's
            # LOITER: AC_WPNav holds its stopping point; after a waypoint: that waypoint)
            ms = nav_delay_ms(item, self.utc_ms())
            self._pending.append(text(delaying(ms)))
            if self.nav is None:
                self._start_nav(self._takeoff_point())
            self._wait_until = self.time + ms / 1000.0
            self._phase = "nav_delay"
        else:  # commands the emulator does not fly are skipped, like unsupported ones
            self.current += 1
            self._start_item()

    def _announce_start(self, item: MissionItem) -> None:
        started = mission_started(self.current, item.command)
        if started:
            self._pending.append(text(started))

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
            out.append(text(reached_command(self.current)))
        out.append(R.MAVLink_mission_item_reached_message(self.current))
        self.current += 1
        self._start_item()

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

    def _verify_auto_nav(self, out: list) -> None:
        """ModeAuto::verify_nav_wp (reached, then the hold time) and verify_land's fly-to
        stage (ModeAuto::land_run: FlyToLocation -> Descending)."""
        nav = self.nav
        if self._phase == "wp":
            item = self._item()
            if nav.reached and item is not None and item.command == CMD_NAV_WAYPOINT:
                if self._hold_s > 0 and self._wait_until is None:  # ModeAuto::verify_nav_wp
                    self._wait_until = self.time + self._hold_s
                if self._wait_until is None or self.time >= self._wait_until:
                    self._reached(out)
        elif self._phase == "land_fly" and nav.reached:
            self._descend_enter()
        elif self._phase == "nav_delay" and self.time > self._wait_until:
            self._reached(out)  # verify_nav_delay: millis() - start > max
