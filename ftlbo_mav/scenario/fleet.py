"""A scenario's ``[vehicle]`` table: what the copters are, one
:class:`~ftlbo_mav.ardupilot.copters.Copter` per UAV (issue 49: the plan fits the
copters)."""

from __future__ import annotations

from pathlib import Path

from ..ardupilot.copters import (
    DEFAULT_RELEASE,
    FLIGHT_PARAM_RANGES,
    FLIGHT_PARAMS,
    PROFILES,
    RELEASES,
    Copter,
    flight_values,
    read_param_text,
    resolve_copter,
)
from ..inputs import read_user_text
from .tables import Table


def read_vehicle(t: Table | None, *, count: int, base_dir: Path | None) -> tuple[Copter, ...]:
    """``[vehicle]``: the copters, one :class:`~ftlbo_mav.ardupilot.copters.Copter` per UAV.

    For all of them: ``profile`` (``"arducopter"``, the default, or ``"3dr-solo"``: the
    values ArduPilot ships for that board), ``firmware`` (the ArduCopter series they run:
    ``"4.5"``, the default, or ``"4.6"``), ``params_file`` (a parameter file saved from
    the copter: Mission Planner's ``.param`` or ``ftlbo-mav download``'s ``.parm``,
    relative to the scenario) and ArduPilot parameters by name and in its units
    (``WPNAV_SPEED = 500`` cm/s, ``ANGLE_MAX = 2000`` cdeg, ...): the named navigation
    values are set by ``upload``, the named tuning values (PSC_*, ATC_*, ANGLE_MAX)
    only describe the copter. A sub-table ``[vehicle.uav2]`` says the same of one copter,
    over what ``[vehicle]`` says."""
    if t is None:
        return (resolve_copter(),) * count
    common = vehicle_settings(t, base_dir=base_dir, allow_uavs=True)
    out = []
    for n in range(count):
        key = f"uav{n + 1}"
        own = (vehicle_settings(t.table(key), base_dir=base_dir, allow_uavs=False)
               if t.has(key) else {})
        settings = {**common, **{k: v for k, v in own.items() if k != "named"}}
        named = {**common.get("named", {}), **own.get("named", {})}
        try:
            out.append(resolve_copter(profile=settings.get("profile", "arducopter"),
                                      release=settings.get("firmware", DEFAULT_RELEASE),
                                      file_values=settings.get("file_values"),
                                      file_source=settings.get("file_source", ""),
                                      named=named))
        except ValueError as exc:
            raise t.error(key if t.has(key) else "profile", str(exc)) from None
    for key in t.data:
        if key.startswith("uav") and isinstance(t.data[key], dict):
            t.used.add(key)
            if not key[3:].isdigit() or not 1 <= int(key[3:]) <= count:
                raise t.error(key, f"names no UAV of this formation (uav1..uav{count})")
    t.done()
    return tuple(out)


def vehicle_settings(t: Table, *, base_dir: Path | None, allow_uavs: bool) -> dict:
    """One ``[vehicle]`` table's own settings (not its ``uavN`` sub-tables)."""
    out: dict = {}
    if t.has("profile"):
        out["profile"] = t.string("profile", choices=tuple(PROFILES))
    if t.has("firmware"):
        out["firmware"] = t.string("firmware", choices=RELEASES)
    if t.has("params_file"):
        name = t.string("params_file")
        path = (base_dir if base_dir is not None else Path(".")) / name
        text = read_user_text(path, error=lambda problem: t.error("params_file",
                                                                   f"{path}: {problem}"))
        try:
            values = read_param_text(text, source=str(path))
            out["file_values"] = flight_values(values, source=str(path))
        except ValueError as exc:
            raise t.error("params_file", str(exc)) from None
        out["file_source"] = str(path)
    named = {}
    for name, (lo, hi) in FLIGHT_PARAM_RANGES.items():
        if t.has(name):
            named[name] = t.number(name, lo=lo, hi=hi)
    out["named"] = named
    if not allow_uavs:
        t.done()
    else:
        unknown = sorted(k for k in set(t.data) - t.used
                         if not (k.startswith("uav") and isinstance(t.data[k], dict)))
        if unknown:
            raise t.error(unknown[0], "unknown key (a typo? the parameters the flown path "
                          f"depends on: {', '.join(FLIGHT_PARAMS)})")
    return out
