"""The compiled flown-path loop (ardupilot.compiled) against the model's own objects
(flight_path.fly_path_stepwise: WaypointNav, SCurve, PositionFollower, as the emulator
flies them): the same path, to 1e-6 m, on random missions, holds, speeds and
parameters; the objects are what tests/conformance holds to ArduCopter SITL."""

from __future__ import annotations

import numpy as np
import pytest

from ftlbo_mav.ardupilot.compiled import CompiledFollower
from ftlbo_mav.ardupilot.flight_path import fly_path, fly_path_stepwise
from ftlbo_mav.ardupilot.navigation import vehicle_navigation
from ftlbo_mav.ardupilot.poscontrol import Airframe, PositionFollower


def _same(a, b) -> None:
    assert len(a.times) == len(b.times)
    assert np.abs(a.times - b.times).max() < 1e-9
    assert np.abs(a.positions - b.positions).max() < 1e-6
    assert np.abs(a.reached - b.reached).max() < 1e-9


def _mission(rng: np.random.Generator) -> np.ndarray:
    count = int(rng.integers(2, 9))
    steps = rng.normal(0.0, 1.0, (count - 1, 3)) * [25.0, 25.0, 1.5]
    steps[rng.random(count - 1) < 0.15] *= 0.02  # some points almost on top of the last
    return np.cumsum(np.vstack([[0.0, 0.0, 5.0], steps]), axis=0)


@pytest.mark.parametrize("seed", range(12))
def test_random_missions_fly_the_same(seed):
    rng = np.random.default_rng(seed)
    points = _mission(rng)
    holds = np.where(rng.random(len(points)) < 0.3, rng.integers(1, 3, len(points)), 0)
    speed = [None, 3.0, 5.0, 9.0][seed % 4]
    params = {} if seed % 3 == 0 else {
        "WPNAV_ACCEL": float(rng.choice([100.0, 250.0, 400.0])),
        "WPNAV_RADIUS": float(rng.choice([50.0, 200.0, 500.0])),
        "WPNAV_JERK": float(rng.choice([1.0, 3.0])),
        "PSC_VELXY_P": float(rng.choice([1.0, 2.0, 3.0])),
    }
    nav = vehicle_navigation(params)
    airframe = None if seed % 5 == 4 else Airframe(drag_bcoef=float(rng.uniform(8.0, 30.0)))
    _same(fly_path(points, nav=nav, speed_m_s=speed, holds_s=holds, airframe=airframe),
          fly_path_stepwise(points, nav=nav, speed_m_s=speed, holds_s=holds, airframe=airframe))


def test_a_mission_too_long_for_its_budget_is_refused_alike():
    points = np.array([[0.0, 0.0, 5.0], [30.0, 0.0, 5.0]])
    with pytest.raises(RuntimeError, match="not flown within"):
        fly_path(points, speed_m_s=5.0, dt=0.02, holds_s=[0, -1e6])
    with pytest.raises(RuntimeError, match="not flown within"):
        fly_path_stepwise(points, speed_m_s=5.0, dt=0.02, holds_s=[0, -1e6])


def test_a_plans_flights_share_one_stepwise_budget(monkeypatch):
    from ftlbo_mav.ardupilot import flight_path as fp

    stepwise = []
    real = fp.fly_path_stepwise

    def counted(*args, **kwargs):
        stepwise.append(True)
        return real(*args, **kwargs)

    monkeypatch.setattr(fp, "fly_path_stepwise", counted)
    monkeypatch.setattr(fp, "_compiled_loaded", False)  # as in a new process
    monkeypatch.setattr(fp, "_cold_left", 0.0)  # whose cache holds the compiled loop
    points = np.array([[0.0, 0.0, 5.0], [40.0, 0.0, 5.0]])  # 40 m at 10 m/s: 4 s expected
    alone = [fp.fly_path(points, speed_m_s=10.0) for _ in range(3)]
    assert len(stepwise) == 3  # alone, each is short: stepwise
    stepwise.clear()
    with fp.stepwise_budget(10.0):
        inside = [fp.fly_path(points, speed_m_s=10.0) for _ in range(4)]
    assert len(stepwise) == 2  # 4 s + 4 s fit in 10 s; the third and after are compiled
    for a, b in zip(alone, inside):
        _same(a, b)
    stepwise.clear()
    fp.fly_path(points, speed_m_s=10.0)
    assert not stepwise  # the compiled loop's start-up is paid: every later flight is compiled


