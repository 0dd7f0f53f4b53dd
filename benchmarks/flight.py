"""Formation error of a naive start versus ftlbo-mav's ``fly``, without and with its keeper.

Flies the shipped example on three emulated copters (or ArduPilot SITL copters when
ARDUPILOT_SITL is set) three ways, each on freshly started vehicles:

- naive: GUIDED takeoff one vehicle after the other; as soon as all are within 1 m of
  their takeoff altitude, set each vehicle's current item and switch it to AUTO, one
  after the other, without waiting for confirmations (the fastest a hand-written script
  goes);
- fly --no-keeper: ``flight.fly.fly`` without its formation keeper (settled takeoff,
  AUTO from the first real leg for all in one burst);
- fly: ``flight.fly.fly`` as ``ftlbo-mav fly`` runs it, with the formation keeper.

Prints formation error (RMS and worst, waypoint legs), seconds on the legs, smallest
separation and clearance and the landing error per strategy and writes
``flight-benchmark.json``. Stops (exit 1) if any upload fails to verify. Run:
``python benchmarks/flight.py``; on SITL set ``ARDUPILOT_SITL`` (and
``ARDUPILOT_SITL_DEFAULTS`` to ArduPilot's copter.parm). ``--profile 3dr-solo`` flies
copters with that board's values (ftlbo_mav/ardupilot/copters.py PROFILES): on SITL a
defaults file after copter.parm, on the emulator each vehicle booted with them.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import shutil
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from ftlbo_mav import clock
from ftlbo_mav.ardupilot.copters import PROFILES
from ftlbo_mav.clock import VirtualClock
from ftlbo_mav.flight.fly import (
    Fleet,
    FlyOptions,
    finished,
    fly,
    make_keeper,
    takeoff_item,
)
from ftlbo_mav.flight.keeper import KeeperOptions
from ftlbo_mav.flight.monitor import Monitor
from ftlbo_mav.flight.outcome import FlightLeftPlan
from ftlbo_mav.flight.planned import load_planned_flight
from ftlbo_mav.flight.report import summarize
from ftlbo_mav.link.budget import choose
from ftlbo_mav.link.swarm import upload_swarm
from ftlbo_mav.link.transfer import Timing
from ftlbo_mav.mission.export import write_plan
from ftlbo_mav.planning.planner import plan
from ftlbo_mav.scenario import load_scenario
from ftlbo_mav.sim.homes import scenario_homes
from tests.integration.fleet import free_udp_port

EXAMPLE = ROOT / "missions" / "nha-trang-orchard.toml"
STRATEGIES = ("naive", "fly --no-keeper", "fly")


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


def version_strings(vehicles, timeout_s: float = 3.0) -> list[str | None]:
    """Each vehicle's version banner as it says it (``ArduCopter V4.5.6 (bbf0b066)``: the
    STATUSTEXT ArduCopter sends for MAV_CMD_DO_SEND_BANNER), else its AUTOPILOT_VERSION
    release (``ArduCopter 4.5.6``), None when it says neither."""
    from pymavlink.dialects.v20 import ardupilotmega as R

    def banner(status) -> str | None:
        return next((t for _t, _sev, t in reversed(status.text_log)
                     if t.startswith("ArduCopter V")), None)

    out = []
    for v in vehicles:
        try:
            if banner(v.status) is None:
                v.send(R.MAVLink_command_long_message(v.sysid, 1, R.MAV_CMD_DO_SEND_BANNER,
                                                      0, 0, 0, 0, 0, 0, 0, 0), step="banner")
                v.wait_for(lambda s: banner(s) is not None, timeout_s)
            text = banner(v.status)
            if text is None:
                raw = v.request_version()
                if raw is not None:
                    text = f"ArduCopter {raw >> 24 & 0xFF}.{raw >> 16 & 0xFF}.{raw >> 8 & 0xFF}"
        except Exception:  # noqa: BLE001 - what it says is for the record only
            text = None
        out.append(text)
    return out


def set_params(urls, settings) -> None:
    """``["2:WPNAV_JERK=0.8", ...]``: PARAM_SET on that vehicle, confirmed by PARAM_VALUE."""
    from pymavlink.dialects.v20 import ardupilotmega as R

    for text in settings:
        sysid, _, assignment = text.partition(":")
        name, _, value = assignment.partition("=")
        sysid, value = int(sysid), float(value)
        url = urls[min(sysid, len(urls)) - 1]  # one url: a shared link to every vehicle
        with Fleet([f"uav{sysid}"], [sysid], [url], position_hz=1.0) as fleet:
            v = fleet.vehicles[0]
            for _ in range(5):
                v.send(R.MAVLink_param_set_message(sysid, 1, name.encode(), value,
                                                   R.MAV_PARAM_TYPE_REAL32))
                got = v.read_param(name)
                if got is not None and abs(got - value) <= 1e-6 * max(1.0, abs(value)):  # float32
                    break
            else:
                raise SystemExit(f"could not set {name} = {value:g} on sysid {sysid}")


def parse_wind(text: str) -> tuple[float, float, float]:
    """``SPD,DIR,TURB`` (m/s, degrees the wind comes from, m/s) for ``--wind``."""
    try:
        spd, direction, turb = (float(x) for x in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"--wind wants SPD,DIR,TURB (e.g. 5,315,2), got {text!r}") from None
    if spd < 0 or turb < 0 or not 0 <= direction <= 360:
        raise argparse.ArgumentTypeError(
            f"--wind {text}: speed and turbulence >= 0, direction 0..360 degrees")
    return spd, direction, turb


def wind_params(wind, n: int) -> list[str]:
    """SITL's own wind on every one of ``n`` copters (libraries/SITL/SITL.cpp SIM_WIND_*;
    SIM_WIND_T 1, WIND_TYPE_NO_LIMIT: full strength down to the ground, where the
    default square-root profile fades it below SIM_WIND_T_ALT, 60 m)."""
    if wind is None:
        return []
    spd, direction, turb = wind
    return [f"{k}:{name}={value:g}" for k in range(1, n + 1) for name, value in (
        ("SIM_WIND_T", 1), ("SIM_WIND_SPD", spd), ("SIM_WIND_DIR", direction),
        ("SIM_WIND_TURB", turb))]


def fly_once(plan_dir: Path, urls, strategy: str, keep: Path | None = None, *,
             link_bytes_per_s: float | None = None) -> dict:
    """``link_bytes_per_s``: the streams at the rates that fit that link, as ``fly
    --link`` chooses them (ftlbo_mav/link/budget.py)."""
    planned = load_planned_flight(plan_dir)
    monitor = Monitor(planned)
    keeper, left = None, None
    sysids = list(range(1, planned.count + 1))
    rates = {}
    if link_bytes_per_s is not None:
        b = choose(planned.count, link_bytes_per_s)
        rates = {"position_hz": b.position_hz, "status_hz": b.status_hz}
    with Fleet(planned.names, sysids, urls, on_position=monitor, **rates) as fleet:
        monitor.vehicles = fleet.vehicles  # Fleet asks each vehicle for 10 Hz positions
        if strategy == "naive":
            for v, m in zip(fleet.vehicles, planned.missions):
                v.set_mode("GUIDED")
                v.arm(budget_s=60)
                v.takeoff(takeoff_item(m)[1])
            naive_start(planned, fleet.vehicles)
            deadline = clock.monotonic() + 300
            while not finished(planned, fleet.vehicles) and clock.monotonic() < deadline:
                clock.sleep(0.1)
        else:
            options = FlyOptions(keeper=KeeperOptions(enabled=strategy == "fly"))
            keeper = make_keeper(planned, options.keeper)
            if keep is not None:
                keeper.trace = []
            try:
                fly(planned, fleet.vehicles, options=options, timing=Timing(),
                    say=lambda t: print(f"    {t}", file=sys.stderr), tick=lambda: None,
                    keeper=keeper)
            except FlightLeftPlan as exc:  # measured all the same, and said
                left = str(exc)
        versions = version_strings(fleet.vehicles)
    times, positions, seqs = monitor.record.grid(sysids, planned.frame)
    summary = summarize(planned, times, positions, seqs)
    summary["left_plan"] = left
    summary["_samples"] = monitor.record.samples  # for --record, not in the JSON summary
    summary["versions"] = versions
    if keep is not None:
        keep.mkdir(parents=True, exist_ok=True)
        shutil.copytree(plan_dir, keep / "plan", dirs_exist_ok=True)
        (keep / "samples.json").write_text(json.dumps(
            {"fields": ["t", "sysid", "lat_e7", "lon_e7", "alt_mm", "seq", "boot_ms"],
             "rows": [list(r) for r in _sample_rows(monitor.record.samples)],
             "keeper": keeper.trace if keeper is not None else None,
             "paths": keeper.paths.tolist() if keeper is not None else None,
             "frame": [planned.frame.origin_lat_deg, planned.frame.origin_lon_deg],
             "t0": monitor.t0}))
    if keeper is not None:
        summary["keeper"] = {"active": keeper.active, "link_gaps": keeper.log.link_gaps,
                             "rough_link_s": round(keeper.log.rough_s, 1),
                             "worst_jitter_s": round(keeper.log.worst_jitter_s, 3),
                             "off_reason": keeper.off_reason,
                             "vehicles": keeper.log.as_dict(planned.names)}
    return summary


def _sample_rows(samples) -> list[list]:
    """The positions sent in AUTO, as a recording's ``samples`` rows."""
    return [[round(x.t, 3), x.sysid, int(round(x.lat_deg * 1e7)), int(round(x.lon_deg * 1e7)),
             int(round(x.alt_m * 1000)), x.seq,
             int(round(x.boot_s * 1000)) if x.boot_s == x.boot_s else None]
            for x in samples if x.mode == "AUTO"]


