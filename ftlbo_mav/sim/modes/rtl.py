"""RTL (ArduCopter/mode_rtl.cpp): climb to the return altitude over the stopping point
(RTL_ALT, never lower than now or than the rally point's, but not above FENCE_ALT_MAX -
FENCE_MARGIN with the altitude fence on), blended into the return to home or the nearer
rally point (ModeRTL::compute_return_target, AP_Rally), loiter RTL_LOIT_TIME, land.
"""

from __future__ import annotations

import numpy as np

from ..physics import WaypointNav


class ModeRTL:
    """The RTL part of :class:`~ftlbo_mav.sim.autopilot.Autopilot`."""

    def _rtl_enter(self) -> None:
        """ModeRTL::init / build_path / climb_start: from the stopping point climb to the
        return altitude (RTL_ALT, never lower than now or than the rally point's, but not
        above FENCE_ALT_MAX - FENCE_MARGIN with the altitude fence on), blended into the
        return to home or the nearer rally point (compute_return_target)."""
        nav = self.nav_params()
        self.nav = WaypointNav(nav, self.position.copy(),
                               nav.rtl_speed if nav.rtl_speed > 0 else None)
        target = self.fence.return_target(self.position, self.home_en)
        alt = max(float(self.position[2]), nav.rtl_alt, float(target[2]))
        limit = self.fence.rtl_alt_limit(self.params)
        if limit is not None:
            alt = min(alt, max(limit, 0.0))
        self._rtl_home = np.array([target[0], target[1], alt])
        self.nav.set_destination(np.array([self.position[0], self.position[1], alt]))
        self.nav.set_destination_next(self._rtl_home)
        self._phase = "rtl_climb"

    def _verify_rtl(self) -> None:
        """ModeRTL::run's stages: climb, return, loiter RTL_LOIT_TIME, then land."""
        nav, phase = self.nav, self._phase
        if phase == "rtl_climb" and nav.reached:
            nav.set_destination(self._rtl_home)  # ModeRTL::return_start
            self._phase = "rtl_return"
        elif phase == "rtl_return" and nav.reached:  # ModeRTL::loiterathome_start
            self._wait_until = self.time + self.nav_params().rtl_loit_time
            self._phase = "rtl_loiter"
        elif phase == "rtl_loiter" and self.time >= self._wait_until:
            self._wait_until = None
            self._descend_enter()  # ModeRTL::land_start (RTL_ALT_FINAL 0)
