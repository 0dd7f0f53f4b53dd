"""Flights held to the plan's navigation budget: a copter whose GPS reports worse than
the budget is refused before anything arms, one whose GPS jumps (a glitch, as a
multipath reflection or a receiver reset gives) during take-off or mid-leg is a departure
that the formation policy answers, and ``fly`` never ends with exit 0 after one.

The emulator, or ArduPilot SITL when ARDUPILOT_SITL is set: the faults are made with
SITL's own knobs from the copter's second port (SIM_GPS_ACC, SIM_GPS_GLITCH_X).
"""

from __future__ import annotations

import csv
import math
import shutil
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav import clock
from ftlbo_mav.cli import main
from ftlbo_mav.flight.planned import load_planned_flight
from ftlbo_mav.sim.gps import METRES_PER_DEGREE

from ..conftest import EXAMPLE
from .fleet import BACKEND, vehicles
from .test_departures import (
    HOMES,
    OPTIONS,
    SecondPort,
    _fly_with,
    _in_auto_for,
    _summary,
    _upload,
)
from .test_homeward import Track


@pytest.fixture(scope="module")
def example(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("example") / "plan"
    shutil.copytree(EXAMPLE.with_suffix(""), folder)
    return folder


@pytest.fixture
def plan_dir(example, tmp_path) -> Path:
    folder = tmp_path / "plan"
    shutil.copytree(example, folder)
    return folder

pytestmark = pytest.mark.sitl

GLITCH_M = 3.0
SPEEDUP = 1.0  # SITL in real time; the emulator on a virtual clock


def test_a_copter_whose_gps_is_worse_than_the_budget_is_refused_before_arming(plan_dir):
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, virtual=True, **OPTIONS) as fleet:
        _upload(plan_dir, fleet.urls)
        station = SecondPort(fleet.serial1_urls[1], 2)
        try:
            station.set_param("SIM_GPS_ACC", 1.5)
            clock.sleep(1.0 / fleet.time_scale)
            result, _took = _fly_with(plan_dir, fleet.urls, clock.monotonic)
            assert not station.armed
        finally:
            station.close()
    out = result.output
    assert result.exit_code != 0, out
    assert "pre-flight failed, nothing armed" in out
    line = next(x for x in out.splitlines() if "uav2 (sysid 2)" in x)
    assert "GPS accuracy 1.50 m, worse than the plan's budget 0.5 m" in line
    assert "rtk-float" in line
    assert not any("uav1 (sysid 1)" in x for x in out.splitlines() if "navigation" in x)


def _glitch(station: SecondPort) -> None:
    station.set_param("SIM_GPS_GLITCH_X", GLITCH_M / METRES_PER_DEGREE)  # north, degrees


def test_a_gps_glitch_mid_leg_is_a_departure_the_others_answer(plan_dir):
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, virtual=True, **OPTIONS) as fleet:
        _upload(plan_dir, fleet.urls)
        station = SecondPort(fleet.serial1_urls[0], 1)

        def fault():
            _in_auto_for(station, 3.0, fleet.time_scale)
            _glitch(station)
            return clock.monotonic()

        try:
            result, took = _fly_with(plan_dir, fleet.urls, fault)
        finally:
            station.close()
    out = result.output
    assert result.exit_code == 1, out
    line = next(x for x in out.splitlines() if x.strip().startswith("uav1 (sysid 1): navigation"))
    # the GPS jumps by the glitch, less what the copter has flown out of it by the next
    # report; or ArduCopter rejects it and says so
    assert "GPS position jumped" in line or "GPS Glitch" in line, line
    # the others pause (a copter starved of CPU time in a loaded run may also be past the
    # formation's bound by then: a departure of its own before the pause, on the same line)
    for other in ("uav2 (sysid 2):", "uav3 (sysid 3):"):
        theirs = next(x for x in out.splitlines() if x.strip().startswith(other))
        assert "stopped on its track (pause)" in theirs, theirs
    assert any("uav1 (sysid 1): navigation" in d for d in _summary(plan_dir)["departures"])
    assert took < 60.0


