"""How far a flight got along its plan, read from its record (flight/progress.py), on the
shipped field survey's missions."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ftlbo_mav.flight.planned import load_planned_flight
from ftlbo_mav.flight.progress import (
    flown,
    progress_document,
    progress_from_document,
    targets,
)
from ftlbo_mav.flight.record import FlightRecord, Photo, Sample
from ftlbo_mav.mission.items import CMD_NAV_LAND

from ..conftest import ROOT


@pytest.fixture(scope="module")
def planned():
    return load_planned_flight(ROOT / "missions" / "field-survey")


def test_every_item_leads_to_the_path_point_its_leg_flies_to(planned):
    mission = planned.missions[0]
    points = planned.paths.shape[1]
    legs = targets(mission, points)
    waypoints = [it.seq for it in mission[2:] if it.command == 16]
    assert [legs[s] for s in waypoints] == list(range(points))
    assert legs[3] == 1  # the DO_CHANGE_SPEED after the start point: on the way to point 1
    land = next(it.seq for it in mission if it.command == CMD_NAV_LAND)
    assert legs[land] == points  # past the goal
    assert 0 not in legs and 1 not in legs  # home and the take-off are not on the path


def _seq_to(mission, point: int) -> int:
    return next(it.seq for it in mission[2:] if it.command == 16 and
                targets(mission, 10_000)[it.seq] == point)


def _record(planned, rows):
    """Samples of uav1 (sysid 1) from ``rows`` of (t, point k + f, mode, seq or None)."""
    path, frame = planned.paths[0], planned.frame
    out = []
    for t, point, mode, seq in rows:
        k = min(int(np.floor(point)), len(path) - 2)
        here = path[k] + (point - k) * (path[k + 1] - path[k])
        lat, lon, alt = frame.to_lla(here)
        if seq is None:
            seq = _seq_to(planned.missions[0], k + 1)
        out.append(Sample(t, 1, float(lat), float(lon), float(alt), mode, True,
                          seq if mode == "AUTO" else -1))
    return FlightRecord(out)


def test_progress_is_the_furthest_point_flown_in_auto_until_it_left_auto(planned):
    record = _record(planned, [(0.0, 0.0, "GUIDED", None), (1.0, 0.4, "AUTO", None),
                               (2.0, 3.25, "AUTO", None), (3.0, 3.5, "AUTO", None),
                               (3.5, 3.5, "BRAKE", None), (4.0, 9.0, "AUTO", None)])
    [p] = flown(planned, record, [1])
    assert p.point == pytest.approx(3.5, abs=1e-3) and p.until_s == 3.0
    assert p.photos is None  # it reported no photo at all


def test_a_way_home_started_before_a_report_came_is_not_the_plan(planned):
    # AUTO throughout: the way home's mission starts at item 1, an item before the last
    record = _record(planned, [(1.0, 2.5, "AUTO", None), (2.0, 4.2, "AUTO", None),
                               (2.1, 4.3, "AUTO", 1), (2.2, 8.0, "AUTO", 4)])
    [p] = flown(planned, record, [1])
    assert p.point == pytest.approx(4.2, abs=1e-3) and p.until_s == 2.0


def test_photos_after_it_left_the_plan_are_not_the_plans(planned):
    record = _record(planned, [(1.0, 2.5, "AUTO", None), (2.0, 3.2, "AUTO", None),
                               (3.0, 3.2, "RTL", None)])
    for t in (1.5, 2.3, 3.0, 4.0):  # after the RTL report: on its way home, camera on
        record.add_photo(Photo(t, 1, 12.2341, 109.1161, 22.0, 0))
    [p] = flown(planned, record, [1])
    assert len(p.photos) == 2  # those that came before the report that it had left


def test_progress_json_reads_back_and_belongs_to_its_plan(planned, tmp_path):
    record = _record(planned, [(1.0, 5.5, "AUTO", None)])
    record.add_photo(Photo(0.9, 1, 12.2342, 109.11603, 22.0, 7))
    progress = flown(planned, record, [1, 2, 3])
    doc = json.loads(json.dumps(progress_document(planned, progress)))
    back = progress_from_document(planned, doc)
    assert [b.point for b in back] == pytest.approx([5.5, 0.0, 0.0], abs=1e-3)
    assert back[0].photos.shape == (1, 3) and back[1].photos is None
    assert np.allclose(back[0].photos, progress[0].photos, atol=1e-3)
    other = dict(doc, uavs=doc["uavs"][:2])
    with pytest.raises(ValueError, match="the plan flies uav1, uav2, uav3"):
        progress_from_document(planned, other)
    doc["uavs"][0]["point"] = 99.0
    with pytest.raises(ValueError, match="not on its path"):
        progress_from_document(planned, doc)
