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

import itertools
import statistics
from collections import deque
from collections.abc import Callable, Iterable, Mapping

from pymavlink.dialects.v20 import ardupilotmega as R

from .. import clock as ground_clock
from ..ardupilot.fence import FENCE_PARAM_DEFAULTS, param_equal
from ..ardupilot.navigation import DEFAULTS as NAV_DEFAULTS
from ..ardupilot.navigation import vehicle_param_differences
from ..ardupilot.streams import PARAM_REQUEST_QUEUE
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


PARAM_WINDOW = PARAM_REQUEST_QUEUE // 2 - 2
"""Parameter requests outstanding at once on one exchange: under half of what ArduPilot
queues, so that two at once (``upload``: the fence's and the [vehicle] parameters) and
another station's requests still fit."""
PARAM_ON_LINK = 16
"""Parameter requests outstanding at once on one link, divided among the vehicles that
share it (at most :data:`PARAM_WINDOW` each): a shared radio's buffer is theirs
together. Three copters ask 5 each, ten 1. Eight divided by the vehicles (three: 2 each)
made the example's 18 [vehicle] parameters nine round trips, the last part of every
upload through the good-day radio on SITL (1.5-3.5 s after the rest); ten copters asking
2 each overflowed an emulated 2 KiB buffer at 3,000 B/s."""

READ_ALONE_ON_LINK = 24
""":data:`PARAM_ON_LINK` for a read that is all the link carries (the copters' flight
parameters read before an upload, to judge the plan with them: nothing else is sent
until it is done). Through the good-day radio on the emulator the example's three copters
read their 33 each in 1.9-2.1 s with 8 outstanding each, 2.6-3.0 s with 5."""


def _exchange(channel, requests: Mapping[str, Callable[[], object]], timing: Timing,
              on_link: int = PARAM_ON_LINK) -> dict[str, float | None]:
    """Send every request (up to :data:`PARAM_WINDOW` unanswered at once, and
    :data:`PARAM_ON_LINK` divided by the channel's ``sharing``, a new one as each answer
    comes) and resend the unanswered ones
    when no answer came for a while:
    ``timing.timeout_s``, or once the link's round trip is known (``channel.srtt``, from
    the mission transfers before) :data:`~.transfer.RESEND_RTTS` round trips (at least
    ``timing.min_resend_s``), as the mission protocol resends; a name not answered within
    ``timing.budget_s`` of its first request is None. The round trip is learnt from the
    answers as they come (the median of the last few requests sent once), as a mission
    transfer learns it: before the first, a resend waits ``timing.first_resend_s``. An
    answer to a request sent once that overtakes an earlier one's has that one asked
    again at once (ArduPilot answers in the order asked, the link keeps the order). Through
    the good-day radio a lost request or answer cost a whole ``timeout_s`` before (the
    copters' 33 flight parameters read before an upload: 3.4-5.1 s on the emulator).

    One round trip for a window of parameters, not one for each: through a shared
    telemetry radio (60 ms each way) 18 parameters took 18 round trips and a lost one
    1.5 s; now a round trip or two (docs/link.md)."""
    clock = getattr(channel, "clock", ground_clock.monotonic)
    window = max(1, min(PARAM_WINDOW, on_link // getattr(channel, "sharing", 1)))
    srtt = getattr(channel, "srtt", None)
    samples: deque[float] = deque([srtt] if srtt else [], maxlen=9)

    def resend_after() -> float:
        if not timing.adaptive:
            return timing.timeout_s
        if not samples:  # as a mission transfer's first message waits
            return min(timing.timeout_s, timing.first_resend_s)
        # all sent: no answer to a later request will show a lost one (TAIL_RTTS)
        return timing.resend_after(statistics.median(samples), tail=not waiting)

    got: dict[str, float | None] = dict.fromkeys(requests)
    waiting = list(requests)  # not sent yet
    out: dict[str, float] = {}  # sent, unanswered: name -> when first sent
    resent: set[str] = set()  # a round trip is measured only on a request sent once
    last: dict[str, int] = {}  # sent, unanswered: name -> the order it last went in
    order = itertools.count()
    since = clock()  # the last progress (or resend)
    while waiting or out:
        while waiting and len(out) < window:
            name = waiting.pop(0)
            channel.send(requests[name]())
            out[name], last[name] = clock(), next(order)
        resend_s = resend_after()  # (sooner once the last request is out)
        deadline = since + resend_s
        left = deadline - clock()
        if left <= 0:
            now = clock()
            for n in [n for n, first in out.items() if now - first >= timing.budget_s]:
                del out[n], last[n]  # never answered
            for n in out:
                channel.send(requests[n]())
                last[n] = next(order)
                resent.add(n)
            since = now
            continue
        msg = channel.recv(left)
        if msg is not None and msg.get_type() == "PARAM_VALUE":
            name = _param_name(msg)
            if name in out:
                first = out.pop(name)
                now = clock()
                if name not in resent:  # its own round trip: the resends learn the link's
                    samples.append(now - first)
                got[name] = float(msg.param_value)
                since = now  # progress
                # ArduPilot answers reads in the order they come (GCS_Param.cpp: one
                # queue, param_requests) and a link keeps each direction's order: one
                # sent before this one (sent once: which of its sendings an answer is
                # to is not known) and not answered was lost, or its answer was
                if timing.adaptive and name not in resent:
                    for n in [n for n in out if last[n] < last[name]]:
                        channel.send(requests[n]())
                        last[n] = next(order)
                        resent.add(n)
                last.pop(name)
    return got


def read_params(channel, names: Iterable[str], *, timing: Timing, alone: bool = False
                ) -> dict[str, float | None]:
    """PARAM_REQUEST_READ by name for each; None for one never answered. ``alone``: the
    link carries nothing else meanwhile (:data:`READ_ALONE_ON_LINK`)."""
    return _exchange(channel, {name: (lambda n=name: R.MAVLink_param_request_read_message(
        channel.sysid, 1, n.encode(), -1)) for name in names}, timing,
        READ_ALONE_ON_LINK if alone else PARAM_ON_LINK)


def set_params(channel, params: Mapping[str, float], *, timing: Timing) -> None:
    """PARAM_SET each and check what it holds; :class:`ParamError` for the first that is
    not answered or not kept.

    ArduPilot answers PARAM_SET with the PARAM_VALUE of what it now holds
    (GCS_Param.cpp ``handle_param_set``: ``set_and_notify``, then
    ``send_parameter_value``): a read-back of its own. Only a parameter whose answer
    differs (a PARAM_VALUE sent before the set, still on its way) is read again: one
    round trip for a window of parameters, where a read-back after the sets was two."""
    def setter(name: str, value: float):
        kind = _TYPES[name].type if name in _TYPES else R.MAV_PARAM_TYPE_REAL32
        return lambda: R.MAVLink_param_set_message(channel.sysid, 1, name.encode(),
                                                   float(value), kind)

    answered = _exchange(channel, {n: setter(n, v) for n, v in params.items()}, timing)
    for name in params:
        if answered[name] is None:
            raise ParamError(channel.sysid, name, f"no PARAM_VALUE answered PARAM_SET within "
                             f"{timing.budget_s:g} s (does this vehicle have it?)")
    again = [n for n, v in params.items() if not param_equal(n, v, answered[n])]
    back = read_params(channel, again, timing=timing) if again else {}
    for name in again:
        value = params[name]
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
