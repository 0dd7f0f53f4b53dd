"""Fence, rally points and fence parameters on one vehicle: send, read back, compare.

Fence and rally points go through the mission protocol's machines
(:mod:`~ftlbo_mav.link.mission_protocol`) with ``mission_type`` FENCE (1) and RALLY (2);
what ArduCopter keeps of each item is :mod:`ftlbo_mav.ardupilot.fence`, so the read-back
is compared in that form. The fence parameters are set and read back by
:mod:`.params` (PARAM_SET, PARAM_REQUEST_READ), compared as AP_Param keeps them.
"""

from __future__ import annotations

from collections.abc import Callable

from .. import clock
from ..mission.fence_files import FenceSet
from .codec import MISSION_TYPE_FENCE, MISSION_TYPE_RALLY, mission_differences
from .mission_protocol import (
    MissionTransferError,
    Timing,
    clear_mission,
    download_mission,
    upload_mission,
)
from .params import ParamError, param_differences, read_params, set_params

Progress = Callable[[str, int, int], None]
PARTS = (("fence", MISSION_TYPE_FENCE), ("rally", MISSION_TYPE_RALLY))


def fence_differences(channel, expected: FenceSet, *, timing: Timing,
                      progress: Progress | None = None) -> list[str]:
    """Read the fence, rally points and fence parameters back and compare them with
    ``expected`` (an empty part is compared too: the vehicle must hold none)."""
    problems = []
    for label, kind in PARTS:
        want = expected.fence if kind == MISSION_TYPE_FENCE else expected.rally
        back = download_mission(channel, timing=timing, mission_type=kind,
                                progress=_labelled(progress, label), expect=len(want))
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
                     progress: Progress | None = None,
                     more_channels: Callable[[], object] | None = None) -> tuple[bool, str]:
    """Upload the fence and the rally points, read both back, set and read back the
    parameters (fence first, FENCE_ENABLE last: the fence is on board before it is on).
    ``(True, what)`` or ``(False, why)``; a part that failed is cleared (and said so).
    ``more_channels()``: another channel to the same vehicle, for the rally points to go
    at the same time as the fence (ArduPilot keeps a protocol per mission type)."""
    def part(ch, label: str, kind: int) -> str | None:
        items = fence_set.fence if kind == MISSION_TYPE_FENCE else fence_set.rally
        try:
            if items:
                upload_mission(ch, items, timing=timing, mission_type=kind,
                               progress=_labelled(progress, label))
            else:
                clear_mission(ch, timing=timing, mission_type=kind)
            back = download_mission(ch, timing=timing, mission_type=kind, expect=len(items),
                                    progress=_labelled(progress, label))
        except MissionTransferError as exc:
            return f"{label} {exc.step} failed: {exc.problem}" + _cleared(ch, timing, label,
                                                                          kind)
        diff = mission_differences(items, back, mission_type=kind)
        if diff:
            return f"{label} read-back differs: {'; '.join(diff[:3])}" + _cleared(
                ch, timing, label, kind)
        return None

    (fence_label, fence_kind), (rally_label, rally_kind) = PARTS
    switch = {k: v for k, v in fence_set.params.items() if k == "FENCE_ENABLE"}
    others = {k: v for k, v in fence_set.params.items() if k != "FENCE_ENABLE"}
    if more_channels is None:
        problems = [part(channel, fence_label, fence_kind)]
        problems.append(part(channel, rally_label, rally_kind) if problems[0] is None else None)
        if not any(problems):
            switch = fence_set.params  # every parameter after the fence, as one window
    else:
        # the rally points beside the fence, then the parameters but FENCE_ENABLE (which
        # change nothing until it is on: one window of round trips fewer at the end)
        def rally() -> str | None:
            with more_channels() as ch:
                problem = part(ch, rally_label, rally_kind)
                if problem is None and others:
                    if progress is not None:
                        progress("parameters", 0, len(others))
                    try:
                        set_params(ch, others, timing=timing)
                    except ParamError as exc:
                        return f"fence parameters: {exc.name}: {exc.problem}"
                return problem

        with clock.Executor(1) as pool:
            later = pool.submit(rally)
            problems = [part(channel, fence_label, fence_kind), later.result()]
    failed = [p for p in problems if p is not None]
    if failed:
        return False, "; ".join(failed)
    if progress is not None and switch:
        progress("parameters", 0, len(switch))
    try:
        if switch:
            set_params(channel, switch, timing=timing)
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
