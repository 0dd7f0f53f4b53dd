"""A UAV's fence files as one value: ``uavN.fence``, ``uavN.rally`` (``QGC WPL 110``, the
format Mission Planner and MAVProxy read) and the folder's ``fence.parm``."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import MissionFileError
from .items import MissionItem
from .params_file import FENCE_PARAMS_FILE, read_params, write_params
from .waypoints import read_waypoints, write_waypoints


@dataclass(frozen=True)
class FenceSet:
    """What a vehicle holds besides its mission: fence items, rally points (seq from 0
    each) and the fence parameters."""

    fence: tuple[MissionItem, ...] = ()
    rally: tuple[MissionItem, ...] = ()
    params: Mapping[str, float] = field(default_factory=dict)

    def describe(self) -> str:
        return (f"fence {len(self.fence)} items, {len(self.rally)} rally point(s), "
                f"{len(self.params)} fence parameters")


def read_fence_set(folder: str | Path, name: str) -> FenceSet | None:
    """``folder/name.fence`` (+ ``name.rally`` if there, + ``fence.parm``), or None when
    the UAV has no ``.fence`` file. :class:`MissionFileError` naming a bad file."""
    folder = Path(folder)
    fence_path = folder / f"{name}.fence"
    if not fence_path.exists():
        return None
    params_path = folder / FENCE_PARAMS_FILE
    if not params_path.exists():
        raise MissionFileError(f"{params_path}: missing (it holds the fence parameters "
                               f"for {fence_path.name}); plan again with `ftlbo-mav plan`")
    rally_path = folder / f"{name}.rally"
    rally = tuple(read_waypoints(rally_path)) if rally_path.exists() else ()
    return FenceSet(tuple(read_waypoints(fence_path)), rally, read_params(params_path))


def write_fence_set(base: str | Path, fence_set: FenceSet) -> list[Path]:
    """``base.fence``, ``base.rally`` and ``base.parm`` (what a vehicle holds)."""
    base = Path(base)
    written = []
    if fence_set.fence:
        written.append(write_waypoints(base.with_suffix(".fence"), fence_set.fence))
    if fence_set.rally:
        written.append(write_waypoints(base.with_suffix(".rally"), fence_set.rally))
    if fence_set.params:
        written.append(write_params(base.with_suffix(".parm"), fence_set.params))
    return written
