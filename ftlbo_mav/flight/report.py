"""After a flight: summary numbers and a picture of planned versus flown.

:func:`summarize` is pure; :func:`render_report_png` draws with matplotlib's Agg back end
and returns PNG bytes (the caller writes them atomically).
"""

from __future__ import annotations

import io

import numpy as np

from ..ardupilot.flight_path import fly_paths
from ..formation import min_separation as planned_separation
from ..mission.items import CMD_NAV_WAYPOINT
from .metrics import formation_error, min_clearance, min_separation
from .planned import PlannedFlight

AIRBORNE_M = 0.5


def leg_range(planned: PlannedFlight) -> tuple[int, int]:
    """Mission item numbers of the first and last waypoint legs (towards W_1 .. the goal).

    A leg is named by the item the vehicle flies towards, as MISSION_CURRENT reports it.
    """
    nav = [it.seq for it in planned.missions[0][1:] if it.command == CMD_NAV_WAYPOINT]
    return nav[0] + 1, nav[-1]


def summarize(planned: PlannedFlight, times, positions, seqs) -> dict:
    """Numbers of a flight on the common grid (see ``FlightRecord.grid``)."""
    if len(times) == 0:
        return {"samples": 0}
    first, last = leg_range(planned)
    legs = np.all((seqs >= first) & (seqs <= last), axis=1)
    airborne = np.all(positions[:, :, 2] > AIRBORNE_M, axis=1)
    err = formation_error(positions, planned.offsets)
    sep = min_separation(positions)
    clear = min_clearance(positions, planned.centres, planned.radii)
    goal = planned.paths[:, -1, :2]
    per_uav = [min_clearance(positions[:, n : n + 1], planned.centres, planned.radii)
               for n in range(positions.shape[1])]
    summary = {
        "samples": len(times),
        "seconds": float(times[-1] - times[0]),
        "leg_seconds": float(legs.sum() * (times[1] - times[0])) if len(times) > 1 else 0.0,
        "formation_error_rms_legs_m": (float(np.sqrt(np.mean(err[legs] ** 2)))
                                       if legs.any() else None),
        "formation_error_max_legs_m": float(err[legs].max()) if legs.any() else None,
        "planned_min_separation_m": planned_separation(planned.offsets),
        "min_separation_legs_m": float(sep[legs].min()) if legs.any() else None,
        # includes takeoff and landing, where UAVs whose homes are closer than the planned
        # separation (offsets differing in altitude only) pass at their homes' distance
        "min_separation_airborne_m": float(sep[airborne].min()) if airborne.any() else None,
        "min_clearance_m": float(clear.min()) if np.isfinite(clear).all() else None,
        # predicted beside flown: what the planner predicted each UAV's flown path keeps
        "clearance_per_uav_m": [_finite(c.min()) for c in per_uav],
        "planned_clearance_m": planned.clearance_m,
        "predicted_clearance_per_uav_m": _listed(planned.predicted_clearance),
        "predicted_min_clearance_m": _least(planned.predicted_clearance),
        "predicted_min_separation_m": _least(planned.predicted_separation),
        "inside_obstacle": bool((clear < 0).any()),
        "final_distance_to_goal_m": [
            float(d) for d in np.linalg.norm(positions[-1, :, :2] - goal, axis=1)],
    }
    return summary


def _finite(value) -> float | None:
    value = float(value)
    return value if np.isfinite(value) else None


def _listed(values) -> list | None:
    return None if values is None else [_finite(v) for v in values]


def _least(values) -> float | None:
    return None if values is None or not len(values) else _finite(np.min(values))


def predicted_paths(planned: PlannedFlight) -> list[np.ndarray] | None:
    """Per UAV ``(T, 3)``: the path each UAV's mission is predicted to fly from its start point
    (:mod:`ftlbo_mav.ardupilot.flight_path`: its DO_CHANGE_SPEED, its holds, the plan's
    ``[vehicle]`` parameters); None for a plan written without the prediction."""
    if planned.predicted_clearance is None or not planned.missions:
        return None
    flown_with = planned.speed_and_holds()
    if flown_with is None:
        return None
    speed, holds = flown_with
    fleet = planned.fleet()
    flown = fly_paths(planned.paths, nav=fleet[0].nav, speed_m_s=speed, holds_s=holds,
                      navs=[c.nav for c in fleet])
    return [f.positions for f in flown]


def render_report_png(planned: PlannedFlight, times, positions, seqs, summary: dict) -> bytes:
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import pyplot as plt
    from matplotlib.patches import Circle

    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    fig, axes = plt.subplots(2, 2, figsize=(13, 9), dpi=100)
    ground, side, ferr, fsep = axes.ravel()
    for c, r in zip(planned.centres, planned.radii):
        ground.add_patch(Circle(c, r, color="tab:green", alpha=0.45, lw=0))
        ground.add_patch(Circle(c, r + planned.clearance_m, fill=False, ls=":", color="tab:green"))
    predicted = predicted_paths(planned)
    for n, name in enumerate(planned.names):
        colour = colours[n % len(colours)]
        p = planned.paths[n]
        ground.plot(p[:, 0], p[:, 1], "--", color=colour, lw=1, label=f"{name} planned")
        if predicted is not None:
            q = predicted[n]
            ground.plot(q[:, 0], q[:, 1], ":", color=colour, lw=1.2,
                        label=f"{name} predicted")
        side.plot(p[:, 0], p[:, 2], "--", color=colour, lw=1)
        if len(times):
            ground.plot(positions[:, n, 0], positions[:, n, 1], color=colour, lw=1.8,
                        label=f"{name} flown")
            side.plot(positions[:, n, 0], positions[:, n, 2], color=colour, lw=1.8)
    flown, least = summary.get("min_clearance_m"), summary.get("predicted_min_clearance_m")
    kept = ("" if flown is None else f"; clearance flown {flown:.2f} m"
            + ("" if least is None else f", predicted {least:.2f} m"))
    ground.set(title=f"Ground track (obstacles green, clearance dotted{kept})",
               xlabel="east [m]", ylabel="north [m]", aspect="equal")
    ground.legend(fontsize=8, ncol=2)
    side.set(title="Vertical profile", xlabel="east [m]", ylabel="altitude above home [m]")

    if len(times):
        t = times - times[0]
        first, last = leg_range(planned)
        legs = np.all((seqs >= first) & (seqs <= last), axis=1)
        for ax in (ferr, fsep):
            ax.fill_between(t, 0, 1, where=legs, transform=ax.get_xaxis_transform(),
                            color="0.9", label="waypoint legs")
        ferr.plot(t, formation_error(positions, planned.offsets), color="tab:red")
        fsep.plot(t, min_separation(positions), color="tab:blue", label="smallest separation")
        fsep.axhline(summary["planned_min_separation_m"], ls="--", color="k", lw=1,
                     label="planned")
        fsep.legend(fontsize=8)
    ferr.set(title="Formation error (RMS distance from slot)", xlabel="time [s]", ylabel="m")
    fsep.set(title="Separation between UAVs", xlabel="time [s]", ylabel="m")
    rms = summary.get("formation_error_rms_legs_m")
    fig.suptitle(
        f"Flight report: formation error {rms:.2f} m RMS on the legs" if rms is not None
        else "Flight report"
    )
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    plt.close(fig)
    return buf.getvalue()
