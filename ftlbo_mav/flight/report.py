"""After a flight: its report. Summary numbers, a picture of planned versus flown, the
files ``fly`` and ``monitor`` leave, the lines they print.

:func:`summarize`, :func:`link_summary`, :func:`battery_summary` and
:func:`summary_lines` are pure; :func:`render_report_png` draws with matplotlib's Agg
back end and returns PNG bytes; :func:`write_flight_report` writes flight.csv,
summary.json and report.png (photos.csv, progress.json) all or nothing.
"""

from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np

from ..ardupilot.firmware import firmware_entry
from ..ardupilot.flight_path import fly_paths
from ..formation import min_separation as planned_separation
from ..mission.files import OutputFolder
from ..mission.items import CMD_NAV_WAYPOINT
from .metrics import formation_error, min_clearance, min_separation
from .monitor import Monitor
from .planned import PlannedFlight
from .progress import flown, progress_document
from .resume import PROGRESS_FILE

AIRBORNE_M = 0.5


def leg_range(planned: PlannedFlight) -> tuple[int, int]:
    """Mission item numbers of the first and last waypoint legs (towards W_1 .. the goal).

    A leg is named by the item the vehicle flies towards, as MISSION_CURRENT reports it:
    the first is W_1's, not the item after the start point, which is the start gate (the
    copters hover there until the start second: counted as a leg, that second or two of
    hovering thinned the formation figures and lengthened the legs' time, before
    2026-12-07) or a DO_CHANGE_SPEED.
    """
    nav = [it.seq for it in planned.missions[0][1:] if it.command == CMD_NAV_WAYPOINT]
    return (nav[1] if len(nav) > 1 else nav[0] + 1), nav[-1]


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


def write_flight_report(planned: PlannedFlight, monitor: Monitor, out_dir: Path,
                        sysids: list[int], *, keeper=None, outcome: list[str] | None = None,
                        events: list[str] | None = None, rtcm=None,
                        progress: bool = False, budget=None,
                        told: tuple[float, str] | None = None, png: bool = True) -> dict:
    """flight.csv, summary.json and report.png in ``out_dir`` (photos.csv when a vehicle
    reported photos; with ``progress``, ``fly``'s progress.json: how far each UAV got
    along its plan, what ``fly --resume`` carries on from); returns the summary.
    ``events``: the departures seen, one line each; ``outcome``: per vehicle, what
    happened and what was done when the flight left its plan; ``png``: draw report.png."""
    times, positions, seqs = monitor.record.grid(sysids, planned.frame)
    summary = summarize(planned, times, positions, seqs)
    summary["position_rate_hz"] = {str(s): round(monitor.record.rate_hz(s), 2) for s in sysids}
    summary["departures"] = list(events or [])
    if outcome is not None:
        summary["outcome"] = list(outcome)
    if keeper is not None:
        summary["keeper"] = {"enabled": keeper.options.enabled,
                             "off_reason": keeper.off_reason,
                             "link_gaps": keeper.log.link_gaps,
                             "rough_link_s": round(keeper.log.rough_s, 1),
                             "worst_jitter_s": round(keeper.log.worst_jitter_s, 3),
                             "worst_gap_s": round(keeper.log.worst_gap_s, 2),
                             "vehicles": keeper.log.as_dict(planned.names)}
    # fly asked for AUTOPILOT_VERSION at its pre-flight
    if any(v.status.firmware_version is not None for v in monitor.vehicles):
        summary["firmware"] = {v.name: firmware_entry(
            vehicle_type=v.status.vehicle_type, autopilot=v.status.autopilot,
            version=v.status.firmware_version) | {"sysid": v.sysid}
            for v in monitor.vehicles}
    if rtcm is not None:
        summary["rtcm"] = rtcm.summary()
    battery = battery_summary(planned, monitor.record, sysids)
    if battery:
        summary["battery"] = battery
    summary["link"] = link_summary(monitor, sysids, planned.names, budget=budget,
                                   told=told)
    files = {"flight.csv": monitor.record.to_csv()}
    if monitor.record.photos:
        files["photos.csv"] = monitor.record.photos_csv()
        summary["photos"] = {planned.names[n]: len(monitor.record.photos_of(s))
                             for n, s in enumerate(sysids) if n < planned.count}
    if progress:
        flown_now = flown(planned, monitor.record, sysids)
        summary["progress"] = {"last_point": planned.paths.shape[1] - 1,
                               "uavs": {p.name: round(p.point, 2) for p in flown_now}}
        files[PROGRESS_FILE] = json.dumps(progress_document(planned, flown_now),
                                          indent=1) + "\n"
    files["summary.json"] = json.dumps(summary, indent=2) + "\n"
    if len(times) and png:
        files["report.png"] = render_report_png(planned, times, positions, seqs, summary)
    with OutputFolder(out_dir, replaces=[r"report\.png", r"photos\.csv", r"progress\.json"]
                      ) as out:  # all, or none
        out.write_all(files)
    return summary