def test_a_short_flight_is_stepwise_until_the_compiled_loop_is_loaded(monkeypatch):
    from ftlbo_mav.ardupilot import flight_path as fp

    monkeypatch.setattr(fp, "_compiled_loaded", False)
    monkeypatch.setattr(fp, "_cold_left", 0.0)
    calls = []
    real = fp.fly_path_stepwise
    monkeypatch.setattr(fp, "fly_path_stepwise", lambda *a, **k: calls.append(1) or real(*a, **k))
    points = np.array([[0.0, 0.0, 5.0], [40.0, 0.0, 5.0]])
    fp.fly_path(points, speed_m_s=10.0)
    assert calls == [1]  # short, numba not loaded: stepwise
    _compiled(points, speed_m_s=10.0)
    calls.clear()
    fp.fly_path(points, speed_m_s=10.0)
    assert calls == []


def test_while_the_compiled_loop_is_not_cached_flights_stay_stepwise_and_it_compiles_later(
        monkeypatch):
    from ftlbo_mav.ardupilot import flight_path as fp

    monkeypatch.setattr(fp, "_compiled_loaded", False)  # a new process
    monkeypatch.setattr(fp, "ready", lambda *f: False)  # its cache cold
    monkeypatch.setattr(fp, "_cold_left", 10.0)
    later = []
    monkeypatch.setattr(fp, "compile_in_background", lambda: later.append(1) or True)
    stepwise = []
    real = fp.fly_path_stepwise
    monkeypatch.setattr(fp, "fly_path_stepwise",
                        lambda *a, **k: stepwise.append(1) or real(*a, **k))
    points = np.array([[0.0, 0.0, 5.0], [40.0, 0.0, 5.0]])  # 4 s expected
    with fp.stepwise_budget(0.0):  # nothing left of the warm budget
        flown = [fp.fly_path(points, speed_m_s=10.0) for _ in range(3)]
    assert len(stepwise) == 2 and len(later) == 2  # 4 s + 4 s of the cold 10 s, then compiled
    _same(flown[0], flown[2])
    assert fp._compiled_loaded


def test_compile_later_starts_nothing_when_told_not_to(monkeypatch):
    from ftlbo_mav import compiling

    monkeypatch.setenv(compiling.BACKGROUND_ENV, "0")
    started = []
    monkeypatch.setattr(compiling.subprocess, "Popen", lambda *a, **k: started.append(a))
    assert not compiling.compile_later("ftlbo_mav.ardupilot.compiled", "x:y")
    assert not started


def test_compile_now_compiles_what_a_plan_and_the_emulator_call():
    """The background job compiles the signatures a plan's flights and the emulator's
    follower use: after it, flying compiled compiles nothing more."""
    from ftlbo_mav.ardupilot import compiled
    from ftlbo_mav.ardupilot import flight_path as fp

    fp.compile_now()
    fly, follow = set(compiled.fly.signatures), set(compiled._follow.signatures)
    with fp.stepwise_budget(0.0):
        points = np.array([[0.0, 0.0, 5.0], [25.0, 5.0, 5.0], [40.0, 30.0, 7.0]])
        fp.fly_path(points, speed_m_s=5.0, holds_s=[0, 2, 0])
        fp.fly_path(points + [0.0, 0.0, 0.5], speed_m_s=5.0, airframe=None)
    compiled.CompiledFollower(points[0]).step(0.0025, points[1], points[2], np.zeros(3))
    assert set(compiled.fly.signatures) == fly
    assert set(compiled._follow.signatures) == follow


