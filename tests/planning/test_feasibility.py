import numpy as np

from ftlbo_mav.planning.feasibility import violations
from ftlbo_mav.planning.problem import PlanningProblem


def _problem(radius_with_clearance: float, offsets=((0.0, 0.0, 0.0),)) -> PlanningProblem:
    return PlanningProblem(
        start=np.array([0.0, 0.0, 4.0]),
        goal=np.array([20.0, 0.0, 4.0]),
        offsets=np.array(offsets, float),
        centres=np.array([[10.0, 3.5]]),
        radii=np.array([radius_with_clearance]),
        h_min=2.0,
        h_max=7.0,
        area_lower=np.array([-5.0, -5.0]),
        area_upper=np.array([25.0, 10.0]),
        waypoints=1,
        weights=np.ones(3),
    )


PATH = np.array([[0.0, 0.0, 4.0], [10.0, 0.0, 4.0], [20.0, 0.0, 4.0]])


def test_clearance_is_part_of_the_radius():
    # A 3 m tree 3.5 m from the path: clear with clearance 0, a violation with clearance 1.
    assert violations(_problem(3.0), PATH) == []
    found = violations(_problem(3.0 + 1.0), PATH)
    assert len(found) == 2 and "obstacle 1" in found[0] and "3.50 m" in found[0]


def test_every_uav_is_checked_band_and_area():
    problem = _problem(3.0, offsets=((0.0, 0.0, 0.0), (0.0, 1.0, 4.0), (0.0, -6.0, 0.0)))
    found = violations(problem, PATH)
    assert any(v.startswith("UAV 2 segment") for v in found)  # 1 m closer to the tree
    assert any("UAV 2 waypoint 1 at 8.00 m" in v for v in found)  # above the band
    assert any(v.startswith("UAV 3 point") and "outside the area" in v for v in found)
    assert not any(v.startswith("UAV 1") for v in found)


def test_long_lists_are_cut_with_a_count():
    problem = _problem(30.0, offsets=[(0.0, 0.1 * i, 0.0) for i in range(20)])
    found = violations(problem, PATH, limit=5)
    assert len(found) == 5 and found[-1].startswith("... and ")
