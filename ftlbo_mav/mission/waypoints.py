"""Mission Planner ``.waypoints`` files (``QGC WPL 110``).

One header line, then one tab-separated line per item::

    seq current frame command p1 p2 p3 p4 lat lon alt autocontinue

Item 0 is home, in frame 0 with current=1. Latitude and longitude carry 8 decimals, as
Mission Planner writes them; pymavlink's ``mavwp.MAVWPLoader`` reads the same format.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from ..errors import MissionFileError
from .files import read_mission_text, write_atomic
from .items import MAX_ITEMS, MissionItem, item_problem

HEADER = "QGC WPL 110"


def _num(value: float) -> str:
    text = f"{value:.6f}".rstrip("0").rstrip(".")
    return "0" if text in ("", "-0") else text


def render_waypoints(items: Iterable[MissionItem]) -> str:
    """Items -> ``.waypoints`` text (with a trailing newline)."""
    lines = [HEADER]
    for it in items:
        fields = [
            str(it.seq),
            str(it.current),
            str(it.frame),
            str(it.command),
            *(_num(p) for p in (it.param1, it.param2, it.param3, it.param4)),
            f"{it.lat_deg:.8f}",
            f"{it.lon_deg:.8f}",
            f"{it.alt_m:.6f}",
            str(it.autocontinue),
        ]
        lines.append("\t".join(fields))
    return "\n".join(lines) + "\n"


def parse_waypoints(text: str, *, source: str = "<waypoints>") -> list[MissionItem]:
    """``.waypoints`` text -> items. Raises :class:`MissionFileError` naming the line."""
    lines = [line for line in text.splitlines() if line.strip()]
    if not lines:
        raise MissionFileError(f"{source}: empty file")
    if not lines[0].strip().startswith("QGC WPL"):
        raise MissionFileError(f"{source}: line 1: expected a 'QGC WPL 110' header")
    if lines[0].split()[-1] != "110":
        raise MissionFileError(f"{source}: line 1: only version 110 is supported")
    if len(lines) - 1 > MAX_ITEMS:
        raise MissionFileError(f"{source}: {len(lines) - 1} items; a mission holds at most "
                               f"{MAX_ITEMS} (MAVLink's 16-bit count)")
    items = []
    for lineno, line in enumerate(lines[1:], start=2):
        fields = line.split()
        if len(fields) != 12:
            raise MissionFileError(
                f"{source}: line {lineno}: expected 12 fields, got {len(fields)}")
        try:
            seq, current, frame, command = (int(f) for f in fields[:4])
            p1, p2, p3, p4, lat, lon, alt = (float(f) for f in fields[4:11])
            autocontinue = int(fields[11])
        except ValueError:
            raise MissionFileError(f"{source}: line {lineno}: a field is not a number") from None
        if seq != len(items):
            raise MissionFileError(
                f"{source}: line {lineno}: item number {seq}, expected {len(items)}"
            )
        item = MissionItem(
            seq=seq,
            command=command,
            frame=frame,
            lat_deg=lat,
            lon_deg=lon,
            alt_m=alt,
            param1=p1,
            param2=p2,
            param3=p3,
            param4=p4,
            current=current,
            autocontinue=autocontinue,
        )
        problem = item_problem(item)
        if problem is not None:
            raise MissionFileError(f"{source}: line {lineno}: {problem}")
        items.append(item)
    if not items:
        raise MissionFileError(f"{source}: no mission items")
    return items


def read_waypoints(path: str | Path) -> list[MissionItem]:
    return parse_waypoints(read_mission_text(path), source=str(path))


def write_waypoints(path: str | Path, items: Iterable[MissionItem]) -> Path:
    return write_atomic(path, render_waypoints(items))
