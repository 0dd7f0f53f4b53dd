"""The fleet in a scenario: ``[vehicle]`` for every copter, ``[vehicle.uavN]`` for one, from
a profile, a saved parameter file or values by name; each UAV's flight predicted with
its own copter, and plan.json saying which (issue 49)."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from ftlbo_mav.cli import main
from ftlbo_mav.errors import ScenarioError
from ftlbo_mav.scenario import load_scenario, parse_scenario


def _scenario(tmp_path, small_text: str, vehicle: str, files: dict[str, str] | None = None):
    for name, text in (files or {}).items():
        (tmp_path / name).write_text(text)
    path = tmp_path / "s.toml"
    path.write_text(small_text + vehicle)
    return path


def test_one_copter_of_the_fleet_is_a_solo(tmp_path, small_text):
    s = load_scenario(_scenario(tmp_path, small_text, '[vehicle]\nWPNAV_ACCEL = 200\n'
                                '[vehicle.uav2]\nprofile = "3dr-solo"\n'))
    fleet = s.fleet()
    assert [c.params["ATC_INPUT_TC"] for c in fleet] == [0.15, 0.25, 0.15]
    assert all(c.params["WPNAV_ACCEL"] == 200.0 for c in fleet)  # [vehicle] for all
    assert [c.to_set() for c in fleet] == [{"WPNAV_ACCEL": 200.0}] * 3
    assert "3DR Solo" in fleet[1].source and "3DR Solo" not in fleet[0].source


def test_a_parameter_file_saved_from_the_copter_is_read(tmp_path, small_text):
    files = {"uav3.param": "#NOTE: saved by Mission Planner\nANGLE_MAX,2500\nRC1_MIN,1000\n"
                           "PSC_VELXY_P,1.5\n"}
    s = load_scenario(_scenario(tmp_path, small_text,
                                '[vehicle.uav3]\nparams_file = "uav3.param"\nfirmware = "4.6"\n',
                                files))
    c = s.fleet()[2]
    assert (c.params["ANGLE_MAX"], c.params["PSC_VELXY_P"], c.release) == (2500.0, 1.5, "4.6")
    assert c.to_set() == {}  # a file describes the copter; nothing of it is written
    assert "uav3.param" in c.source


@pytest.mark.parametrize("vehicle, files, said", [
    ('[vehicle]\nparams_file = "none.param"\n', {}, r"vehicle\.params_file: .*none\.param: "
                                                   "no such file"),
    ('[vehicle]\nparams_file = "bad.param"\n', {"bad.param": "ANGLE_MAX\n"},
     r"vehicle\.params_file: .*bad\.param, line 1: 'ANGLE_MAX' is not a parameter line"),
    ('[vehicle]\nparams_file = "far.param"\n', {"far.param": "ANGLE_MAX 9000\n"},
     r"far\.param: ANGLE_MAX = 9000 is outside ArduCopter's range"),
    ('[vehicle.uav4]\nprofile = "3dr-solo"\n', {}, r"vehicle\.uav4: names no UAV of this "
                                                   r"formation \(uav1\.\.uav3\)"),
    ('[vehicle]\nprofile = "dji"\n', {}, r"vehicle\.profile: must be one of arducopter, "
                                         "3dr-solo"),
    ('[vehicle]\nfirmware = "4.7"\n', {}, r"vehicle\.firmware: must be one of 4\.5, 4\.6"),
    ('[vehicle.uav1]\nWPNAV_SPEDE = 5\n', {}, r"vehicle\.uav1\.WPNAV_SPEDE: unknown key"),
])
def test_bad_fleet_input_is_one_line_naming_file_and_field(tmp_path, small_text, vehicle,
                                                           files, said):
    path = _scenario(tmp_path, small_text, vehicle, files)
    with pytest.raises(ScenarioError, match=said):
        load_scenario(path)
    result = CliRunner().invoke(main, ["plan", str(path), "-o", str(tmp_path / "out"), "-q"])
    assert result.exit_code == 2 and len(result.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def test_plan_json_says_each_uavs_copter_and_what_upload_sets(tmp_path, small_text):
    path = _scenario(tmp_path, small_text,
                     '[vehicle]\nWPNAV_RADIUS = 150\n[vehicle.uav2]\nfirmware = "4.6"\n')
    result = CliRunner().invoke(main, ["plan", str(path), "-o", str(tmp_path / "out"), "-q",
                                       "--allow-infeasible"])
    assert result.exit_code == 0, result.output
    doc = json.loads((tmp_path / "out" / "plan.json").read_text())
    copters = [u["vehicle"] for u in doc["uavs"]]
    assert [c["release"] for c in copters] == ["4.5", "4.6", "4.5"]
    assert all(c["set"] == {"WPNAV_RADIUS": 150.0} for c in copters)
    assert copters[0]["params"]["ANGLE_MAX"] == 3000.0


def test_copters_that_fly_apart_are_said_at_plan_time(tmp_path, small_text):
    """A Solo among two default copters: without a [mission] speed each flies its own
    WPNAV_SPEED (the Solo 3 m/s, the others 10), and the Solo falls behind; the plan says
    which UAVs, how far and when, as a note (fly's formation keeper waits for it). Three
    Solos fly alike."""
    from ftlbo_mav.planning.planner import plan
    from ftlbo_mav.planning.repair import fleet_lags

    solo_two = '[vehicle.uav2]\nprofile = "3dr-solo"\n'
    apart = fleet_lags(plan(parse_scenario(small_text + solo_two)))
    alike = fleet_lags(plan(parse_scenario(small_text + '[vehicle]\nprofile = "3dr-solo"\n')))
    assert apart and all(v.startswith("UAV ") and "from its slot" in v for v in apart)
    assert alike == []
    path = _scenario(tmp_path, small_text, solo_two)
    result = CliRunner().invoke(main, ["plan", str(path), "-o", str(tmp_path / "out"), "-q",
                                       "--allow-infeasible"])
    assert result.exit_code == 1, result.output  # written, infeasible: 1.91 m apart
    assert "note: UAV 2 is predicted 15.14 m from its slot" in result.stderr