def link_summary(monitor: Monitor, sysids: list[int], names, *, budget=None,
                 told: tuple[float, str] | None = None) -> dict:
    """summary.json's ``link``: the link ``fly`` was told of (``--link``), what the flight
    asked of it (:mod:`ftlbo_mav.link.budget`) and what it used: bytes a second from each
    vehicle over the flight (flight.csv's ``link_bytes``), sent by this station, in all and
    as a share of the link (per second of the vehicles' clock: an emulator run faster
    than real time is measured as it flies); the ground radio's last RADIO_STATUS."""
    record = monitor.record
    down = {names[n] if n < len(names) else str(s): record.link_bytes_per_s(s)
            for n, s in enumerate(sysids)}
    links = {id(v.link): v.link for v in monitor.vehicles if hasattr(v, "link")}.values()
    span = max((s.t for s in record.samples), default=0.0) - min(
        (s.t for s in record.samples), default=0.0)
    span *= record.clock_rate()  # in the vehicles' seconds, as the streams are
    up = (sum(getattr(k, "bytes_out", 0) for k in links) / span) if span > 0 else None
    used = (sum(v for v in down.values() if v is not None) + (up or 0.0)
            if any(v is not None for v in down.values()) else None)
    out = {"told": None if told is None else {"name": told[1], "bytes_per_s": told[0]},
           "asked": None if budget is None else {
               "position_hz": budget.position_hz, "status_hz": budget.status_hz,
               "down_bytes_per_s_each": round(budget.down, 1),
               "up_bytes_per_s_each": round(budget.up, 1), "total": round(budget.total, 1)},
           "measured": {"down_bytes_per_s": {k: None if v is None else round(v, 1)
                                             for k, v in down.items()},
                        "up_bytes_per_s": None if up is None else round(up, 1),
                        "total": None if used is None else round(used, 1),
                        "share_of_link": (round(used / told[0], 3)
                                          if used is not None and told else None)}}
    radio = next((k.radio_status for k in links
                  if getattr(k, "radio_status", None) is not None), None)
    if radio is not None:
        out["radio"] = {"txbuf": radio.txbuf, "rssi": radio.rssi, "remrssi": radio.remrssi,
                        "rxerrors": radio.rxerrors, "slowdown_ms": max(
                            getattr(k, "slowdown_ms", 0) for k in links)}
    return out


def battery_summary(planned: PlannedFlight, record, sysids: list[int]) -> dict:
    """summary.json's ``battery``: per vehicle the charge it reported first and last (per
    cent, SYS_STATUS) and what it used; with the plan's ``[battery]``, that in mAh beside
    the mission's predicted charge. Empty when no vehicle reported its battery."""
    out = {}
    plan = planned.battery
    for n, sysid in enumerate(sysids):
        seen = record.battery(sysid)
        if seen is None:
            continue
        first, last = seen
        entry = {"first_pct": first, "last_pct": last, "used_pct": first - last}
        if plan is not None and n < len(plan.total_mah):
            entry["used_mah"] = round((first - last) / 100.0 * plan.battery.capacity_mah, 1)
            entry["predicted_mah"] = round(plan.total_mah[n], 1)
        out[planned.names[n] if n < len(planned.names) else str(sysid)] = entry
    return out


