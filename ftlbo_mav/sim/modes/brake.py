"""BRAKE (ArduCopter/mode_brake.cpp) and the stop before any new mode's navigation:
the deceleration measured on SITL (:mod:`ftlbo_mav.ardupilot.navigation` BRAKE_*), and
for the other modes AC_PosControl's stopping point at WPNAV_ACCEL; then GUIDED, LOITER
and BRAKE hold where the copter stopped."""

from __future__ import annotations

import numpy as np

from ...ardupilot.navigation import BRAKE_DECEL_MAX_M_S2, BRAKE_RAMP_S, BRAKE_TIME_CONSTANT_S
from .common import BRAKE


class ModeBrake:
    """The BRAKE (and hold) part of :class:`~ftlbo_mav.sim.autopilot.Autopilot`."""

    def _hold_enter(self) -> None:
        self.nav = None
        self._phase = "hover" if self._takeoff_done_at is not None else "hold"

    def _brake(self, dt: float, *, vertical: bool = True) -> bool:
        """Stop before a new mode's navigation starts (AC_PosControl's stopping point,
        reached at WPNAV_ACCEL); True while still moving. ``vertical`` False: only the
        horizontal speed is stopped, the climb rate kept (the new mode starts from the
        vertical stopping point itself: AUTO, AC_WPNav::wp_and_spline_init)."""
        kept = 0.0 if vertical else float(self.velocity[2])
        velocity = self.velocity.copy()
        velocity[2] -= kept
        speed = float(np.linalg.norm(velocity))
        if speed < 1e-3:
            self.velocity[:] = (0.0, 0.0, kept)
            return False
        if self.mode == BRAKE:  # as measured on SITL (ardupilot.navigation BRAKE_*)
            ramp = min(1.0, (self.time - self._brake_since) / BRAKE_RAMP_S)
            accel = min(BRAKE_DECEL_MAX_M_S2, speed / BRAKE_TIME_CONSTANT_S) * ramp
            if speed < 0.02:
                accel = speed / dt
        else:
            accel = self.nav_params().wp_accel
        cut = min(speed, accel * dt)
        new = velocity * (1.0 - cut / speed)
        new[2] += kept
        self.position = self.position + (self.velocity + new) / 2 * dt
        self.position[2] = max(self.position[2], 0.0)
        self.velocity = new
        return True
