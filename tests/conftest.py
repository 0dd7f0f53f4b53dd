"""Shared fixtures: the shipped example and small scenario texts."""

from __future__ import annotations

import os
from pathlib import Path

# Before any test module imports pymavlink (as ftlbo_mav/__init__.py does for the package):
# pymavlink picks MAVLink 1 or 2 from this when it first loads a dialect.
os.environ.setdefault("MAVLINK20", "1")
# A first run after an install compiles numba's loops in the background
# (ftlbo_mav/compiling.py): not from the many processes of a test run.
os.environ.setdefault("FTLBO_MAV_BACKGROUND_COMPILE", "0")

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "missions" / "nha-trang-orchard.toml"

SMALL = """\
name = "test field"
[navigation]
horizontal_error = 0.0
[area]
corner_a = [12.2335526, 109.1144313]
corner_b = [12.2331044, 109.1152252]
min_altitude = 2.0
max_altitude = 7.0
[start]
lat = 12.2332099
lon = 109.1145051
alt = 4.0
[goal]
lat = 12.233474
lon = 109.1151763
alt = 4.0
[formation]
offsets = [[0.0, 0.0, 2.0], [3.0, 0.0, -1.0], [-3.0, 0.0, -1.0]]
clearance = 1.0
[[obstacles]]
lat = 12.2333
lon = 109.1148
radius = 3.0
[planner]
students = 12
waypoints = 4
iterations = 8
seed = 0
"""


@pytest.fixture(scope="module")
def planned():
    """The shipped example's plan as ``fly`` loads it (its shipped folder), once a module."""
    from ftlbo_mav.flight.planned import load_planned_flight

    return load_planned_flight(EXAMPLE.with_suffix(""))


@pytest.fixture
def example_path() -> Path:
    return EXAMPLE


@pytest.fixture
def small_text() -> str:
    return SMALL


@pytest.fixture
def small_path(tmp_path: Path) -> Path:
    path = tmp_path / "small.toml"
    path.write_text(SMALL)
    return path
