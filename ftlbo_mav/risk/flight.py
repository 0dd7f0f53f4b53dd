"""One risk flight: the plan flown on the emulator as ``fly`` flies it, in the conditions
of its seed, judged by where the copters truly were.

Each flight starts its own emulated copters (:class:`~ftlbo_mav.sim.server.Simulator`,
ports chosen by the system, so several flights run side by side on one machine), uploads
the plan's missions as ``upload`` does, runs ``fly`` (pre-flight, take-off, the
synchronized start, the keeper, the departure watch and its policy, landing) with its log
in a temporary folder, and removes everything when it ends. The figures come from the
copters' true positions (SIM_STATE's truth, recorded at every step of the emulator: its
estimate less its fused GPS error), not from what they reported. Only the plan folder is
read; nothing is written to it.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import tempfile
import time
from pathlib import Path

import numpy as np

from .. import clock
from ..ardupilot.firmware import RECORDED_RELEASES
from ..clock import ClockStopped, VirtualClock
from ..flight.metrics import min_clearance, min_separation
from ..flight.planned import PlannedFlight, load_planned_flight
from ..link.endpoints import Link
from ..link.swarm import upload_swarm
from ..sim.gps import GpsErrorOptions
from ..sim.inprocess import InProcessSimulator
from ..sim.physics import FlightLimits
from ..sim.server import Simulator
from ..sim.vehicle import VehicleOptions
from .conditions import Conditions

START_UTC_S = 1_767_225_600.0
"""GPS time at a flight's start on the virtual clock (2026-01-01 00:00 UTC): the same for
every flight, so that the start gate (a whole GPS second) waits as long each time."""
AIRBORNE_M = 1.0  # above its home: separation counts only in the air (homes may be close)


def homes_of(planned: PlannedFlight) -> list[tuple[float, float, float]]:
    """Each copter's home: its mission's item 0, on the ground (0 m AMSL)."""
    return [(m[0].lat_deg, m[0].lon_deg, 0.0) for m in planned.missions]


def fly_one(plan_dir: str | Path, conditions: Conditions, *,
            time_scale: float | None = None, live: bool = False) -> dict:
    """Fly ``plan_dir`` once in ``conditions``; the flight's record (:func:`judge`).

    By default the ground station and the emulated copters run together on a virtual
    clock (:mod:`ftlbo_mav.clock`, :mod:`ftlbo_mav.sim.inprocess`): the flight takes only
    the computation it needs and the same seed flies the same flight. ``time_scale``: fly
    instead on the wall clock against the emulator on TCP ports, its clock running that
    many times faster (how risk flights ran before; a comparison). ``live``: fly's output
    (its live view) to this process's stderr, as ``fly`` shows it."""
    planned = load_planned_flight(Path(plan_dir))
    started = time.monotonic()
    if time_scale is not None:
        return _fly_one(plan_dir, planned, conditions, started, live=live,
                        sim=_simulator(planned, conditions, time_scale=time_scale))
    with VirtualClock(utc_s=START_UTC_S) as vc:
        t0 = vc.monotonic()
        try:
            record = _fly_one(plan_dir, planned, conditions, started, live=live,
                              sim=_simulator(planned, conditions, time_scale=None))
        except ClockStopped:  # stalled (clock.VirtualClock._watch): a failed flight
            record = _record(conditions, planned, None, exit_code=2, summary={},
                             wall_s=time.monotonic() - started, problem="stalled")
        # the whole run's simulated seconds: upload, pre-flight, the flight, the landing
        record["simulated_s"] = round(vc.monotonic() - t0, 2)
    if vc.stalled:
        record["problem"] = f"the simulation stalled: {vc.stall_reason}"
        record["outcome"] = f"failed: {record['problem']}"
    return record


def _simulator(planned: PlannedFlight, conditions: Conditions, *, time_scale: float | None):
    """The emulated copters of one flight: in this process on the virtual clock, or
    (``time_scale``) behind TCP ports the system chooses."""
    homes = homes_of(planned)
    gps = [GpsErrorOptions(wander_m=conditions.gps_wander_m,
                           correlation_s=conditions.gps_correlation_s, seed=s)
           for s in conditions.gps_seeds[:len(homes)]]
    # each copter as the plan says it is (its release and values: plan.json uavs[].vehicle)
    copters = planned.fleet()
    options = [VehicleOptions(gps=g, firmware=RECORDED_RELEASES[c.release],
                              limits=FlightLimits(nav=c.nav))
               for g, c in zip(gps, copters)]
    settings = {"homes": homes, "seed": conditions.seed, "vary": conditions.vary,
                "wind": conditions.wind, "options": options}
    if time_scale is None:
        return InProcessSimulator(**settings)
    return Simulator(base_port=0, time_scale=time_scale, **settings)


