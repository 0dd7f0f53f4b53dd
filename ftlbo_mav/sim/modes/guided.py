"""GUIDED (ArduCopter/mode_guided.cpp) and the user takeoff it runs.

MAV_CMD_NAV_TAKEOFF is accepted in GUIDED when armed (ArduCopter/GCS_Mavlink.cpp
``handle_command_long_packet``, ``Mode::do_user_takeoff``); the copter leaves the ground
after the spool-up and throttle slew (recorded ~3 s) and climbs as ``_AutoTakeoff::run``
asks (AC_PosControl's jerk-limited vertical shaping), then hovers. A position target
flies there with AC_WPNav (ModeGuided::set_destination), refused outside the fence.
"""

from __future__ import annotations

import numpy as np

from ..physics import VerticalShaper
from .common import AUTO, GUIDED


class ModeGuided:
    """The GUIDED part of :class:`~ftlbo_mav.sim.autopilot.Autopilot`."""

    def takeoff(self, alt_m: float, now: float | None = None) -> bool:
        """MAV_CMD_NAV_TAKEOFF: Mode::do_user_takeoff refuses unless armed, landed
        (``ap.land_complete``) and in a mode that has a user takeoff (GUIDED here)."""
        if not self.armed or self.mode != GUIDED or alt_m <= 0 or not self.landed:
            return False
        self._start_takeoff(alt_m, self.time if now is None else now)
        return True

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

    def _start_takeoff(self, alt_m: float, now: float) -> None:
        """Mode::do_user_takeoff / ModeAuto::takeoff_start -> _AutoTakeoff::start: from
        the ground the climb starts after the spool-up and throttle slew."""
        self._enter = None
        self._takeoff_alt = alt_m
        self._takeoff_done_at = None
        delay = self.options.limits.takeoff_delay_s if self.landed else 0.0
        self._takeoff_at = now + delay
        self._takeoff_from_ground = self.landed
        self._takeoff_xy = self.position[:2].copy()  # the horizontal target it holds
        self.z = VerticalShaper(pos=float(self.position[2]), vel=float(self.velocity[2]))
        self._phase = "takeoff"

    def _takeoff_step(self, dt: float, out: list) -> None:
        """_AutoTakeoff::run: shape the altitude to the takeoff altitude at WPNAV_SPEED_UP,
        WPNAV_ACCEL_Z, PSC_JERK_Z; complete when the target is within the stopping distance
        of a tenth of the climb speed and climbs slower than that."""
        if self._takeoff_at is not None:
            if self.time < self._takeoff_at:
                return  # motors spooling up, throttle slewing (still on the ground)
            self._takeoff_at = None
            if self._takeoff_from_ground and self._windy():
                self._new_follower(airborne=False)  # it lifts off level
                self._followed_until = self.time - dt
        nav = self.nav_params()
        self.z.to_altitude(self._takeoff_alt, dt, up=nav.wp_speed_up, down=nav.wp_speed_dn,
                           accel_max=nav.wp_accel_z, jerk=nav.psc_jerk_z)
        # the copter follows its target (AC_PosControl::update_z_controller), not on it
        self._takeoff_follow(dt)
        # complete by its target, not by where the copter is (_AutoTakeoff::run)
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
        altitude (ModeGuided::takeoff_run goes on running _AutoTakeoff::run); the copter
        follows it, overshooting and coming back over seconds
        (:class:`~ftlbo_mav.ardupilot.poscontrol.VerticalFollower`)."""
        nav = self.nav_params()
        self.z.to_altitude(self._takeoff_alt, dt, up=nav.wp_speed_up, down=nav.wp_speed_dn,
                           accel_max=nav.wp_accel_z, jerk=nav.psc_jerk_z)
        self._takeoff_follow(dt)

    def _windy(self) -> bool:
        return self.gusts is not None and self.gusts.wind.speed_m_s > 0

    def _takeoff_follow(self, dt: float) -> None:
        """_AutoTakeoff::run's position control: the vertical target climbs; horizontally
        the target holds where the takeoff started (input_vel_accel_xy with zero velocity,
        ArduCopter/takeoff.cpp) and in wind the copter follows it with the airframe's drag
        (AC_PosControl::update_xy_controller): having lifted off level, it is blown
        downwind until the velocity loop's I term holds the wind (ArduCopter 4.5.6 SITL
        in 6.6 m/s: 0.84-0.86 m, 2 s after liftoff, back within 0.1 m 4-5 s later). In
        calm air it stays where it is (the follower would hold it still: skipped)."""
        if not self._windy():
            self.position[2], vz = self._climb(dt, self.z.pos, self.z.vel, self.z.accel)
            self.velocity[:] = (0.0, 0.0, vz)
            return
        x, y = self._takeoff_xy.tolist()
        self._follow(dt, (x, y, self.z.pos), (0.0, 0.0, self.z.vel),
                     (0.0, 0.0, self.z.accel))
