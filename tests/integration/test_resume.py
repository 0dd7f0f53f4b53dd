"""A survey that ended early, carried on with ``fly --resume`` (issue 29, part 4): the
shipped field survey, one copter stopped in a lane by its pilot (BRAKE, then RTL from
its second port) while the others fly home; then ``fly --resume`` from where the least
far got. Every UAV's photos of both flights, as its camera reported them
(CAMERA_FEEDBACK, a servo camera: CAM1_TYPE 1), are the survey's: each planned photo
taken, none twice but those the resume says are taken again (the others, stopped a
moment after the one their pilot stopped, got further than it).

The emulator, or ArduPilot SITL when ARDUPILOT_SITL is set (docs/flight.md has the SITL
run).
"""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
from click.testing import CliRunner

from ftlbo_mav import clock
from ftlbo_mav.cli import main
from ftlbo_mav.flight.planned import load_planned_flight
from ftlbo_mav.flight.progress import flown, progress_from_document
from ftlbo_mav.flight.record import FlightRecord
from ftlbo_mav.mission.export import plan_missions
from ftlbo_mav.mission.photos import plan_photos
from ftlbo_mav.mission.plan_reader import read_plan
from ftlbo_mav.scenario import load_scenario
from ftlbo_mav.sim.homes import scenario_homes

from ..conftest import ROOT
from .fleet import BACKEND, vehicles
from .test_departures import OPTIONS, SecondPort, _fly_with, _upload

pytestmark = pytest.mark.sitl

SURVEY = ROOT / "missions" / "field-survey"
SPEEDUP = 1.0  # SITL in real time; the emulator on a virtual clock
STOP_AFTER_S = 56.0  # in AUTO: in lane 3, after 4-6 of its 11 photos
PHOTO_TOLERANCE_M = 2.0
"""How far a taken photo may be from where the plan puts it: the 50 Hz trigger's step,
and the turns at a lane's ends (the plan's photos follow the lane's straight line to
its exit; the copter rounds the corner there: the survey's last photo, 1.3-1.6 m off on
the emulator, is the farthest)."""


def _on_plan_photos(folder, sysids) -> list[np.ndarray]:
    """Per UAV the photos it reported while it flew ``folder``'s plan (metres ENU)."""
    planned = load_planned_flight(folder)
    log = folder / "flight"
    record = FlightRecord.from_csv((log / "flight.csv").read_text())
    record.photos = FlightRecord.photos_from_csv((log / "photos.csv").read_text())
    return [p.photos for p in flown(planned, record, sysids)]


def _in_frame(planned, enu, frame) -> np.ndarray:
    lat, lon, alt = planned.frame.to_lla(enu)
    return frame.to_enu(lat_deg=lat, lon_deg=lon, alt_m=alt).reshape(-1, 3)


def test_a_survey_stopped_in_a_lane_resumes_and_every_photo_is_taken_once(tmp_path):
    folder = tmp_path / "survey"
    shutil.copytree(SURVEY, folder)
    homes = scenario_homes(load_scenario(SURVEY.with_suffix(".toml")))
    with vehicles(3, homes=homes, speedup=SPEEDUP, virtual=True, params={"CAM1_TYPE": 1},
                  **OPTIONS) as fleet:
        _upload(folder, fleet.urls)
        pilot = SecondPort(fleet.serial1_urls[2], 3)
        try:
            def stop_in_a_lane() -> float:
                assert pilot.wait(lambda p: p.armed and p.mode == "AUTO", 120.0)
                pilot.wait(lambda p: False, STOP_AFTER_S / fleet.time_scale)
                pilot.set_mode("BRAKE")
                pilot.wait(lambda p: False, 3.0 / fleet.time_scale)
                pilot.set_mode("RTL")  # the pilot brings it home
                return clock.monotonic()

            first, _took = _fly_with(folder, fleet.urls, stop_in_a_lane)
            assert first.exit_code == 1, first.output
            assert "--resume" in first.stdout  # the user is told how to carry on
            assert pilot.wait(lambda p: not p.armed, 300.0 / fleet.time_scale + 60.0)
        finally:
            pilot.close()
        resumed = CliRunner().invoke(main, ["fly", str(folder), "--resume",
                                            "--sysid", "1..3",
                                            "--control-port", "0", "--no-keeper",
                                            "--connect", " ".join(fleet.urls)])
        print(f"[{BACKEND}] fly --resume, exit {resumed.exit_code}:\n{resumed.output}")
        assert resumed.exit_code == 0, resumed.output
    assert "resuming at lane 3" in resumed.stdout
    assert "all vehicles finished their missions" in resumed.stdout
    plan = read_plan(SURVEY)
    wanted = plan_photos(plan, plan_missions(plan))
    frame = plan.scenario.frame
    # the first flight's photos as the resume counted them (progress.json), the rest's
    first = load_planned_flight(folder)
    counted = progress_from_document(first, json.loads(
        (folder / "flight" / "progress.json").read_text()))
    rest = load_planned_flight(folder / "resume")
    rest_photos = _on_plan_photos(folder / "resume", [1, 2, 3])
    again = json.loads((folder / "resume" / "resumed.json").read_text())["again"]
    distance = plan.scenario.survey.trigger_distance_m
    for n in range(3):
        taken = np.concatenate([_in_frame(first, counted[n].photos, frame),
                                _in_frame(rest, rest_photos[n], frame)])[:, :2]
        want = wanted[n].positions[:, :2]
        print(f"uav{n + 1}: {len(counted[n].photos)} + {len(rest_photos[n])} photos, "
              f"{len(want)} planned, {again[n]} said to be taken again")
        gaps = np.hypot(*(want[:, None] - taken[None]).transpose(2, 0, 1))
        worst = int(np.argmax(gaps.min(axis=1)))
        print(f"  farthest planned photo from a taken one: #{worst + 1}, "
              f"{gaps.min(axis=1)[worst]:.2f} m")
        assert gaps.min(axis=1).max() < PHOTO_TOLERANCE_M  # every planned photo taken
        # none twice but those the resume said it would take again: a UAV stopped by
        # its pilot stops before the others are stopped for it, and the formation
        # resumes from it; the others take the photos they took past it again
        assert len(taken) == len(want) + again[n]
        apart = np.hypot(*(taken[:, None] - taken[None]).transpose(2, 0, 1))
        twice = int((np.triu(apart < distance / 2, k=1)).sum())
        assert twice == again[n]
