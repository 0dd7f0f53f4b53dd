"""How far a flight got along its plan, from its record (pure).

Each UAV's progress is a position along its planned path, ``k + f``: path point ``k``
reached and the fraction ``f`` of the way on to point ``k + 1`` (0: it never left its
start point; ``P - 1``: it reached the goal). It is read from what the vehicle reported
while it flew the plan's mission: from the first position report in AUTO to the last
one before it left AUTO (a pause keeps it in AUTO; a stop, a way home, an abort, a mode
taken over, a lost link end it) and before its current item went back (the mission's
current item only goes forward while it flies the plan: an earlier one is another
mission, a way home started quicker than a report came), each report placed on the leg
it was flying (MISSION_CURRENT's item) by its projection on that leg, and the furthest
counted. The
photos a UAV reported (CAMERA_FEEDBACK) before the report that showed it off the plan
came are the ones it took on the plan (one link keeps a vehicle's messages in order; a
photo taken in the second or so before its HEARTBEAT told of a new mode was taken where
it braked on its track, and :mod:`ftlbo_mav.planning.resume` counts only photos on a
lane's line).

``fly`` writes this as ``progress.json`` beside the flight log; ``fly --resume`` plans
the rest of the survey from it (:mod:`ftlbo_mav.planning.resume`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..mission.items import (
    CMD_NAV_LAND,
    CMD_NAV_LOITER_UNLIM,
    CMD_NAV_RETURN_TO_LAUNCH,
    CMD_NAV_TAKEOFF,
    CMD_NAV_WAYPOINT,
)
from .planned import PlannedFlight
from .record import FlightRecord

_ENDS = (CMD_NAV_LAND, CMD_NAV_RETURN_TO_LAUNCH, CMD_NAV_LOITER_UNLIM)


@dataclass(frozen=True, eq=False)
class UavProgress:
    """One UAV's progress: ``point`` (``k + f``, module notes), ``until_s`` when it last
    flew the plan (seconds of the record; None: it never did) and ``photos (K, 3)``,
    metres ENU in the plan's frame, the photos it took on the plan (None: it reported no
    photo at all in the flight, so its camera may not send CAMERA_FEEDBACK)."""

    name: str
    point: float
    until_s: float | None
    photos: np.ndarray | None


def targets(mission, points: int) -> dict[int, int]:
    """Mission item seq -> the path point its leg flies to: the plan's n-th NAV_WAYPOINT
    after NAV_TAKEOFF is path point n; a DO item counts as the navigation item after it
    (it runs on the way there); the mission's end (NAV_LAND, RTL, LOITER_UNLIM) is
    ``points``, past the goal."""
    out, nav, pending = {}, -1, []
    for it in mission[1:]:
        if it.command == CMD_NAV_TAKEOFF:
            pending = []
            nav = -1
            continue
        pending.append(it.seq)
        if it.command == CMD_NAV_WAYPOINT:
            nav += 1
        elif it.command not in _ENDS:
            continue
        target = min(nav, points - 1) if it.command == CMD_NAV_WAYPOINT else points
        for seq in pending:
            out[seq] = target
        pending = []
    return out


def flown(planned: PlannedFlight, record: FlightRecord, sysids: list[int]) -> list[UavProgress]:
    """Every UAV's progress along its plan in ``record`` (module notes)."""
    out = []
    for n, sysid in enumerate(sysids):
        path = planned.paths[n]
        legs = targets(planned.missions[n], len(path))
        samples = record.of(sysid)
        point, until, last, left = 0.0, None, 0, float("inf")
        if samples:
            enu = planned.frame.to_enu(lat_deg=[s.lat_deg for s in samples],
                                       lon_deg=[s.lon_deg for s in samples])[:, :2]
            for s, here in zip(samples, enu):
                if s.mode != "AUTO":
                    if until is not None:
                        left = s.t  # it left the plan's mission: what came after is not
                        break
                    continue
                target = legs.get(s.seq)
                if target is None:
                    continue
                if target < last:  # an item before the one it flew: another mission
                    left = s.t
                    break
                last, until = target, s.t
                if target >= len(path):
                    point = float(len(path) - 1)
                elif target >= 1:
                    point = max(point, target - 1 + _along(path[target - 1, :2],
                                                           path[target, :2], here))
        photos = None
        taken = record.photos_of(sysid)
        if taken:
            kept = [p for p in taken if until is not None and p.t < left]
            photos = (planned.frame.to_enu(lat_deg=[p.lat_deg for p in kept],
                                           lon_deg=[p.lon_deg for p in kept],
                                           alt_m=[p.alt_m for p in kept]).reshape(-1, 3)
                      if kept else np.zeros((0, 3)))
        out.append(UavProgress(planned.names[n], point, until, photos))
    return out


def _along(a: np.ndarray, b: np.ndarray, p: np.ndarray) -> float:
    """How far along the segment a->b the projection of p lies, clipped to [0, 1]."""
    d = b - a
    length2 = float(d @ d)
    if length2 < 1e-12:
        return 1.0
    return float(np.clip((p - a) @ d / length2, 0.0, 1.0))


def progress_document(planned: PlannedFlight, progress: list[UavProgress]) -> dict:
    """``progress.json``: the plan it belongs to (each mission's SHA-256, as plan.json
    records it) and per UAV its progress and photos (lat, lon, alt above home)."""
    doc = {"plan": str(planned.folder), "uavs": []}
    for p in progress:
        photos = None
        if p.photos is not None:
            lat, lon, alt = (planned.frame.to_lla(p.photos) if len(p.photos)
                             else (np.zeros(0),) * 3)
            photos = [[round(float(a), 8), round(float(b), 8), round(float(c), 3)]
                      for a, b, c in zip(lat, lon, alt)]
        doc["uavs"].append({"name": p.name, "point": round(p.point, 4),
                            "points": int(planned.paths.shape[1]),
                            "photos": photos})
    return doc


def progress_from_document(planned: PlannedFlight, doc: dict) -> list[UavProgress]:
    """``progress.json`` back (:func:`progress_document`); ValueError when it does not
    fit ``planned`` (other UAVs or another number of path points)."""
    uavs = doc["uavs"]
    if [u["name"] for u in uavs] != list(planned.names):
        raise ValueError(f"it is for {', '.join(u['name'] for u in uavs)}, the plan flies "
                         f"{', '.join(planned.names)}")
    out = []
    for u in uavs:
        if int(u["points"]) != planned.paths.shape[1]:
            raise ValueError(f"{u['name']}'s path had {u['points']} points, the plan's has "
                             f"{planned.paths.shape[1]}")
        point = float(u["point"])
        if not 0.0 <= point <= planned.paths.shape[1] - 1:
            raise ValueError(f"{u['name']}: point {point:g} is not on its path")
        photos = u["photos"]
        if photos is not None:
            rows = np.array(photos, float).reshape(-1, 3)
            photos = (planned.frame.to_enu(lat_deg=rows[:, 0], lon_deg=rows[:, 1],
                                           alt_m=rows[:, 2]).reshape(-1, 3))
        out.append(UavProgress(str(u["name"]), point, None, photos))
    return out


__all__ = ["UavProgress", "flown", "progress_document",
           "progress_from_document", "targets"]
