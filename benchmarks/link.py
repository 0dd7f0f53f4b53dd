"""Mission link speed and robustness: seconds to upload and verify 3 x 15 items.

Plain ``python benchmarks/link.py`` (``--quick`` for fewer runs). Prints tables and writes
JSON (``--json``, default ``link-benchmark.json``).

1. Real sockets, real time: three emulated ArduCopters on TCP (``ftlbo_mav.sim``), one
   upload + read-back + compare of a 15-item mission each, all concurrently, as
   ``ftlbo-mav upload`` does it. Clean link, 20% loss each way, and 30% loss each way with
   5% duplicated and 5% reordered packets. Median and worst wall seconds over the runs,
   and how many runs verified all three vehicles. Wall clock on this machine as loaded
   now; the load average is printed and stored.
2. Virtual time, many seeds: one vehicle over the in-process loopback link with
   ArduPilot's timings (1 s re-request, 8 s cancel), ours next to a plain request/answer
   uploader (answers MISSION_REQUEST[_INT], resends MISSION_COUNT every 1.5 s up to 5
   times, relies on the vehicle's re-requests otherwise, ends on the first ACK) - the kind
   the issue measured against ArduCopter SITL. Completed uploads and mean seconds of the
   upload alone (no read-back), per loss rate.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as R

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from ftlbo_mav.link.mission_protocol import (
    MissionTransferError,
    Timing,
    Upload,
    _Transfer,
    run_transfer,
)
from ftlbo_mav.link.swarm import Assignment, upload_swarm
from ftlbo_mav.sim.faults import Faults
from ftlbo_mav.sim.homes import default_homes
from ftlbo_mav.sim.loopback import LoopbackChannel
from ftlbo_mav.sim.server import Simulator
from ftlbo_mav.sim.vehicle import Vehicle, VehicleOptions
from tests.link.support import make_mission

LINKS = {
    "clean": Faults(),
    "20% loss": Faults(loss_up=0.2, loss_down=0.2),
    "30% loss + 5% dup + 5% reorder": Faults(loss_up=0.3, loss_down=0.3, duplicate=0.05,
                                             reorder=0.05),
}


def real_sockets(runs: int) -> list[dict]:
    missions = [tuple(make_mission(k)) for k in range(3)]
    rows = []
    for name, faults in LINKS.items():
        seconds, verified = [], 0
        for run in range(runs):
            with Simulator(homes=default_homes(3), base_port=0, faults=faults, seed=run,
                           options=VehicleOptions(heartbeat_s=0.2)) as sim:
                assignments = [Assignment(f"uav{k + 1}", k + 1, m) for k, m in enumerate(missions)]
                t0 = time.perf_counter()
                results = upload_swarm(assignments, sim.urls)
                seconds.append(time.perf_counter() - t0)
                verified += all(r.verified for r in results)
        rows.append({"link": name, "runs": runs, "all_verified_runs": verified,
                     "median_s": statistics.median(seconds), "max_s": max(seconds),
                     "seconds": seconds})
    return rows


class PlainUpload(_Transfer):
    """The baseline: answer requests, resend only MISSION_COUNT, stop at the first ACK."""

    step = "plain upload"

    def __init__(self, items, **kw):
        super().__init__(**kw)
        self.items, self.n, self.tries, self.asked = list(items), len(items), 0, False

    def start(self, now):
        return self._count(now)

    def _count(self, now):
        self.deadline = now + self.timing.timeout_s
        return [R.MAVLink_mission_count_message(self.sysid, self.compid, self.n, 0)]

    def on_message(self, msg, now):
        kind = msg.get_type()
        if kind in ("MISSION_REQUEST", "MISSION_REQUEST_INT") and msg.seq < self.n:
            self.asked = True
            self.deadline = now + 10.0  # wait for the vehicle: it re-requests, or cancels
            it = self.items[msg.seq]
            return [R.MAVLink_mission_item_int_message(
                self.sysid, self.compid, it.seq, it.frame, it.command, it.current,
                it.autocontinue, it.param1, it.param2, it.param3, it.param4,
                round(it.lat_deg * 1e7), round(it.lon_deg * 1e7), it.alt_m, 0)]
        if kind == "MISSION_ACK":
            if msg.type == R.MAV_MISSION_ACCEPTED:
                return self._done()
            return self._fail(f"ACK {msg.type}", result=msg.type)
        return []

    def on_timeout(self, now):
        self.tries += 1
        if self.asked or self.tries > self.timing.retries:
            return self._fail("timeout")
        return self._count(now)


def virtual_time(seeds: int) -> list[dict]:
    items = make_mission()
    rows = []
    cases = [("10% loss", Faults(loss_up=0.1, loss_down=0.1)),
             ("20% loss", Faults(loss_up=0.2, loss_down=0.2)),
             ("30% loss", Faults(loss_up=0.3, loss_down=0.3)),
             ("5% duplicates", Faults(duplicate=0.05)),
             ("30% loss + 5% dup + 5% reorder", LINKS["30% loss + 5% dup + 5% reorder"])]
    for name, faults in cases:
        row = {"link": name, "seeds": seeds}
        for who in ("ours", "plain"):
            done, secs = 0, []
            for seed in range(seeds):
                vehicle = Vehicle(sysid=1, home=(items[0].lat_deg, items[0].lon_deg, 10.0))
                ch = LoopbackChannel(vehicle, faults=faults, rng=np.random.default_rng(seed))
                kw = {"sysid": 1, "compid": 1, "own": (255, 190), "timing": Timing(),
                      "progress": None}
                machine = Upload(items, **kw) if who == "ours" else PlainUpload(items, **kw)
                try:
                    run_transfer(machine, ch)
                except MissionTransferError:
                    continue
                # "completed" means the vehicle holds the whole mission
                if len(vehicle.missions.items) == len(items):
                    done += 1
                    secs.append(ch.now - vehicle.boot_time)
            row[f"{who}_completed"] = done
            row[f"{who}_mean_s"] = statistics.mean(secs) if secs else None
        rows.append(row)
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="3 socket runs, 30 seeds")
    ap.add_argument("--json", default="link-benchmark.json", help="where to write the figures")
    args = ap.parse_args()
    runs, seeds = (3, 30) if args.quick else (5, 100)
    load = os.getloadavg()
    print(f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}, {os.cpu_count()} cores")

    print("\n1. upload + read-back + compare, 3 vehicles x 15 items, emulator over TCP")
    print(f"{'link':34s} {'verified runs':>13s} {'median s':>9s} {'worst s':>8s}")
    real = real_sockets(runs)
    for r in real:
        print(f"{r['link']:34s} {r['all_verified_runs']:>6d}/{r['runs']:<6d} "
              f"{r['median_s']:9.2f} {r['max_s']:8.2f}")

    print(f"\n2. upload alone, 1 vehicle x 15 items, virtual time, {seeds} seeds")
    print(f"{'link':34s} {'ours done':>10s} {'ours s':>7s} {'plain done':>11s} {'plain s':>8s}")
    virt = virtual_time(seeds)

    def fmt(v):
        return f"{v:.2f}" if v is not None else "-"

    for r in virt:
        print(f"{r['link']:34s} {r['ours_completed']:>5d}/{seeds:<4d} {fmt(r['ours_mean_s']):>7s} "
              f"{r['plain_completed']:>6d}/{seeds:<4d} {fmt(r['plain_mean_s']):>8s}")

    out = {"load_average": load, "cores": os.cpu_count(), "real_sockets": real,
           "virtual_time": virt}
    Path(args.json).write_text(json.dumps(out, indent=2) + "\n")
    print(f"\nwrote {args.json}")


if __name__ == "__main__":
    main()