def _fly_one(plan_dir, planned: PlannedFlight, conditions: Conditions, started: float, *,
             live: bool, sim) -> dict:
    with tempfile.TemporaryDirectory(prefix="ftlbo-risk-") as tmp, sim:
        uploaded = upload_swarm(planned.assignments(), sim.urls)
        failed = [r for r in uploaded if not r.verified]
        if failed:
            return _record(conditions, planned, None, exit_code=None, summary={},
                           wall_s=time.monotonic() - started,
                           problem="; ".join(f"{r.name}: {r.message}" for r in failed))
        for r in sim.runners:
            r.truth = []
        scale = getattr(sim, "time_scale", 1.0)
        faults = _schedule_faults(sim, conditions, scale)
        code, output = _fly(Path(plan_dir), sim.urls, Path(tmp) / "flight", live=live)
        for fault in faults:
            fault.cancel()
        summary_file = Path(tmp) / "flight" / "summary.json"
        summary = json.loads(summary_file.read_text()) if summary_file.exists() else {}
        truth = [list(r.truth or []) for r in sim.runners]
    problem = None if summary else output.strip().splitlines()[-1:] or ["no summary"]
    return _record(conditions, planned, truth, exit_code=code, summary=summary,
                   wall_s=time.monotonic() - started,
                   problem=problem if problem is None else problem[0])


class _Fault:
    """A fault ``after_s`` seconds of the vehicles' clock after copter ``index`` starts its
    mission (AUTO): ``kill`` (its emulator gone, as a killed SITL process) or ``takeover``
    (switched to BRAKE from its SERIAL1 port, as a pilot's or another station's
    MAV_CMD_DO_SET_MODE). ``scale``: the vehicles' seconds per second of this clock."""

    def __init__(self, sim, index: int, after_s: float, scale: float, kind: str) -> None:
        self.sim, self.index, self.after_s, self.scale, self.kind = (
            sim, index, after_s, scale, kind)
        self._stop = clock.Event()
        self.at: float | None = None  # the vehicles' seconds after their missions began
        self.thread = clock.Thread(self._run, name=f"{kind} uav{index + 1}")
        self.thread.start()

    def _run(self) -> None:
        ap = self.sim.runners[self.index].vehicle.autopilot
        while not self._stop.is_set() and ap.mode_name() != "AUTO":
            self._stop.wait(0.01)
        if self._stop.wait(self.after_s / self.scale):
            return
        if self.kind == "kill":
            self.sim.kill(self.index)
        else:
            self._take_over()
        self.at = self.after_s

    def _take_over(self) -> None:
        from pymavlink.dialects.v20 import ardupilotmega as R

        from ..ardupilot.modes import CopterMode

        with Link(self.sim.serial1_urls[self.index]) as link:
            sysid = self.index + 1
            for _ in range(3):  # as a pilot's station: sent until the mode shows
                link.send(R.MAVLink_command_long_message(
                    sysid, 1, R.MAV_CMD_DO_SET_MODE, 0, R.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
                    CopterMode.BRAKE, 0, 0, 0, 0, 0))
                if self._stop.wait(0.2 / self.scale) or (
                        self.sim.runners[self.index].vehicle.autopilot.mode_name() == "BRAKE"):
                    return

    def cancel(self) -> None:
        self._stop.set()
        self.thread.join(timeout=5.0)


def _schedule_faults(sim, conditions: Conditions, scale: float) -> list[_Fault]:
    """The copter this flight loses and the one whose mode is taken over (module notes of
    :mod:`.conditions`), each at its time after its missions start."""
    return [_Fault(sim, which[0], which[1], scale, kind)
            for kind, which in (("kill", conditions.lost), ("takeover", conditions.takeover))
            if which is not None and which[0] < len(sim.runners)]


