"""A copter as data: its release, its values and where they come from (ardupilot/copters.py)."""

from __future__ import annotations

import pytest

from ftlbo_mav.ardupilot.copters import (
    FLIGHT_PARAMS,
    PROFILES,
    ParamFileError,
    copter_of,
    defaults,
    differences,
    flight_values,
    is_tuning,
    nearest_release,
    read_param_text,
    release_for,
    resolve_copter,
)
from ftlbo_mav.ardupilot.firmware import Firmware
from ftlbo_mav.ardupilot.navigation import Navigation


def test_tuning_is_the_controllers_never_the_navigation():
    for name in ("PSC_VELXY_P", "ATC_INPUT_TC", "ANGLE_MAX", "INS_GYRO_FILTER", "MOT_SPIN_MIN"):
        assert is_tuning(name)
    for name in ("WPNAV_SPEED", "WPNAV_ACCEL", "WPNAV_RADIUS", "LAND_SPEED", "RTL_ALT"):
        assert not is_tuning(name)


def test_every_parameter_file_kind_is_read():
    mission_planner = "#NOTE: 07/12/2026 saved\nWPNAV_SPEED,500\nANGLE_MAX,2000\n"
    mavproxy = "WPNAV_SPEED 500.000000 # cm/s\n\nANGLE_MAX\t2000\n"
    qgc = "# Onboard parameters\n1\t1\tWPNAV_SPEED\t500\t9\n1\t1\tANGLE_MAX\t2000\t4\n"
    for text in (mission_planner, mavproxy, qgc):
        assert read_param_text(text, source="f") == {"WPNAV_SPEED": 500.0, "ANGLE_MAX": 2000.0}


@pytest.mark.parametrize("text, problem", [
    ("WPNAV_SPEED\n", "line 1: 'WPNAV_SPEED' is not a parameter line"),
    ("A 1\nWPNAV_SPEED fast\n", "line 2: WPNAV_SPEED: 'fast' is not a number"),
    ("WPNAV_SPEED nan\n", "line 1: WPNAV_SPEED: nan is not finite"),
])
def test_a_file_that_cannot_be_read_names_the_file_and_line(text, problem):
    with pytest.raises(ParamFileError, match=f"^solo.param, {problem}"):
        read_param_text(text, source="solo.param")


def test_values_out_of_arducopters_range_are_named():
    with pytest.raises(ValueError, match=r"solo.param: ANGLE_MAX = 9000 is outside "
                                         r"ArduCopter's range \[1000, 8000\]"):
        flight_values({"ANGLE_MAX": 9000.0}, source="solo.param")
    # a file's other parameters are left out; a scenario's unknown name is an error
    assert flight_values({"RC1_MIN": 1000.0, "WPNAV_SPEED": 300.0}, source="f") == {
        "WPNAV_SPEED": 300.0}
    with pytest.raises(ValueError, match="RC1_MIN is not a parameter the flown path"):
        flight_values({"RC1_MIN": 1000.0}, source="f", only_known=True)


def test_the_solo_profile_is_cubesolos_defaults_parm():
    solo = PROFILES["3dr-solo"].params
    # the seven values the 3DR Solo ships with that ArduCopter's defaults do not have
    assert {k: solo[k] for k in ("WPNAV_SPEED", "WPNAV_SPEED_UP", "WPNAV_SPEED_DN",
                                 "PSC_VELXY_P", "PSC_VELXY_I", "ANGLE_MAX", "ATC_INPUT_TC")} == {
        "WPNAV_SPEED": 300.0, "WPNAV_SPEED_UP": 320.0, "WPNAV_SPEED_DN": 240.0,
        "PSC_VELXY_P": 1.41, "PSC_VELXY_I": 0.51, "ANGLE_MAX": 2000.0, "ATC_INPUT_TC": 0.25}
    assert set(solo) <= set(FLIGHT_PARAMS)
    assert "CubeSolo/defaults.parm" in PROFILES["3dr-solo"].source


def test_later_sources_win_and_only_named_navigation_is_set():
    c = resolve_copter(profile="3dr-solo", file_values={"WPNAV_SPEED": 400.0},
                       file_source="mine.parm",
                       named={"WPNAV_ACCEL": 200.0, "ANGLE_MAX": 2500.0})
    assert c.params["WPNAV_SPEED"] == 400.0  # the file over the profile
    assert c.params["ATC_INPUT_TC"] == 0.25  # the profile over ArduCopter's defaults
    assert c.params["ANGLE_MAX"] == 2500.0  # named over all
    assert c.to_set() == {"WPNAV_ACCEL": 200.0}  # never ANGLE_MAX: tuning
    assert "3DR Solo" in c.source and "mine.parm" in c.source
    assert c.nav.atc_input_tc == 0.25 and c.nav.wp_speed == 4.0


def test_a_copter_as_it_is_keeps_what_the_plan_sets():
    planned = resolve_copter(named={"WPNAV_ACCEL": 200.0})
    onboard = defaults() | {"WPNAV_ACCEL": 250.0, "PSC_VELXY_P": 1.0}
    actual = planned.with_onboard(onboard, release="4.6", source="sysid 2")
    assert actual.params["WPNAV_ACCEL"] == 200.0  # upload writes it
    assert actual.params["PSC_VELXY_P"] == 1.0  # its own
    assert differences(planned, actual) == [("PSC_VELXY_P", 2.0, 1.0)]
    assert actual.release == "4.6" and actual.nav.release == "4.6"


def test_a_document_round_trips():
    c = resolve_copter(profile="3dr-solo", release="4.6", named={"WPNAV_RADIUS": 100.0})
    back = type(c).from_document(c.document())
    assert back.params == pytest.approx(c.params) and back.release == "4.6"
    assert back.to_set() == {"WPNAV_RADIUS": 100.0}
    assert copter_of(Navigation()).params == defaults()


def test_releases_by_autopilot_version():
    assert release_for(Firmware(4, 5, 6, 255).encode()) == "4.5"
    assert release_for(Firmware(4, 6, 3, 255).encode()) == "4.6"
    assert release_for(Firmware(4, 7, 0, 255).encode()) == "4.6"
    assert release_for(Firmware(4, 4, 4, 255).encode()) == "4.5"
    assert release_for(None, "4.6") == "4.6"
    assert nearest_release(5, 0) == "4.6" and nearest_release(3, 9) == "4.5"


@pytest.mark.parametrize("release, series", [("4.5.6", "4.5"), ("4.6.3", "4.6")])
def test_each_releases_defaults_are_what_its_sitl_reads_back(release, series):
    """tests/data/ardupilot-<release>/flight_params.json: the 33 flight parameters read from
    SITL started with copter.parm (4.6.3 changed PSC_VELXY_D's default, 0.5 -> 0.25)."""
    import json
    from pathlib import Path

    path = Path(__file__).parents[1] / "data" / f"ardupilot-{release}" / "flight_params.json"
    recorded = json.loads(path.read_text())["params"]
    assert set(recorded) == set(FLIGHT_PARAMS)
    assert defaults(series) == pytest.approx({k: float(v) for k, v in recorded.items()},
                                             rel=1e-6)


def test_an_emulated_copter_takes_its_releases_defaults():
    from ftlbo_mav.ardupilot.navigation import with_release

    assert with_release(Navigation(), "4.6").psc_velxy_d == 0.25
    assert with_release(Navigation(psc_velxy_d=0.3), "4.6").psc_velxy_d == 0.3  # set: kept
    assert with_release(Navigation(), "4.5").psc_velxy_d == 0.5
