"""What the risk flights say, written down: risk.json (every flight and the summary),
risk.md (for a person) and risk.png (the distributions)."""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import asdict
from pathlib import Path

from .conditions import Ranges
from .stats import ecdf, probability, spread

WORST_LISTED = 5

SIMULATOR_NOTE = (
    "Flown on ftlbo-mav's emulator of ArduCopter 4.5/4.6 (ftlbo_mav/sim), each copter as the "
    "plan says it is (its release and values), not on ArduPilot: "
    "its position controller and waypoint navigation are the flight model the plan was "
    "predicted with (held to SITL recordings in CI), its wind SITL's SIM_WIND_* "
    "(steady wind and turbulence; along-track error within the recorded SITL flights, "
    "docs/flight.md), its GPS error a per-copter Gauss-Markov wander fused by EKF3 as "
    "recorded on SITL. Not modelled: the airframe's own dynamics beyond the position "
    "controller, battery sag, magnetometer and barometer errors, RC failsafes, radio "
    "loss (only a vehicle killed outright). The ground station (fly itself) and the "
    "emulator run on one simulated clock (unless --time-scale): the ground computes in "
    "no time, and a seed always flies the same flight. Against ArduCopter 4.5.6 SITL on ten seeded "
    "conditions of the example (docs/risk.md): clearance agrees within the spread; the "
    "formation error's worst is about seven tenths of SITL's (0.125 against 0.174 m "
    "median; four SITL flights of ten passed the emulator's largest, 0.193 m), so this "
    "report still understates it (the copters' vertical approach to their takeoff "
    "altitude and the stopping point AUTO starts from are modelled; how SITL's copters "
    "fall behind their targets along the track while accelerating in wind is not); the "
    "smallest separation is about 0.1 m smaller than SITL's (2.86 against 2.98 m "
    "median).")


def _where(records, key):
    return [r.get(key) for r in records]


def summarize(records: Sequence[dict], *, planned_clearance_m: float,
              min_separation_m: float) -> dict:
    """The distributions and the probabilities (95 % Clopper-Pearson intervals) over the
    flights that flew (an upload that failed is counted, not judged)."""
    flown = [r for r in records if r.get("exit_code") is not None]
    clear = [r.get("true_min_clearance_m") for r in flown]
    sep = [r.get("true_min_separation_m") for r in flown]

    def below(values, limit):
        return [v is not None and v < limit for v in values]

    probabilities = [
        probability("true clearance below 0 (inside an obstacle)", below(clear, 0.0)),
        probability(f"true clearance below half the plan's ({planned_clearance_m / 2:g} m)",
                    below(clear, planned_clearance_m / 2)),
        probability(f"separation below min_separation ({min_separation_m:g} m)",
                    below(sep, min_separation_m)),
        probability("left the plan (a departure)",
                    [r.get("outcome") == "left the plan" for r in flown]),
        probability("did not complete", [r.get("outcome") != "completed" for r in flown]),
    ] if flown else []
    worst = sorted(flown, key=lambda r: (r.get("true_min_clearance_m") is None,
                                         r.get("true_min_clearance_m") or 0.0))
    return {
        "flights": len(records), "flown": len(flown),
        "not_flown": len(records) - len(flown),
        "true_min_clearance_m": spread(clear),
        "true_min_separation_m": spread(sep),
        "formation_error_rms_m": spread(_where(flown, "formation_error_rms_m")),
        "formation_error_max_m": spread(_where(flown, "formation_error_max_m")),
        "flight_s": spread(_where(flown, "flight_s")),
        "landing_error_max_m": spread(_where(flown, "landing_error_max_m")),
        "probabilities": [p.document() for p in probabilities],
        "worst_clearance_seeds": [r["seed"] for r in worst[:WORST_LISTED]],
        "worst_formation_seeds": [r["seed"] for r in sorted(
            flown, key=lambda r: -(r.get("formation_error_max_m") or 0.0))[:WORST_LISTED]],
        "_probabilities": probabilities,
    }


def clock_text(time_scale: float | None) -> str:
    """How the flights were timed, for the report."""
    return ("one simulated clock for the ground station and the emulator"
            if time_scale is None else f"wall clock, emulator time scale {time_scale:g}")