class UploadFailed(Exception):
    pass


def fly_fresh(plan_dir: Path, homes, strategy: str, *, binary: str | None = None,
              speedup: float = 1.0, seed: int = 0, vary: bool = False,
              params=(), wind=None, keep: Path | None = None, radio=None,
              profile: str | None = None, virtual: bool = False) -> dict:
    """One flight of ``plan_dir`` on freshly started vehicles (SITL when ``binary``, else
    the emulator, ``vary`` and ``seed`` giving each copter its differences) flown the
    ``strategy`` way, in ``wind`` (SPD, DIR, TURB: SITL's SIM_WIND_* set on each instance,
    the emulator's wind model); its summary. ``keep``: a folder for the flight's samples
    and keeper trace and SITL's instance folders (DataFlash logs in ``instanceN/logs``).
    ``radio`` (:class:`~ftlbo_mav.sim.radio.RadioOptions`): every vehicle behind one radio
    (SITL: the router, sim/router.py; the emulator: its shared link), seeded by ``seed``.
    ``profile`` (a :data:`~ftlbo_mav.ardupilot.copters.PROFILES` name): every copter with
    that board's values (SITL: a defaults file after copter.parm; the emulator: each
    vehicle booted with them). ``virtual``: the emulated copters in this process, flown
    with the ground station on a virtual clock (:mod:`ftlbo_mav.sim.inprocess`; no radio,
    ``speedup`` unused): the flight costs only its computation."""
    if virtual and (binary or radio is not None):
        raise ValueError("a virtual clock flies the emulator's copters, no radio")
    with VirtualClock() if virtual else contextlib.nullcontext():
        return _fly_fresh(plan_dir, homes, strategy, binary=binary, speedup=speedup,
                          seed=seed, vary=vary, params=params, wind=wind, keep=keep,
                          radio=radio, profile=profile, virtual=virtual)


