"""Where the emulated (or SITL) vehicles start: each UAV's start position, or a default row.

A home is ``(lat_deg, lon_deg, alt_m)`` with the altitude above mean sea level.
"""

from __future__ import annotations

import math

from ..scenario import Scenario

# ArduPilot SITL's default location, Canberra Model Aircraft Club (Tools/autotest/locations.txt)
CMAC = (-35.363261, 149.165230, 584.0)
DEFAULT_SPACING_M = 5.0


def default_homes(count: int, *, origin: tuple[float, float, float] = CMAC,
                  spacing_m: float = DEFAULT_SPACING_M) -> list[tuple[float, float, float]]:
    """``count`` homes in a row due east of ``origin``, ``spacing_m`` apart."""
    lat, lon, alt = origin
    m_per_deg_lon = 111_320.0 * math.cos(math.radians(lat))
    return [(lat, lon + i * spacing_m / m_per_deg_lon, alt) for i in range(count)]


def scenario_homes(scenario: Scenario, *,
                   ground_alt_m: float = 0.0) -> list[tuple[float, float, float]]:
    """Each UAV's start on the ground: the centroid start plus its formation offset.

    UAV n starts at ``frame.to_lla(start_enu + offsets_m[n])`` (its first mission item,
    home); the altitude is ``ground_alt_m`` AMSL since a scenario's altitudes are
    relative to home.
    """
    enu = scenario.start_enu()[None, :] + scenario.offsets_m
    lat, lon, _alt = scenario.frame.to_lla(enu)
    return [(float(a), float(o), ground_alt_m) for a, o in zip(lat, lon)]
