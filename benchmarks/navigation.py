"""Where the copters truly were: a flight of the shipped example with GPS error, judged by
the true position.

Flies ``missions/nha-trang-orchard.toml``'s plan (planned here, ``[navigation]
rtk-float``) with ``fly`` on three emulated copters, or ArduPilot SITL copters when
ARDUPILOT_SITL is set, each copter's GPS given an error through SITL's own knobs on its
second port (SERIAL1, another station's link): ``SIM_GPS_ACC`` (the accuracy it reports)
and ``SIM_GPS_GLITCH_X/Y`` (an offset, degrees), set a few times a second to a slowly
wandering error (independent per copter, first-order Gauss-Markov: ``--wander`` metres
standard deviation per axis, ``--tau`` seconds) plus an optional sudden ``--glitch``. The
same second link asks for SIM_STATE (the simulator's true position) and
GLOBAL_POSITION_INT (the copter's estimate) at 10 Hz; the flight is judged on both:
smallest clearance from a tree's surface, smallest separation, formation error (legs),
landing error. Prints one row per run and writes ``navigation-benchmark.json``.

``python benchmarks/navigation.py --runs 2 --wander 0.2``; on SITL with
``ARDUPILOT_SITL`` (and ``ARDUPILOT_SITL_DEFAULTS`` = ArduPilot's copter.parm), inside a
loopback-only network namespace.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pymavlink import mavutil  # noqa: E402
from pymavlink.dialects.v20 import ardupilotmega as R  # noqa: E402

from ftlbo_mav.flight.fly import Fleet, FlyOptions, fly, make_keeper  # noqa: E402
from ftlbo_mav.flight.keeper import KeeperOptions  # noqa: E402
from ftlbo_mav.flight.metrics import formation_error  # noqa: E402
from ftlbo_mav.flight.outcome import FlightLeftPlan  # noqa: E402
from ftlbo_mav.flight.planned import load_planned_flight  # noqa: E402
from ftlbo_mav.flight.preflight import PreflightError  # noqa: E402
from ftlbo_mav.flight.record import fitted_times  # noqa: E402
from ftlbo_mav.link.rtcm import RtcmForwarder, frames_from, parse_source  # noqa: E402
from ftlbo_mav.link.swarm import upload_swarm  # noqa: E402
from ftlbo_mav.link.transfer import Timing  # noqa: E402
from ftlbo_mav.mission.export import write_plan  # noqa: E402
from ftlbo_mav.planning.planner import plan  # noqa: E402
from ftlbo_mav.scenario import load_scenario  # noqa: E402
from ftlbo_mav.sim.gps import METRES_PER_DEGREE  # noqa: E402
from ftlbo_mav.sim.homes import scenario_homes  # noqa: E402
from tests.link.ntrip_caster import FakeCaster  # noqa: E402
from tests.link.rtcm_base import base_station  # noqa: E402

EXAMPLE = ROOT / "missions" / "nha-trang-orchard.toml"
INJECT_HZ = 5.0


class Judge:
    """One copter's second link: sets its GPS error and records truth and estimate."""

    def __init__(self, url: str, sysid: int, *, lat_deg: float, rng, wander_m: float,
                 tau_s: float, acc_m: float, glitch=None, speedup: float = 1.0) -> None:
        self.sysid, self.lat = sysid, lat_deg
        self.conn = mavutil.mavlink_connection(url, source_system=245, dialect="ardupilotmega",
                                               retries=20)
        self.rng, self.wander_m, self.tau_s, self.acc_m = rng, wander_m, tau_s, acc_m
        self.glitch = glitch  # (trigger, metres north): trigger(judge) -> bool
        self.glitched = False
        self.speedup = speedup
        self.error = rng.normal(0.0, wander_m, 2) if wander_m else np.zeros(2)
        self.truth: list = []  # (received, lat, lon, alt)
        self.estimate: list = []  # (received, lat, lon, rel_alt, time_boot_s)
        self.armed = False
        self.mode = 0
        self.auto_since: float | None = None  # when it was first seen in AUTO
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)

    def _param(self, name: str, value: float) -> None:
        self.conn.mav.param_set_send(self.sysid, 1, name.encode(), value,
                                     R.MAV_PARAM_TYPE_REAL32)

    def _interval(self, msgid: int, hz: float) -> None:
        self.conn.mav.command_long_send(self.sysid, 1, R.MAV_CMD_SET_MESSAGE_INTERVAL, 0,
                                        msgid, 1e6 / hz, 0, 0, 0, 0, 0)

    def start(self) -> None:
        self.conn.wait_heartbeat(timeout=60)
        self._param("SIM_GPS_ACC", self.acc_m)
        self.thread.start()

    def _inject(self, dt: float) -> None:
        if self.wander_m:
            a = math.exp(-dt / self.tau_s)
            self.error = a * self.error + self.wander_m * math.sqrt(1 - a * a) * \
                self.rng.normal(0, 1, 2)
        north = float(self.error[1])
        if self.glitch is not None and not self.glitched and self.glitch[0](self):
            self.glitched = True
            self.glitch_t = time.monotonic()
        if self.glitched:
            north += self.glitch[1]
        self._param("SIM_GPS_GLITCH_X", north / METRES_PER_DEGREE)
        self._param("SIM_GPS_GLITCH_Y", float(self.error[0]) / (
            METRES_PER_DEGREE * math.cos(math.radians(self.lat))))

    def _run(self) -> None:
        next_ask = next_inject = 0.0
        last = time.monotonic()
        while not self.stop.is_set():
            now = time.monotonic()
            if now >= next_ask:
                self._interval(R.MAVLINK_MSG_ID_SIM_STATE, 10.0)
                self._interval(R.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, 10.0)
                next_ask = now + 5.0
            if now >= next_inject and (self.wander_m or self.glitch):
                self._inject((now - last) * self.speedup)
                last, next_inject = now, now + 1.0 / INJECT_HZ
            msg = self.conn.recv_match(blocking=True, timeout=0.05)
            if msg is None or msg.get_srcSystem() != self.sysid:
                continue
            kind = msg.get_type()
            if kind == "SIM_STATE":
                lat = msg.lat_int * 1e-7 if msg.lat_int else msg.lat
                lon = msg.lon_int * 1e-7 if msg.lon_int else msg.lon
                self.truth.append((time.monotonic(), lat, lon, msg.alt))
            elif kind == "GLOBAL_POSITION_INT":
                self.estimate.append((time.monotonic(), msg.lat * 1e-7, msg.lon * 1e-7,
                                      msg.relative_alt / 1000.0, msg.time_boot_ms / 1000.0))
            elif kind == "HEARTBEAT" and msg.type != R.MAV_TYPE_GCS:
                self.armed = bool(msg.base_mode & R.MAV_MODE_FLAG_SAFETY_ARMED)
                self.mode = msg.custom_mode
                if self.mode == 3 and self.auto_since is None:  # AUTO
                    self.auto_since = time.monotonic()

    def close(self) -> None:
        self.stop.set()
        self.thread.join(timeout=2)
        self.conn.close()