def test_a_loop_compiled_by_another_process_is_ready_from_its_cache(tmp_path):
    """What :func:`ftlbo_mav.compiling.compile_later` relies on, with a small loop: a
    process that compiles it (``python -m ftlbo_mav.compiling module:function``) leaves it
    in numba's cache, where :func:`ftlbo_mav.compiling.ready` finds it for the next."""
    import subprocess
    import sys
    from pathlib import Path

    (tmp_path / "small_loop.py").write_text(
        "from ftlbo_mav.compiling import njit\n\n"
        "@njit(cache=True)\ndef twice(x):\n    return 2.0 * x\n\n"
        "def compile_now():\n    twice(1.0)\n")
    root = Path(__file__).resolve().parents[2]
    env = {"PYTHONPATH": f"{tmp_path}:{root}", "PATH": "/usr/bin:/bin"}
    check = ("import small_loop; from ftlbo_mav import compiling; "
             "print(compiling.ready(small_loop.twice))")

    def run(*args):
        return subprocess.run([sys.executable, *args], cwd=tmp_path, env=env,
                              capture_output=True, text=True, timeout=120)

    assert run("-c", check).stdout.split() == ["False"]
    assert run("-m", "ftlbo_mav.compiling", "small_loop:compile_now").returncode == 0
    assert run("-c", check).stdout.split() == ["True"]


@pytest.mark.parametrize("name", ["nha-trang-orchard", "orchard-survey", "six-tree-slalom"])
def test_the_shipped_plans_fly_the_same_compiled_and_stepwise(name):
    # issue 30: old (the objects' loop) and new (compiled) agree within 1 mm on the
    # shipped plans, every UAV's mission as planned (its speed, its holds): the plan
    # folder where one is shipped (the survey's held to what the planner writes by
    # tests/test_survey_scenario.py), else the scenario planned
    from ftlbo_mav.mission.plan_reader import read_plan
    from ftlbo_mav.planning.planner import plan
    from ftlbo_mav.planning.repair import flight_model
    from ftlbo_mav.scenario import load_scenario

    from ..conftest import ROOT

    folder = ROOT / "missions" / name
    p = read_plan(folder) if folder.is_dir() else plan(load_scenario(folder.with_suffix(".toml")))
    model = flight_model(p.scenario)
    for path in p.uav_paths:
        kwargs = dict(nav=model.nav, speed_m_s=model.speed_m_s, holds_s=p.holds_s)
        old, new = fly_path_stepwise(path, **kwargs), _compiled(path, **kwargs)
        assert len(old.times) == len(new.times)
        assert np.abs(old.positions - new.positions).max() < 1e-3
        assert np.abs(old.reached - new.reached).max() < 1e-9


def _compiled(points, **kwargs):
    from ftlbo_mav.ardupilot import flight_path as fp

    with fp.stepwise_budget(0.0):  # nothing left for the stepwise loop: compiled
        return fp.fly_path(points, **kwargs)


def _fresh(points, **kwargs):
    """``points`` flown compiled from the first point, nothing flown before reused."""
    from ftlbo_mav.ardupilot import flight_path as fp

    saved = fp._FLOWN
    fp._FLOWN = fp._Flown()
    try:
        return _compiled(points, **kwargs)
    finally:
        fp._FLOWN = saved


def _taken_up(monkeypatch) -> list[int]:
    """The waypoints the compiled flights are taken up at from now on (0: the start)."""
    from ftlbo_mav.ardupilot import compiled

    at: list[int] = []
    real = compiled.fly

    def spy(*args):
        at.append(int(args[14][3]))  # resume_i: its waypoint
        return real(*args)

    monkeypatch.setattr(compiled, "fly", spy)
    return at


