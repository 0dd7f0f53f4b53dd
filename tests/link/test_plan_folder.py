"""Issue 12: ``upload`` (and ``fly``) refuse a folder whose ``plan.json`` is not the plan
its mission files came from: another plan's plan.json, a changed mission file, a file of
an earlier, larger plan, a plan.json too old to tell. All before any vehicle is contacted."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

from ftlbo_mav.cli import main
from ftlbo_mav.mission.plan_reader import check_plan_folder, read_plan_json

ROOT = Path(__file__).resolve().parents[2]
PLANNED = ROOT / "missions" / "nha-trang-orchard"
OTHER = ROOT / "missions" / "orchard-survey"


def _another_plans_json(folder: Path) -> None:
    shutil.copy(OTHER / "plan.json", folder / "plan.json")


def _a_changed_mission(folder: Path) -> None:
    path = folder / "uav2.waypoints"
    text = path.read_text()
    assert "\t3.000000\t" in text
    path.write_text(text.replace("\t3.000000\t", "\t3.500000\t", 1))


def _a_stale_fourth_uav(folder: Path) -> None:
    shutil.copy(folder / "uav1.waypoints", folder / "uav4.waypoints")


def _an_old_plan_json(folder: Path) -> None:
    doc = json.loads((folder / "plan.json").read_text())
    for u in doc["uavs"]:
        del u["mission_sha256"]
    (folder / "plan.json").write_text(json.dumps(doc))


def _missions_of_another_plan(folder: Path) -> None:
    for n in (1, 2, 3):
        shutil.copy(OTHER / f"uav{n}.waypoints", folder / f"uav{n}.waypoints")


MIXES = {"another plan's plan.json": (_another_plans_json, "SHA-256 differs"),
         "a changed mission file": (_a_changed_mission, "uav2.waypoints: not the mission"),
         "a stale uav4.waypoints": (_a_stale_fourth_uav, "uav4.waypoints: not a mission"),
         "a plan.json without digests": (_an_old_plan_json, "older ftlbo-mav"),
         "the missions of another plan": (_missions_of_another_plan, "SHA-256 differs")}


@pytest.fixture
def folder(tmp_path) -> Path:
    shutil.copytree(PLANNED, tmp_path / "plan")
    return tmp_path / "plan"


def test_the_shipped_plan_folders_hold_their_own_missions():
    for planned in (PLANNED, OTHER):
        doc, source = read_plan_json(planned)
        assert [p.name for p in check_plan_folder(planned, doc, source=source)] == [
            "uav1.waypoints", "uav2.waypoints", "uav3.waypoints"]


@pytest.mark.parametrize("command", ["upload", "fly"])
@pytest.mark.parametrize("mix", list(MIXES))
def test_a_folder_that_mixes_two_plans_is_refused_before_any_vehicle(command, mix, folder):
    make, words = MIXES[mix]
    make(folder)
    result = CliRunner().invoke(main, [command, str(folder), "--sysid", "1..3",
                                       "--connect", "tcp:127.0.0.1:9"])
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and words in lines[0], lines
    assert "cannot connect" not in result.output  # refused before any link was opened