def _fly_fresh(plan_dir: Path, homes, strategy: str, *, binary, speedup, seed, vary, params,
               wind, keep, radio, profile, virtual: bool) -> dict:
    planned = load_planned_flight(plan_dir)
    udp_out = ("127.0.0.1", free_udp_port()) if radio is not None else None
    n = len(homes)
    if binary:
        from sitl import SitlSwarm

        swarm = SitlSwarm(binary=binary, homes=homes, speedup=speedup, workdir=keep,
                          instance_params=[PROFILES[profile].params] * n if profile else None)
    else:
        from ftlbo_mav.sim.commands import fleet_options
        from ftlbo_mav.sim.inprocess import InProcessSimulator
        from ftlbo_mav.sim.server import Simulator
        from ftlbo_mav.sim.vehicle import VehicleOptions

        options = (fleet_options(VehicleOptions(), n, profile=[profile]) if profile
                   else None)
        settings = {"homes": homes, "seed": seed, "vary": vary, "options": options,
                    **({"wind": wind} if wind else {})}
        swarm = (InProcessSimulator(**settings) if virtual else
                 Simulator(base_port=0, time_scale=speedup, udp_out=udp_out, radio=radio,
                           **settings))
    with swarm as started, contextlib.ExitStack() as stack:
        vehicles = _Urls(started.urls, None)
        if radio is not None and binary:
            from ftlbo_mav.sim.router import RadioRouter

            router = stack.enter_context(RadioRouter(started.urls, udp_out, radio, seed=seed,
                                                     time_scale=speedup))
            vehicles = _Urls([router.udp_url], router.radio)
        elif radio is not None:
            vehicles = _Urls([started.udp_url], started.radio)
        # as `ftlbo-mav upload` sends them: mission, the fence and rally points if any,
        # and the plan's [vehicle] parameters
        assignments = planned.assignments()
        t0 = clock.monotonic()
        results = upload_swarm(assignments, vehicles.urls, timing=Timing())
        upload_s = clock.monotonic() - t0
        failed = [r for r in results if not r.verified]
        if failed:
            raise UploadFailed("; ".join(f"upload failed: {r.name} -> sysid {r.sysid}: "
                                         f"{r.message}" for r in failed))
        set_params(vehicles.urls, list(params) + (wind_params(wind, len(homes)) if binary
                                                  else []))
        summary = fly_once(plan_dir, vehicles.urls, strategy, keep,
                           link_bytes_per_s=None if radio is None else radio.bytes_per_s)
        summary["upload_s"] = round(upload_s, 2)  # the whole upload, verified (issue 28)
        if vehicles.radio is not None:
            c = vehicles.radio.counts
            summary["radio"] = {"sent": c.sent, "lost": c.lost, "full": c.full,
                                "air_s": round(c.air_s, 1)}
        return summary


