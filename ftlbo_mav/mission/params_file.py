"""Parameter files: ``NAME VALUE`` per line, as MAVProxy's ``param load`` and Mission
Planner's *Load from file* read them (Mission Planner also writes ``NAME,VALUE``; both are
read here). ``#`` starts a comment."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from ..errors import MissionFileError
from .files import read_mission_text, write_atomic

FENCE_PARAMS_FILE = "fence.parm"


def render_params(params: Mapping[str, float]) -> str:
    """Parameters -> file text (trailing newline)."""
    lines = ["# ArduCopter fence parameters written by ftlbo-mav plan "
             "(ftlbo-mav upload sets them; MAVProxy: param load fence.parm)"]
    lines += [f"{name} {value:g}" for name, value in params.items()]
    return "\n".join(lines) + "\n"


def parse_params(text: str, *, source: str = "<params>") -> dict[str, float]:
    """File text -> ``{name: value}``; :class:`MissionFileError` naming the line."""
    out: dict[str, float] = {}
    for lineno, line in enumerate(text.splitlines(), start=1):
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        fields = line.replace(",", " ").split()
        if len(fields) != 2:
            raise MissionFileError(f"{source}: line {lineno}: expected NAME VALUE")
        name, value = fields
        if not name.replace("_", "").isalnum() or len(name) > 16:
            raise MissionFileError(f"{source}: line {lineno}: {name!r} is not a parameter name")
        try:
            out[name] = float(value)
        except ValueError:
            raise MissionFileError(f"{source}: line {lineno}: {value!r} is not a number") from None
    return out


def read_params(path: str | Path) -> dict[str, float]:
    return parse_params(read_mission_text(path), source=str(path))


def write_params(path: str | Path, params: Mapping[str, float]) -> Path:
    return write_atomic(path, render_params(params))