def write_report(out_dir: Path, plan_dir: Path, records: Sequence[dict], ranges: Ranges, *,
                 planned_clearance_m: float, min_separation_m: float,
                 time_scale: float | None,
                 engine: str, wall_s: float) -> list[Path]:
    """risk.json, risk.md and risk.png in ``out_dir``; the paths written."""
    out_dir.mkdir(parents=True, exist_ok=True)
    summary = summarize(records, planned_clearance_m=planned_clearance_m,
                        min_separation_m=min_separation_m)
    probs = summary.pop("_probabilities")
    doc = {"plan": str(plan_dir), "ranges": asdict(ranges), "time_scale": time_scale,
           "engine": engine, "wall_s": round(wall_s, 1), "simulator": SIMULATOR_NOTE,
           "summary": summary, "flights": list(records)}
    paths = [out_dir / "risk.json", out_dir / "risk.md", out_dir / "risk.png"]
    paths[0].write_text(json.dumps(doc, indent=1, allow_nan=False) + "\n")
    paths[1].write_text(_markdown(doc, probs, ranges, plan_dir))
    _figure(paths[2], records, planned_clearance_m, min_separation_m)
    return paths


def _fmt(s: dict, unit: str = "m") -> str:
    if not s.get("n"):
        return "-"
    return (f"{s['min']:.2f} / {s['p5']:.2f} / {s['median']:.2f} / {s['p95']:.2f} / "
            f"{s['max']:.2f} {unit}")


def _markdown(doc: dict, probs, ranges: Ranges, plan_dir: Path) -> str:
    s = doc["summary"]
    lines = [f"# Risk: {plan_dir.name}, {s['flights']} flights", "",
             f"Conditions drawn per flight: {ranges.describe()}.", "",
             f"Flown {s['flown']} (not flown: {s['not_flown']}), "
             f"{clock_text(doc['time_scale'])}, {doc['engine']}, {doc['wall_s']:g} s.", "",
             "| figure | min / 5 % / median / 95 % / max |", "|---|---|",
             f"| smallest true clearance | {_fmt(s['true_min_clearance_m'])} |",
             f"| smallest true separation in the air | {_fmt(s['true_min_separation_m'])} |",
             f"| formation error RMS on the legs | {_fmt(s['formation_error_rms_m'])} |",
             f"| formation error worst on the legs | {_fmt(s['formation_error_max_m'])} |",
             f"| flight time | {_fmt(s['flight_s'], 's')} |",
             f"| landing error (worst copter) | {_fmt(s['landing_error_max_m'])} |", "",
             "Probabilities (95 % Clopper-Pearson intervals; with no event, the upper bound "
             "is what this many flights can show):", ""]
    lines += [f"- {p.describe()}" for p in probs]
    lines += ["", "Worst flights by clearance (seeds): "
              + ", ".join(map(str, s["worst_clearance_seeds"]))
              + "; by formation error: " + ", ".join(map(str, s["worst_formation_seeds"]))
              + f". Fly one again with its live view: `ftlbo-mav risk {plan_dir} --replay "
              "SEED` (with the same condition options).", "",
              "## The simulator", "", doc["simulator"], ""]
    return "\n".join(lines)


def _figure(path: Path, records, planned_clearance_m: float, min_separation_m: float) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
    x, y = ecdf(_where(records, "true_min_clearance_m"))
    ax = axes[0]
    if len(x):
        ax.step([x[0], *x], [0.0, *y], where="post")
    for limit, label in ((0.0, "obstacle"), (planned_clearance_m / 2, "half the plan's")):
        ax.axvline(limit, color="red" if limit == 0 else "orange", lw=1, label=label)
    ax.set(xlabel="smallest true clearance (m)", ylabel="fraction of flights",
           title="clearance, empirical CDF")
    ax.legend(fontsize=8)
    for ax, key, title, limit in (
            (axes[1], "formation_error_max_m", "formation error, worst on the legs", None),
            (axes[2], "true_min_separation_m", "smallest separation in the air",
             min_separation_m)):
        values = [v for v in _where(records, key) if v is not None and math.isfinite(v)]
        if values:
            ax.hist(values, bins=min(30, max(5, len(values) // 3)))
        if limit is not None:
            ax.axvline(limit, color="red", lw=1, label="min_separation")
            ax.legend(fontsize=8)
        ax.set(xlabel="m", ylabel="flights", title=title)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
