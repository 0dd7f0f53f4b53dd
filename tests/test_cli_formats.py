"""`ftlbo-mav plan --formats/--plot` and `ftlbo-mav plot FOLDER`."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from dataclasses import replace

import numpy as np
from click.testing import CliRunner

from ftlbo_mav.cli import main
from ftlbo_mav.mission.plan_reader import read_plan
from ftlbo_mav.mission.qgc_plan import read_plan_file
from ftlbo_mav.mission.waypoints import read_waypoints
from ftlbo_mav.plots import FIGURES

from .conftest import SMALL

FAST = ["--algorithm", "ftlbo", "--seed", "3", "--iterations", "5", "--students", "12", "-q"]
UAVS = ("uav1", "uav2", "uav3")


def _plan(scenario, out, *extra):
    return CliRunner().invoke(main, ["plan", str(scenario), "-o", str(out), *FAST, *extra])


def test_formats_all_and_plot_write_everything_next_to_the_waypoints(small_path, tmp_path):
    out = tmp_path / "out"
    result = _plan(small_path, out, "--formats", "all", "--plot")
    assert result.exit_code == 0, result.output
    names = {p.name for p in out.iterdir()}
    fence = {f"{u}.{ext}" for u in UAVS for ext in ("fence", "rally")} | {"fence.parm"}
    assert names == ({f"{u}.waypoints" for u in UAVS} | {f"{u}.plan" for u in UAVS} | fence
                     | {"plan.json", "plan.geojson", "plan.kml"} | set(FIGURES))
    for name in names:
        assert f"wrote {out / name}" in result.stdout
    json.loads((out / "plan.geojson").read_text())
    ET.parse(out / "plan.kml")
    for u in UAVS:  # the .plan holds the .waypoints' items (which carry 8 decimals)
        plan_items = read_plan_file(out / f"{u}.plan")
        waypoints = read_waypoints(out / f"{u}.waypoints")
        assert [replace(i, lat_deg=0, lon_deg=0, alt_m=0) for i in plan_items] == [
            replace(i, lat_deg=0, lon_deg=0, alt_m=0) for i in waypoints]
        assert np.allclose([(i.lat_deg, i.lon_deg) for i in plan_items],
                           [(i.lat_deg, i.lon_deg) for i in waypoints], atol=1e-7)
        assert np.allclose([i.alt_m for i in plan_items], [i.alt_m for i in waypoints],
                           atol=1e-5)


def test_formats_subset_and_default(small_path, tmp_path):
    out = tmp_path / "some"
    assert _plan(small_path, out, "--formats", "kml, geojson").exit_code == 0
    assert {"plan.kml", "plan.geojson"} <= {p.name for p in out.iterdir()}
    assert not list(out.glob("*.plan")) and not list(out.glob("*.png"))
    plain = tmp_path / "plain"
    assert _plan(small_path, plain).exit_code == 0
    assert sorted(p.suffix for p in plain.iterdir()) == sorted(
        [".json", ".parm"] + [".waypoints", ".fence", ".rally"] * 3)
    bare = tmp_path / "bare"
    assert _plan(small_path, bare, "--no-fence").exit_code == 0
    assert sorted(p.suffix for p in bare.iterdir()) == [".json"] + [".waypoints"] * 3


def test_unknown_format_is_a_usage_error(small_path, tmp_path):
    result = _plan(small_path, tmp_path / "x", "--formats", "geojson,shp")
    assert result.exit_code == 2
    assert "unknown format 'shp'" in result.output
    assert not (tmp_path / "x").exists()


def test_formats_all_beside_other_names_is_every_format(small_path, tmp_path):
    everything = tmp_path / "all"
    assert _plan(small_path, everything, "--formats", "all").exit_code == 0
    for value in ("all,kml", "kml, ALL"):
        out = tmp_path / value.replace(",", "_").replace(" ", "")
        result = _plan(small_path, out, "--formats", value)
        assert result.exit_code == 0, result.output
        assert sorted(p.name for p in out.iterdir()) == sorted(
            p.name for p in everything.iterdir())
    result = _plan(small_path, tmp_path / "x", "--formats", "all,shp")
    assert result.exit_code == 2 and "unknown format 'shp'" in result.output
    assert not (tmp_path / "x").exists()


def test_infeasible_plan_gets_gis_files_but_no_plan_files(tmp_path):
    wall = "".join(
        f"[[obstacles]]\nlat = {12.2331044 + k * 0.00008:.7f}\nlon = 109.11485\nradius = 5.0\n"
        for k in range(7))
    scenario = tmp_path / "wall.toml"
    scenario.write_text(SMALL.split("[[obstacles]]")[0] + wall)
    out = tmp_path / "out"
    result = _plan(scenario, out, "--formats", "all", "--plot")
    assert result.exit_code == 1
    names = {p.name for p in out.iterdir()}
    assert {"plan.geojson", "plan.kml", "plan.json"} | set(FIGURES) <= names
    assert not list(out.glob("*.plan")) and not list(out.glob("*.waypoints"))
    doc = json.loads((out / "plan.geojson").read_text())
    paths = [f for f in doc["features"] if f["properties"]["kind"] == "uav_path"]
    assert paths and all(f["properties"]["feasible"] is False for f in paths)


def test_plot_folder_redraws_the_plan_from_plan_json(small_path, tmp_path):
    out = tmp_path / "out"
    assert _plan(small_path, out).exit_code == 0
    figures = tmp_path / "figures"
    result = CliRunner().invoke(main, ["plot", str(out), "-o", str(figures)])
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in figures.iterdir()) == sorted(FIGURES)
    # what is drawn is what was written
    p = read_plan(out)
    doc = json.loads((out / "plan.json").read_text())
    assert np.allclose(p.lla(p.uav_paths[1])[:, :2],
                       [[w["lat"], w["lon"]] for w in doc["uavs"][1]["waypoints"]], atol=1e-7)
    assert len(p.scenario.obstacles) == 1 and p.scenario.clearance_m == 1.0


def test_plot_shipped_example(example_path, tmp_path):
    result = CliRunner().invoke(main, ["plot", str(example_path.with_suffix("")),
                                       "-o", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert len(list(tmp_path.glob("*.png"))) == len(FIGURES)


def test_plot_without_a_plan_is_one_line_error(tmp_path):
    result = CliRunner().invoke(main, ["plot", str(tmp_path)])
    assert result.exit_code == 2  # a bad plan folder is bad input
    assert result.stderr.strip().splitlines() == [
        f"error: {tmp_path / 'plan.json'}: no such file (run `ftlbo-mav plan` first)"]
    (tmp_path / "plan.json").write_text('{"seed": 1}')
    result = CliRunner().invoke(main, ["plot", str(tmp_path)])
    assert result.exit_code == 2 and "not a plan.json" in result.stderr
    assert "Traceback" not in result.output
