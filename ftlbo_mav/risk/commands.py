"""``ftlbo-mav risk``: the plan flown many times on the emulator, on Dask."""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import click

from ..cli_errors import user_errors
from ..cli_types import FiniteFloat
from ..errors import BadInput
from ..flight.planned import load_planned_flight
from .conditions import Ranges, draw
from .engine import Tally, run_flights
from .report import clock_text, write_report


def _progress(tally: Tally) -> None:
    least = "-" if tally.least_clearance_m is None else f"{tally.least_clearance_m:.2f} m"
    click.echo(f"  {tally.done}/{tally.total} flown, {tally.running} running, "
               f"{tally.elapsed_s:.0f} s; smallest true clearance so far {least}, "
               f"{tally.left_plan} left the plan", err=True)


@click.command(name="risk")
@click.argument("plan_dir", type=click.Path(exists=True, file_okay=False, path_type=Path))
@click.option("--flights", type=click.IntRange(1, 100_000), default=100, show_default=True,
              help="How many flights.")
@click.option("--seed", type=click.IntRange(0, 2**31 - 1), default=0, show_default=True,
              help="Flight k is flown in the conditions of seed SEED + k.")
@click.option("--wind-max", type=FiniteFloat(0, 30), default=8.0, show_default=True,
              help="Steady wind: uniform from 0 to this (m/s), from any direction.")
@click.option("--turbulence-max", type=FiniteFloat(0, 30), default=2.0, show_default=True,
              help="Turbulence (gusts, SIM_WIND_TURB): uniform from 0 to this (m/s).")
@click.option("--gps-wander", type=FiniteFloat(0, 10), default=None,
              help="Each copter's GPS wander, standard deviation per axis (m); default "
                   "from the plan's navigation budget.")
@click.option("--vary/--no-vary", default=True, show_default=True,
              help="Each copter differs as a real fleet does (start latency, jerk).")
@click.option("--lost-rate", type=FiniteFloat(0, 1), default=0.0, show_default=True,
              help="Probability that a flight loses one copter (killed) on its legs.")
@click.option("--takeover-rate", type=FiniteFloat(0, 1), default=0.0, show_default=True,
              help="Probability that one copter's mode is taken over (BRAKE, from its "
                   "second port) on its legs.")
@click.option("--workers", type=click.IntRange(1, 256), default=None,
              help="Local Dask workers (default: one per core).")
@click.option("--scheduler", default=None, metavar="ADDRESS",
              help="Send the flights to a running Dask cluster (tcp://host:8786).")
@click.option("--time-scale", type=FiniteFloat(1, 20), default=None,
              help="Fly on the wall clock against the emulator on TCP ports, its clock "
                   "this many times faster (default: the ground station and the emulator "
                   "share one simulated clock: faster, and each seed flies one flight).")
@click.option("--replay", type=click.IntRange(0, 2**31 - 1), default=None, metavar="SEED",
              help="Fly the flight of this seed once, here, with fly's live view.")
@click.option("-o", "--output", type=click.Path(file_okay=False, path_type=Path),
              default=None, help="Where risk.json, risk.md, risk.png go (default "
                                 "PLAN_DIR/risk).")
@user_errors
def risk(plan_dir, flights, seed, wind_max, turbulence_max, gps_wander, vary, lost_rate,
         takeover_rate, workers, scheduler, time_scale, replay, output):
    """Fly PLAN_DIR many times on the emulator, each flight as `fly` flies it, in
    conditions drawn per flight (wind, gusts, GPS error, fleet variation, a lost copter, a
    mode taken over), and report the distributions: true clearance, separation,
    formation error, flight time, landing error, departures, with 95 % intervals for the
    probabilities that matter. Each flight is a Dask task: a local cluster by default,
    --scheduler for a running one."""
    planned = load_planned_flight(plan_dir)
    ranges = Ranges(wind_max_m_s=wind_max, turbulence_max_m_s=turbulence_max,
                    gps_wander_m=gps_wander, vary=vary, lost_rate=lost_rate,
                    takeover_rate=takeover_rate).with_budget(planned.navigation.horizontal_m)
    if replay is not None:
        from .flight import fly_one

        conditions = draw(ranges, replay, planned.count)
        click.echo(f"replaying {conditions.describe()}", err=True)
        record = fly_one(plan_dir, conditions, time_scale=time_scale, live=True)
        click.echo(json.dumps(record, indent=1))
        code = record["exit_code"]
        if code != 0:  # as fly ends; an upload that failed is 1, as upload's
            sys.exit(1 if code is None else code)
        return
    if scheduler is not None and workers is not None:
        raise BadInput("--workers is for the local cluster; a --scheduler has its own")
    out_dir = output or plan_dir / "risk"
    click.echo(f"risk: {flights} flights of {plan_dir} ({planned.count} copters); "
               f"{ranges.describe()}; {clock_text(time_scale)}; "
               + (f"Dask scheduler {scheduler}" if scheduler else
                  f"a local Dask cluster of {workers or 'one worker per core'}"), err=True)
    started = time.monotonic()
    records = run_flights(plan_dir, ranges, list(range(seed, seed + flights)),
                          scheduler=scheduler, workers=workers, time_scale=time_scale,
                          on_progress=_progress)
    engine = f"Dask {'at ' + scheduler if scheduler else 'local cluster'}"
    paths = write_report(out_dir, plan_dir, records, ranges,
                         planned_clearance_m=planned.clearance_m,
                         min_separation_m=planned.min_separation_m, time_scale=time_scale,
                         engine=engine, wall_s=time.monotonic() - started)
    click.echo(paths[1].read_text().split("## The simulator")[0].rstrip())
    click.echo(f"wrote {', '.join(p.name for p in paths)} in {out_dir}", err=True)
    sys.stdout.flush()