def restamp(judge) -> tuple[list, list, dict]:
    """The judge's estimate and truth with the times they were taken, not received.

    GLOBAL_POSITION_INT carries the vehicle's ``time_boot_ms``: its arrival times are
    refitted on it (flight/record.fitted_times). SIM_STATE carries no time; ArduPilot sends
    messages asked for at the same interval together (GCS_MAVLINK's deferred-message
    buckets, libraries/GCS_MAVLink/GCS_Common.cpp), so each is given the delay of the
    GLOBAL_POSITION_INT that arrived nearest to it. Returns both tracks and the link's
    delay figures (ms)."""
    est = judge.estimate
    if len(est) < 3 or not judge.truth:
        return est, judge.truth, {}
    received = np.array([r[0] for r in est])
    taken = fitted_times(received, np.array([r[4] for r in est]))
    delay = received - taken
    estimate = [(float(s), *r[1:]) for s, r in zip(taken, est)]
    truth_received = np.array([r[0] for r in judge.truth])
    k = np.clip(np.searchsorted(received, truth_received), 1, len(received) - 1)
    nearest = np.where(np.abs(received[k - 1] - truth_received)
                       < np.abs(received[k] - truth_received), k - 1, k)
    truth = [(float(t - delay[n]), *r[1:]) for t, n, r in
             zip(truth_received, nearest, judge.truth)]
    pair = np.abs(received[nearest] - truth_received)
    return estimate, truth, {"delay_median_ms": round(float(np.median(delay)) * 1e3, 1),
                             "delay_p99_ms": round(float(np.percentile(delay, 99)) * 1e3, 1),
                             "sim_state_pair_median_ms": round(float(np.median(pair)) * 1e3,
                                                               1)}