def summary_lines(summary: dict, out_dir: Path) -> list[str]:
    """What ``fly`` and ``monitor`` print after a flight, from its summary: formation
    error, separation and clearance, the keeper, the link, RTCM, how far the UAVs got."""
    lines: list[str] = []

    def m(key):
        v = summary.get(key)
        return "n/a" if v is None else f"{v:.2f} m"

    lines.append(f"formation error on the legs: {m('formation_error_rms_legs_m')} RMS, "
                  f"{m('formation_error_max_legs_m')} worst; smallest separation "
                  f"{m('min_separation_legs_m')} on the legs, {m('min_separation_airborne_m')} in "
                  f"the air (planned {m('planned_min_separation_m')}); "
                  f"smallest clearance {m('min_clearance_m')} (predicted "
                  f"{m('predicted_min_clearance_m')})")
    keeper = summary.get("keeper")
    if keeper and keeper["off_reason"]:
        lines.append(f"formation keeper off: {keeper['off_reason']}")
    elif keeper and keeper["enabled"]:
        waited = {n: v for n, v in keeper["vehicles"].items() if v["pauses"]}
        lines.append("formation keeper: " + (keeper_line(waited) if waited
                                              else "no vehicle needed to wait") + (
            f"; stood aside {keeper['link_gaps']}x for link gaps" if keeper["link_gaps"] else "")
            + (f"; no pauses for {keeper['rough_link_s']:.0f} s: " + _rough_link(keeper)
               + " (a pause could not be timed or undone)" if keeper.get("rough_link_s")
               else ""))
    link = summary.get("link") or {}
    measured = link.get("measured") or {}
    if measured.get("total") is not None:
        share = measured.get("share_of_link")
        lines.append(f"link used: {measured['total']:,.0f} B/s both ways"
                      + (f", {100 * share:.0f} % of {link['told']['name']}" if share else "")
                      + (f"; radio txbuf {link['radio']['txbuf']} %, {link['radio']['rxerrors']} "
                         f"errors" if link.get("radio") else ""))
    rtcm = summary.get("rtcm")
    if rtcm:
        lines.append(f"RTCM corrections: {rtcm['frames']} frames, {rtcm['bytes']} bytes "
                      f"({rtcm['bytes_per_s']:.0f} bytes/s), {rtcm['dropped']} dropped")
    progress = summary.get("progress")
    if progress and min(progress["uavs"].values(), default=0) < progress["last_point"]:
        lines.append("got along the plan to path points " + ", ".join(
            f"{n} {p:.2f}" for n, p in progress["uavs"].items())
            + f" of {progress['last_point']}: to carry on from there, `ftlbo-mav fly "
            f"{out_dir.parent} --resume`" + ("" if out_dir.name == "flight" else
                                            f" --progress {out_dir / PROGRESS_FILE}"))
    lines.append(f"flight log, summary and report in {out_dir}/")
    return lines


def _rough_link(keeper: dict) -> str:
    """Why the keeper made no pauses: what of the link was rough (its delays, its
    silences), only what was."""
    why = []
    if keeper.get("worst_jitter_s"):
        why.append(f"the link's delays varied by up to {keeper['worst_jitter_s']:.2f} s")
    if keeper.get("worst_gap_s"):
        whose = "its" if why else "the link's"
        why.append(f"{whose} reports stopped for up to {keeper['worst_gap_s']:.1f} s")
    return " and ".join(why) or "the link was rough"


def keeper_line(waited: dict, *, listed: int = 6) -> str:
    """Each waiting vehicle's pauses; past ``listed`` vehicles, the ranges and the ones
    that waited longest (summary.json keeps every vehicle)."""
    def one(n, v):
        return (f"{n} waited {v['pauses']}x ({v['seconds_paused']:.1f} s paused, largest "
                f"lead {v['largest_lead_m']:+.2f} m)")

    if len(waited) <= listed:
        return "; ".join(one(n, v) for n, v in waited.items())
    pauses = [v["pauses"] for v in waited.values()]
    paused = [v["seconds_paused"] for v in waited.values()]
    longest = sorted(waited.items(), key=lambda nv: -nv[1]["seconds_paused"])[:3]
    return (f"{len(waited)} vehicles waited {min(pauses)}-{max(pauses)}x "
            f"({min(paused):.1f}-{max(paused):.1f} s paused); longest: "
            + "; ".join(one(n, v) for n, v in longest) + " (every vehicle in summary.json)")
