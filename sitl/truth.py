"""Where SITL's copters truly flew, from their own DataFlash logs: the formation judged by
the truth, not by the telemetry that reached the ground station.

``python -m sitl.truth DIR [DIR ...] [--json OUT]`` reads each flight folder that
``benchmarks/flight.py --keep DIR`` or ``benchmarks/fleet.py --keep DIR`` kept on SITL
(a folder per flight: ``plan/`` and one ``instanceN/logs/*.BIN`` per copter) and prints,
per flight,
the formation error on the legs by the true positions, where the true worst was (which
copter, how many seconds into the legs, along or across its track), and for each copter
when its start gate opened and when it began to move, in milliseconds after the first.

- **The true position** is SITL's ``SIM`` message (libraries/SITL/SIM_Aircraft.cpp
  ``Aircraft::update_dynamics`` logs the simulated vehicle's own state, 10 Hz), not its
  EKF's estimate nor its GPS.
- **One clock for every copter**: each instance logs ``GPS`` (GPS week and milliseconds
  of the week) against its own ``TimeUS``; a straight line fitted through them puts its
  ``SIM`` rows on GPS time, which every instance's simulated GPS takes from the same wall
  clock (speedup 1). The reported positions are put on one clock from their arrival
  times (``flight/record.py``): through a radio with tens of milliseconds of jitter,
  which at 5 m/s is centimetres to decimetres of apparent formation error.
- **The legs**: the mission item each copter flew, from its own log (ArduCopter's "Mission:
  N ..." as each item starts), as ``flight/report.py`` counts them.
- **The start**: a copter's gate opened when ArduCopter started the item after it (its
  ``MSG`` "Mission: N ..."); it began to move when ``SIM2`` (logged at the simulation's
  rate) first shows it 0.5 m/s across the ground, 2 m up. On fifteen flights of
  2026-12-07 the gates opened within 5 ms of each other; the copters began to move up to
  98 ms apart (docs/link.md).
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import re
import sys
from pathlib import Path

import numpy as np
from pymavlink import DFReader

from ftlbo_mav.flight.metrics import formation_error
from ftlbo_mav.flight.planned import load_planned_flight
from ftlbo_mav.flight.report import leg_range
from ftlbo_mav.flight.start import start_gate

RATE_HZ = 20.0
"""The common grid both measures are resampled on."""
GPS_WEEK_S = 7 * 24 * 3600.0
GPS_DISAGREE_S = 0.1
"""Logs whose GPS times differ by more than this, against the ground's clock, are put on
the ground's (:func:`_one_clock`). The ground's places a copter's boot clock within 11 ms
through TCP and 40 ms through the rough-day radio (flights of one release, against their
GPS times); the releases' GPS times differ by 0.17 s."""


MOVING_M_S = 0.5
MISSION_TEXT = re.compile(r"Mission: (\d+) ")
"""ArduCopter's announcement of each mission item it starts (ModeAuto::start_command:
"Mission: 4 ChangeSpeed"), logged as MSG with the time it started."""
"""A copter has begun its legs once it moves this fast across the ground, 2 m up."""


def read_instance(bin_path: Path) -> dict:
    """``SIM`` rows on GPS time: ``{"t": (K,) s, "lat", "lon", "alt" (AMSL m)}``, the fit
    from the log's ``TimeUS`` to GPS seconds (``gps = a + b * TimeUS``) and ``began``,
    when it first moved across the ground 2 m up (GPS seconds; ``SIM2``, logged at the
    simulation's own rate: to the millisecond, where ``SIM``'s 10 Hz would say it to
    0.1 s)."""
    log = DFReader.DFReader_binary(str(bin_path))
    sim, gps, began, items = [], [], None, []
    while True:
        m = log.recv_match(type=["SIM", "SIM2", "GPS", "MSG"])
        if m is None:
            break
        kind = m.get_type()
        if kind == "MSG":
            if (found := MISSION_TEXT.match(m.Message)) is not None:
                items.append((m.TimeUS, int(found.group(1))))
        elif kind == "SIM":
            sim.append((m.TimeUS, m.Lat, m.Lng, m.Alt))
        elif kind == "SIM2":
            if began is None and m.PD < -2.0 and math.hypot(m.VN, m.VE) > MOVING_M_S:
                began = m.TimeUS
        elif getattr(m, "I", 0) == 0 and m.GWk > 0:
            gps.append((m.TimeUS, m.GWk * GPS_WEEK_S + m.GMS / 1000.0))
    if len(sim) < 2 or len(gps) < 2:
        raise SystemExit(f"{bin_path}: no SIM or GPS messages (a SITL DataFlash log?)")
    us, g = np.array(gps, float).T
    b, a = np.polyfit(us / 1e6, g, 1)
    rows = np.array(sim, float)
    return {"s": rows[:, 0] / 1e6, "lat": rows[:, 1], "lon": rows[:, 2], "alt": rows[:, 3],
            "gps_fit": (a, b), "began_s": None if began is None else began / 1e6,
            "items_s": [(us / 1e6, seq) for us, seq in items]}


