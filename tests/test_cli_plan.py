"""`ftlbo-mav plan`: files, plan.json, summary, infeasible plans."""

from __future__ import annotations

import json

import numpy as np
from click.testing import CliRunner
from pymavlink import mavwp

from ftlbo_mav.cli import main
from ftlbo_mav.mission.waypoints import read_waypoints
from ftlbo_mav.scenario import parse_scenario

from .conftest import SMALL

PLAN_KEYS = {"algorithm", "seed", "feasible", "violations", "cost", "seconds", "evaluations",
             "history", "centroid", "uavs"}


def test_plan_writes_one_mission_per_uav_and_plan_json(small_path, tmp_path):
    out = tmp_path / "out"
    result = CliRunner().invoke(
        main, ["plan", str(small_path), "-o", str(out), "--seed", "3", "--iterations", "6",
               "--students", "10"])
    assert result.exit_code == 0, result.output
    assert "feasible" in result.stdout and "length" in result.stdout
    assert "planning" in result.stderr  # progress on stderr
    doc = json.loads((out / "plan.json").read_text())
    assert PLAN_KEYS <= set(doc)
    assert doc["seed"] == 3 and doc["feasible"] is True and doc["violations"] == []
    assert set(doc["cost"]) == {"total", "length", "safety", "task"}
    assert len(doc["history"]) == 6 and doc["evaluations"] == 10 + 6 * 21
    assert len(doc["centroid"]) == 4 + 2  # start, 4 waypoints, goal
    assert [u["name"] for u in doc["uavs"]] == ["uav1", "uav2", "uav3"]

    scenario = parse_scenario(small_path.read_text())
    for n, uav in enumerate(doc["uavs"]):
        file = out / uav["mission_file"]
        items = read_waypoints(file)
        assert mavwp.MAVWPLoader().load(str(file)) == len(items)
        # home, takeoff, start, its gate, 4 waypoints, goal, land
        assert len(items) == 1 + 1 + 1 + 6 + 1 and items[3].name == "DELAY"
        flown = [(i.lat_deg, i.lon_deg, i.alt_m) for i in items[2:-1] if i.name != "DELAY"]
        listed = [(p["lat"], p["lon"], p["alt"]) for p in uav["waypoints"]]
        assert np.allclose(flown, listed, atol=1e-6)
        # the UAV's first point is the centroid start plus its offset
        start = scenario.start_enu() + scenario.offsets_m[n]
        enu = scenario.frame.to_enu(lat_deg=flown[0][0], lon_deg=flown[0][1], alt_m=flown[0][2])
        assert np.allclose(enu, start, atol=1e-3)
        assert items[1].alt_m == flown[0][2]  # takes off to its start altitude


WALL = "\n".join(
    f"[[obstacles]]\nlat = {12.2331044 + k * 0.00008:.7f}\nlon = 109.11485\nradius = 5.0\n"
    for k in range(7)
)


def test_infeasible_plan_writes_plan_json_only_and_exits_1(tmp_path):
    scenario = tmp_path / "wall.toml"
    scenario.write_text(SMALL.split("[[obstacles]]")[0] + WALL + "\n[planner]\nstudents = 8\n"
                        "waypoints = 3\niterations = 3\n")
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["plan", str(scenario), "-o", str(out)])
    assert result.exit_code == 1
    assert "INFEASIBLE" in result.stdout and "no mission files written" in result.stderr
    doc = json.loads((out / "plan.json").read_text())
    assert doc["feasible"] is False and doc["violations"]
    assert doc["cost"]["total"] is None  # infinite cost: null in JSON
    assert not list(out.glob("*.waypoints"))

    again = CliRunner().invoke(main, ["plan", str(scenario), "-o", str(out), "--allow-infeasible"])
    assert again.exit_code == 1
    assert sorted(p.name for p in out.glob("*.waypoints")) == [
        "uav1.waypoints", "uav2.waypoints", "uav3.waypoints"]
    assert json.loads((out / "plan.json").read_text())["uavs"][0]["mission_file"]


def test_shipped_example_missions_match_their_plan(example_path):
    folder = example_path.with_suffix("")
    doc = json.loads((folder / "plan.json").read_text())
    assert doc["feasible"] is True
    for uav in doc["uavs"]:
        items = read_waypoints(folder / uav["mission_file"])
        flown = [(i.lat_deg, i.lon_deg, i.alt_m) for i in items if i.command == 16][1:]
        listed = [(p["lat"], p["lon"], p["alt"]) for p in uav["waypoints"]]
        assert np.allclose(flown, listed, atol=1e-6)


def test_a_large_swarm_says_what_it_wrote_in_a_line_per_kind(capsys, tmp_path):
    from pathlib import Path

    from ftlbo_mav.cli_plan import _say_written

    paths = [tmp_path / f"uav{n}{s}" for s in (".waypoints", ".fence") for n in range(1, 51)]
    _say_written(paths + [tmp_path / "plan.json"])
    assert capsys.readouterr().out.splitlines() == [
        f"  wrote 50 files uav1.waypoints .. uav50.waypoints in {tmp_path}",
        f"  wrote 50 files uav1.fence .. uav50.fence in {tmp_path}",
        f"  wrote plan.json in {tmp_path}"]
    _say_written([Path("a/uav1.waypoints")])
    assert capsys.readouterr().out == "  wrote a/uav1.waypoints\n"
