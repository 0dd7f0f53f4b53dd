"""Planner speed: wall time per plan, cost evaluations per second, scaling.

Plain ``python benchmarks/planner.py`` (add ``--quick`` for fewer repeats). Prints tables
and writes JSON (``--json``, default ``planner-benchmark.json``). Timings are wall clock
on this machine as it is loaded right now: the load average is printed and stored next to
the figures, and every median is over several seeds or repeats.

1. Median wall seconds of ``plan()`` per algorithm on the shipped example at the paper's
   settings (100 students, 10 waypoints, 150 iterations), with the centroid length over
   the lower bound.
2. Path evaluations per second of the vectorized cost (population 100) for 3 UAVs, 10
   waypoints and 6 cylinders, and how the time per evaluation grows with obstacles
   (6, 25, 100), UAVs (3, 10, 30) and waypoints (10, 20, 40), one factor at a time,
   normalised per UAV x obstacle x segment; the default planner's wall time on the same
   fields; peak memory of one class evaluation on the largest field.
3. Maps: the default planner on a set of different maps (the shipped example, the
   orchard survey, random fields of 6, 25 and 100 trees, random orchards), with the
   scenario's fixed waypoints (10) and with ``waypoints = "auto"`` side by side: centroid
   length over the lower bound, wall seconds, waypoints, over seeds 0..2 (the same plan
   for every seed says the planner is deterministic there); and ``auto`` on the dense
   100-tree field timed alone (median of 5).
5. Planning time as ``ftlbo-mav plan`` plans (``--only flown``): ``plan()`` with the
   scenario's own settings, including the prediction of every UAV's flown path and the
   clearance keeping (``Plan.seconds``; of it ``Plan.predict_seconds``), median of 5, on
   the example, the slalom, the zigzag at 10 m/s and a ten-UAV formation
   (``benchmarks/scenarios/``). Goals: the example in <= 0.2 s, ten UAVs in <= 1 s.
4. When the optional ``mealpy`` package is importable: its TLBO (``OriginalTLO``) on our
   cost, one path per call as mealpy evaluates, at the same evaluation budget, next to
   ours (cost and time). mealpy pins numpy <= 1.26, so run it from its own virtual
   environment (docs/planning.md).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from ftlbo_mav.formation import regular_formation
from ftlbo_mav.planning.cost import search_cost
from ftlbo_mav.planning.geometric import shortest_route
from ftlbo_mav.planning.optimizers import (
    OPTIMIZERS,
    Objective,
    evaluation_budget,
    tlbo,
)
from ftlbo_mav.planning.planner import plan
from ftlbo_mav.planning.problem import PlanningProblem, problem_from_scenario
from ftlbo_mav.scenario import load_scenario

EXAMPLE = ROOT / "missions" / "nha-trang-orchard.toml"
SURVEY = ROOT / "missions" / "orchard-survey.toml"
PAPER = dict(students=100, waypoints=10, iterations=150)


def load() -> str:
    one, five, fifteen = os.getloadavg()
    return f"{one:.2f} {five:.2f} {fifteen:.2f}"


def table(headers: list[str], rows: list[list], *, left: tuple[int, ...] = ()) -> str:
    """Columns right-aligned, those numbered in ``left`` left-aligned."""
    cells = [[str(h) for h in headers]] + [[str(c) for c in r] for r in rows]
    widths = [max(len(row[i]) for row in cells) for i in range(len(headers))]
    lines = ["  ".join(c.ljust(w) if i in left else c.rjust(w)
                       for i, (c, w) in enumerate(zip(row, widths))) for row in cells]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


# ----------------------------------------------------------------------- 1. algorithms


def bench_algorithms(seeds: int) -> list[dict]:
    scenario = load_scenario(EXAMPLE)
    plan(scenario, algorithm="ftlbo", iterations=2)  # warm up imports and caches
    out = []
    for algorithm in OPTIMIZERS:
        walls, ratios, costs, evals, feasible = [], [], [], [], 0
        for seed in range(seeds):
            t0 = time.perf_counter()
            p = plan(scenario, algorithm=algorithm, seed=seed, **PAPER)
            walls.append(time.perf_counter() - t0)
            feasible += p.feasible
            costs.append(p.cost.total)
            evals.append(p.evaluations)
            if p.length_ratio is not None:
                ratios.append(p.length_ratio)
        out.append(dict(
            algorithm=algorithm, seeds=seeds, wall_median_s=statistics.median(walls),
            wall_min_s=min(walls), wall_max_s=max(walls),
            evaluations_median=statistics.median(evals),
            evaluations_per_s=statistics.median(e / w for e, w in zip(evals, walls)),
            cost_median=statistics.median(costs), ratio_median=statistics.median(ratios),
            feasible=feasible,
        ))
    return out


# ----------------------------------------------------------------------- 2. scaling


def field(*, obstacles: int, uavs: int, waypoints: int, seed: int = 0) -> PlanningProblem:
    """A 100 m x 60 m field, start and goal 80 m apart, ``obstacles`` trees of radius
    0.5-1.5 m (clearance 0.5 m) away from start and goal, a ring formation of radius 2 m."""
    rng = np.random.default_rng(seed)
    start, goal = np.array([10.0, 30.0, 4.0]), np.array([90.0, 30.0, 4.0])
    centres, radii = [], []
    while len(centres) < obstacles:
        c = rng.uniform([15.0, 5.0], [85.0, 55.0])
        r = rng.uniform(0.5, 1.5)
        if min(np.linalg.norm(c - start[:2]), np.linalg.norm(c - goal[:2])) > r + 5.0:
            centres.append(c)
            radii.append(r)
    return PlanningProblem(
        start=start, goal=goal,
        offsets=regular_formation(count=uavs, radius_m=2.0, plane="horizontal"),
        centres=np.array(centres), radii=np.array(radii) + 0.5, h_min=2.0, h_max=7.0,
        area_lower=np.array([0.0, 0.0]), area_upper=np.array([100.0, 60.0]),
        waypoints=waypoints, weights=np.ones(3),
    )


def evaluations_per_second(problem: PlanningProblem, *, population: int = 100,
                           repeats: int = 5, seconds: float = 0.3) -> float:
    """Best-of-``repeats`` throughput of ``search_cost`` on random classes (paths/s)."""
    lower, upper = problem.bounds()
    rng = np.random.default_rng(1)
    x = lower + rng.random((population, problem.waypoints, 3)) * (upper - lower)
    search_cost(problem, x)
    best = 0.0
    for _ in range(repeats):
        n, t0 = 0, time.perf_counter()
        while (elapsed := time.perf_counter() - t0) < seconds:
            search_cost(problem, x)
            n += 1
        best = max(best, n * population / elapsed)
    return best


def default_planner_wall(problem: PlanningProblem, seeds: int) -> tuple[float, float, float]:
    """Median wall seconds of the default planner's optimizer+seeding, of the geometry
    alone, and the median length ratio (NaN when no route)."""
    from ftlbo_mav.planning.planner import solve
    from ftlbo_mav.scenario import PlannerSettings
    from ftlbo_mav.scenario import load_scenario as _load

    scenario = _load(EXAMPLE)  # only carried along in the Plan; the problem is ours
    walls, ratios = [], []
    for seed in range(seeds):
        settings = PlannerSettings(algorithm="ftlbo-seeded", students=100,
                                   waypoints=problem.waypoints, iterations=150, seed=seed)
        t0 = time.perf_counter()
        p = solve(problem, scenario, settings)
        walls.append(time.perf_counter() - t0)
        if p.feasible and p.length_ratio:
            ratios.append(p.length_ratio)
    t0 = time.perf_counter()
    shortest_route(problem)
    geometry = time.perf_counter() - t0
    return statistics.median(walls), geometry, statistics.median(ratios) if ratios else math.nan


def bench_scaling(repeats: int, seeds: int) -> list[dict]:
    base = dict(obstacles=6, uavs=3, waypoints=10)
    cases = [dict(base)]
    cases += [dict(base, obstacles=k) for k in (25, 100)]
    cases += [dict(base, uavs=n) for n in (10, 30)]
    cases += [dict(base, waypoints=m) for m in (20, 40)]
    out = []
    for case in cases:
        problem = field(**case)
        rate = evaluations_per_second(problem, repeats=repeats)
        work = case["uavs"] * case["obstacles"] * (case["waypoints"] + 1)
        wall, geometry, ratio = default_planner_wall(problem, seeds)
        out.append(dict(case, evaluations_per_s=rate, us_per_evaluation=1e6 / rate,
                        ns_per_pair=1e9 / rate / work, default_wall_median_s=wall,
                        geometry_s=geometry, default_ratio_median=ratio))
    return out


def bench_memory() -> dict:
    """Peak traced memory of one class evaluation on the largest field (chunked)."""
    problem = field(obstacles=100, uavs=30, waypoints=40)
    lower, upper = problem.bounds()
    x = lower + np.random.default_rng(0).random((100, 40, 3)) * (upper - lower)
    tracemalloc.start()
    t0 = time.perf_counter()
    search_cost(problem, x)
    seconds = time.perf_counter() - t0
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    unchunked = 100 * 41 * 30 * 100 * 8  # one float64 (N*K, S*J) array without chunking
    return dict(obstacles=100, uavs=30, waypoints=40, students=100, seconds=seconds,
                peak_mib=peak / 2**20, one_unchunked_array_mib=unchunked / 2**20)


# ----------------------------------------------------------------------- 3. maps


def orchard(seed: int, offsets: np.ndarray) -> PlanningProblem:
    """A random orchard on the example's area: 5-11 trees of radius 2-4.5 m (+1 m
    clearance) between start and goal (as in tests/planning/test_seeded.py)."""
    rng = np.random.default_rng(seed)
    start, goal = np.array([8.0, 12.0, 4.0]), np.array([80.0, 40.0, 4.0])
    centres, radii, count = [], [], rng.integers(5, 12)
    while len(centres) < count:
        c, r = rng.uniform([15, 5], [75, 45]), rng.uniform(2.0, 4.5)
        if min(np.linalg.norm(c - start[:2]), np.linalg.norm(c - goal[:2])) > r + 7.0:
            centres.append(c)
            radii.append(r)
    return PlanningProblem(
        start=start, goal=goal, offsets=offsets, centres=np.array(centres),
        radii=np.array(radii) + 1.0, h_min=2.0, h_max=7.0, area_lower=np.array([0.0, 0.0]),
        area_upper=np.array([86.0, 49.5]), waypoints=10, weights=np.ones(3))


def maps() -> list[tuple[str, object]]:
    """(label, scenario path or PlanningProblem) of every map in the table."""
    triangle = np.array([[0, 0, 2], [3, 0, -1], [-3, 0, -1]], float)
    return [
        ("nha-trang-orchard.toml (7 trees, 1 leg)", EXAMPLE),
        ("orchard-survey.toml (33 obstacles, 9 legs)", SURVEY),
        ("field: 6 trees, 3 UAVs", field(obstacles=6, uavs=3, waypoints=10)),
        ("field: 25 trees, 3 UAVs", field(obstacles=25, uavs=3, waypoints=10)),
        ("field: 100 trees, 3 UAVs (dense)", field(obstacles=100, uavs=3, waypoints=10)),
        ("field: 6 trees, 10 UAVs", field(obstacles=6, uavs=10, waypoints=10)),
        ("orchard 50: triangle", orchard(50, triangle)),
        ("orchard 51: 4-ring r 3 m", orchard(51, regular_formation(count=4, radius_m=3.0,
                                                                   plane="horizontal"))),
        ("orchard 52: 6-ring r 4 m", orchard(52, regular_formation(count=6, radius_m=4.0,
                                                                   plane="horizontal"))),
    ]


def run_map(target, *, waypoints, seed: int):
    """One default plan of a map: (wall seconds, Plan)."""
    from ftlbo_mav.planning.planner import solve
    from ftlbo_mav.scenario import PlannerSettings

    t0 = time.perf_counter()
    if isinstance(target, Path):
        p = plan(load_scenario(target), waypoints=waypoints, seed=seed)
    else:
        p = solve(target, load_scenario(EXAMPLE),
                  PlannerSettings(waypoints=waypoints, seed=seed))
    return time.perf_counter() - t0, p


def bench_maps(seeds: int) -> list[dict]:
    rows = []
    for label, target in maps():
        row = {"map": label}
        for mode in (10, "auto"):
            walls, ratios, counts, feasible = [], [], [], 0
            for seed in range(seeds):
                wall, p = run_map(target, waypoints=mode, seed=seed)
                walls.append(wall)
                feasible += p.feasible
                ratios.append(p.length_ratio if p.length_ratio is not None else math.nan)
                counts.append(p.waypoint_count)
            row[str(mode)] = dict(wall_median_s=statistics.median(walls),
                                  ratio_min=min(ratios), ratio_max=max(ratios),
                                  points=counts[0], feasible=feasible, seeds=seeds,
                                  same_for_every_seed=len(set(ratios)) == 1)
        rows.append(row)
    return rows


def bench_dense_auto(repeats: int = 5) -> dict:
    """``waypoints = "auto"`` on the 100-tree field, timed alone (issue 13's target)."""
    problem = field(obstacles=100, uavs=3, waypoints=10)
    walls, p = [], None
    for seed in range(repeats):
        wall, p = run_map(problem, waypoints="auto", seed=seed)
        walls.append(wall)
    return dict(wall_median_s=statistics.median(walls), wall_max_s=max(walls),
                ratio=p.length_ratio, waypoints=p.legs[0].waypoints, feasible=p.feasible,
                repeats=repeats)


# ----------------------------------------------------------------------- goals


def quick_figures(repeats: int = 3) -> dict:
    """The figures benchmarks/goals.py holds to the planner's goals, measured now in this
    process (after one warm-up plan, timed as ``example_first_wall_s``, and one with the
    compiled prediction loaded): medians over ``repeats`` runs (seeds 0.. where a
    seed matters) of the example's ``plan()`` (wall and ``Plan.seconds``), of the
    example's ``plan()`` at the paper's settings, of ``Plan.seconds`` of the ten-UAV
    formation (``--only flown``), the path evaluations per second of 3 UAVs, 10 waypoints
    and 6 cylinders, and ``waypoints = "auto"`` on the dense 100-tree field (wall median
    and the worst seed's length over the bound)."""
    from ftlbo_mav.ardupilot.flight_path import fly_path, stepwise_budget

    scenario = load_scenario(EXAMPLE)
    t0 = time.perf_counter()
    first_plan = plan(scenario)  # the first plan: imports and caches, predicted stepwise
    first = time.perf_counter() - t0
    with stepwise_budget(0.0):  # and the compiled loop loaded, as after any larger plan
        fly_path(first_plan.uav_paths[0])

    def timed(run) -> tuple[float, object]:
        t0 = time.perf_counter()
        p = run()
        return time.perf_counter() - t0, p

    example = [timed(lambda: plan(scenario)) for _ in range(repeats)]
    paper = [timed(lambda s=seed: plan(scenario, seed=s, **PAPER)) for seed in range(repeats)]
    ten = load_scenario(FLOWN_MAPS[-1])
    ten_uavs = [plan(ten) for _ in range(repeats)]
    dense = field(obstacles=100, uavs=3, waypoints=10)
    auto = [run_map(dense, waypoints="auto", seed=seed) for seed in range(repeats)]
    return {
        "repeats": repeats,
        "example_wall_s": statistics.median(w for w, _ in example),
        "example_first_wall_s": first,
        "example_plan_seconds": statistics.median(p.seconds for _, p in example),
        "paper_settings_wall_s": statistics.median(w for w, _ in paper),
        "ten_uavs_scenario": FLOWN_MAPS[-1].name, "ten_uavs_count": ten.uav_count,
        "ten_uavs_plan_seconds": statistics.median(p.seconds for p in ten_uavs),
        "evaluations_per_s": evaluations_per_second(field(obstacles=6, uavs=3, waypoints=10),
                                                    repeats=repeats),
        "dense_auto_wall_s": statistics.median(w for w, _ in auto),
        "dense_auto_ratio_max": max(p.length_ratio if p.length_ratio is not None else math.inf
                                    for _, p in auto),
        "dense_auto_feasible": sum(p.feasible for _, p in auto),
    }


# ----------------------------------------------------------------------- 4. mealpy


def bench_mealpy(seeds: int) -> list[dict] | None:
    try:
        from mealpy import FloatVar
        from mealpy.human_based.TLO import OriginalTLO  # mealpy 3: TLBO is "TLO"
    except ImportError:
        return None
    scenario = load_scenario(EXAMPLE)
    problem = problem_from_scenario(scenario, waypoints=10)
    m = problem.waypoints
    lower, upper = (b.ravel() for b in problem.bounds())
    budget = evaluation_budget(100, 150)
    rows = []
    for seed in range(seeds):
        calls = [0]

        def one(x, calls=calls):
            calls[0] += 1
            return float(search_cost(problem, np.asarray(x).reshape(1, m, 3))[0])

        spec = {"obj_func": one, "bounds": FloatVar(lb=lower, ub=upper), "minmax": "min",
                "log_to": None}
        model = OriginalTLO(epoch=10_000, pop_size=100)
        t0 = time.perf_counter()
        best = model.solve(spec, termination={"max_fe": budget}, seed=seed)
        mealpy_s = time.perf_counter() - t0
        objective = Objective(lambda x: search_cost(problem, x.reshape(-1, m, 3)), lower, upper)
        t0 = time.perf_counter()
        ours = tlbo(objective, students=100, iterations=150, rng=np.random.default_rng(seed))
        ours_s = time.perf_counter() - t0
        rows.append(dict(seed=seed, mealpy_cost=float(best.target.fitness),
                         mealpy_s=mealpy_s, mealpy_evaluations=calls[0], ours_cost=ours.cost,
                         ours_s=ours_s, ours_evaluations=ours.evaluations))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer seeds and repeats")
    parser.add_argument("--json", default="planner-benchmark.json", help="output JSON path")
    parser.add_argument("--only", choices=("algorithms", "scaling", "maps", "mealpy", "flown"),
                        help="run one part only")
    args = parser.parse_args()
    seeds, repeats = (3, 2) if args.quick else (7, 5)
    doc = {"python": sys.version.split()[0], "numpy": np.__version__,
           "cpus": os.cpu_count(), "load_before": load()}
    print(f"load average before (1/5/15 min): {doc['load_before']}; {os.cpu_count()} CPUs")

    def part(name: str) -> bool:
        return args.only in (None, name)

    if part("algorithms"):
        report_algorithms(doc, seeds)
    if part("scaling"):
        report_scaling(doc, seeds, repeats)
    if part("maps"):
        report_maps(doc, 3)
    if part("mealpy"):
        report_mealpy(doc, seeds)
    if part("flown"):
        report_flown(doc)
    doc["load_after"] = load()
    print(f"\nload average after (1/5/15 min): {doc['load_after']}")
    Path(args.json).write_text(json.dumps(doc, indent=1) + "\n")
    print(f"wrote {args.json}")


FLOWN_MAPS = (EXAMPLE, ROOT / "missions" / "six-tree-slalom.toml",
              ROOT / "benchmarks" / "scenarios" / "zigzag-fast.toml",
              ROOT / "benchmarks" / "scenarios" / "orchard-ten-uavs.toml")


def report_flown(doc: dict, repeats: int = 5) -> None:
    rows, out = [], []
    for path in FLOWN_MAPS:
        scenario = load_scenario(path)
        runs = [plan(scenario) for _ in range(repeats)]
        total = statistics.median(r.seconds for r in runs)
        predict = statistics.median(r.predict_seconds for r in runs)
        last = runs[-1]
        out.append({"scenario": path.name, "uavs": scenario.uav_count, "seconds": total,
                    "predict_seconds": predict, "corners_moved": last.corners_moved,
                    "corner_stops": last.corner_stops, "replans": last.replans,
                    "predicted_min_clearance_m": float(last.prediction.clearance.min()),
                    "clearance_m": scenario.clearance_m})
        rows.append([path.name, scenario.uav_count, f"{total:.3f}", f"{predict:.3f}",
                     last.corners_moved, last.corner_stops, last.replans,
                     f"{last.prediction.clearance.min():.3f}", f"{scenario.clearance_m:g}"])
    doc["flown"] = out
    print(f"\n5. planning time with the flown-path prediction (plan(), the scenario's settings, "
          f"median of {repeats})")
    print(table(["scenario", "UAVs", "plan s", "of it predicting s", "corners moved",
                 "stops", "re-plans", "predicted clearance m", "clearance m"], rows))


def report_algorithms(doc: dict, seeds: int) -> None:
    doc["algorithms"] = algorithms = bench_algorithms(seeds)
    print(f"\n1. plan() on {EXAMPLE.name}, paper's settings, {seeds} seeds each")
    print(table(
        ["algorithm", "median s", "min s", "max s", "evaluations", "evals/s", "median cost",
         "length/bound", "feasible"],
        [[a["algorithm"], f"{a['wall_median_s']:.3f}", f"{a['wall_min_s']:.3f}",
          f"{a['wall_max_s']:.3f}", f"{a['evaluations_median']:.0f}",
          f"{a['evaluations_per_s']:,.0f}", f"{a['cost_median']:.2f}",
          f"{a['ratio_median']:.4f}", f"{a['feasible']}/{a['seeds']}"] for a in algorithms]))



def report_scaling(doc: dict, seeds: int, repeats: int) -> None:
    doc["scaling"] = scaling = bench_scaling(repeats, max(seeds // 2, 1))
    print("\n2. cost evaluations (class of 100 random paths) and the default planner, "
          "one factor at a time")
    print(table(
        ["obstacles", "UAVs", "waypoints", "paths/s", "us/path", "ns/(UAV*obst*seg)",
         "default plan s", "geometry s", "length/bound"],
        [[s["obstacles"], s["uavs"], s["waypoints"], f"{s['evaluations_per_s']:,.0f}",
          f"{s['us_per_evaluation']:.1f}", f"{s['ns_per_pair']:.2f}",
          f"{s['default_wall_median_s']:.3f}", f"{s['geometry_s']:.3f}",
          f"{s['default_ratio_median']:.4f}"] for s in scaling]))

    doc["memory"] = memory = bench_memory()
    print(f"\nlargest field ({memory['obstacles']} obstacles, {memory['uavs']} UAVs, "
          f"{memory['waypoints']} waypoints, {memory['students']} students): one class in "
          f"{memory['seconds']:.2f} s, peak traced memory {memory['peak_mib']:.1f} MiB "
          f"(one unchunked distance array would be {memory['one_unchunked_array_mib']:.0f} MiB)")



def report_maps(doc: dict, seeds: int) -> None:
    doc["maps"] = rows = bench_maps(seeds)
    print(f"\n3. the default planner (ftlbo-seeded) on different maps, seeds 0..{seeds - 1}: "
          "10 waypoints per leg vs auto")

    def spread(r: dict) -> str:
        return "0" if r["same_for_every_seed"] else f"{r['ratio_max'] - r['ratio_min']:.0e}"

    print(table(
        ["map", "10: length/bound", "spread", "s", "points", "auto: length/bound", "spread",
         "s", "points", "feasible"],
        [[r["map"], f"{r['10']['ratio_max']:.4f}", spread(r["10"]),
          f"{r['10']['wall_median_s']:.2f}", r["10"]["points"],
          f"{r['auto']['ratio_max']:.4f}", spread(r["auto"]),
          f"{r['auto']['wall_median_s']:.2f}", r["auto"]["points"],
          f"{r['10']['feasible']}/{seeds}, {r['auto']['feasible']}/{seeds}"] for r in rows]))
    print("   length/bound: the worst seed's; spread: worst minus best over the seeds (0: the "
          "same plan for every seed);\n   s: median wall seconds of the whole plan(); points: "
          "points between start and goal (every leg's waypoints and the via points)")
    doc["dense_auto"] = dense = bench_dense_auto()
    print(f"\nwaypoints = auto on the dense 100-tree field: {dense['waypoints']} waypoints, "
          f"length x{dense['ratio']:.4f} of the bound, "
          f"{'feasible' if dense['feasible'] else 'INFEASIBLE'}; whole plan "
          f"{dense['wall_median_s']:.2f} s median, {dense['wall_max_s']:.2f} s max over "
          f"{dense['repeats']} seeds (target: within 1% in under 2 s)")


def report_mealpy(doc: dict, seeds: int) -> None:
    doc["mealpy"] = rows = bench_mealpy(max(seeds // 2, 1))
    if rows is None:
        print("\n4. mealpy not installed: `pip install mealpy` to compare its TLBO")
    else:
        print(f"\n4. mealpy's OriginalTLO (TLBO) vs our tlbo on the example, budget "
              f"{evaluation_budget(100, 150)} evaluations (mealpy finishes its epoch)")
        print(table(["seed", "mealpy cost", "mealpy s", "mealpy evals", "ours cost", "ours s",
                     "ours evals"],
                    [[r["seed"], f"{r['mealpy_cost']:.2f}", f"{r['mealpy_s']:.2f}",
                      r["mealpy_evaluations"], f"{r['ours_cost']:.2f}", f"{r['ours_s']:.2f}",
                      r["ours_evaluations"]] for r in rows]))


if __name__ == "__main__":
    main()