def ground_offsets(folder: Path) -> dict[int, float] | None:
    """Per system id, the ground's clock less the copter's boot clock, from the least
    delayed of the positions the ground station received (the kept ``samples.json``, or
    ``plan/flight/flight.csv``); None when neither was kept."""
    pairs: list[tuple[int, float]] = []
    if (folder / "samples.json").exists():
        rows = json.loads((folder / "samples.json").read_text())["rows"]
        pairs = [(int(r[1]), r[0] - r[6] / 1000.0) for r in rows if r[6] is not None]
    elif (folder / "plan" / "flight" / "flight.csv").exists():
        with open(folder / "plan" / "flight" / "flight.csv", newline="") as f:
            pairs = [(int(r["sysid"]), float(r["t"]) - float(r["boot_s"]))
                     for r in csv.DictReader(f) if r.get("boot_s")]
    if not pairs:
        return None
    out: dict[int, float] = {}
    for sysid, offset in pairs:
        out[sysid] = min(out.get(sysid, offset), offset)
    return out


def _seq_on(times: np.ndarray, stamps: np.ndarray, seqs: np.ndarray) -> np.ndarray:
    """The mission item at each of ``times`` (the last one reported at or before it; -1
    before the first and after a silence of over 2 s)."""
    order = np.argsort(stamps, kind="stable")
    stamps, seqs = stamps[order], seqs[order]
    idx = np.searchsorted(stamps, times, side="right") - 1
    out = np.where(idx >= 0, seqs[np.clip(idx, 0, None)], -1)
    gap = np.diff(stamps, prepend=stamps[0])  # a silence of over 2 s: not in AUTO then
    late = times - stamps[np.clip(idx, 0, None)] > max(2.0, float(np.median(gap)) * 20)
    return np.where(late, -1, out)


def flight_truth(folder: Path) -> dict:
    """The formation on the legs of the flight kept in ``folder``, by the truth."""
    planned = load_planned_flight(folder / "plan")
    tracks = []
    for k in range(planned.count):
        logs = sorted((folder / f"instance{k}" / "logs").glob("*.BIN"))
        if not logs:
            raise SystemExit(f"{folder}: no DataFlash log for instance{k}")
        tracks.append(read_instance(logs[-1]))
    clock = _one_clock(tracks, ground_offsets(folder))
    for k, inst in enumerate(tracks):
        at = clock["at"][k]
        inst["t"] = at(inst["s"])
        inst["began"] = None if inst["began_s"] is None else float(at(inst["began_s"]))
        inst["items"] = [(float(at(s_)), seq) for s_, seq in inst["items_s"]]
        # the item it flew towards: from its own announcements, as each item started
        inst["seq_t"] = np.array([t for t, _seq in inst["items"]], float)
        inst["seq"] = np.array([seq for _t, seq in inst["items"]], float)
        if not len(inst["seq"]):
            raise SystemExit(f"{folder}: instance{k}'s log says no mission item started")
    gate = start_gate(planned.missions[0], planned.frame)
    # the gate opened when the item after it started (the gate's own announcement comes
    # when AUTO reaches it, long before)
    opened = [next((t for t, seq in tr["items"] if gate is not None and seq > gate), None)
              for tr in tracks]
    try:
        return {"flight": folder.name, "clock": clock["name"],
                **formation_truth(planned, tracks),
                "gate_opened_after_first_ms": _after_first(opened),
                "began_after_first_ms": _after_first([tr["began"] for tr in tracks])}
    except ValueError as exc:
        raise SystemExit(f"{folder}: {exc}") from None


def _one_clock(tracks: list[dict], ground: dict[int, float] | None) -> dict:
    """The clock every copter's log is put on: GPS time (each log's own GPS messages), or
    the ground's (each copter's boot clock as its received reports place it) where their
    GPS times disagree: ArduCopter 4.6.3 SITL's GPS time is 0.17 s behind 4.5.6's on the
    same machine (three mixed flights of 2026-12-07: their boot clocks within 11 ms of
    each other on the ground's, GPS at the same boot time 167-170 ms apart)."""
    gps = [tr["gps_fit"] for tr in tracks]
    if ground is not None and all(k + 1 in ground for k in range(len(tracks))):
        apart = [a - ground[k + 1] for k, (a, _b) in enumerate(gps)]
        if max(apart) - min(apart) > GPS_DISAGREE_S:
            return {"name": f"the ground's (their GPS times {1000 * (max(apart) - min(apart)):.0f}"
                            " ms apart)",
                    "at": [lambda s_, o=ground[k + 1]: np.asarray(s_) + o
                           for k in range(len(tracks))]}
    return {"name": "GPS", "at": [lambda s_, a=a, b=b: a + b * np.asarray(s_) for a, b in gps]}


