"""The plan judged with the copters as they are (flight/fit.py): pure, on the shipped
example's plan (made for ArduCopter 4.5's defaults)."""

from __future__ import annotations

from dataclasses import replace

from ftlbo_mav.ardupilot.copters import resolve_copter
from ftlbo_mav.flight.fit import fit_fleet


def _with(copter, **values):
    return replace(copter, params=dict(copter.params) | values)


def test_copters_as_planned_need_no_second_prediction(planned):
    fit = fit_fleet(planned, list(planned.fleet()))
    assert fit == type(fit)((), None, ()) and fit.holds and fit.notes() == []


def test_three_solos_keep_every_promise_and_are_said(planned):
    fit = fit_fleet(planned, [resolve_copter(profile="3dr-solo")] * 3,
                    [f"uav{n} (sysid {n})" for n in (1, 2, 3)])
    assert fit.holds
    assert fit.changed[0].startswith("uav1 (sysid 1), uav2 (sysid 2), uav3 (sysid 3): "
                                     "WPNAV_SPEED 300 (planned 1000)")
    notes = fit.notes()
    assert notes[-1].startswith("predicted again with the copters' own values: clearance ")
    assert notes[-1].endswith("every promise holds")


def test_a_copter_retuned_far_loses_separation_naming_its_values(planned):
    default = planned.fleet()[0]
    slow = _with(default, PSC_VELXY_P=0.3, ANGLE_MAX=1000.0)
    fit = fit_fleet(planned, [default, slow, default])
    assert not fit.holds
    assert fit.broken[0].startswith("uav2 with its PSC_VELXY_P 0.3 (planned 2), ANGLE_MAX "
                                    "1000 (planned 3000): ")
    assert "(min_separation)" in fit.broken[0]
    # said, not refused, with --any-params
    assert fit.notes() == list(f"{c}: the copter's own values, kept as they are"
                               for c in fit.changed)
    assert any(n.endswith("not promised (--any-params)") for n in fit.notes(any_params=True))


def test_all_copters_retuned_lose_the_clearance(planned):
    slow = _with(planned.fleet()[0], PSC_VELXY_P=0.3, ANGLE_MAX=1000.0)
    fit = fit_fleet(planned, [slow] * 3)
    assert any("from obstacle" in b and "(clearance and navigation budget)" in b
               for b in fit.broken)


def test_a_promise_lost_names_at_most_four_values(planned):
    default = planned.fleet()[0]
    bad = _with(resolve_copter(profile="3dr-solo"), PSC_VELXY_P=0.3, ANGLE_MAX=1000.0)
    fit = fit_fleet(planned, [default, bad, default])
    assert fit.broken and all(" more: " in b for b in fit.broken)
    assert "ATC_INPUT_TC" in fit.changed[0]  # the note before names every one
