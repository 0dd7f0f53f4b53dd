"""What many flights say together, and one flight judged by its true positions."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ftlbo_mav.flight.planned import load_planned_flight
from ftlbo_mav.risk.conditions import Ranges
from ftlbo_mav.risk.flight import judge
from ftlbo_mav.risk.report import summarize, write_report

from ..conftest import EXAMPLE


def _flight(seed, clearance, separation, outcome="completed", formation=0.1):
    return {"seed": seed, "exit_code": 0 if outcome == "completed" else 1,
            "outcome": outcome, "true_min_clearance_m": clearance,
            "true_min_separation_m": separation, "formation_error_rms_m": formation / 2,
            "formation_error_max_m": formation, "flight_s": 40.0,
            "landing_error_max_m": 0.1, "departures": []}


RECORDS = [_flight(0, 1.4, 3.0), _flight(1, -0.2, 2.9, "left the plan", 1.2),
           _flight(2, 0.4, 1.5, "left the plan", 0.8), _flight(3, 1.1, 2.95),
           {"seed": 4, "exit_code": None, "outcome": "not flown (upload failed)"}]


def test_the_summary_counts_each_event_over_the_flights_that_flew():
    s = summarize(RECORDS, planned_clearance_m=1.0, min_separation_m=2.0)
    assert (s["flights"], s["flown"], s["not_flown"]) == (5, 4, 1)
    events = {p["what"].split(" (")[0]: p["events"] for p in s["probabilities"]}
    assert events == {"true clearance below 0": 1, "true clearance below half the plan's": 2,
                      "separation below min_separation": 1, "left the plan": 2,
                      "did not complete": 2}
    assert all(p["flights"] == 4 for p in s["probabilities"])
    assert s["worst_clearance_seeds"][:2] == [1, 2]
    assert s["worst_formation_seeds"][0] == 1
    assert s["true_min_clearance_m"]["min"] == -0.2


def test_the_report_is_written_as_json_markdown_and_figure(tmp_path):
    paths = write_report(tmp_path, EXAMPLE.with_suffix(""), RECORDS, Ranges(gps_wander_m=0.1),
                         planned_clearance_m=1.0, min_separation_m=2.0, time_scale=4.0,
                         engine="Dask local cluster", wall_s=12.0)
    assert [p.name for p in paths] == ["risk.json", "risk.md", "risk.png"]
    doc = json.loads(paths[0].read_text())
    assert len(doc["flights"]) == 5 and doc["summary"]["flown"] == 4
    assert "emulator" in doc["simulator"] and "Against ArduCopter 4.5.6 SITL" in doc["simulator"]
    md = paths[1].read_text()
    assert "1 of 4 flights" in md and "--replay SEED" in md
    assert paths[2].stat().st_size > 10_000


def test_a_flight_is_judged_by_where_the_copters_truly_were():
    planned = load_planned_flight(EXAMPLE.with_suffix(""))
    tree, radius = planned.centres[0], planned.radii[0]
    frame = planned.frame
    t = np.arange(0.0, 20.0, 0.1)
    # copter 1 rises, flies past the first tree 0.3 m from its surface, lands; copter 2
    # stands 1.0 m from copter 1 on the ground (homes may be close), 3 m in the air
    up = np.clip(np.minimum(t, 20.0 - t) * 2.0, 0.0, 5.0)
    east = tree[0] - 10.0 + t
    north = np.full_like(t, tree[1] + radius + 0.3)
    truth = []
    for dn, gap in ((0.0, 0.0), (1.0, 2.0)):
        lat, lon, _ = frame.to_lla(np.column_stack([east, north + dn + gap * (up > 1.0),
                                                    up]))
        truth.append([(ti, a, o, u) for ti, a, o, u in zip(t, lat, lon, up)])
    got = judge(planned, truth)
    assert got["true_min_clearance_m"] == pytest.approx(0.3, abs=0.02)
    assert got["true_min_separation_m"] == pytest.approx(3.0, abs=0.01)  # not 1.0 on the ground
    assert got["flight_s"] == pytest.approx(19.4 - 0.6, abs=0.11)  # above 1 m: 0.6-19.4 s