def _after_first(times: list[float | None]) -> list[int | None]:
    """Milliseconds after the earliest of ``times`` (None stays None)."""
    known = [t for t in times if t is not None]
    if not known:
        return [None] * len(times)
    return [None if t is None else round(1000 * (t - min(known))) for t in times]


def formation_truth(planned, tracks: list[dict]) -> dict:
    """The formation on the legs, from each copter's true track (``t`` seconds on one
    clock, ``lat``, ``lon``, ``alt`` AMSL, its first row on the ground) and the mission
    items it reported (``seq_t``, ``seq``): RMS and worst formation error
    (:func:`~ftlbo_mav.flight.metrics.formation_error`) and where the worst was."""
    n = planned.count
    first, last = leg_range(planned)
    start = max(tr["t"][0] for tr in tracks)
    stop = min(tr["t"][-1] for tr in tracks)
    times = np.arange(start, stop, 1.0 / RATE_HZ)
    lat = np.stack([np.interp(times, tr["t"], tr["lat"]) for tr in tracks], axis=1)
    lon = np.stack([np.interp(times, tr["t"], tr["lon"]) for tr in tracks], axis=1)
    alt = np.stack([np.interp(times, tr["t"], tr["alt"]) - tr["alt"][0] for tr in tracks],
                   axis=1)  # above where it stood before take-off
    enu = planned.frame.to_enu(lat_deg=lat.ravel(), lon_deg=lon.ravel(), alt_m=alt.ravel())
    positions = np.asarray(enu).reshape(len(times), n, 3)
    seqs = np.stack([_seq_on(times, tr["seq_t"], tr["seq"]) for tr in tracks], axis=1)
    legs = np.all((seqs >= first) & (seqs <= last), axis=1)
    if not legs.any():
        raise ValueError("no time when every copter was on the legs")
    err = formation_error(positions, planned.offsets)
    out = {"legs_s": round(float(legs.sum()) / RATE_HZ, 1),
           "true_rms_m": round(float(np.sqrt(np.mean(err[legs] ** 2))), 3),
           "true_worst_m": round(float(err[legs].max()), 3)}
    # where the worst was: the copter furthest from its slot then, along / across its track
    k = int(np.flatnonzero(legs)[np.argmax(err[legs])])
    slots = positions[k].mean(axis=0) + planned.offsets - planned.offsets.mean(axis=0)
    off = positions[k] - slots
    who = int(np.argmax(np.linalg.norm(off, axis=1)))
    heading = (positions[min(k + 1, len(times) - 1), who, :2]
               - positions[max(k - 1, 0), who, :2])
    heading = heading / (np.linalg.norm(heading) or 1.0)
    out["true_worst_at"] = {
        "uav": planned.names[who],
        "s_into_legs": round(float(times[k] - times[np.flatnonzero(legs)[0]]), 1),
        "along_m": round(float(off[who, :2] @ heading), 3),
        "across_m": round(float(off[who, 1] * heading[0] - off[who, 0] * heading[1]), 3)}
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m sitl.truth", description=__doc__.split("\n")[0])
    p.add_argument("folders", nargs="+", type=Path,
                   help="flight folders kept by benchmarks/flight.py --keep (runN-STRATEGY)")
    p.add_argument("--json", type=Path, help="write the figures here too")
    args = p.parse_args(argv)
    found = []
    for folder in args.folders:
        found += sorted(f for f in folder.iterdir() if (f / "plan").is_dir()) \
            if not (folder / "plan").is_dir() else [folder]
    results = []
    for folder in found:
        if not (folder / "plan").is_dir() or not (folder / "instance0").is_dir():
            print(f"{folder}: not a whole flight (no plan/ or instance0/): skipped")
            continue
        r = flight_truth(folder)
        results.append(r)
        w = r["true_worst_at"]
        print(f"{folder}: on {r['clock']} clock, on the legs ({r['legs_s']} s) true "
              "formation error "
              f"{r['true_rms_m']:.3f} m RMS, {r['true_worst_m']:.3f} m worst ({w['uav']}, "
              f"{w['s_into_legs']} s into the legs, {w['along_m']:+.2f} m along its track, "
              f"{w['across_m']:+.2f} m across); ms after the first: gate opened "
              + ", ".join(f"uav{k + 1} {ms}" for k, ms in enumerate(
                  r["gate_opened_after_first_ms"]))
              + "; moving " + ", ".join(f"uav{k + 1} {ms}" for k, ms in enumerate(
                  r["began_after_first_ms"])))
    if args.json:
        args.json.write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
