"""``python -m sitl.truth``: the formation judged by where SITL's copters truly were, on
made-up tracks whose answer is known (the DataFlash reading itself runs on SITL's logs:
docs/flight.md)."""

from __future__ import annotations

import numpy as np
import pytest

from ftlbo_mav.flight.report import leg_range
from sitl.truth import formation_truth

SPEED = 5.0


def _tracks(planned, late_s: tuple[float, ...]):
    """Each copter flying east at 5 m/s from its slot, 3 m up, beginning ``late_s`` after
    t = 10 s; every one on the legs (the first leg's item) from t = 10 s."""
    first = leg_range(planned)[0]
    t = np.arange(0.0, 40.0, 0.1)
    out = []
    for offset, late in zip(planned.offsets, late_s):
        east = offset[0] + SPEED * np.clip(t - 10.0 - late, 0.0, None)
        enu = np.column_stack([east, np.full_like(t, offset[1]), np.full_like(t, 3.0 + offset[2])])
        lat, lon, alt = planned.frame.to_lla(enu)
        ground = 7.0  # AMSL where it stood
        alt = np.concatenate([[ground], ground + np.asarray(alt)[1:]])
        out.append({"t": t, "lat": np.asarray(lat), "lon": np.asarray(lon), "alt": alt,
                    "seq_t": np.array([0.0, 10.0]), "seq": np.array([first - 1.0, first])})
    return out


def test_copters_that_began_together_are_in_formation(planned):
    got = formation_truth(planned, _tracks(planned, (0.0, 0.0, 0.0)))
    assert got["true_worst_m"] < 0.01 and got["legs_s"] == pytest.approx(30.0, abs=0.2)


def test_one_that_began_70_ms_late_is_behind_along_its_track(planned):
    got = formation_truth(planned, _tracks(planned, (0.0, 0.0, 0.07)))
    # 0.35 m behind the other two: 2/3 of it from the slot the centroid gives it
    w = got["true_worst_at"]
    assert w["uav"] == "uav3" and w["along_m"] == pytest.approx(-0.35 * 2 / 3, abs=0.01)
    assert abs(w["across_m"]) < 0.01
    assert got["true_rms_m"] > 0.15
