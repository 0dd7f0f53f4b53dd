"""Formation error of a naive start versus ftlbo-mav's synchronized start.

Flies the shipped example on three emulated copters (or ArduPilot SITL copters when
ARDUPILOT_SITL is set) twice:

- naive: as soon as all are within 1 m of their takeoff altitude, set each vehicle's
  current item and switch it to AUTO, one vehicle after the other, without waiting for
  confirmations (the fastest a hand-written script goes);
- ftlbo-mav: wait until every vehicle hovers (within 0.3 m, climb < 0.15 m/s), set every
  current item, then switch all to AUTO in one burst (``flight.fly.start_together``).

Prints formation error (RMS and worst, waypoint legs) and smallest separation per
strategy and writes ``flight-benchmark.json``. Stops (exit 1) if any upload fails to
verify. Run: ``python benchmarks/flight.py``; on SITL set ``ARDUPILOT_SITL`` (and
``ARDUPILOT_SITL_DEFAULTS`` to ArduPilot's copter.parm).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from ftlbo_mav.flight.fly import (
    Fleet,
    FlyOptions,
    finished,
    start_together,
    take_off,
    takeoff_item,
)
from ftlbo_mav.flight.monitor import Monitor
from ftlbo_mav.flight.planned import load_planned_flight
from ftlbo_mav.flight.report import summarize
from ftlbo_mav.link.swarm import Assignment, upload_swarm
from ftlbo_mav.link.transfer import Timing
from ftlbo_mav.scenario import load_scenario
from ftlbo_mav.sim.homes import scenario_homes

EXAMPLE = ROOT / "missions" / "nha-trang-orchard.toml"


def naive_start(planned, vehicles) -> None:
    targets = [takeoff_item(m)[1] for m in planned.missions]
    for v, alt in zip(vehicles, targets):
        v.wait_for(lambda s, alt=alt: s.alt_m >= alt - 1.0, 60.0)
    from pymavlink.dialects.v20 import ardupilotmega as R

    for v, m in zip(vehicles, planned.missions):
        v.send(R.MAVLink_mission_set_current_message(v.sysid, 1, takeoff_item(m)[0] + 1))
        v.send_mode("AUTO")
    for v in vehicles:
        v.set_mode("AUTO")


def fly_once(plan_dir: Path, urls, strategy: str) -> dict:
    planned = load_planned_flight(plan_dir)
    monitor = Monitor(planned)
    with Fleet(planned.names, [1, 2, 3], urls, on_position=monitor) as fleet:
        monitor.vehicles = fleet.vehicles  # Fleet asks each vehicle for 10 Hz positions
        if strategy == "naive":
            for v, m in zip(fleet.vehicles, planned.missions):
                v.set_mode("GUIDED")
                v.arm(budget_s=60)
                v.takeoff(takeoff_item(m)[1])
            naive_start(planned, fleet.vehicles)
        else:
            take_off(planned, fleet.vehicles, FlyOptions(), say=lambda _t: None)
            start_together(planned, fleet.vehicles)
        deadline = time.monotonic() + 300
        while not finished(planned, fleet.vehicles) and time.monotonic() < deadline:
            time.sleep(0.1)
    times, positions, seqs = monitor.record.grid([1, 2, 3], planned.frame)
    return summarize(planned, times, positions, seqs)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--speedup", type=float, default=2.0,
                        help="emulator time scale / SITL --speedup")
    parser.add_argument("--out", default="flight-benchmark.json")
    args = parser.parse_args()
    homes = scenario_homes(load_scenario(EXAMPLE))
    binary = os.environ.get("ARDUPILOT_SITL")
    rows = {"naive": [], "synchronized": []}
    with tempfile.TemporaryDirectory() as tmp:
        plan_dir = Path(tmp) / "plan"
        shutil.copytree(EXAMPLE.with_suffix(""), plan_dir)
        planned = load_planned_flight(plan_dir)
        for run in range(args.runs):
            for strategy in rows:
                if binary:
                    from sitl import SitlSwarm

                    swarm = SitlSwarm(binary=binary, homes=homes, speedup=args.speedup)
                else:
                    from ftlbo_mav.sim.server import Simulator

                    swarm = Simulator(homes=homes, base_port=0, time_scale=args.speedup,
                                      seed=run)
                with swarm as vehicles:
                    assignments = [Assignment(n, i + 1, m) for i, (n, m) in
                                   enumerate(zip(planned.names, planned.missions))]
                    results = upload_swarm(assignments, vehicles.urls, timing=Timing())
                    failed = [r for r in results if not r.verified]
                    if failed:  # flying a vehicle without its mission measures nothing
                        for r in failed:
                            print(f"upload failed: {r.name} -> sysid {r.sysid}: {r.message}",
                                  file=sys.stderr)
                        return 1
                    summary = fly_once(plan_dir, vehicles.urls, strategy)
                rows[strategy].append(summary)
                print(f"run {run} {strategy:>12}: formation error "
                      f"{summary['formation_error_rms_legs_m']:.3f} m RMS, "
                      f"{summary['formation_error_max_legs_m']:.3f} m worst", flush=True)
    print(f"\nback end: {'ArduPilot SITL' if binary else 'emulator'}, speedup {args.speedup:g}, "
          f"{args.runs} runs each")
    print("| start | formation error RMS (median) | worst (max) | smallest separation on legs |")
    print("|---|---|---|---|")
    result = {}
    for strategy, summaries in rows.items():
        rms = sorted(s["formation_error_rms_legs_m"] for s in summaries)
        worst = max(s["formation_error_max_legs_m"] for s in summaries)
        sep = min(s["min_separation_legs_m"] for s in summaries)
        result[strategy] = {"rms_median_m": rms[len(rms) // 2], "worst_m": worst,
                            "min_separation_legs_m": sep, "runs": summaries}
        print(f"| {strategy} | {rms[len(rms) // 2]:.3f} m | {worst:.3f} m | {sep:.2f} m |")
    Path(args.out).write_text(json.dumps(result, indent=2) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
