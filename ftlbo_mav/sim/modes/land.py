"""LAND (ArduCopter/mode_land.cpp) and every landing's descent: Mode::
land_run_vertical_control (WPNAV_SPEED_DN above LAND_ALT_LOW, LAND_SPEED below); the
land detector's delay then disarms (recorded ~2.1 s)."""

from __future__ import annotations

from ..physics import VerticalShaper, landing_rate


class ModeLand:
    """The LAND part of :class:`~ftlbo_mav.sim.autopilot.Autopilot`."""

    def _descend_enter(self) -> None:
        """Landing: the vertical target starts where the copter is; horizontally the
        position controller holds the target it had (ModeAuto::land_start keeps the xy
        controller running; Mode::land_run_horizontal_control shapes its velocity to
        zero), so a copter that overshot its landing point comes back to it."""
        self._land_target = (self.position.copy() if self.nav is None
                             else self.nav.target.copy())
        self.nav = None
        self.z = VerticalShaper(pos=float(self.position[2]), vel=float(self.velocity[2]))
        self._phase = "descend"
        # a release that holds its altitude a moment first (Navigation.land_descent_delay_s)
        self._descend_from = self.time + self.nav_params().land_descent_delay_s

    def _descend_step(self, dt: float) -> None:
        """Mode::land_run_vertical_control: descend at :func:`physics.landing_rate`
        (the copter achieving ``land_rate_achieved`` of it), shaped by WPNAV_ACCEL_Z and
        PSC_JERK_Z; on the ground the land detector's delay starts."""
        nav = self.nav_params()
        rate = landing_rate(nav, float(self.position[2]), dt)
        rate *= self.options.limits.land_rate_achieved
        if self.time < self._descend_from:
            rate = 0.0
        self.z.at_rate(rate, dt, accel_max=nav.wp_accel_z, jerk=nav.psc_jerk_z)
        target = self._land_target
        # vertically on its target: SITL's landings descend at 0.46-0.48 m/s without the
        # overshoot that AC_PosControl's vertical loops as modelled give from a standing
        # start (ardupilot.poscontrol.VerticalFollower, 0.54 m/s): held to the recording
        self._follow(dt, (target[0], target[1], max(self.z.pos, 0.0)), (0.0, 0.0, self.z.vel),
                     (0.0, 0.0, 0.0), vertical=False)
        if self.position[2] <= 0.0:
            self.velocity[:] = 0.0
            self._touchdown_at = self.time
