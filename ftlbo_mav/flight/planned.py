"""A plan folder as the flight side sees it: ``plan.json`` plus one mission per UAV."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..ardupilot.copters import Copter, copter_of
from ..ardupilot.navigation import VEHICLE_PARAMS, vehicle_navigation
from ..energy import battery_from_document
from ..errors import FtlboError, MissionFileError
from ..geo import LocalFrame
from ..gnss import NO_BUDGET, NavigationBudget, budget_from_document
from ..mission.fence_files import FenceSet, read_fence_set
from ..mission.items import CMD_DO_CHANGE_SPEED, CMD_NAV_TAKEOFF, CMD_NAV_WAYPOINT, MissionItem
from ..mission.plan_reader import check_plan_folder, plan_from_document, read_plan_json
from ..mission.waypoints import read_waypoints
from .battery import MissionBattery


class PlanFolderError(FtlboError):
    """A plan folder lacks ``plan.json`` or a mission file, or they disagree."""

    bad_input = True


@dataclass(frozen=True, eq=False)
class PlannedFlight:
    """What ``fly`` and ``monitor`` compare the vehicles against.

    ``offsets``: ``(N, 3)`` metres ENU; ``paths``: ``(N, P, 3)`` each UAV's planned
    points (start .. goal) in ``frame``; ``centres`` ``(K, 2)`` and ``radii`` ``(K,)``
    the obstacles (their own radii, without clearance); ``fences``: each UAV's fence,
    rally points and fence parameters (None: it has no ``uavN.fence``);
    ``predicted_clearance`` / ``predicted_separation``: ``(N,)`` metres each UAV's
    predicted flown path keeps from the obstacles and the other UAVs (``plan.json``;
    None for a plan written without the prediction).
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
    predicted_clearance: np.ndarray | None = None
    predicted_separation: np.ndarray | None = None
    vehicle: dict[str, float] | None = None  # plan.json's [vehicle] parameters, if any
    navigation: NavigationBudget = NO_BUDGET  # plan.json's navigation budget
    battery: MissionBattery | None = None  # plan.json's [battery] and each mission's charge
    # plan.json's min_separation, altitude band (above home) and area (ENU east/north:
    # lower, upper), for the routes home (flight/homeward.py)
    min_separation_m: float = 2.0
    band: tuple[float, float] | None = None
    area: tuple[np.ndarray, np.ndarray] | None = None
    # plan.json's formation bound: a UAV farther from its slot in flight is a departure
    # (None: a plan written before it, not watched)
    formation_bound_m: float | None = None
    # each UAV's copter as its flight was predicted (plan.json uavs[].vehicle: release,
    # parameters, what upload sets); empty for a plan written before them
    copters: tuple[Copter, ...] = ()

    @property
    def count(self) -> int:
        return len(self.names)

    def fleet(self) -> tuple[Copter, ...]:
        """One copter per UAV as the plan predicted it (ArduCopter's defaults with
        plan.json's ``vehicle`` for a plan written before ``uavs[].vehicle``)."""
        if len(self.copters) == self.count:
            return self.copters
        return (copter_of(vehicle_navigation({k: v for k, v in (self.vehicle or {}).items()
                                              if k in VEHICLE_PARAMS}),
                          source="plan.json"),) * self.count

    def speed_and_holds(self) -> tuple[float | None, np.ndarray] | None:
        """The missions' cruise speed (their DO_CHANGE_SPEED, None: WPNAV_SPEED) and each
        planned point's hold ``(P,)`` seconds, as the flown path is predicted with; None
        when the missions do not hold one waypoint per planned point."""
        if not self.missions:
            return None
        items = self.missions[0]
        speeds = [it.param2 for it in items if it.command == CMD_DO_CHANGE_SPEED]
        holds = [it.param1 for it in items[2:] if it.command == CMD_NAV_WAYPOINT]
        if len(holds) != self.paths.shape[1]:
            return None
        return (speeds[0] if speeds else None), np.array(holds, float)

    def assignments(self) -> list:
        """Each UAV's upload with system id i+1 (:class:`~ftlbo_mav.link.swarm.Assignment`:
        its mission, fence, the navigation values its scenario named and its copter), as
        ``upload`` sends it."""
        from ..link.swarm import Assignment

        fleet = self.fleet()
        return [Assignment(n, i + 1, m, f, fleet[i].to_set(), fleet[i]) for i, (n, m, f) in
                enumerate(zip(self.names, self.missions, self.fences))]


def load_planned_flight(folder: str | Path) -> PlannedFlight:
    """``folder``'s plan and its mission files, checked to belong together
    (:func:`~ftlbo_mav.mission.plan_reader.check_plan_folder`); :class:`PlanFolderError`."""
    folder = Path(folder)
    try:
        doc, doc_path = read_plan_json(folder)
        plan_from_document(doc, source=doc_path)  # its values checked, as `plot` does
    except MissionFileError as exc:
        raise PlanFolderError(str(exc)) from None
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
        predicted = [_predicted(u, "predicted_clearance_m") for u in uavs]
        separated = [_predicted(u, "predicted_separation_m") for u in uavs]
        vehicle = {str(k): float(v) for k, v in (doc.get("vehicle") or {}).items()}
        copters = (tuple(Copter.from_document(u["vehicle"]) for u in uavs)
                   if all(isinstance(u.get("vehicle"), dict) for u in uavs) else ())
        navigation = budget_from_document(doc.get("navigation"))
        battery = _mission_battery(doc)
        min_separation = float(doc.get("min_separation", 2.0))
        bound = (doc.get("formation_bound") or {}).get("error_m")
        area = doc["area"]
        band = ((float(area["min_altitude"]), float(area["max_altitude"]))
                if "min_altitude" in area else None)
        corners = frame.to_enu(lat_deg=[lat_a, lat_b], lon_deg=[lon_a, lon_b])[:, :2]
        box = (corners.min(axis=0), corners.max(axis=0))
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise PlanFolderError(f"{doc_path}: not a plan.json written by ftlbo-mav ({exc})") from None
    missions = []
    try:
        for file in check_plan_folder(folder, doc, source=doc_path):
            items = tuple(read_waypoints(file))
            if not any(it.command == CMD_NAV_TAKEOFF for it in items):
                raise PlanFolderError(f"{file}: no NAV_TAKEOFF item; `fly` takes off with it")
            missions.append(items)
        fences = tuple(read_fence_set(folder, name) for name in names)
    except MissionFileError as exc:
        raise PlanFolderError(str(exc)) from None
    return PlannedFlight(folder, names, offsets, paths, tuple(missions), frame, centres, radii,
                         clearance, fences,
                         None if None in predicted else np.array(predicted, float),
                         None if None in separated else np.array(separated, float),
                         vehicle or None, navigation, battery, min_separation, band, box,
                         None if bound is None else float(bound), copters)


def _mission_battery(doc: dict) -> MissionBattery | None:
    """plan.json's ``battery`` and each UAV's predicted charge, when the plan has them."""
    battery = battery_from_document(doc.get("battery"))
    if battery is None or not all("battery" in u for u in doc["uavs"]):
        return None
    return MissionBattery(battery, tuple(float(u["battery"]["mah"]) for u in doc["uavs"]),
                          tuple(np.array(u["battery"]["to_end_mah"], float)
                                for u in doc["uavs"]))


def _predicted(uav: dict, key: str) -> float | None:
    """A predicted figure of one UAV in plan.json (null: infinite, no obstacles)."""
    if key not in uav:
        return None
    return float("inf") if uav[key] is None else float(uav[key])