def _grid(tracks, frame, times):
    """Each copter's track resampled at ``times``: (N, T, 2) east/north."""
    out = []
    for track in tracks:
        t = np.array([r[0] for r in track])
        en = frame.to_enu(lat_deg=[r[1] for r in track], lon_deg=[r[2] for r in track])
        en = np.asarray(en, float).reshape(-1, 3)[:, :2]
        out.append(np.column_stack([np.interp(times, t, en[:, 0]),
                                    np.interp(times, t, en[:, 1])]))
    return np.stack(out)


def judged(planned, stamped, legs: tuple[float, float]) -> dict:
    """Truth and estimate over the flight: clearance, separation, formation error on the
    legs (``legs``: monotonic start and end), landing error. ``stamped``: per copter, its
    estimate and truth tracks as :func:`restamp` gives them. Heights are the estimate's
    in both views (the injected error is horizontal)."""
    out = {}
    for name, which in (("believed", 0), ("true", 1)):
        tracks = [s[which] for s in stamped]
        if any(len(t) < 10 for t in tracks):
            out[name] = None
            continue
        t0 = max(t[0][0] for t in tracks)
        t1 = min(t[-1][0] for t in tracks)
        times = np.arange(t0, t1, 0.1)
        en = _grid(tracks, planned.frame, times)
        height = np.stack([np.interp(times, [r[0] for r in s[0]], [r[3] for r in s[0]])
                           for s in stamped])
        airborne = height > 1.0
        pos = np.concatenate([en, height[..., None]], axis=-1)
        fly = airborne.any(axis=0)
        d = planned.centres[None, None, :, :] - en[:, :, None, :]
        surface = np.hypot(d[..., 0], d[..., 1]) - planned.radii[None, None, :]
        surface[~airborne] = np.inf
        sep = np.inf
        for a in range(len(stamped)):
            for b in range(a + 1, len(stamped)):
                both = airborne[a] & airborne[b]
                if both.any():
                    sep = min(sep, float(np.linalg.norm(pos[a, both] - pos[b, both],
                                                        axis=-1).min()))
        # on the legs: after the start in AUTO, every copter at its legs' altitude
        leg_alt = np.median(planned.paths[:, 1:-1, 2], axis=1)
        level = (np.abs(pos[..., 2] - leg_alt[:, None]) < 0.5).all(axis=0)
        on_legs = (times >= legs[0]) & (times <= legs[1]) & level
        # as fly's summary has it: per instant the RMS over the copters of their slot
        # errors (flight/metrics.formation_error), then its RMS and worst over the legs
        at_legs = pos[:, on_legs].transpose(1, 0, 2)  # (T, N, 3)
        errs = formation_error(at_legs, planned.offsets) if on_legs.any() else np.zeros(1)
        landing = [None if not fly.any() else
                   float(np.hypot(*(en[n, -1] - planned.paths[n, -1, :2])))
                   for n in range(len(stamped))]
        out[name] = {"min_clearance_m": float(surface.min()) if np.isfinite(surface.min())
                     else None,
                     "min_separation_m": sep if math.isfinite(sep) else None,
                     "formation_rms_m": float(np.sqrt(np.mean(errs ** 2))),
                     "formation_worst_m": float(errs.max()),
                     "landing_error_worst_m": max((x for x in landing if x is not None),
                                                  default=None)}
    return out


