"""Parameters on one vehicle: read by name, set and read back, compare.

PARAM_REQUEST_READ by name and PARAM_SET are both answered with PARAM_VALUE
(libraries/GCS_MAVLink/GCS_Param.cpp ``handle_param_request_read`` /
``handle_param_set``, then ``GCS::send_parameter_value``); a name the vehicle lacks gets no
answer. A read-back is compared as AP_Param keeps the value (integer types cast, REAL32
a float32). Used for the fence parameters (:mod:`.geofence`) and for the ``[vehicle]``
parameters a plan predicted its flown path with (:func:`set_vehicle_params`,
:func:`read_vehicle_params`).
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Mapping

from pymavlink.dialects.v20 import ardupilotmega as R

from ..ardupilot.fence import FENCE_PARAM_DEFAULTS, param_equal
from ..ardupilot.navigation import DEFAULTS as NAV_DEFAULTS
from ..ardupilot.navigation import vehicle_param_differences
from ..errors import FtlboError
from .transfer import Timing

_TYPES = {**NAV_DEFAULTS, **FENCE_PARAM_DEFAULTS}


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
        kind = _TYPES[name].type if name in _TYPES else R.MAV_PARAM_TYPE_REAL32
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


def read_vehicle_params(channel, planned: Mapping[str, float], *, timing: Timing
                        ) -> list[tuple[str, float | None, float]]:
    """The plan's ``[vehicle]`` parameters the vehicle holds other values of:
    ``(name, onboard or None when not answered, planned)``
    (:func:`~ftlbo_mav.ardupilot.navigation.vehicle_param_differences`)."""
    return vehicle_param_differences(planned, read_params(channel, planned, timing=timing))


def set_vehicle_params(channel, planned: Mapping[str, float], *, timing: Timing
                       ) -> list[tuple[str, float, float]]:
    """Give the vehicle the plan's ``[vehicle]`` parameters: read them, PARAM_SET only the
    ones that differ (each PARAM_SET is a write to the vehicle's parameter storage), read
    those back. ``(name, old, new)`` for each one changed; :class:`ParamError` for one the
    vehicle does not answer or does not keep."""
    differ = read_vehicle_params(channel, planned, timing=timing)
    for name, old, _new in differ:
        if old is None:
            raise ParamError(channel.sysid, name, f"not answered to PARAM_REQUEST_READ within "
                             f"{timing.budget_s:g} s (does this vehicle have it?)")
    set_params(channel, {name: new for name, _old, new in differ}, timing=timing)
    return [(name, float(old), new) for name, old, new in differ]
