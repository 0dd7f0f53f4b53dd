"""Test missions built without the planner: 15 items (home, takeoff, 11 waypoints, goal, land)."""

from __future__ import annotations

from pathlib import Path

from ftlbo_mav.mission.items import MissionItem, build_mission
from ftlbo_mav.mission.waypoints import write_waypoints

HOME = (12.2332099, 109.1145051)


def make_mission(k: int = 0, *, points: int = 12) -> list[MissionItem]:
    """UAV ``k``'s mission: a zig-zag of ``points`` path points (the last is the goal)."""
    lat0, lon0 = HOME[0], HOME[1] + k * 3e-5
    path = [(lat0 + i * 2.1e-5 + (i % 2) * 3.3e-6, lon0 + i * 6.7e-5, 4.0 + 0.37 * i + 0.1 * k)
            for i in range(points)]
    return build_mission(home=(lat0, lon0), takeoff_alt_m=3.0, path=path)


def write_missions(folder: Path, count: int) -> list[list[MissionItem]]:
    missions = [make_mission(k) for k in range(count)]
    for k, items in enumerate(missions):
        write_waypoints(folder / f"uav{k + 1}.waypoints", items)
    return missions
