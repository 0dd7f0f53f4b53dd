"""``fly --resume`` before any vehicle is contacted: what it carries on from, and the
refusals (flight/resume.py, flight/commands.py). The flight itself: tests/integration/
test_resume.py."""

from __future__ import annotations

import json
import shutil

import pytest
from click.testing import CliRunner

from ftlbo_mav.cli import main
from ftlbo_mav.flight.planned import load_planned_flight
from ftlbo_mav.flight.progress import UavProgress, progress_document
from ftlbo_mav.flight.resume import plan_rest
from ftlbo_mav.planning.resume import NothingToResume

from ..conftest import ROOT

# nothing listens here: a command that got as far as the vehicles would fail to connect
NOWHERE = "tcp:127.0.0.1:9"


@pytest.fixture
def survey(tmp_path):
    folder = tmp_path / "survey"
    shutil.copytree(ROOT / "missions" / "field-survey", folder)
    return folder


def _progress(folder, points):
    planned = load_planned_flight(folder)
    (folder / "flight").mkdir(exist_ok=True)
    doc = progress_document(planned, [UavProgress(n, p, None, None)
                                      for n, p in zip(planned.names, points)])
    path = folder / "flight" / "progress.json"
    path.write_text(json.dumps(doc))
    return planned, path


def _fly(*args):
    return CliRunner().invoke(main, ["fly", *map(str, args), "--sysid", "1..3",
                                     "--connect", NOWHERE, "--discover-timeout", "0.2"])


def test_without_a_flight_before_there_is_nothing_to_resume_from(survey):
    result = _fly(survey, "--resume")
    assert result.exit_code == 2
    assert "progress.json: no such file" in result.output
    assert not (survey / "resume").exists()


def test_a_plan_flown_to_its_goal_is_not_flown_again(survey):
    _progress(survey, [26.0, 26.0, 26.0])
    result = _fly(survey, "--resume")
    assert result.exit_code == 0, result.output
    assert "flown to its end, nothing to resume" in result.output


def test_progress_without_resume_is_refused(survey):
    result = _fly(survey, "--progress", survey / "x.json")
    assert result.exit_code == 2 and "--resume" in result.output


def test_the_progress_of_another_plan_is_refused(survey, tmp_path):
    _progress(survey, [3.0, 3.0, 3.0])
    other = tmp_path / "progress.json"
    doc = json.loads((survey / "flight" / "progress.json").read_text())
    doc["uavs"][0]["points"] = 12
    other.write_text(json.dumps(doc))
    result = _fly(survey, "--resume", "--progress", other)
    assert result.exit_code == 2 and "not the progress of a flight of" in result.output


def test_the_rest_is_a_plan_folder_that_says_what_it_carries_on_from(survey):
    planned, path = _progress(survey, [11.3, 11.4, 11.2])
    rest = plan_rest(planned, path)
    assert rest.folder == survey / "resume" and rest.at.lane == 2
    resumed = json.loads((rest.folder / "resumed.json").read_text())
    assert resumed["lane"] == 3 and resumed["flown_to"]["uav3"] == 11.2
    assert load_planned_flight(rest.folder).count == 3  # flown as any plan
    doc = json.loads((rest.folder / "plan.json").read_text())
    assert doc["mission"] == {"end_action": "land", "speed": 5.0}  # from the missions
    with pytest.raises(NothingToResume):
        plan_rest(planned, _progress(survey, [26.0] * 3)[1])


def test_a_swarm_the_link_cannot_carry_is_refused_before_any_vehicle(survey):
    result = CliRunner().invoke(main, ["fly", str(survey), "--sysid", "1..3", "--link", "500",
                                       "--connect", NOWHERE, "--discover-timeout", "0.2"])
    assert result.exit_code == 2
    assert "the link cannot carry this swarm" in result.output
    assert "at most 1 copter(s) fit" in result.output
    bad = CliRunner().invoke(main, ["fly", str(survey), "--sysid", "1..3", "--link", "fast",
                                    "--connect", NOWHERE])
    assert bad.exit_code == 2 and "sik-64" in bad.output
