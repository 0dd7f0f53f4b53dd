"""``ftlbo-mav risk`` flies the plan on a two-worker local Dask cluster, each flight as
``fly`` flies it, and leaves nothing behind; one flight judged by the true positions.

On the emulator (the flights of ``risk`` always are)."""

from __future__ import annotations

import json
import shutil
import tempfile
from pathlib import Path

import pytest
from click.testing import CliRunner

from ftlbo_mav.cli import main
from ftlbo_mav.flight.planned import load_planned_flight
from ftlbo_mav.risk.conditions import Ranges, draw
from ftlbo_mav.risk.flight import fly_one

from ..conftest import EXAMPLE

pytestmark = pytest.mark.solo  # two workers flying: run alone, after the rest (pyproject)


@pytest.fixture(scope="module")
def plan_dir(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("risk") / "plan"
    shutil.copytree(EXAMPLE.with_suffix(""), folder)
    return folder


def _leftovers() -> set[str]:
    return {p.name for p in Path(tempfile.gettempdir()).glob("ftlbo-risk-*")}


def test_risk_flies_on_a_local_dask_cluster_and_reports_each_flight(plan_dir, tmp_path):
    before = sorted(p.name for p in plan_dir.rglob("*"))
    leftovers = _leftovers()
    result = CliRunner().invoke(main, ["risk", str(plan_dir), "--flights", "2", "--workers",
                                       "2", "--lost-rate", "1", "-o", str(tmp_path / "out")])
    assert result.exit_code == 0, result.output
    doc = json.loads((tmp_path / "out" / "risk.json").read_text())
    flights = doc["flights"]
    assert [f["seed"] for f in flights] == [0, 1]
    ranges = Ranges(lost_rate=1.0).with_budget(load_planned_flight(plan_dir).navigation
                                               .horizontal_m)
    for f in flights:
        # the conditions are the seed's; each flight lost its copter and fly said so
        c = draw(ranges, f["seed"], 3)
        assert f["conditions"]["wind_m_s"] == c.wind[0]
        assert f["conditions"]["lost"]["uav"] == f"uav{c.lost[0] + 1}"
        assert f["outcome"] == "left the plan", f
        assert any(f"{f['conditions']['lost']['uav']} (sysid" in d and "link lost" in d
                   for d in f["departures"]), f["departures"]
        assert f["true_min_clearance_m"] is not None
    assert len({f["worker_pid"] for f in flights}) == 2  # one flight on each worker
    left = next(p for p in doc["summary"]["probabilities"] if p["what"].startswith("left"))
    assert left["events"] == 2 and left["ci95"][0] > 0.15
    assert (tmp_path / "out" / "risk.png").exists() and "2 of 2 flights" in result.output
    assert sorted(p.name for p in plan_dir.rglob("*")) == before  # the plan untouched
    assert _leftovers() <= leftovers  # every flight's folders removed


def test_one_flight_in_calm_air_completes_and_keeps_its_predicted_clearance(plan_dir):
    planned = load_planned_flight(plan_dir)
    calm = Ranges(wind_max_m_s=0.0, turbulence_max_m_s=0.0, gps_wander_m=0.0, vary=False)
    record = fly_one(plan_dir, draw(calm, 5, planned.count))
    assert record["outcome"] == "completed", record
    predicted = min(planned.predicted_clearance)
    # GPS exact: where the copters truly were is where they reported (flight/report.py)
    assert record["true_min_clearance_m"] == pytest.approx(predicted, abs=0.1)
    assert record["true_min_separation_m"] > planned.min_separation_m
    assert record["formation_error_max_m"] < 0.3 and record["flight_s"] > 20


def test_a_scheduler_and_local_workers_together_are_refused(plan_dir):
    result = CliRunner().invoke(main, ["risk", str(plan_dir), "--scheduler",
                                       "tcp://127.0.0.1:1", "--workers", "2"])
    assert result.exit_code == 2 and "--workers is for the local cluster" in result.output


def test_a_replayed_flight_with_a_mode_taken_over_shows_fly_and_ends_as_fly(plan_dir):
    """``--replay SEED`` flies that seed's conditions once with fly's live view; the copter
    taken over is a departure, left alone, and the exit code is fly's."""
    calm = ["--wind-max", "0", "--turbulence-max", "0", "--gps-wander", "0", "--no-vary"]
    result = CliRunner().invoke(main, ["risk", str(plan_dir), "--replay", "3",
                                       "--takeover-rate", "1", *calm])
    planned = load_planned_flight(plan_dir)
    conditions = draw(Ranges(wind_max_m_s=0.0, turbulence_max_m_s=0.0, gps_wander_m=0.0,
                             vary=False, takeover_rate=1.0), 3, planned.count)
    who = f"uav{conditions.takeover[0] + 1}"
    out = result.output
    assert result.exit_code == 1, out
    assert "replaying seed 3: wind 0.0 m/s" in out and f"{who} taken over" in out
    assert "pre-flight: firmware, missions, GPS, pre-arm checks" in out  # fly's own view
    assert f"{who} (sysid {conditions.takeover[0] + 1}): mode: switched to BRAKE" in out
    assert "left to what it chose: not commanded" in out
    record = json.loads(out[out.index("{\n"):])
    assert record["outcome"] == "left the plan" and record["seed"] == 3
    assert record["conditions"]["takeover"]["uav"] == who


def test_a_seed_flies_the_same_flight_every_time(plan_dir):
    """On the simulated clock the ground's timing is part of the flight, not of the
    machine: wind, gusts, GPS wander and fleet variation drawn from one seed give the same
    figures each time, however busy the machine is."""
    planned = load_planned_flight(plan_dir)
    conditions = draw(Ranges().with_budget(planned.navigation.horizontal_m), 2, planned.count)
    first, again = fly_one(plan_dir, conditions), fly_one(plan_dir, conditions)
    for record in (first, again):
        assert record["outcome"] == "completed", record
        del record["wall_s"]
    assert first == again
    assert first["simulated_s"] > first["flight_s"] > 20  # upload, pre-flight, flight
