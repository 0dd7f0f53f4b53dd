"""Pre-flight: every vehicle holds exactly its planned mission and fence (read back and
compared as ``upload`` verifies), has a 3D GPS fix and passes its pre-arm checks. Any
failure stops the flight here, one line per vehicle, before anything is armed."""

from __future__ import annotations

import time
from collections.abc import Sequence

from ..errors import FtlboError
from ..link.codec import mission_differences
from ..link.endpoints import is_ready, readiness_problems
from ..link.geofence import fence_differences
from ..link.mission_protocol import download_mission
from ..link.transfer import Timing
from .fleet import concurrently
from .planned import PlannedFlight
from .vehicle import FlightVehicle


class PreflightError(FtlboError):
    """Pre-flight checks failed; ``problems`` holds one line per failing vehicle."""

    def __init__(self, problems: list[str]) -> None:
        self.problems = problems
        super().__init__("pre-flight failed, nothing armed:\n  " + "\n  ".join(problems))


def preflight(planned: PlannedFlight, vehicles: Sequence[FlightVehicle], *,
              timing: Timing, ready_timeout_s: float) -> None:
    """Raise :class:`PreflightError` unless every vehicle is ready to fly its mission."""

    def mission_problem(pair) -> str | None:
        vehicle, expected, fence = pair
        try:
            with vehicle.link.channel(vehicle.sysid) as channel:
                onboard = download_mission(channel, timing=timing)
                fence_diff = ([] if fence is None
                              else fence_differences(channel, fence, timing=timing))
        except FtlboError as exc:
            return f"cannot read its mission or fence back: {exc}"
        diff = mission_differences(expected, onboard)
        if diff:
            return (f"holds a different mission than {vehicle.name}.waypoints "
                    f"({diff[0]}); run `ftlbo-mav upload` first")
        if fence_diff:  # the fence, rally points and FENCE_* of uavN.fence/.rally, fence.parm
            return (f"holds a different fence than {vehicle.name}.fence "
                    f"({fence_diff[0]}); run `ftlbo-mav upload` first")
        return None

    fences = planned.fences or (None,) * len(planned.missions)
    missions = concurrently(mission_problem, list(zip(vehicles, planned.missions, fences)))
    deadline = time.monotonic() + ready_timeout_s
    while time.monotonic() < deadline and not all(is_ready(v.link, v.sysid) for v in vehicles):
        time.sleep(0.1)
    problems = []
    for v, mission in zip(vehicles, missions):
        why = [mission] if mission else []
        if not is_ready(v.link, v.sysid):
            why += readiness_problems(v.link, v.sysid)
        if v.status.armed:
            why.append("already armed")
        if why:
            problems.append(f"{v.name} (sysid {v.sysid}): " + "; ".join(why))
    if problems:
        raise PreflightError(problems)