def test_a_gps_glitch_during_take_off_is_a_departure(plan_dir):
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, virtual=True, **OPTIONS) as fleet:
        _upload(plan_dir, fleet.urls)
        station = SecondPort(fleet.serial1_urls[2], 3)

        def fault():
            assert station.wait(lambda p: p.armed, 120.0)
            _glitch(station)
            return clock.monotonic()

        try:
            result, _took = _fly_with(plan_dir, fleet.urls, fault)
        finally:
            station.close()
    out = result.output
    assert result.exit_code == 1, out
    assert any(x.strip().startswith("uav3 (sysid 3): navigation") for x in out.splitlines()), out


def test_a_copter_whose_gps_puts_it_ahead_of_its_start_moves_there_before_the_legs(plan_dir):
    """Its estimate 1.2 m east of where it stands (the first leg runs east): it takes off
    where it believes it is, moves to its start point, and every copter leaves from its
    own. Started where it hovered, it would fly the legs 1.2 m ahead of the others.

    Without the keeper and with a loose formation bound: this is about where the legs
    begin. On SITL the copter that moved gains 1.2 m on the others while the first leg
    speeds up (SITL, two runs; with the keeper on it is paused back and the flight
    passes the plan's bound), which the plan's 0.77 m bound would call a departure; the
    emulator does not show that gain (docs/flight.md, "When a vehicle leaves the plan")."""
    ahead_m = 1.2
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, virtual=True, **OPTIONS) as fleet:
        _upload(plan_dir, fleet.urls)
        station = SecondPort(fleet.serial1_urls[1], 2)
        try:
            station.set_param("SIM_GPS_GLITCH_Y", ahead_m / (
                METRES_PER_DEGREE * math.cos(math.radians(HOMES[1][0]))))
            clock.sleep(10.0 / fleet.time_scale)  # EKF3 takes a GPS step up over about 5 s
            result = CliRunner().invoke(main, ["fly", str(plan_dir), "--sysid", "1..3",
                                               "--control-port", "0", "--no-keeper",
                                               "--formation-bound", "5",
                                               "--connect", " ".join(fleet.urls)])
        finally:
            station.close()
    out = result.output
    assert result.exit_code == 0, out
    line = next(x for x in out.splitlines() if "moving to the start points first" in x)
    assert "uav2" in line and "uav1" not in line and "uav3" not in line, line
    # in its own estimate each copter was at its start point when AUTO began
    planned = load_planned_flight(plan_dir)
    rows = list(csv.DictReader((plan_dir / "flight" / "flight.csv").open()))
    for n in range(3):
        first = next(r for r in rows if int(r["sysid"]) == n + 1 and r["mode"] == "AUTO")
        enu = planned.frame.to_enu(lat_deg=[float(first["lat_deg"])],
                                   lon_deg=[float(first["lon_deg"])])
        off = float(np.hypot(*(enu[0, :2] - planned.paths[n][0][:2])))
        assert off < 0.3, (n + 1, off)


# -- the answer judged where the copters truly are (SIM_STATE) -----------------------------

class Truth(Track):
    """A vehicle's second link recording SIM_STATE (the simulator's true position) at
    10 Hz on the test's clock, its HEARTBEAT and MISSION_CURRENT; the one station on that
    port (SITL's SERIAL1 takes one connection), which the test also sends its knobs by."""

    ASKS = ((R.MAVLINK_MSG_ID_SIM_STATE, 1e5), (R.MAVLINK_MSG_ID_MISSION_CURRENT, 2e5))

    def __init__(self, url: str, sysid: int, home_alt_m: float) -> None:
        self.home_alt_m = home_alt_m
        super().__init__(url, sysid)

    def record(self, msg, now: float) -> None:
        if msg.get_type() == "SIM_STATE":
            lat = msg.lat_int * 1e-7 if getattr(msg, "lat_int", 0) else msg.lat
            lon = msg.lon_int * 1e-7 if getattr(msg, "lon_int", 0) else msg.lon
            self.rows.append((now, lat, lon, msg.alt - self.home_alt_m))  # t, lat, lon, up
        elif msg.get_type() == "MISSION_CURRENT":
            self.seq = msg.seq

    def enu(self, frame) -> np.ndarray:
        """``(T, 4)``: time, east, north, up above home."""
        t, lat, lon, alt = np.array(self.rows, float).T
        return np.column_stack([t, frame.to_enu(lat_deg=lat, lon_deg=lon, alt_m=alt)])