@dataclass
class _Urls:
    urls: list
    radio: object | None



def print_clearance(scenario: Path, rows: dict, *, binary: str | None) -> None:
    """Per UAV: the clearance planned, predicted (plan.json) and flown (worst run)."""
    print(f"\nclearance per UAV, {scenario.name} on "
          f"{'ArduPilot SITL' if binary else 'the emulator'} (flown: worst run)")
    print("| flight | UAV | planned | predicted | flown | flown - planned | flown - predicted |")
    print("|---|---|---|---|---|---|---|")
    for strategy, summaries in rows.items():
        if strategy == "naive" or not summaries:
            continue
        planned = summaries[0]["planned_clearance_m"]
        predicted = summaries[0]["predicted_clearance_per_uav_m"] or []
        flown = [min(s["clearance_per_uav_m"][n] for s in summaries)
                 for n in range(len(summaries[0]["clearance_per_uav_m"]))]
        for n, (f, p) in enumerate(zip(flown, predicted)):
            print(f"| {strategy} | uav{n + 1} | {planned:.2f} m | {p:.2f} m | {f:.2f} m | "
                  f"{f - planned:+.2f} m | {f - p:+.2f} m |")


def write_recording(path: Path, plan_dir: Path, samples, summary: dict, *, strategy: str,
                    binary: str | None, speedup: float, scenario: Path,
                    profile: str | None = None) -> None:
    """The flight as tests/data's recordings are: what was flown (every position sample
    in AUTO), the plan and missions it flew, how it was recorded: the version each SITL
    copter said it runs (its banner) and the profile it was started with. A scenario
    outside the repository is kept whole (``scenario_toml``), as the plan was made from
    it."""
    when = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    versions = sorted({v for v in summary.get("versions") or [] if v})
    said = " and ".join(f"`{v}`" for v in versions) or "a version it did not say"
    with_ = (f"copter.parm then the `{profile}` profile's values ({PROFILES[profile].source},"
             " as a defaults file)" if profile else "copter.parm only")
    if binary:
        back = (f"{said} SITL ($ARDUPILOT_SITL: {binary}, started by `python -m sitl`'s "
                f"launcher with {with_}, --speedup {speedup:g})")
    else:
        back = (f"the emulator (time scale {speedup:g}"
                + (f", every vehicle booted with the `{profile}` profile's values"
                   if profile else "") + ")")
    try:
        shown = scenario.resolve().relative_to(ROOT)
        text = None
    except ValueError:  # outside the repository: kept whole
        shown, text = scenario, scenario.read_text()
    options = f"--scenario {shown}" + (f" --profile {profile}" if profile else "")
    doc = {
        "about": (f"Recorded {when} by `python benchmarks/flight.py {options} "
                  f"--record ...` against {back}: the plan folder uploaded as `ftlbo-mav "
                  f"upload` does, then flown as `{strategy}` ("
                  f"{'with' if strategy == 'fly' else 'without'} the formation keeper). "
                  "`samples` are the GLOBAL_POSITION_INT positions each vehicle sent in "
                  "AUTO at 10 Hz (lat/lon 1e-7 degrees, altitude above "
                  "home mm), t in seconds on the recorder's clock, boot_ms the vehicle's."),
        "scenario": str(shown),
        **({"scenario_toml": text} if text is not None else {}),
        "profile": profile,
        "strategy": strategy,
        "plan": json.loads((plan_dir / "plan.json").read_text()),
        "missions": {p.stem: p.read_text() for p in sorted(plan_dir.glob("uav*.waypoints"))},
        "samples": {
            "fields": ["t", "sysid", "lat_e7", "lon_e7", "alt_mm", "seq", "boot_ms"],
            "rows": _sample_rows(samples),
        },
        "summary": summary,
    }
    path.write_text(json.dumps(doc, indent=1) + "\n")
    print(f"recorded {path}", flush=True)


