"""Issue 12: writes are all or nothing. Every command that writes a folder writes it
through :class:`~ftlbo_mav.mission.files.OutputFolder`: an output that cannot be written
is one line and exit 2 with what was there untouched (checked before the work is done),
and a re-plan never leaves an earlier plan's files beside its own."""

from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

from ftlbo_mav.cli import main
from ftlbo_mav.errors import OutputError
from ftlbo_mav.mission.files import OutputFolder, write_atomic

from ..conftest import ROOT, SMALL

PLANNED = ROOT / "missions" / "nha-trang-orchard"
FAST = ["--iterations", "3", "--students", "8", "-q"]

# A row of trees across the whole area, north to south: no route, an infeasible plan.
WALL = "".join(f"[[obstacles]]\nlat = {12.23310 + k * 2e-5:.5f}\nlon = 109.1149\nradius = 2.0\n"
               for k in range(24))


def snapshot(folder: Path) -> dict[str, str]:
    if not folder.exists():
        return {}
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            if p.is_file() else "dir" for p in sorted(folder.rglob("*"))}


def commands(scenario: Path):
    """Every command that writes a folder, as argv with the output folder last."""
    return {
        "plan": ["plan", str(scenario), *FAST, "-o"],
        "plan --formats all": ["plan", str(scenario), *FAST, "--formats", "all", "-o"],
        "plan --plot": ["plan", str(scenario), *FAST, "--plot", "-o"],
        "compare": ["compare", str(scenario), "--runs", "1", "--algorithms", "ga",
                    "--iterations", "2", "--students", "8", "--processes", "1", "-q", "-o"],
        "plot": ["plot", str(PLANNED), "-o"],
    }


COMMANDS = list(commands(Path("x")))


def _target(kind: str, tmp_path: Path) -> Path:
    """An output folder that cannot be written, of each kind the issue names."""
    if kind == "a file":
        path = tmp_path / "afile"
        path.write_text("keep me\n")
        return path
    if kind == "under /proc":
        return Path("/proc/ftlbo-mav-test-output")
    if kind == "a name too long":
        return tmp_path / ("x" * 300)
    if kind == "under a file":
        (tmp_path / "afile").write_text("keep me\n")
        return tmp_path / "afile" / "out"
    # an output's own name is a folder there, beside an earlier plan's files
    out = tmp_path / "out"
    shutil.copytree(PLANNED, out)
    for name in ("uav2.waypoints", "uav1.plan", "plan-3d.png", "table.csv"):
        if (out / name).exists():
            (out / name).unlink()
        (out / name).mkdir()
    return out


KINDS = ["a file", "under /proc", "a name too long", "under a file", "an output is a folder"]


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("command", COMMANDS)
def test_an_output_that_cannot_be_written_is_one_line_exit_2_and_nothing_changed(
        command, kind, small_path, tmp_path):
    target = _target(kind, tmp_path)
    argv = commands(small_path)[command] + [str(target)]
    before = snapshot(tmp_path)
    result = CliRunner().invoke(main, argv)
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error:") and "Traceback" not in result.output
    assert snapshot(tmp_path) == before  # nothing written, nothing removed, no temp folder


def test_a_failure_while_working_leaves_the_folder_as_it_was(tmp_path):
    shutil.copytree(PLANNED, tmp_path / "out")
    before = snapshot(tmp_path)
    with pytest.raises(KeyboardInterrupt):
        with OutputFolder(tmp_path / "out", replaces=[r"uav\d+\.waypoints"]) as out:
            out.write("plan.json", "{}\n")
            raise KeyboardInterrupt  # Ctrl-C, SIGTERM, a bug
    assert snapshot(tmp_path) == before


def test_a_new_folder_appears_whole_and_only_at_the_end(tmp_path):
    with OutputFolder(tmp_path / "a" / "b") as out:
        out.write("one.txt", "1\n")
        assert not (tmp_path / "a" / "b").exists()
    assert sorted(p.name for p in (tmp_path / "a" / "b").iterdir()) == ["one.txt"]
    assert [p.name for p in (tmp_path / "a").iterdir()] == ["b"]  # no temp folder left


def test_a_single_file_that_cannot_be_written_is_an_output_error(tmp_path):
    (tmp_path / "d.waypoints").mkdir()
    for path in (tmp_path / "d.waypoints", tmp_path / ("y" * 300), Path("/proc/x.waypoints")):
        with pytest.raises(OutputError, match="nothing was written"):
            write_atomic(path, "QGC WPL 110\n")


def _plan(scenario: Path, out: Path, *extra: str):
    return CliRunner().invoke(main, ["plan", str(scenario), "-o", str(out), *FAST, *extra])


def test_a_small_plan_over_a_large_one_leaves_none_of_its_files(small_path, tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    mission = (PLANNED / "uav1.waypoints").read_text()
    for n in range(1, 201):
        (out / f"uav{n}.waypoints").write_text(mission)
        (out / f"uav{n}.plan").write_text("{}")
    (out / "plan.kml").write_text("<kml/>")
    (out / "notes.txt").write_text("mine")  # not a plan output: kept
    result = _plan(small_path, out)
    assert result.exit_code == 0, result.output
    left = sorted(p.name for p in out.iterdir() if not p.name.endswith((".fence", ".rally")))
    assert left == ["fence.parm", "notes.txt", "plan.json", "uav1.waypoints", "uav2.waypoints",
                    "uav3.waypoints"]
    assert all(p.name.startswith(("uav1.", "uav2.", "uav3.")) for p in out.iterdir()
               if p.name.endswith((".fence", ".rally")))


def test_an_infeasible_replan_removes_the_earlier_plans_missions(tmp_path):
    out = tmp_path / "out"
    shutil.copytree(PLANNED, out)
    wall = tmp_path / "wall.toml"
    wall.write_text(SMALL.replace("[planner]", WALL + "[planner]"))
    result = _plan(wall, out, "--formats", "all")
    assert result.exit_code == 1, result.output
    assert sorted(p.name for p in out.iterdir()) == ["plan.geojson", "plan.json", "plan.kml"]
    doc = json.loads((out / "plan.json").read_text())
    assert doc["feasible"] is False and all(u["mission_file"] is None for u in doc["uavs"])
    result = CliRunner().invoke(main, ["upload", str(out), "--sysid", "1..3",
                                       "--connect", "tcp:127.0.0.1:9"])
    assert result.exit_code == 2 and "infeasible" in result.stderr


def test_plan_json_names_the_digest_of_every_mission_file_it_was_written_with(small_path,
                                                                            tmp_path):
    out = tmp_path / "out"
    assert _plan(small_path, out).exit_code == 0
    doc = json.loads((out / "plan.json").read_text())
    for u in doc["uavs"]:
        data = (out / u["mission_file"]).read_bytes()
        assert u["mission_sha256"] == hashlib.sha256(data).hexdigest()
