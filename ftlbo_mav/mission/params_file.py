"""Parameter files: ``NAME VALUE`` per line, as MAVProxy's ``param load`` and Mission
Planner's *Load from file* read them (Mission Planner also writes ``NAME,VALUE``; both are
read here, by :func:`ftlbo_mav.ardupilot.copters.read_param_text`). ``#`` starts a
comment. ``ftlbo-mav download`` saves a copter's fence and flight parameters in one."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from ..ardupilot.copters import ParamFileError, read_param_text
from ..errors import MissionFileError
from .files import read_mission_text, write_atomic

FENCE_PARAMS_FILE = "fence.parm"


def render_params(params: Mapping[str, float], *, header: str | None = None) -> str:
    """Parameters -> file text (trailing newline)."""
    lines = [header or "# ArduCopter fence parameters written by ftlbo-mav plan "
             "(ftlbo-mav upload sets them; MAVProxy: param load fence.parm)"]
    lines += [f"{name} {value:g}" for name, value in params.items()]
    return "\n".join(lines) + "\n"


def parse_params(text: str, *, source: str = "<params>") -> dict[str, float]:
    """File text -> ``{name: value}`` (:func:`~ftlbo_mav.ardupilot.copters.read_param_text`:
    ``NAME VALUE``, ``NAME,VALUE`` or QGroundControl's tab-separated lines);
    :class:`MissionFileError` naming the line."""
    try:
        return read_param_text(text, source=source)
    except ParamFileError as exc:
        raise MissionFileError(str(exc)) from None


def read_params(path: str | Path) -> dict[str, float]:
    return parse_params(read_mission_text(path), source=str(path))


def write_params(path: str | Path, params: Mapping[str, float], *,
                 header: str | None = None) -> Path:
    return write_atomic(path, render_params(params, header=header))
