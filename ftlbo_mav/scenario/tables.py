"""One TOML table of a scenario being read: typed fields, each mistake a
:class:`~ftlbo_mav.errors.ScenarioError` naming file and field, unknown keys refused."""

from __future__ import annotations

import math
from typing import Any

from ..errors import ScenarioError
from .model import GeoPoint


class Table:
    """One TOML table being read: tracks which keys were used, to refuse the rest."""

    def __init__(self, data: Any, path: str, source: str) -> None:
        if not isinstance(data, dict):
            raise ScenarioError(source, path, f"must be a table, got {_kind(data)}")
        self.data, self.path, self.source = data, path, source
        self.used: set[str] = set()

    def _field(self, key: str) -> str:
        return f"{self.path}.{key}" if self.path else key

    def error(self, key: str, problem: str) -> ScenarioError:
        return ScenarioError(self.source, self._field(key), problem)

    def has(self, key: str) -> bool:
        return key in self.data

    def raw(self, key: str, default: Any = ..., *, required: bool = True) -> Any:
        self.used.add(key)
        if key in self.data:
            return self.data[key]
        if default is not ... or not required:
            return None if default is ... else default
        raise self.error(key, "missing (required)")

    def number(self, key: str, default: Any = ..., *, lo=None, hi=None, lo_open=False,
               unit: str = "") -> float:
        return checked_number(self.raw(key, default), lambda problem: self.error(key, problem),
                              lo=lo, hi=hi, lo_open=lo_open, unit=unit)

    def integer(self, key: str, default: Any = ..., *, lo: int | None = None,
                hi: int | None = None) -> int:
        value = self.raw(key, default)
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(key, f"must be an integer, got {_kind(value)}")
        if (lo is not None and value < lo) or (hi is not None and value > hi):
            raise self.error(key, f"must be {_range(lo, hi)}, got {value}")
        return value

    def string(self, key: str, default: Any = ..., *, choices=None) -> str:
        value = self.raw(key, default)
        if not isinstance(value, str):
            raise self.error(key, f"must be a string, got {_kind(value)}")
        bad = next((c for c in value if (ord(c) < 0x20 and c not in "\t\n\r")
                    or 0x7F <= ord(c) < 0xA0 or 0xD800 <= ord(c) < 0xE000), None)
        if bad is not None:
            raise self.error(key, f"holds the control character U+{ord(bad):04X}: "
                                  "names and paths are printable text")
        if choices is not None and value not in choices:
            raise self.error(key, f"must be one of {', '.join(choices)}; got {value!r}")
        return value

    def table(self, key: str, *, required: bool = True) -> Table | None:
        value = self.raw(key, required=required)
        if value is None and not required:
            return None
        return Table(value, self._field(key), self.source)

    def lat_lon(self, key: str) -> tuple[float, float]:
        value = self.raw(key)
        if (
            not isinstance(value, list)
            or len(value) != 2
            or any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in value)
        ):
            raise self.error(key, f"must be [lat, lon] in degrees, got {value!r}")
        lat, lon = float(value[0]), float(value[1])
        _check_lat_lon(lat, lon, lambda what, problem: self.error(f"{key}[{what}]", problem))
        return lat, lon

    def point(self, *, alt: bool = True, max_alt: float | None = None) -> GeoPoint:
        """``lat``, ``lon`` (degrees) and, with ``alt``, ``alt`` (metres, within
        ``[-max_alt, max_alt]`` when given)."""
        lat = self.number("lat")
        lon = self.number("lon")
        _check_lat_lon(lat, lon, lambda what, problem: self.error(("lat", "lon")[what], problem))
        height = 0.0
        if alt:
            height = self.number("alt", lo=None if max_alt is None else -max_alt, hi=max_alt,
                                 unit="m")
        return GeoPoint(lat_deg=lat, lon_deg=lon, alt_m=height)

    def done(self) -> None:
        unknown = sorted(set(self.data) - self.used)
        if unknown:
            raise self.error(unknown[0], "unknown key (a typo?)")


def checked_number(value: Any, error, *, lo=None, hi=None, lo_open=False,
                   unit: str = "") -> float:
    """``value`` as a float when it is a finite number in range, else ``error(problem)``
    raised: the one check every number of a scenario goes through. ``lo_open``: ``lo``
    itself is out; ``unit`` is said with the range (``"m"``)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise error(f"must be a number, got {_kind(value)}")
    value = float(value)
    if not math.isfinite(value):
        raise error(f"must be a finite number{_said(lo, hi, lo_open, unit)}, got {value}")
    if (lo is not None and (value <= lo if lo_open else value < lo)) or (
            hi is not None and value > hi):
        raise error(f"must be {_range(lo, hi, lo_open, unit)}, got {value:g}")
    return value


def _range(lo, hi, lo_open: bool = False, unit: str = "") -> str:
    u = f" {unit}" if unit else ""

    def num(v) -> str:
        return str(v) if isinstance(v, int) else f"{v:g}"

    if lo is not None and hi is not None:
        return f"within {'(' if lo_open else '['}{num(lo)}, {num(hi)}]{u}"
    if lo is not None:
        return f"{'>' if lo_open else '>='} {num(lo)}{u}"
    return f"<= {num(hi)}{u}"


def _said(lo, hi, lo_open: bool, unit: str) -> str:
    return "" if lo is None and hi is None else f" {_range(lo, hi, lo_open, unit)}"


def _check_lat_lon(lat: float, lon: float, error) -> None:
    if not -90.0 <= lat <= 90.0:
        raise error(0, f"latitude {lat:g} is outside [-90, 90]")
    if not -180.0 <= lon <= 180.0:
        raise error(1, f"longitude {lon:g} is outside [-180, 180]")


def _kind(value: Any) -> str:
    return {
        bool: "a boolean",
        int: "an integer",
        float: "a number",
        str: "a string",
        list: "an array",
        dict: "a table",
    }.get(type(value), type(value).__name__)
