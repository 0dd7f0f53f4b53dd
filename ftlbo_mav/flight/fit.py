"""Does the plan still fit the copters as they truly are?

A plan is predicted with each copter's release and parameters as the scenario described
them (plan.json ``uavs[].vehicle``). Before anything is sent (``upload``) or armed
(``fly``) each copter is asked what it runs and what its values are; where they differ,
the flight is predicted again with the copters' own values and judged on the plan's
promises: the clearance from every obstacle (with the navigation budget), the separation
between copters where they truly are, the area and the altitude band. How far apart the
copters drift before ``fly``'s formation keeper waits for the laggards is said, not
judged (the keeper makes a lag along the track up). The copters are never made to fit
the plan: their tuning is theirs.

Pure computation: the values read are given.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..ardupilot.copters import Copter, differences
from ..planning.predicted import FlightModel, Prediction, predict
from .metrics import slot_errors
from .planned import PlannedFlight

_TOL = 1e-6
BLAME_MOST = 4  # values named in a promise lost (all of them in the note before it)


@dataclass(frozen=True)
class Fit:
    """The verdict: ``changed`` one line per copter whose values or release differ from
    the plan's (copters that differ alike in one line); ``kept`` what the flight
    predicted with their own values keeps (None: nothing differed, nothing predicted
    again); ``broken`` one line per promise lost,
    naming the copter, its values and the promise (empty: every promise holds)."""

    changed: tuple[str, ...]
    kept: str | None
    broken: tuple[str, ...]

    @property
    def holds(self) -> bool:
        return not self.broken

    def notes(self, *, any_params: bool = False) -> list[str]:
        """What ``upload`` and ``fly`` say before anything is sent or armed: each copter
        that differs, each promise lost (where ``any_params`` goes on anyway) and what the
        prediction with the copters' own values keeps."""
        out = [f"{line}: the copter's own values, kept as they are" for line in self.changed]
        if self.broken and not any_params:
            return out
        out += [f"{b}: not promised (--any-params)" for b in self.broken]
        if self.kept is not None:
            out.append(f"predicted again with the copters' own values: {self.kept}"
                       + ("" if self.broken else ": every promise holds"))
        return out


def describe_change(planned: Copter, actual: Copter, *, most: int | None = None) -> str:
    """What differs on one copter, e.g. ``PSC_VELXY_P 1.41 (planned 2), ArduCopter 4.6``;
    ``most``: name at most that many, then how many more."""
    parts = [f"{n} {b:g} (planned {a:g})" for n, a, b in differences(planned, actual)]
    if planned.release != actual.release:
        parts.append(f"ArduCopter {actual.release} (planned {planned.release})")
    if most is not None and len(parts) > most:
        parts = parts[:most] + [f"{len(parts) - most} more"]
    return ", ".join(parts)


def predict_fleet(planned: PlannedFlight, copters: Sequence[Copter]) -> Prediction | None:
    """The flight of ``planned`` predicted with ``copters`` (one per UAV); None when its
    missions do not say how it is flown (a plan written without the prediction)."""
    flown_with = planned.speed_and_holds()
    if flown_with is None:
        return None
    speed, holds = flown_with
    model = FlightModel.of_fleet([c.nav for c in copters], speed)
    return predict(planned.paths, model=model, centres=planned.centres, radii=planned.radii,
                   holds_s=holds, pair_error_m=planned.navigation.pair_m)


def fit_fleet(planned: PlannedFlight, actual: Sequence[Copter],
              labels: Sequence[str] | None = None) -> Fit:
    """Judge ``planned`` flown by the ``actual`` copters (one per UAV, as read from
    them). ``labels``: how each copter is named (default its UAV name)."""
    labels = list(labels or planned.names)
    fleet = planned.fleet()
    changes = [describe_change(p, a) for p, a in zip(fleet, actual)]
    short = [describe_change(p, a, most=BLAME_MOST) for p, a in zip(fleet, actual)]
    alike: dict[str, list[str]] = {}  # copters that differ alike are said together
    for lab, c in zip(labels, changes):
        if c:
            alike.setdefault(c, []).append(lab)
    changed = tuple(f"{', '.join(labs)}: {c}" for c, labs in alike.items())
    if not changed:
        return Fit((), None, ())
    pred = predict_fleet(planned, actual)
    if pred is None:
        return Fit(changed, None, tuple(
            f"{lab}: flies with {c}, and this plan holds no prediction to check it "
            "against: plan again" for lab, c in zip(labels, changes) if c))
    broken = []

    def blame(n: int) -> str:
        """Whose values lose a promise at UAV ``n``: its own, else every changed one."""
        if short[n]:
            return f"{labels[n]} with its {short[n]}"
        return " and ".join(f"{lab} with its {c}" for lab, c in zip(labels, short) if c)

    need = planned.clearance_m + planned.navigation.horizontal_m
    for n in np.flatnonzero(pred.clearance < need - _TOL):
        i, k = pred.worst[n]
        broken.append(f"{blame(int(n))}: {labels[n]}'s flown path is predicted to pass "
                      f"{pred.clearance[n]:.2f} m from obstacle {k + 1} "
                      f"{pred.times[i]:.1f} s into its legs; the plan keeps {need:.2f} m "
                      "(clearance and navigation budget)")
    true = pred.separation if pred.true_separation is None else pred.true_separation
    for n in np.flatnonzero(true < planned.min_separation_m - _TOL):
        broken.append(f"{blame(int(n))}: {labels[n]} is predicted as close as "
                      f"{true[n]:.2f} m to another copter where they truly are; the plan "
                      f"keeps {planned.min_separation_m:g} m (min_separation)")
    if planned.area is not None:
        lo, hi = planned.area
        xy = pred.positions[..., :2]
        out = ((xy < lo - _TOL) | (xy > hi + _TOL)).any(axis=(1, 2))
        for n in np.flatnonzero(out):
            broken.append(f"{blame(int(n))}: {labels[n]}'s flown path is predicted to "
                          "leave the area")
    if planned.band is not None:
        z = pred.positions[..., 2]
        low, high = planned.band
        for n in np.flatnonzero(((z < low - _TOL) | (z > high + _TOL)).any(axis=1)):
            broken.append(f"{blame(int(n))}: {labels[n]}'s flown path is predicted to "
                          f"leave the altitude band [{low:g}, {high:g}] m")
    worst_slot = None
    if planned.count > 1:
        # at the same instant, as fly's departure watch measures it, but without the
        # formation keeper, whose waits make up a lag along the track: a copter with slower
        # S-curves is said, not refused (ArduCopter 4.5.6 SITL, a Solo among two default
        # copters on the example: predicted here 1.75 m, flown 0.30 m worst with the keeper)
        errors = slot_errors(pred.positions.transpose(1, 0, 2), planned.offsets)  # (T, N)
        worst_slot = errors.max(axis=0)
    kept = (f"clearance {float(pred.clearance.min()):.2f} m (kept {need:.2f}), separation "
            f"{float(true.min()):.2f} m (kept {planned.min_separation_m:g})")
    if worst_slot is not None:
        kept += (f", up to {float(worst_slot.max()):.2f} m from a slot before the formation "
                 "keeper's waits")
    return Fit(changed, kept, tuple(broken))
