"""The emulated copter's geofence and rally points, as ArduCopter 4.5 enforces them.

:class:`FenceGuard` holds what the fence and rally protocols stored and the FENCE_*
parameters, and :meth:`FenceGuard.check` is ``Copter::fence_check`` (ArduCopter/fence.cpp,
25 Hz): ``AC_Fence::check`` finds the *new* breaches (a type already breached is not
breached again until it has cleared; libraries/AC_Fence/AC_Fence.cpp ``record_breach`` /
``clear_breach``), and while armed a new breach announces "Fence Breached" (in the air)
and switches to the FENCE_ACTION's mode (brake, RTL, land; landed: disarm). Rules and
numbers are :mod:`ftlbo_mav.ardupilot.fence`. Not emulated: the altitude fence's 20 m
backup after a breach, manual recovery, exclusion polygons, inclusion circles, the
FENCE_RADIUS circle (FENCE_TYPE bit 2), FENCE_ALT_MIN, and the pre-arm fence checks.
:meth:`FenceGuard.destination_ok` is the check GUIDED makes of every target: ArduCopter
refuses a destination outside the fence, so a copter sent *into* a tree's exclusion
circle does not move at all; one sent past the tree breaches on the way and brakes.

:meth:`FenceGuard.return_target` is AP_Rally::calc_best_rally_or_home_location (the nearer
of home and the nearest rally point, RALLY_INCL_HOME 1, within RALLY_LIMIT_KM 0.3) and
:meth:`FenceGuard.rtl_alt_limit` ModeRTL::compute_return_target's fence clamp
(FENCE_ALT_MAX - FENCE_MARGIN when the altitude fence is enabled).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np

from ..ardupilot import fence as ap
from ..ardupilot.storage import WireItem


class FenceGuard:
    """One copter's stored fence and rally points, and its breach state."""

    def __init__(self, to_en: Callable[[float, float], tuple[float, float]]) -> None:
        self.to_en = to_en
        self.geometry = ap.FenceGeometry((), np.zeros((0, 3)))
        self.rally = np.zeros((0, 3))  # east, north, alt above home (m)
        self.breached = 0              # AC_Fence::_breached_fences
        self.next_check = 0.0

    def load(self, fence: list[WireItem], rally: list[WireItem]) -> None:
        """What the fence and rally protocols stored (read-back form)."""
        self.geometry = ap.fence_geometry(fence, self.to_en)
        self.rally = np.array([(*self.to_en(r.x * 1e-7, r.y * 1e-7), r.z) for r in rally],
                              float).reshape(-1, 3)

    @staticmethod
    def enabled(params: Mapping[str, float]) -> bool:
        return int(params.get("FENCE_ENABLE", 0)) == 1

    def check(self, *, position: np.ndarray, params: Mapping[str, float]) -> int:
        """AC_Fence::check: the fence types newly breached at ``position`` (ENU metres,
        relative to home); 0 when the fence is disabled."""
        if not self.enabled(params):
            self.breached = 0
            return 0
        now = ap.breaches(self.geometry, east_north=position[:2], alt_m=float(position[2]),
                          fence_type=int(params.get("FENCE_TYPE", 7)),
                          alt_max_m=float(params.get("FENCE_ALT_MAX", 100.0)))
        new = now & ~self.breached
        self.breached = now
        return new

    def destination_ok(self, target: np.ndarray, params: Mapping[str, float]) -> bool:
        """AC_Fence::check_destination_within_fence, which ModeGuided::set_destination
        asks before it accepts a target: not above FENCE_ALT_MAX, not outside the
        inclusion polygon or inside an exclusion circle (fence enabled)."""
        if not self.enabled(params):
            return True
        return ap.breaches(self.geometry, east_north=target[:2], alt_m=float(target[2]),
                           fence_type=int(params.get("FENCE_TYPE", 7)),
                           alt_max_m=float(params.get("FENCE_ALT_MAX", 100.0))) == 0

    def breach_distance(self, position: np.ndarray, params: Mapping[str, float]) -> float:
        """AC_Fence::get_breach_distance, for the give-up rule: how far above the
        altitude fence (the polygon's distance is not emulated: 0)."""
        return max(0.0, float(position[2]) - float(params.get("FENCE_ALT_MAX", 100.0)))

    def return_target(self, position: np.ndarray, home_en=(0.0, 0.0)) -> np.ndarray:
        """Where RTL goes: ``(east, north, alt)``, home at ``home_en`` and altitude 0."""
        k = ap.rtl_target(position[:2], home_en, self.rally[:, :2]) if len(
            self.rally) else None
        return np.array([*home_en, 0.0], float) if k is None else self.rally[k].copy()

    def rtl_alt_limit(self, params: Mapping[str, float]) -> float | None:
        """The highest RTL return altitude the altitude fence allows, or None."""
        if not self.enabled(params) or not int(params.get("FENCE_TYPE", 7)) & ap.TYPE_ALT_MAX:
            return None
        return float(params.get("FENCE_ALT_MAX", 100.0)) - float(params.get("FENCE_MARGIN", 2.0))