def _radio(text: str):
    from ftlbo_mav.sim.radio import parse_radio

    try:
        return parse_radio(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--speedup", type=float, default=2.0,
                        help="emulator time scale / SITL --speedup")
    parser.add_argument("--out", default="flight-benchmark.json")
    parser.add_argument("--vary", action="store_true",
                        help="emulator only: each copter differs as a real fleet does (a "
                             "start latency up to 0.3 s, WPNAV_JERK within 5%%; seeded by the "
                             "run number)")
    parser.add_argument("--only", action="append", default=[],
                        choices=STRATEGIES,
                        help="fly only this way (repeatable; default all three)")
    parser.add_argument("--set", dest="params", action="append", default=[],
                        metavar="SYSID:NAME=VALUE",
                        help="set a parameter on one vehicle before each flight (PARAM_SET, "
                             "read back), e.g. 2:WPNAV_JERK=0.8 for a copter that is slower "
                             "than the others; repeatable. `fly` reads every copter's flight "
                             "parameters and release and predicts again with them "
                             "(ftlbo_mav/flight/fit.py): a copter that differs from the plan "
                             "is flown as it is, said, when every promise (clearance, "
                             "separation, formation) still holds, refused otherwise")
    parser.add_argument("--record", type=Path, default=None,
                        help="write the first `fly` flight's telemetry (in AUTO), its plan and "
                             "missions as JSON here (tests/data/ardupilot-<release>/"
                             "flown-*.json); its `about` names the version SITL said it "
                             "runs and the --profile")
    parser.add_argument("--scenario", type=Path, default=EXAMPLE,
                        help="scenario to fly (default the shipped example); planned with "
                             "the default planner unless a folder of its name holds missions")
    parser.add_argument("--profile", choices=sorted(PROFILES), default=None,
                        help="every copter with this board's values (ftlbo_mav/ardupilot/"
                             "copters.py PROFILES, e.g. 3dr-solo: CubeSolo's defaults.parm): "
                             "on SITL a defaults file of them after copter.parm, on the "
                             "emulator each vehicle booted with them. The plan is the "
                             "scenario's: give it the same copter ([vehicle] profile)")
    parser.add_argument("--wind", type=parse_wind, default=None, metavar="SPD,DIR,TURB",
                        help="wind on every copter: speed m/s, direction it comes from "
                             "(degrees), turbulence m/s; on SITL its SIM_WIND_SPD/DIR/TURB "
                             "(and SIM_WIND_T 1, full strength to the ground) set on each "
                             "instance, on the emulator its wind model")
    parser.add_argument("--radio", type=_radio, default=None, metavar="SPEC",
                        help="every copter behind one telemetry radio: good, rough or "
                             "key=value pairs (ftlbo-mav sim --radio); on SITL through the "
                             "router (ftlbo_mav/sim/router.py)")
    parser.add_argument("--keep", type=Path, default=None, metavar="DIR",
                        help="keep each flight's positions and what the keeper saw "
                             "(DIR/runN-STRATEGY/samples.json) and, on SITL, its instance "
                             "folders (DataFlash logs with the position targets, PSCN/PSCE)")
    args = parser.parse_args()
    scenario = load_scenario(args.scenario)
    homes = scenario_homes(scenario)
    binary = os.environ.get("ARDUPILOT_SITL")
    rows = {k: [] for k in STRATEGIES if not args.only or k in args.only}
    with tempfile.TemporaryDirectory() as tmp:
        plan_dir = Path(tmp) / "plan"
        shipped = args.scenario.with_suffix("")
        if (shipped / "plan.json").exists():
            shutil.copytree(shipped, plan_dir)
        else:
            write_plan(plan(scenario), plan_dir)
        recorded = False
        for run in range(args.runs):
            for strategy in rows:
                try:
                    summary = fly_fresh(plan_dir, homes, strategy, binary=binary,
                                        speedup=args.speedup, seed=run, vary=args.vary,
                                        params=args.params, wind=args.wind,
                                        radio=args.radio, profile=args.profile,
                                        keep=(args.keep / f"run{run}-{strategy.replace(' ', '')}"
                                              if args.keep else None))
                except UploadFailed as exc:  # flying without its mission measures nothing
                    print(exc, file=sys.stderr)
                    return 1
                samples = summary.pop("_samples")
                if args.record and strategy != "naive" and not recorded:
                    write_recording(args.record, plan_dir, samples, summary,
                                    strategy=strategy, binary=binary, speedup=args.speedup,
                                    scenario=args.scenario, profile=args.profile)
                    recorded = True
                rows[strategy].append(summary)
                print(f"run {run} {strategy:>15}: formation error "
                      f"{summary['formation_error_rms_legs_m']:.3f} m RMS, "
                      f"{summary['formation_error_max_legs_m']:.3f} m worst, legs "
                      f"{summary['leg_seconds']:.1f} s, clearance "
                      f"{summary['min_clearance_m']:.2f} m, landing error "
                      f"{max(summary['final_distance_to_goal_m']):.2f} m, upload "
                      f"{summary['upload_s']:.1f} s"
                      + (f"; left the plan: {summary['left_plan']}" if summary["left_plan"]
                         else ""), flush=True)
    print(f"\n{args.scenario.name}; back end: {'ArduPilot SITL' if binary else 'emulator'}, "
          f"speedup {args.speedup:g}, {args.runs} runs each"
          + (f"; profile {args.profile}" if args.profile else "")
          + (f"; parameters set: {', '.join(args.params)}" if args.params else "")
          + ("; per-vehicle variation (--vary)" if args.vary else "")
          + ("; wind {:g} m/s from {:g} deg, turbulence {:g} m/s".format(*args.wind)
             if args.wind else ""))
    print("| flight | formation error RMS (median) | worst (max) | legs (median) | smallest "
          "separation on legs | smallest clearance | landing error (max) |")
    print("|---|---|---|---|---|---|---|")
    result = {}
    for strategy, summaries in rows.items():
        rms = sorted(s["formation_error_rms_legs_m"] for s in summaries)
        worst = max(s["formation_error_max_legs_m"] for s in summaries)
        sep = min(s["min_separation_legs_m"] for s in summaries)
        clear = min(s["min_clearance_m"] for s in summaries)
        land = max(max(s["final_distance_to_goal_m"]) for s in summaries)
        legs = sorted(s["leg_seconds"] for s in summaries)[len(summaries) // 2]
        result[strategy] = {"rms_median_m": rms[len(rms) // 2], "worst_m": worst,
                            "min_separation_legs_m": sep, "min_clearance_m": clear,
                            "landing_error_m": land, "leg_seconds_median": legs,
                            "runs": summaries}
        print(f"| {strategy} | {rms[len(rms) // 2]:.3f} m | {worst:.3f} m | {legs:.1f} s | "
              f"{sep:.2f} m | "
              f"{clear:.2f} m | {land:.2f} m |")
    print_clearance(args.scenario, rows, binary=binary)
    Path(args.out).write_text(json.dumps(result, indent=2) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
