"""How fast ``ftlbo-mav risk`` flies, and how close its emulator is to ArduCopter SITL.

Speed (the default): the shipped example's plan flown ``--flights`` times by
:func:`ftlbo_mav.risk.engine.run_flights` on a local Dask cluster of 1 worker, then of 2
(one per core), in the same seeded conditions; prints per cluster the wall time, flights
per minute, the vehicles' flight seconds per wall second (how much faster than real time
one worker flies), the speed-up of 2 workers over 1, and the time 100 and 1,000 flights
would take at that rate (measured when ``--flights 100``, else said to be estimated).

Calibration (``--sitl``, with ``ARDUPILOT_SITL`` and ``ARDUPILOT_SITL_DEFAULTS`` =
ArduPilot's copter.parm, inside a loopback-only network namespace): ``--flights`` seeded
conditions (:func:`ftlbo_mav.risk.conditions.draw`; fleet variation off, as SITL copters
are all alike, no lost copter) flown once on the emulator (as ``risk`` flies them) and
once on ArduCopter SITL: SITL's own wind (SIM_WIND_SPD/DIR/TURB, SIM_WIND_T 1 as the
emulator's), each copter's GPS wander set a few times a second through its second port
(SIM_GPS_GLITCH_X/Y, :class:`navigation.Judge`, the same Gauss-Markov law and parameters;
its own draw, not the emulator's trace), ``fly`` run as the user runs it, the flight
judged on SIM_STATE (SITL's true position) with the same :func:`ftlbo_mav.risk.flight.judge`.
Prints both distributions side by side and writes ``risk-calibration.json``.

``python benchmarks/risk.py --flights 8``; ``python benchmarks/risk.py --sitl --flights 10``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from ftlbo_mav.flight.planned import load_planned_flight  # noqa: E402
from ftlbo_mav.link.swarm import upload_swarm  # noqa: E402
from ftlbo_mav.mission.export import write_plan  # noqa: E402
from ftlbo_mav.planning.planner import plan  # noqa: E402
from ftlbo_mav.risk.conditions import Conditions, Ranges, draw  # noqa: E402
from ftlbo_mav.risk.engine import run_flights  # noqa: E402
from ftlbo_mav.risk.flight import _fly, _record, fly_one, homes_of  # noqa: E402
from ftlbo_mav.risk.report import clock_text  # noqa: E402
from ftlbo_mav.scenario import load_scenario  # noqa: E402

EXAMPLE = ROOT / "missions" / "nha-trang-orchard.toml"
FIGURES = ("true_min_clearance_m", "true_min_separation_m", "formation_error_rms_m",
           "formation_error_max_m", "landing_error_max_m", "flight_s")


def _plan(scenario: Path) -> Path:
    folder = Path(tempfile.mkdtemp(prefix="risk-bench-"))
    write_plan(plan(load_scenario(scenario)), folder)
    return folder


def speed(plan_dir: Path, ranges: Ranges, flights: int, seed: int,
          time_scale: float | None) -> dict:
    seeds = list(range(seed, seed + flights))
    rows, figures = {}, {}
    for workers in (1, 2):
        started = time.monotonic()
        records = run_flights(plan_dir, ranges, seeds, workers=workers, time_scale=time_scale)
        wall = time.monotonic() - started
        flown = [r["flight_s"] for r in records if r.get("flight_s")]
        one = [r["simulated_s"] / r["wall_s"] for r in records
               if r.get("simulated_s") and r.get("wall_s")]
        rows[workers] = {
            "flights": flights, "wall_s": round(wall, 1),
            "flights_per_min": round(60.0 * flights / wall, 2),
            # the vehicles' seconds in the air per wall second of the whole run
            "air_vs_real_time": round(sum(flown) / wall, 2),
            # one flight's whole run (upload, pre-flight, flight, landing) in simulated
            # seconds per second of its worker's time: how much faster than real time
            # one core flies (virtual clock only)
            "one_core_vs_real_time": round(float(np.median(one)), 1) if one else None,
            "completed": sum(r.get("outcome") == "completed" for r in records),
            "left_plan": sum(r.get("outcome") == "left the plan" for r in records),
            "mean_flight_wall_s": round(float(np.mean([r["wall_s"] for r in records
                                                       if "wall_s" in r])), 2)}
        figures[workers] = [{k: r.get(k) for k in FIGURES + ("outcome",)} for r in records]
        for r in records:
            if r.get("outcome") not in ("completed", "left the plan"):
                print(f"  seed {r['seed']}: {r.get('outcome')}", flush=True)
        r = rows[workers]
        core = (f"; one flight {r['one_core_vs_real_time']:.1f}x real time on its core"
                if r["one_core_vs_real_time"] else "")
        print(f"{workers} worker(s): {flights} flights in {r['wall_s']:.1f} s, "
              f"{r['flights_per_min']:.2f} flights/min, {r['air_vs_real_time']:.2f} s in the "
              f"air per wall second{core}; {r['completed']} completed, {r['left_plan']} "
              f"left the plan; one flight {r['mean_flight_wall_s']:.2f} s of wall time on "
              "average", flush=True)
    two = rows[2]
    out = {"time_scale": time_scale, "workers": rows,
           "speed_up_2_over_1": round(two["flights_per_min"] / rows[1]["flights_per_min"], 2),
           # on the virtual clock a seed is one flight, whichever worker flies it
           "same_figures_1_and_2_workers": figures[1] == figures[2]}
    measured = "measured" if flights == 100 else f"estimated from {flights} flights"
    for n in (100, 1000):
        out[f"minutes_for_{n}"] = round(n / two["flights_per_min"], 1)
    print(f"2 workers over 1: {out['speed_up_2_over_1']:.2f}x; 100 flights "
          f"{out['minutes_for_100']:.1f} min ({measured}), "
          f"1,000 flights {out['minutes_for_1000']:.0f} min (estimated; the goal is 15); "
          f"every seed's figures the same on 1 and 2 workers: "
          f"{'yes' if out['same_figures_1_and_2_workers'] else 'NO'}")
    return out


def fly_sitl(plan_dir: Path, conditions: Conditions, binary: str) -> dict:
    """One flight on ArduCopter SITL in ``conditions`` (module notes), its risk record."""
    from flight import set_params, wind_params
    from navigation import Judge

    from sitl import SitlSwarm

    planned = load_planned_flight(plan_dir)
    homes = homes_of(planned)
    started = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="ftlbo-risk-sitl-") as tmp, \
            SitlSwarm(binary=binary, homes=homes) as swarm:
        set_params(swarm.urls, wind_params(conditions.wind, planned.count))
        assignments = planned.assignments()
        uploaded = upload_swarm(assignments, swarm.urls)
        if not all(r.verified for r in uploaded):
            return _record(conditions, planned, None, exit_code=None, summary={},
                           wall_s=time.monotonic() - started,
                           problem="; ".join(r.message for r in uploaded if not r.verified))
        judges = [Judge(f"tcp:127.0.0.1:{int(u.rsplit(':', 1)[1]) + 2}", i + 1,
                        lat_deg=homes[i][0], rng=np.random.default_rng(conditions.gps_seeds[i]),
                        wander_m=conditions.gps_wander_m, tau_s=conditions.gps_correlation_s,
                        acc_m=0.3)
                  for i, u in enumerate(swarm.urls)]
        try:
            for j in judges:
                j.start()
            time.sleep(2.0)  # the wander's first values fused before the pre-flight
            code, output = _fly(plan_dir, swarm.urls, Path(tmp) / "flight", live=False)
            time.sleep(1.0)
        finally:
            for j in judges:
                j.close()
        summary_file = Path(tmp) / "flight" / "summary.json"
        summary = json.loads(summary_file.read_text()) if summary_file.exists() else {}
    truth = [[(t, lat, lon, alt) for t, lat, lon, alt in j.truth] for j in judges]
    problem = None if summary else (output.strip().splitlines()[-1:] or ["no summary"])[0]
    return _record(conditions, planned, truth, exit_code=code, summary=summary,
                   wall_s=time.monotonic() - started, problem=problem)


def _spread(values) -> str:
    v = np.array([x for x in values if x is not None], float)
    if not len(v):
        return "-"
    return f"{np.median(v):.3f} [{v.min():.3f}, {v.max():.3f}]"


def calibrate(plan_dir: Path, ranges: Ranges, flights: int, seed: int, binary: str,
              time_scale: float | None) -> dict:
    planned = load_planned_flight(plan_dir)
    rows = []
    for k in range(flights):
        c = draw(ranges, seed + k, planned.count)
        emu = fly_one(plan_dir, c, time_scale=time_scale)
        real = fly_sitl(plan_dir, c, binary)
        rows.append({"conditions": c.describe(), "emulator": emu, "sitl": real})
        print(f"{c.describe()}", flush=True)
        for name, r in (("emulator", emu), ("SITL", real)):
            print(f"  {name:>8}: {r['outcome']}; clearance {r.get('true_min_clearance_m')} m, "
                  f"separation {r.get('true_min_separation_m')} m, formation RMS/worst "
                  f"{r.get('formation_error_rms_m')}/{r.get('formation_error_max_m')} m, "
                  f"landing {r.get('landing_error_max_m')} m, {r.get('flight_s')} s in the air",
                  flush=True)
    print(f"\n{flights} flights, median [min, max]       emulator                  SITL")
    for key in FIGURES:
        print(f"{key:<32} {_spread(r['emulator'].get(key) for r in rows):<25} "
              f"{_spread(r['sitl'].get(key) for r in rows)}")
    for name in ("emulator", "sitl"):
        done = sum(r[name]["outcome"] == "completed" for r in rows)
        print(f"{name}: {done} of {flights} completed")
    return {"rows": rows}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenario", type=Path, default=EXAMPLE)
    ap.add_argument("--flights", type=int, default=8)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--wind-max", type=float, default=8.0)
    ap.add_argument("--turbulence-max", type=float, default=2.0)
    ap.add_argument("--time-scale", type=float, default=None,
                    help="fly on the wall clock, the emulator this many times faster "
                         "(default: the simulated clock, as risk flies)")
    ap.add_argument("--sitl", action="store_true",
                    help="fly the same seeded conditions on ArduCopter SITL (ARDUPILOT_SITL)")
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    plan_dir = _plan(args.scenario)
    planned = load_planned_flight(plan_dir)
    ranges = Ranges(wind_max_m_s=args.wind_max, turbulence_max_m_s=args.turbulence_max,
                    vary=not args.sitl).with_budget(planned.navigation.horizontal_m)
    print(f"{args.scenario.name}: {ranges.describe()}; {clock_text(args.time_scale)}",
          flush=True)
    if args.sitl:
        binary = os.environ.get("ARDUPILOT_SITL")
        if not binary:
            print("error: --sitl needs ARDUPILOT_SITL (the arducopter SITL binary)",
                  file=sys.stderr)
            return 2
        result = calibrate(plan_dir, ranges, args.flights, args.seed, binary, args.time_scale)
        out = args.out or Path("risk-calibration.json")
    else:
        result = speed(plan_dir, ranges, args.flights, args.seed, args.time_scale)
        out = args.out or Path("risk-benchmark.json")
    out.write_text(json.dumps({"scenario": str(args.scenario), "ranges": ranges.describe(),
                               **result}, indent=1, default=str))
    print(f"written {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
