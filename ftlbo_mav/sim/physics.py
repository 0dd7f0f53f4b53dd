"""Point-mass copter kinematics for the emulator: speed, acceleration and climb limits.

Pure functions on ENU metres relative to home. The defaults are ArduCopter's waypoint
navigation defaults (libraries/AC_WPNav/AC_WPNav.h: WPNAV_WP_RADIUS 200 cm,
WPNAV_WP_SPEED_UP 250 cm/s, WPNAV_WP_SPEED_DOWN 150 cm/s; ArduCopter/Parameters.cpp:
LAND_SPEED 50 cm/s), with a horizontal speed of 5 m/s (WPNAV_SPEED's pre-4.0 default,
kept for low orchard flights) and WPNAV_ACCEL 250 cm/s/s. No attitude, no wind: the
emulator is for checking what ftlbo-mav commands, not how a copter flies.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class FlightLimits:
    speed_m_s: float = 5.0
    accel_m_s2: float = 2.5
    climb_m_s: float = 2.5
    descent_m_s: float = 1.5
    land_m_s: float = 0.5
    wp_radius_m: float = 2.0
    spool_up_s: float = 0.0


def step_towards(
    position: np.ndarray,
    velocity: np.ndarray,
    target: np.ndarray,
    dt: float,
    limits: FlightLimits,
    *,
    stop: bool = True,
    speed_m_s: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Advance ``dt`` seconds flying straight at ``target``; all arrays ``(3,)`` ENU metres.

    The desired velocity points at the target, at most ``speed_m_s`` (default the limit's)
    horizontally and the climb/descent limit vertically; with ``stop`` it shrinks to
    ``sqrt(2 a d)`` near the target, so the copter halts there instead of overshooting.
    The velocity moves towards the desired one by at most ``accel * dt``.
    """
    speed = limits.speed_m_s if speed_m_s is None else speed_m_s
    delta = np.asarray(target, float) - position
    dist_h = float(np.hypot(delta[0], delta[1]))
    desired = np.zeros(3)
    if dist_h > 1e-9:
        v_h = speed if not stop else min(speed, np.sqrt(2.0 * limits.accel_m_s2 * dist_h))
        v_h = min(v_h, dist_h / dt) if stop else v_h
        desired[:2] = delta[:2] / dist_h * v_h
    dz = float(delta[2])
    v_up = min(limits.climb_m_s, np.sqrt(2.0 * limits.accel_m_s2 * abs(dz)), abs(dz) / dt)
    v_dn = min(limits.descent_m_s, np.sqrt(2.0 * limits.accel_m_s2 * abs(dz)), abs(dz) / dt)
    desired[2] = v_up if dz > 0 else -v_dn
    change = desired - velocity
    norm = float(np.linalg.norm(change))
    max_change = limits.accel_m_s2 * dt
    if norm > max_change:
        change *= max_change / norm
    velocity = velocity + change
    return position + velocity * dt, velocity


def reached(position: np.ndarray, target: np.ndarray, limits: FlightLimits) -> bool:
    """ArduCopter's arrival test: within the waypoint radius (3D here)."""
    return float(np.linalg.norm(np.asarray(target, float) - position)) <= limits.wp_radius_m
