"""Fence, rally points and fence parameters on one vehicle: send, read back, compare.

Fence and rally points go through the mission protocol's machines
(:mod:`~ftlbo_mav.link.mission_protocol`) with ``mission_type`` FENCE (1) and RALLY (2);
what ArduCopter keeps of each item is :mod:`ftlbo_mav.ardupilot.fence`, so the read-back
is compared in that form. Parameters are set with PARAM_SET and read back with
PARAM_REQUEST_READ (libraries/GCS_MAVLink/GCS_Param.cpp: both answered with PARAM_VALUE),
compared as AP_Param keeps them (integer types cast, REAL32 a float32).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Mapping

from pymavlink.dialects.v20 import ardupilotmega as R

from ..ardupilot.fence import FENCE_PARAM_DEFAULTS, param_equal
from ..errors import FtlboError
from ..mission.fence_files import FenceSet
from .codec import MISSION_TYPE_FENCE, MISSION_TYPE_RALLY, mission_differences
from .mission_protocol import (
    MissionTransferError,
    Timing,
    clear_mission,
    download_mission,
    upload_mission,
)

Progress = Callable[[str, int, int], None]
PARTS = (("fence", MISSION_TYPE_FENCE), ("rally", MISSION_TYPE_RALLY))


class ParamError(FtlboError):
    """A parameter could not be set or read; names the vehicle and the parameter."""

    def __init__(self, sysid: int, name: str, problem: str):
        self.sysid, self.name, self.problem = sysid, name, problem
        super().__init__(f"vehicle {sysid}: parameter {name}: {problem}")


def _param_name(msg) -> str:
    name = msg.param_id if isinstance(msg.param_id, str) else msg.param_id.decode()
    return name.rstrip("\x00")


def _exchange(channel, send, name: str, timing: Timing) -> float | None:
    """Send (and resend) until a PARAM_VALUE for ``name`` arrives; its value or None."""
    clock = getattr(channel, "clock", time.monotonic)
    for _ in range(timing.retries + 1):
        channel.send(send())
        deadline = clock() + timing.timeout_s
        while (left := deadline - clock()) > 0:
            msg = channel.recv(left)
            if msg is not None and msg.get_type() == "PARAM_VALUE" and _param_name(msg) == name:
                return float(msg.param_value)
    return None


def read_params(channel, names: Iterable[str], *, timing: Timing) -> dict[str, float | None]:
    """PARAM_REQUEST_READ by name for each; None for one never answered."""
    return {name: _exchange(channel, lambda n=name: R.MAVLink_param_request_read_message(
        channel.sysid, 1, n.encode(), -1), name, timing) for name in names}


def set_params(channel, params: Mapping[str, float], *, timing: Timing) -> None:
    """PARAM_SET each, then read each back; :class:`ParamError` for the first that is
    not answered or not kept."""
    for name, value in params.items():
        kind = FENCE_PARAM_DEFAULTS[name].type if name in FENCE_PARAM_DEFAULTS else \
            R.MAV_PARAM_TYPE_REAL32
        got = _exchange(channel, lambda n=name, v=value, k=kind: R.MAVLink_param_set_message(
            channel.sysid, 1, n.encode(), float(v), k), name, timing)
        if got is None:
            raise ParamError(channel.sysid, name, f"no PARAM_VALUE answered PARAM_SET within "
                             f"{timing.budget_s:g} s (does this vehicle have it?)")
    back = read_params(channel, params, timing=timing)
    for name, value in params.items():
        if back[name] is None:
            raise ParamError(channel.sysid, name, "set, but not answered on read-back")
        if not param_equal(name, value, back[name]):
            raise ParamError(channel.sysid, name, f"set to {value:g}, reads back {back[name]:g}")


def param_differences(channel, params: Mapping[str, float], *, timing: Timing) -> list[str]:
    """Why the vehicle's parameters are not ``params``; empty when they are."""
    back = read_params(channel, params, timing=timing)
    out = []
    for name, value in params.items():
        if back[name] is None:
            out.append(f"{name} not answered")
        elif not param_equal(name, value, back[name]):
            out.append(f"{name} is {back[name]:g}, expected {value:g}")
    return out


def fence_differences(channel, expected: FenceSet, *, timing: Timing,
                      progress: Progress | None = None) -> list[str]:
    """Read the fence, rally points and fence parameters back and compare them with
    ``expected`` (an empty part is compared too: the vehicle must hold none)."""
    problems = []
    for label, kind in PARTS:
        want = expected.fence if kind == MISSION_TYPE_FENCE else expected.rally
        back = download_mission(channel, timing=timing, mission_type=kind,
                                progress=_labelled(progress, label))
        problems += [f"{label}: {p}" for p in mission_differences(want, back, mission_type=kind)]
    problems += [f"parameter {p}" for p in param_differences(channel, expected.params,
                                                             timing=timing)]
    return problems


def download_fence_set(channel, *, timing: Timing) -> FenceSet:
    """What the vehicle holds: its fence, rally points and FENCE_* parameters."""
    fence = download_mission(channel, timing=timing, mission_type=MISSION_TYPE_FENCE)
    rally = download_mission(channel, timing=timing, mission_type=MISSION_TYPE_RALLY)
    names = ("FENCE_ENABLE", "FENCE_TYPE", "FENCE_ACTION", "FENCE_ALT_MAX", "FENCE_MARGIN")
    params = {k: v for k, v in read_params(channel, names, timing=timing).items()
              if v is not None}
    return FenceSet(tuple(fence), tuple(rally), params)


def _labelled(progress: Progress | None, label: str) -> Progress | None:
    if progress is None:
        return None
    return lambda step, done, total: progress(f"{label} {step}", done, total)


def upload_fence_set(channel, fence_set: FenceSet, *, timing: Timing,
                     progress: Progress | None = None) -> tuple[bool, str]:
    """Upload the fence and the rally points, read both back, set and read back the
    parameters (fence first, FENCE_ENABLE last: the fence is on board before it is on).
    ``(True, what)`` or ``(False, why)``; a part that failed is cleared (and said so)."""
    for label, kind in PARTS:
        items = fence_set.fence if kind == MISSION_TYPE_FENCE else fence_set.rally
        try:
            if items:
                upload_mission(channel, items, timing=timing, mission_type=kind,
                               progress=_labelled(progress, label))
            else:
                clear_mission(channel, timing=timing, mission_type=kind)
            back = download_mission(channel, timing=timing, mission_type=kind,
                                    progress=_labelled(progress, label))
        except MissionTransferError as exc:
            return False, f"{label} {exc.step} failed: {exc.problem}" + _cleared(
                channel, timing, label, kind)
        diff = mission_differences(items, back, mission_type=kind)
        if diff:
            return False, f"{label} read-back differs: {'; '.join(diff[:3])}" + _cleared(
                channel, timing, label, kind)
    if progress is not None:
        progress("parameters", 0, len(fence_set.params))
    try:
        set_params(channel, fence_set.params, timing=timing)
    except ParamError as exc:
        return False, f"fence parameters: {exc.name}: {exc.problem}"
    return True, fence_set.describe()


def _cleared(channel, timing: Timing, label: str, kind: int) -> str:
    try:
        clear_mission(channel, timing=timing, mission_type=kind)
        left = download_mission(channel, timing=timing, mission_type=kind)
    except MissionTransferError as exc:
        return f"; clearing the {label} failed too ({exc.problem})"
    if left:
        return f"; after MISSION_CLEAR_ALL it still holds {len(left)} {label} items"
    return f"; its {label} was cleared"