GLITCHES = {  # SIM_GPS_GLITCH_X / _Y (degrees) of a 3 m jump
    "north": (GLITCH_M / METRES_PER_DEGREE, 0.0),
    "south": (-GLITCH_M / METRES_PER_DEGREE, 0.0),
    "east": (0.0, GLITCH_M / (METRES_PER_DEGREE * math.cos(math.radians(HOMES[0][0])))),
    "west": (0.0, -GLITCH_M / (METRES_PER_DEGREE * math.cos(math.radians(HOMES[0][0])))),
}


def _kept_where_they_truly_are(planned, tracks: list[np.ndarray], since: float) -> dict:
    """From ``since`` (the fault) on, where the copters truly were: the smallest
    separation of each pair and clearance of each copter in the air, against what they
    were at ``since`` and the plan's promises: each may not go below the lesser of the
    two (min_separation; clearance less 0.05 m)."""
    t = np.linspace(since, min(tr[-1, 0] for tr in tracks), 3000)
    at = np.stack([np.column_stack([np.interp(t, tr[:, 0], tr[:, k]) for k in (1, 2, 3)])
                   for tr in tracks])  # (N, T, 3)
    up = at[..., 2] > 0.3
    out = {"separation": {}, "clearance": {}}
    for a in range(len(at)):
        for b in range(a + 1, len(at)):
            d = np.linalg.norm(at[a] - at[b], axis=1)
            air = up[a] | up[b]
            if not air.any():
                continue
            floor = min(float(d[0]), planned.min_separation_m)
            k = int(np.argmin(np.where(air, d, np.inf)))
            out["separation"][f"uav{a + 1}-uav{b + 1}"] = (round(float(d[k]), 2),
                                                          round(floor, 2))
            pair = f"uav{a + 1}-uav{b + 1}"
            out.setdefault("closest_s", {})[pair] = round(float(t[k] - since), 1)
        gap = (np.hypot(*(at[a][:, None, :2] - planned.centres[None]).transpose(2, 0, 1))
               - planned.radii).min(axis=1)
        floor = min(float(gap[0]), planned.clearance_m - 0.05)
        if up[a].any():  # (one still on the ground is no obstacle's concern)
            out["clearance"][f"uav{a + 1}"] = (round(float(gap[up[a]].min()), 2),
                                               round(floor, 2))
    out["kept"] = all(v >= f - 1e-3 for part in ("separation", "clearance")
                      for v, f in out[part].values())
    return out


@pytest.mark.parametrize("when,who,direction", [
    ("legs", 0, "north"), ("legs", 0, "south"), ("legs", 0, "east"), ("legs", 0, "west"),
    ("take-off", 2, "east"), ("take-off", 2, "west")])
def test_a_copter_whose_gps_jumped_lands_where_it_is_and_the_others_keep_clear(
        plan_dir, when, who, direction):
    planned = load_planned_flight(plan_dir)
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, virtual=True, **OPTIONS) as fleet:
        _upload(plan_dir, fleet.urls)
        truth = [Truth(url, i + 1, HOMES[i][2]) for i, url in enumerate(fleet.serial1_urls)]
        station = truth[who]
        times = {}

        def fault():
            if when == "legs":
                _in_auto_for(station, 3.0, fleet.time_scale)
            else:  # climbing, 2 m up
                assert truth[who].wait(lambda p: p.rows and p.rows[-1][3] > 2.0, 120.0)
            times["fault"] = clock.monotonic()
            north, east = GLITCHES[direction]
            station.set_param("SIM_GPS_GLITCH_X", north)
            station.set_param("SIM_GPS_GLITCH_Y", east)
            return times["fault"]

        try:
            result, _took = _fly_with(plan_dir, fleet.urls, fault)
            for tr in truth:
                assert tr.wait(lambda p: not p.armed, 120.0)
            clock.sleep(0.5)
        finally:
            for tr in truth:
                tr.close()
    out = result.output
    judged = _kept_where_they_truly_are(planned, [tr.enu(planned.frame) for tr in truth],
                                        times["fault"])
    print(f"[{BACKEND}] GPS of uav{who + 1} jumped 3 m {direction} ({when}): {judged}")
    assert result.exit_code == 1 and "Traceback" not in out, out
    line = [x for x in out.splitlines() if x.strip().startswith(f"uav{who + 1} (sysid")][-1]
    assert "navigation" in line and "landing where it is (LAND)" in line, line
    assert "holding where it stopped" in line, line
    assert line.endswith("landed (disarmed)"), line
    assert judged["kept"], judged