@pytest.mark.parametrize("seed", range(6))
def test_a_corner_moved_is_flown_from_the_last_waypoint_before_it(seed, monkeypatch):
    # issue 30: what comes before a moved corner is not flown again, and the flight is
    # the one flown from the start, number for number
    from ftlbo_mav.ardupilot import flight_path as fp

    monkeypatch.setattr(fp, "_FLOWN", fp._Flown())
    rng = np.random.default_rng(100 + seed)
    points = np.cumsum(np.vstack([[0.0, 0.0, 5.0],
                                  rng.normal(0.0, 1.0, (11, 3)) * [20.0, 20.0, 0.5]]), axis=0)
    holds = np.where(rng.random(12) < 0.25, 1, 0) if seed % 2 else None
    _compiled(points, holds_s=holds)
    at = _taken_up(monkeypatch)
    for j in (9, 4, 7):
        moved = points.copy()
        moved[j, :2] += rng.normal(0.0, 0.4, 2)
        again = _compiled(moved, holds_s=holds)
        whole = _fresh(moved, holds_s=holds)
        assert np.array_equal(again.times, whole.times)
        assert np.array_equal(again.positions, whole.positions)
        assert np.array_equal(again.reached, whole.reached)
    assert at[0::2] == [8, 3, 6]  # taken up at the waypoint before the moved corner


def test_a_flight_flown_again_is_not_flown_and_its_copy_is_the_callers(monkeypatch):
    from ftlbo_mav.ardupilot import flight_path as fp

    monkeypatch.setattr(fp, "_FLOWN", fp._Flown())
    points = np.array([[0.0, 0.0, 5.0], [30.0, 0.0, 5.0], [30.0, 30.0, 6.0], [0.0, 40.0, 5.0]])
    first = _compiled(points)
    at = _taken_up(monkeypatch)
    first.positions[:] = 0.0  # the caller's to change
    again = _compiled(points)
    assert at == []  # not flown again
    assert np.array_equal(again.positions, _fresh(points).positions)


def test_a_hold_changed_before_a_corner_is_flown_from_before_the_hold(monkeypatch):
    from ftlbo_mav.ardupilot import flight_path as fp

    monkeypatch.setattr(fp, "_FLOWN", fp._Flown())
    points = np.array([[0.0, 0.0, 5.0], [30.0, 0.0, 5.0], [30.0, 30.0, 6.0], [0.0, 40.0, 5.0],
                       [-20.0, 10.0, 5.0], [-30.0, -20.0, 5.0]])
    _compiled(points)
    at = _taken_up(monkeypatch)
    holds = np.array([0, 0, 1, 0, 0, 0])  # a stop at point 2: the state from 3 on changes
    moved = points.copy()
    moved[4, :2] += 0.5
    flown = _compiled(moved, holds_s=holds)
    assert at == [2]
    assert np.array_equal(flown.positions, _fresh(moved, holds_s=holds).positions)


@pytest.mark.parametrize("seed", range(4))
def test_the_compiled_follower_follows_as_the_objects_do_in_wind(seed):
    """The emulator's copters on a simulated clock follow their targets with
    CompiledFollower: the same positions, velocities and controller state as
    PositionFollower, steps of any length (a 20 ms step, a shortened one, none)."""
    rng = np.random.default_rng(seed)
    nav = vehicle_navigation({"PSC_VELXY_P": float(rng.choice([1.0, 2.0, 3.0]))})
    start, velocity, wind = rng.normal(0, 5, 2), rng.normal(0, 2, 2), rng.normal(0, 4, 2)
    ours = PositionFollower(start, velocity, nav=nav, wind=wind)
    compiled = CompiledFollower(start, velocity, nav=nav, wind=wind)
    for k in range(200):
        dt = (0.02, 0.013, 0.0, 0.05)[k % 4]
        target = np.append(start + rng.normal(0, 3, 2), 5.0)
        target_vel, target_accel = rng.normal(0, 3, 3), rng.normal(0, 1, 3)
        a = ours.step(dt, target, target_vel, target_accel)
        b = compiled.step(dt, target, target_vel, target_accel)
        assert np.abs(a - b).max() < 1e-9
        assert abs(ours.vx - compiled.vx) < 1e-9 and abs(ours.vy - compiled.vy) < 1e-9
        assert abs(ours._ix - compiled._ix) < 1e-9 and ours._carry == compiled._carry