def one_flight(plan_dir: Path, homes, *, binary, speedup, seed, wander_m, tau_s, acc_m,
               glitch, rtcm: bool = False, tracks: Path | None = None,
               use_keeper: bool = True) -> dict:
    planned = load_planned_flight(plan_dir)
    if binary:
        from sitl import SitlSwarm

        swarm = SitlSwarm(binary=binary, homes=homes, speedup=speedup)
    else:
        from ftlbo_mav.sim.server import Simulator

        swarm = Simulator(homes=homes, base_port=0, time_scale=speedup, seed=seed)
    with swarm as vehicles:
        assignments = planned.assignments()
        results = upload_swarm(assignments, vehicles.urls, timing=Timing())
        if not all(r.verified for r in results):
            raise SystemExit("upload failed: " + "; ".join(r.message for r in results))
        serial1 = (vehicles.serial1_urls if not binary else
                   [f"tcp:127.0.0.1:{int(u.rsplit(':', 1)[1]) + 2}" for u in vehicles.urls])
        judges = []
        for i, url in enumerate(serial1):
            g = None
            if glitch is not None and glitch[0] == i + 1:
                when, metres = glitch[1], glitch[2]
                if when == "takeoff":
                    def trig(j):
                        return j.armed
                else:
                    def trig(j, s=float(when)):
                        return (j.auto_since is not None
                                and time.monotonic() - j.auto_since >= s / speedup)
                g = (trig, metres)
            judges.append(Judge(url, i + 1, lat_deg=homes[i][0],
                                rng=np.random.default_rng([seed, i]), wander_m=wander_m,
                                tau_s=tau_s, acc_m=acc_m, glitch=g, speedup=speedup))
        for j in judges:
            j.start()
        time.sleep(2.0 / speedup)
        options = FlyOptions(keeper=KeeperOptions(enabled=use_keeper))
        keeper = make_keeper(planned, options.keeper) if use_keeper else None
        if keeper is not None and tracks is not None:
            keeper.trace = []
        lines: list[str] = []
        outcome = "completed"

        def say(text: str) -> None:
            lines.append(text)

        start = time.monotonic()
        corrections: dict = {}
        try:
            with contextlib.ExitStack() as stack:
                fleet = stack.enter_context(
                    Fleet(planned.names, list(range(1, planned.count + 1)), vehicles.urls))
                if rtcm:  # a base station's stream from an NTRIP caster, as fly --rtcm
                    caster = stack.enter_context(FakeCaster(
                        lambda: base_station(3600, lat=homes[0][0], lon=homes[0][1]),
                        interval_s=1.0 / speedup))
                    source = parse_source(f"ntrip://me:secret@127.0.0.1:{caster.port}/BASE1")
                    forwarder = stack.enter_context(
                        RtcmForwarder(frames_from(source), fleet.links))
                    stack.callback(lambda: corrections.update(forwarder.summary()))
                fly(planned, fleet.vehicles, options=options, timing=Timing(), say=say,
                    tick=lambda: None, keeper=keeper)
        except PreflightError as exc:
            outcome = "refused: " + "; ".join(exc.problems)
        except FlightLeftPlan as exc:
            outcome = "left the plan: " + str(exc).replace("\n", " | ")
        end = time.monotonic()
        time.sleep(1.0 / speedup)
        for j in judges:
            j.close()
    autos = [j.auto_since for j in judges if j.auto_since is not None]
    legs = (max(autos) if autos else start, end)
    stamped = [restamp(j) for j in judges]
    row = {"seed": seed, "outcome": outcome, "seconds": round(end - start, 1),
           **judged(planned, stamped, legs), "link": [s[2] for s in stamped],
           "rtcm": corrections or None,
           "keeper": keeper.log.as_dict(planned.names) if keeper is not None else None}
    if tracks is not None:  # each copter's restamped estimate and truth, for a closer look
        np.savez_compressed(tracks, **{f"{view}{n + 1}": np.array(s[w], float)
                                       for n, s in enumerate(stamped)
                                       for w, view in ((0, "estimate"), (1, "truth"))},
                            legs=np.array(legs))
        if keeper is not None:
            tracks.with_suffix(".keeper.json").write_text(json.dumps(keeper.trace))
    return row


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenario", type=Path, default=EXAMPLE,
                    help="the scenario to plan and fly (default: the shipped example)")
    ap.add_argument("--runs", type=int, default=1)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--wander", type=float, default=0.2,
                    help="GPS wander, m standard deviation per axis (0.2: rtk-float's 0.5 m "
                         "at 95 %%)")
    ap.add_argument("--tau", type=float, default=30.0, help="its correlation time, s")
    ap.add_argument("--acc", type=float, default=0.3, help="SIM_GPS_ACC, m")
    ap.add_argument("--glitch", help="UAV:WHEN:METRES, WHEN 'takeoff' or seconds into the "
                                     "legs (e.g. 1:takeoff:3 or 2:5:3): a sudden north offset")
    ap.add_argument("--rtcm", action="store_true",
                    help="RTK corrections flowing: a generated base station's MSM7 stream "
                         "(~1 kB/s) from a local NTRIP caster to every copter, as fly --rtcm")
    ap.add_argument("--no-keeper", action="store_true", help="fly as fly --no-keeper")
    ap.add_argument("--tracks", type=Path, default=None,
                    help="write each run's restamped tracks to TRACKS.<run>.npz")
    ap.add_argument("--speedup", type=float, default=None)
    ap.add_argument("--out", type=Path, default=Path("navigation-benchmark.json"))
    args = ap.parse_args()
    glitch = None
    if args.glitch:
        uav, when, metres = args.glitch.split(":")
        glitch = (int(uav), when, float(metres))
    binary = os.environ.get("ARDUPILOT_SITL")
    speedup = args.speedup or (1.0 if binary else 6.0)
    scenario = load_scenario(args.scenario)
    folder = Path(tempfile.mkdtemp(prefix="navigation-"))
    write_plan(plan(scenario), folder)
    homes = scenario_homes(scenario)
    rows = []
    backend = "ArduCopter SITL" if binary else "emulator"
    print(f"{backend}: {args.scenario.name} ([navigation] {scenario.navigation.describe()}, "
          f"clearance {scenario.clearance_m:g} m, min_separation "
          f"{scenario.min_separation_m:g} m); GPS wander {args.wander:g} m per axis, "
          f"tau {args.tau:g} s, SIM_GPS_ACC {args.acc:g} m, glitch {args.glitch or 'none'}")
    for k in range(args.runs):
        row = one_flight(folder, homes, binary=binary, speedup=speedup, seed=args.seed + k,
                         wander_m=args.wander, tau_s=args.tau, acc_m=args.acc, glitch=glitch,
                         rtcm=args.rtcm, use_keeper=not args.no_keeper,
                         tracks=args.tracks and args.tracks.with_suffix(f".{k}.npz"))
        rows.append(row)
        for view in ("believed", "true"):
            r = row.get(view) or {}
            print(f"seed {row['seed']} {view:>8}: clearance {r.get('min_clearance_m')} m, "
                  f"separation {r.get('min_separation_m')} m, formation RMS/worst "
                  f"{r.get('formation_rms_m')}/{r.get('formation_worst_m')} m, landing "
                  f"{r.get('landing_error_worst_m')} m")
        print(f"seed {row['seed']} outcome: {row['outcome'][:300]}")
        if row["keeper"]:
            print(f"seed {row['seed']} keeper: {row['keeper']}")
        if row["rtcm"]:
            print(f"seed {row['seed']} RTCM: {row['rtcm']}")
    args.out.write_text(json.dumps({"backend": backend, "args": vars(args), "rows": rows},
                                   indent=1, default=str))
    return 0


if __name__ == "__main__":
    sys.exit(main())
