"""A plan folder as the flight side sees it: ``plan.json`` plus one mission per UAV."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import FtlboError, MissionFileError
from ..geo import LocalFrame
from ..mission.fence_files import FenceSet, read_fence_set
from ..mission.items import CMD_NAV_TAKEOFF, MissionItem
from ..mission.waypoints import read_waypoints


class PlanFolderError(FtlboError):
    """A plan folder lacks ``plan.json`` or a mission file, or they disagree."""

    bad_input = True


@dataclass(frozen=True, eq=False)
class PlannedFlight:
    """What ``fly`` and ``monitor`` compare the vehicles against.

    ``offsets``: ``(N, 3)`` metres ENU; ``paths``: ``(N, P, 3)`` each UAV's planned
    points (start .. goal) in ``frame``; ``centres`` ``(K, 2)`` and ``radii`` ``(K,)``
    the obstacles (their own radii, without clearance); ``fences``: each UAV's fence,
    rally points and fence parameters (None: it has no ``uavN.fence``).
    """

    folder: Path
    names: tuple[str, ...]
    offsets: np.ndarray
    paths: np.ndarray
    missions: tuple[tuple[MissionItem, ...], ...]
    frame: LocalFrame
    centres: np.ndarray
    radii: np.ndarray
    clearance_m: float
    fences: tuple[FenceSet | None, ...] = ()

    @property
    def count(self) -> int:
        return len(self.names)


def load_planned_flight(folder: str | Path) -> PlannedFlight:
    folder = Path(folder)
    doc_path = folder / "plan.json"
    try:
        doc = json.loads(doc_path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise PlanFolderError(f"{doc_path}: no such file (run `ftlbo-mav plan` first)") from None
    except (OSError, ValueError) as exc:
        raise PlanFolderError(f"{doc_path}: cannot read: {exc}") from None
    try:
        uavs = doc["uavs"]
        lat_a, lon_a = doc["area"]["corner_a"]
        lat_b, lon_b = doc["area"]["corner_b"]
        frame = LocalFrame(origin_lat_deg=min(lat_a, lat_b), origin_lon_deg=min(lon_a, lon_b))
        names = tuple(u["name"] for u in uavs)
        offsets = np.array([u["offset"] for u in uavs], float).reshape(-1, 3)
        paths = np.stack(
            [
                frame.to_enu(
                    lat_deg=[p["lat"] for p in u["waypoints"]],
                    lon_deg=[p["lon"] for p in u["waypoints"]],
                    alt_m=[p["alt"] for p in u["waypoints"]],
                )
                for u in uavs
            ]
        )
        obstacles = doc.get("obstacles", [])
        centres = np.zeros((0, 2))
        if obstacles:
            centres = frame.to_enu(lat_deg=[o["lat"] for o in obstacles],
                                   lon_deg=[o["lon"] for o in obstacles])[:, :2]
        radii = np.array([o["radius"] for o in obstacles], float)
        clearance = float(doc.get("clearance", 0.0))
        files = [u["mission_file"] for u in uavs]
    except (KeyError, TypeError, ValueError) as exc:
        raise PlanFolderError(f"{doc_path}: not a plan.json written by ftlbo-mav ({exc})") from None
    if any(f is None for f in files):
        raise PlanFolderError(f"{doc_path}: the plan is infeasible and has no mission files")
    missions = []
    try:
        fences = tuple(read_fence_set(folder, name) for name in names)
    except MissionFileError as exc:
        raise PlanFolderError(str(exc)) from None
    for f in files:
        try:
            items = tuple(read_waypoints(folder / f))
        except MissionFileError as exc:
            raise PlanFolderError(str(exc)) from None
        if not any(it.command == CMD_NAV_TAKEOFF for it in items):
            raise PlanFolderError(f"{folder / f}: no NAV_TAKEOFF item; `fly` takes off with it")
        missions.append(items)
    return PlannedFlight(folder, names, offsets, paths, tuple(missions), frame, centres, radii,
                         clearance, fences)
