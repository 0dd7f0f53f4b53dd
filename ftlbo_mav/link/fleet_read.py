"""What the copters are, read from them: each one's release and flight parameters, for
``plan --fleet`` (the plan made for the copters as they are, not the other way round)."""

from __future__ import annotations

from collections.abc import Sequence

from ..ardupilot.copters import FLIGHT_PARAMS, Copter, release_for
from ..ardupilot.firmware import Firmware
from ..errors import BadInput
from .discovery import describe_missing, discover, mavlink1_problem
from .endpoints import LinkError, open_links
from .firmware import request_version
from .params import read_params
from .transfer import Timing


def read_fleet(planned: Sequence[Copter], sysids: Sequence[int], urls: Sequence[str], *,
               timing: Timing | None = None, discover_timeout_s: float = 5.0) -> list[Copter]:
    """Each of ``planned`` (one per UAV, as the scenario says) as the vehicle of the same
    place in ``sysids`` is: its AUTOPILOT_VERSION's release and every flight parameter it
    answers for; the values the scenario names stay (``upload`` sets them)."""
    timing = timing or Timing()
    links = open_links(list(urls), connect_timeout_s=discover_timeout_s)
    try:
        found, missing = discover(links, list(sysids), timeout_s=discover_timeout_s)
        if missing:
            raise LinkError("; ".join(describe_missing(s, links, discover_timeout_s)
                                      for s in missing))
        out = []
        for copter, sysid in zip(planned, sysids):
            link = found[sysid]
            if link.heartbeats[sysid].mavlink1:
                raise LinkError(mavlink1_problem(sysid, link.url))
            with link.channel(sysid) as channel:
                version = request_version(channel, timeout_s=timing.timeout_s)
                values = read_params(channel, FLIGHT_PARAMS, timing=timing)
            held = {n: v for n, v in values.items() if v is not None}
            if not held:
                raise BadInput(f"system id {sysid} answered none of its flight parameters "
                               "(PARAM_REQUEST_READ): not an ArduCopter to plan for")
            runs = Firmware.decode(version).describe() if version is not None else "unknown"
            out.append(copter.with_onboard(
                held, release=release_for(version, copter.release),
                source=f"read from sysid {sysid} (ArduCopter {runs}, {len(held)} "
                       "flight parameters)"))
        return out
    finally:
        for link in links:
            link.close()