def _fly(plan_dir: Path, urls: list[str], log_dir: Path, *, live: bool) -> tuple[int, str]:
    """``ftlbo-mav fly`` in this process: its exit code and what it printed."""
    from ..cli import main  # the command as a user runs it (imported here: no cycle)

    args = ["fly", str(plan_dir), "--sysid", f"1..{len(urls)}", "--control-port", "0",
            "--connect", " ".join(urls), "--log-dir", str(log_dir)]
    if not live:  # a replay draws it, as fly does; the runs need only the figures
        args.append("--no-report-png")
    if live:
        try:
            main.main(args, standalone_mode=False)
        except ClockStopped:
            raise
        except SystemExit as exc:
            return int(exc.code or 0), ""
        return 0, ""
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(out):
        try:
            main.main(args, standalone_mode=False)
            code = 0
        except ClockStopped:
            raise
        except SystemExit as exc:
            code = int(exc.code or 0)
        except Exception as exc:  # noqa: BLE001 - a flight that breaks is a flight's outcome
            print(f"{type(exc).__name__}: {exc}")
            code = 2
    return code, out.getvalue()


def _true_enu(planned: PlannedFlight, truth: list[list[tuple]]) -> tuple[np.ndarray, np.ndarray]:
    """Every copter's true positions on the first copter's times: ``(T,)`` seconds and
    ``(T, N, 3)`` ENU metres in the plan's frame (a copter's last position held after it
    died)."""
    if not truth or not truth[0]:
        return np.zeros(0), np.zeros((0, len(truth), 3))
    times = np.array([row[0] for row in truth[0]])
    out = np.empty((len(times), len(truth), 3))
    for n, rows in enumerate(truth):
        a = np.array(rows) if rows else np.array([[times[0], *truth[0][0][1:]]])
        enu = planned.frame.to_enu(lat_deg=a[:, 1], lon_deg=a[:, 2], alt_m=a[:, 3])
        for k in range(3):
            out[:, n, k] = np.interp(times, a[:, 0], enu[:, k])
    return times, out


def judge(planned: PlannedFlight, truth) -> dict:
    """The true figures of a flight, from the recorded true positions: the smallest
    clearance from any obstacle (the whole flight), the smallest separation while every
    copter is in the air, and the flight's time."""
    times, pos = _true_enu(planned, truth)
    if len(times) == 0:
        return {}
    ground = pos[0, :, 2]
    airborne = np.all(pos[:, :, 2] - ground > AIRBORNE_M, axis=1)
    clear = min_clearance(pos, planned.centres, planned.radii)
    up = np.flatnonzero(np.any(pos[:, :, 2] - ground > AIRBORNE_M, axis=1))
    return {"true_min_clearance_m": _num(clear.min()),
            "true_min_separation_m": _num(min_separation(pos[airborne]).min())
            if airborne.any() else None,
            # the vehicles' seconds from the first copter leaving the ground to the last
            # one landing
            "flight_s": _num(times[up[-1]] - times[up[0]]) if len(up) else None}


def _num(x) -> float | None:
    x = float(x)
    return round(x, 4) if math.isfinite(x) else None


def _record(conditions: Conditions, planned: PlannedFlight, truth, *, exit_code, summary,
            wall_s: float, problem: str | None) -> dict:
    flown = judge(planned, truth) if truth is not None else {}
    landing = summary.get("final_distance_to_goal_m") or []
    record = {
        "seed": conditions.seed,
        "conditions": {"wind_m_s": conditions.wind[0], "wind_from_deg": conditions.wind[1],
                       "turbulence_m_s": conditions.wind[2],
                       "gps_wander_m": conditions.gps_wander_m, "vary": conditions.vary,
                       "lost": _fault_record(planned, conditions.lost),
                       "takeover": _fault_record(planned, conditions.takeover)},
        "exit_code": exit_code,
        "outcome": _outcome(exit_code, summary, problem),
        "departures": summary.get("departures", []),
        **flown,
        "formation_error_rms_m": summary.get("formation_error_rms_legs_m"),
        "formation_error_max_m": summary.get("formation_error_max_legs_m"),
        "landing_error_max_m": max(landing) if landing else None,
        "planned_clearance_m": planned.clearance_m,
        "min_separation_m": planned.min_separation_m,
        "wall_s": round(wall_s, 2),
    }
    if problem:
        record["problem"] = problem
    return record


def _fault_record(planned: PlannedFlight, fault: tuple[int, float] | None) -> dict | None:
    return None if fault is None else {"uav": planned.names[fault[0]],
                                       "after_s": round(fault[1], 2)}


def _outcome(code, summary: dict, problem: str | None) -> str:
    if code is None:
        return "not flown (upload failed)"
    if code == 0:
        return "completed"
    if summary.get("departures"):
        return "left the plan"
    return f"failed (exit {code})" + (f": {problem}" if problem else "")
