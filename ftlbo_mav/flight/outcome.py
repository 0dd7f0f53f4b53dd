"""How a flight ends when it does not end as planned: the abort (Ctrl-C, ``ftlbo-mav
abort``, a timeout) and the error a flight that left its plan ends with."""

from __future__ import annotations

from collections.abc import Sequence

from .. import clock
from ..errors import FtlboError
from .fleet import concurrently
from .vehicle import FlightError, FlightVehicle

ABORT_CONFIRM_S = 1.5  # an abort is sent, confirmed and reported within 2 s


class FlightLeftPlan(FtlboError):
    """A vehicle left the plan and the flight answered by its policy; ``lines`` says,
    per vehicle, what happened and what was done (flight/policy.py)."""

    def __init__(self, lines: list[str]) -> None:
        self.lines = lines
        super().__init__("the flight left its plan:\n  " + "\n  ".join(lines))


def abort(vehicles: Sequence[FlightVehicle], *, mode: str = "RTL",
          timeout_s: float = ABORT_CONFIRM_S) -> list[str]:
    """Send every vehicle to ``mode`` at once (one burst), then confirm each; returns the
    names of those not confirmed (a vehicle whose link is down among them, at once).
    Never raises for one vehicle's link. From then on the flight sends the vehicles
    nothing else (:class:`~ftlbo_mav.flight.vehicle.FlightAborted`)."""
    reachable = []
    for v in vehicles:
        try:
            v.abort_to(mode)
            reachable.append(v)
        except FlightError:  # its link is down: nothing can reach it now
            pass
    deadline = clock.monotonic() + timeout_s

    def confirm(v: FlightVehicle) -> str | None:
        try:
            v.set_mode(mode, timeout_s=max(0.1, deadline - clock.monotonic()))
        except FlightError:
            return v.name
        return None

    late = set(concurrently(confirm, reachable)) if reachable else set()
    return [v.name for v in vehicles if v not in reachable or v.name in late]


def aborted(vehicles: Sequence[FlightVehicle]) -> str | None:
    """The mode of an abort already under way, if any."""
    return next((v.aborted_to for v in vehicles if v.aborted_to), None)
