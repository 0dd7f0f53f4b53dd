"""Swarm size: the whole ``ftlbo-mav plan`` process, every default output written, as the
number of UAVs and of obstacles grows.

Plain ``python benchmarks/scale.py`` (``--quick``: one repeat, fewer rows). Each row is a
scenario written here (``scenario_text``): a square field, the formation a grid of UAVs
3 m apart (rows of 10), the start near one corner and the goal near the opposite one,
trees of 2-4 m radius scattered by a seeded generator (none on the start's or the goal's
formation). Each is planned by a fresh ``python -m ftlbo_mav plan SCENARIO -o DIR -q``
(waypoints, fences, rally points, fence.parm, plan.json: what a user gets), timed from
process start to exit, the median over the repeats. Printed: wall seconds, how the time
grows against the row before (x time for x UAVs or obstacles), whether the plan is
feasible, and the load average at the start, since the machine is shared.

The goals (issue 21): 10 UAVs <= 1.5 s, 50 UAVs <= 5 s, 200 UAVs <= 30 s on a 2-core
machine.

Issue 51 (``issue51_rows``, for ``benchmarks/goals.py``; ``--issue51`` prints them): the
same whole process on a circle of 10 / 50 / 200 UAVs (radius 100 m) crossing a 1 km field
(``circle_scenario_text``), every file written: <= 3 / 10 / 30 s, under 2 GiB. Before the
rally search was bounded the 200-UAV circle spent over 300 s in it and wrote nothing.
"""

from __future__ import annotations

import argparse
import compileall
import json
import math
import os
import signal
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from planner import table  # the benchmarks' one table printer (run as a script, beside it)

ROOT = Path(__file__).resolve().parents[1]
LAT0, LON0 = 12.2331044, 109.1144313  # the example's south-west corner
M_PER_DEG_LAT = 110_574.0


def grid_offsets(count: int, spacing_m: float = 3.0, per_row: int = 10) -> np.ndarray:
    """``count`` UAVs in rows of ``per_row`` across the east axis, ``spacing_m`` apart,
    centred: (count, 3) metres ENU."""
    i = np.arange(count)
    east = (i % per_row) * spacing_m
    north = (i // per_row) * spacing_m
    offsets = np.column_stack([east, north, np.zeros(count)])
    offsets[:, :2] -= offsets[:, :2].mean(axis=0)
    return offsets


def scenario_text(*, uavs: int, obstacles: int, side_m: float, seed: int = 0) -> str:
    """A scenario TOML: ``uavs`` in a grid formation crossing a ``side_m`` square field
    diagonally among ``obstacles`` trees (seeded)."""
    offsets = grid_offsets(uavs)
    half = np.abs(offsets[:, :2]).max(axis=0) + 6.0  # the formation's half size, spare
    start = half
    goal = np.array([side_m, side_m]) - half
    trees = _scattered_trees(obstacles, side_m, seed, lambda centre, radius: all(
        np.all(np.abs(centre - p) > half + radius + 2.0) for p in (start, goal)))

    # a swarm 3 m apart among trees needs RTK (docs/planning.md)
    return _field_text(f"{uavs} UAVs, {obstacles} trees, {side_m:g} m field", side_m=side_m,
                       offsets=offsets, start=start, goal=goal, trees=trees,
                       navigation="rtk-fixed")


def _scattered_trees(count: int, side_m: float, seed: int, clear) -> list:
    """``count`` trees of 2-4 m radius, (centre, radius) pairs, uniform over the ``side_m``
    square field (seeded), each one for which ``clear(centre, radius)`` holds."""
    rng = np.random.default_rng(seed)
    trees = []
    while len(trees) < count:
        centre = rng.uniform(0.0, side_m, 2)
        radius = float(rng.uniform(2.0, 4.0))
        if clear(centre, radius):
            trees.append((centre, radius))
    return trees


def _field_text(name: str, *, side_m: float, offsets: np.ndarray, start: np.ndarray,
                goal: np.ndarray, trees: list, navigation: str) -> str:
    """A scenario TOML on a ``side_m`` square field at the example's corner: the formation
    ``offsets`` (N, 3) from ``start`` to ``goal`` (ENU metres) among ``trees`` ((centre,
    radius) pairs), ``[navigation] class = navigation``."""
    m_lon = M_PER_DEG_LAT * np.cos(np.radians(LAT0))

    def ll(e: float, n: float) -> tuple[float, float]:
        return LAT0 + n / M_PER_DEG_LAT, LON0 + e / m_lon

    lines = [f'name = "{name}"',
             "[area]", f"corner_a = [{LAT0}, {LON0}]",
             "corner_b = [{:.7f}, {:.7f}]".format(*ll(side_m, side_m)),
             "min_altitude = 2.0", "max_altitude = 7.0",
             "[start]", "lat = {:.7f}\nlon = {:.7f}\nalt = 4.0".format(*ll(*start)),
             "[goal]", "lat = {:.7f}\nlon = {:.7f}\nalt = 4.0".format(*ll(*goal)),
             "[formation]",
             "offsets = [" + ", ".join(f"[{e:.2f}, {n:.2f}, 0.0]" for e, n, _ in offsets) + "]",
             "clearance = 1.0",
             "[navigation]", f'class = "{navigation}"']
    for centre, radius in trees:
        lines += ["[[obstacles]]", "lat = {:.7f}\nlon = {:.7f}".format(*ll(*centre)),
                  f"radius = {radius:.2f}"]
    return "\n".join(lines) + "\n"


def circle_offsets(count: int, radius_m: float) -> np.ndarray:
    """``count`` UAVs evenly on a circle of ``radius_m`` around the centroid, the first due
    east, counter-clockwise: (count, 3) metres ENU."""
    angle = 2.0 * np.pi * np.arange(count) / count
    return np.column_stack([radius_m * np.cos(angle), radius_m * np.sin(angle),
                            np.zeros(count)])


def circle_scenario_text(*, uavs: int, radius_m: float = 100.0, side_m: float = 1000.0,
                         obstacles: int = 5, seed: int = 0) -> str:
    """Issue 51's scenario: ``uavs`` evenly on a circle of ``radius_m`` crossing a
    ``side_m`` square field diagonally among a few trees (seeded, none on the start's or
    the goal's formation), ``[navigation] class = "rtk-float"``."""
    offsets = circle_offsets(uavs, radius_m)
    half = radius_m + 10.0
    start = np.array([half, half])
    goal = np.array([side_m, side_m]) - half
    trees = _scattered_trees(obstacles, side_m, seed, lambda centre, radius: all(
        np.hypot(*(centre - p)) > half + radius + 2.0 for p in (start, goal)))

    return _field_text(f"{uavs} UAVs on a {radius_m:g} m circle, {side_m:g} m field",
                       side_m=side_m, offsets=offsets, start=start, goal=goal, trees=trees,
                       navigation="rtk-float")


def compile_package() -> None:
    """Write the package's bytecode, as installing it from a wheel does: a process started
    with ``PYTHONDONTWRITEBYTECODE`` set (this machine's default) from an editable
    checkout would otherwise compile every module of the package again in every ``plan``
    process measured (0.3 s of a 10-UAV plan here). Quick when it is up to date."""
    compileall.compile_dir(ROOT / "ftlbo_mav", quiet=1)


_LAUNCHER = """
import os, sys, time
t0 = time.perf_counter()
pid = os.posix_spawn(sys.argv[2], sys.argv[2:], os.environ)
_, status, usage = os.wait4(pid, 0)
with open(sys.argv[1], "w") as f:
    f.write(f"{time.perf_counter() - t0} {usage.ru_maxrss} {os.waitstatus_to_exitcode(status)}")
"""
"""Started in place of the plan process, it starts it and reports its wall seconds, peak
resident memory and exit code. A child's ``ru_maxrss`` starts at its parent's resident
size when it is forked, so a plan process started straight from a benchmark that has
planned in its own process (``goals.py``: some 360 MiB) reports that size, not its own;
started from this small launcher it reports its own (the launcher's few MiB aside)."""


def plan_process(path: Path, out: Path, *, timeout_s: float | None = None) -> dict:
    """One fresh ``python -m ftlbo_mav plan path -o out -q``: wall seconds from process
    start to exit, its peak resident memory (``os.wait4``'s ``ru_maxrss``, MiB, measured
    by :data:`_LAUNCHER`), exit code (None when killed after ``timeout_s``), whether it
    said feasible, files written and its last output line. The package's bytecode is
    written first (:func:`compile_package`)."""
    compile_package()
    with tempfile.TemporaryFile("w+") as log, tempfile.TemporaryDirectory() as tmp:
        report = Path(tmp) / "report"
        proc = subprocess.Popen([sys.executable, "-c", _LAUNCHER, str(report), sys.executable,
                                 "-m", "ftlbo_mav", "plan", str(path), "-o", str(out), "-q"],
                                stdout=log, stderr=subprocess.STDOUT, text=True, cwd=ROOT,
                                start_new_session=True)  # a group: a kill ends both
        killed = False
        try:
            proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
            killed = True
        log.seek(0)
        text = log.read()
        fields = report.read_text().split() if not killed else []
    lines = text.strip().splitlines()
    if not killed and len(fields) != 3:  # the launcher itself failed: not a timing
        raise RuntimeError(f"plan process launcher exit {proc.returncode}: "
                           f"{lines[-1] if lines else 'no output'}")
    seconds, maxrss_kib, code = ((float(fields[0]), int(fields[1]), int(fields[2]))
                                 if fields else (math.nan, 0, None))
    return {"seconds": seconds, "peak_rss_mib": maxrss_kib / 1024,
            "returncode": code, "timed_out": killed,
            "feasible": code == 0 and "feasible;" in text,
            "files": len(list(out.iterdir())) if out.is_dir() else 0,
            "last_line": lines[-1] if lines else ""}


def run_plan(text: str, repeats: int) -> dict:
    """Time ``python -m ftlbo_mav plan`` on the scenario ``text``: median wall seconds."""
    times, feasible, files = [], None, 0
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "scenario.toml"
        path.write_text(text)
        for r in range(repeats):
            run = plan_process(path, Path(tmp) / f"out{r}")
            times.append(run["seconds"])
            feasible, files = run["feasible"], run["files"]
            if run["returncode"] not in (0, 1):
                raise SystemExit(f"plan failed ({run['returncode']}): {run['last_line']}")
    return {"seconds": statistics.median(times), "runs": [round(t, 3) for t in times],
            "feasible": bool(feasible), "files": files}


ISSUE51 = {10: 3.0, 50: 10.0, 200: 30.0}
"""Issue 51's limits, seconds of a whole ``plan`` process on its circle scenario
(:func:`circle_scenario_text`): "every plan of up to 200 UAVs answers in seconds"."""
ISSUE51_MEMORY_MIB = 2048.0


def _written(out: Path, uavs: int) -> tuple[bool, int]:
    """Whether ``out`` holds every file ``plan`` writes for ``uavs`` UAVs (plan.json,
    fence.parm, a .waypoints and a .fence each), and how many UAVs its plan.json says
    have no rally point because the rally search stopped at its bound."""
    doc = out / "plan.json"
    if not doc.is_file():
        return False, 0
    stopped = sum(any(n.startswith("no rally point, search stopped")
                      for n in u.get("fence_notes", ()))
                  for u in json.loads(doc.read_text())["uavs"])
    ok = ((out / "fence.parm").is_file()
          and len(list(out.glob("uav*.waypoints"))) == uavs
          and len(list(out.glob("uav*.fence"))) == uavs)
    return ok, stopped


def issue51_rows(*, sizes: tuple[int, ...] = (10, 50, 200), timeout_s: float = 120.0,
                 deadline: float | None = None) -> list[dict]:
    """Issue 51's goals, one row per size (in ``benchmarks/goals.py``'s format): a fresh
    ``python -m ftlbo_mav plan SCENARIO -o DIR -q`` (:func:`plan_process`) on the circle
    scenario (:func:`circle_scenario_text`: the UAVs evenly on a circle of radius 100 m,
    crossing a 1 km field among 5 trees, rtk-float), wall seconds from process start to
    exit and its own peak RSS, against :data:`ISSUE51` and 2 GiB; met only when every
    file was written (plan.json, fence.parm, each UAV's .waypoints and .fence). Each size
    runs twice and the second is measured: the first compiles what numba's on-disk cache
    does not hold yet (after an install or a change to a compiled loop; its time is in the
    note); nothing else is cold or warm on purpose (the OS file cache is warm). The note
    also says how many UAVs have no rally point because their rally search stopped at its
    bound. A run is killed after ``timeout_s``, or at ``deadline`` (``time.monotonic()``),
    after which no size starts."""
    import time

    from goals import row  # the benchmarks' one row format (run as a script, beside it)

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for uavs in sizes:
            limit = ISSUE51[uavs]
            goal = f"plan process: {uavs} UAVs on a 100 m circle, 1 km field, files written"
            left = math.inf if deadline is None else deadline - time.monotonic()
            if left < 2 * limit + 1.0:
                rows.append(row(goal, "issue 51", f"<= {limit:g} s", "not run", None,
                                status="not measured", limit_value=limit,
                                note="time budget spent"))
                continue
            path = Path(tmp) / f"circle-{uavs}.toml"
            path.write_text(circle_scenario_text(uavs=uavs))
            first = plan_process(path, Path(tmp) / f"first-{uavs}",
                                 timeout_s=min(timeout_s, left))
            wait = min(timeout_s, math.inf if deadline is None else deadline - time.monotonic())
            out = Path(tmp) / f"out-{uavs}"
            run = plan_process(path, out, timeout_s=wait)
            before = "timeout" if first["timed_out"] else f"{first['seconds']:.2f} s"
            mib = run["peak_rss_mib"]
            if run["timed_out"]:
                rows.append(row(goal, "issue 51", f"<= {limit:g} s",
                                f"timeout > {wait:.0f} s", False, limit_value=limit,
                                peak_rss_mib=mib, note="killed; nothing written"))
                continue
            written, stopped = _written(out, uavs)
            seconds = run["seconds"]
            note = ("files written" if written else
                    f"files missing (exit {run['returncode']}: {run['last_line'][:60]})")
            note += (f"; {stopped} UAVs without rally point (search bound)" if stopped
                     else "") + f"; second run (the first: {before})"
            rows.append(row(goal, "issue 51", f"<= {limit:g} s, < 2 GiB", f"{seconds:.2f} s",
                            written and seconds <= limit and mib < ISSUE51_MEMORY_MIB,
                            value=seconds, limit_value=limit, peak_rss_mib=mib, note=note))
    return rows


def growth(rows: list[dict], key: str) -> None:
    for before, row in zip(rows, rows[1:]):
        if before["seconds"] > 0 and before[key] > 0:
            row["growth"] = (f"x{row['seconds'] / before['seconds']:.1f} time for "
                             f"x{row[key] / before[key]:.2g} {key}")


GOALS = {10: 1.5, 50: 5.0, 200: 30.0}


def report(uav_rows: list[dict], obstacle_rows: list[dict]) -> str:
    """The two tables as printed (also from a saved JSON: ``--show PATH``)."""
    def show(rows, goals):
        return [[r["uavs"], r["obstacles"], f"{r['side_m']:g} m", f"{r['seconds']:.2f}"]
                + ([f"<= {GOALS[r['uavs']]:g}" if r["uavs"] in GOALS else ""] if goals else [])
                + ["yes" if r["feasible"] else "no", r["files"], r.get("growth", "")]
                for r in rows]

    head = ["UAVs", "trees", "field", "plan s"]
    tail = ["feasible", "files", "growth"]
    return ("\nwhole `plan` process against the number of UAVs (20 trees)\n"
            + table(head + ["goal s"] + tail, show(uav_rows, True))
            + "\n\nagainst the number of trees (50 UAVs, 400 m field)\n"
            + table(head + tail, show(obstacle_rows, False)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="one repeat, fewer rows")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--json", default="scale-benchmark.json", help="output JSON path")
    parser.add_argument("--show", metavar="JSON", help="print the tables of a saved run")
    parser.add_argument("--issue51", action="store_true",
                        help="only issue 51's rows (the 10/50/200-UAV circle), as JSON")
    args = parser.parse_args()
    if args.issue51:
        load = "{:.2f} {:.2f} {:.2f}".format(*os.getloadavg())
        print(json.dumps({"load_start": load, "rows": issue51_rows(),
                          "load_end": "{:.2f} {:.2f} {:.2f}".format(*os.getloadavg())},
                         indent=1))
        return
    if args.show:
        doc = json.loads(Path(args.show).read_text())
        print(f"load average {doc['load']}; median of {doc['repeats']} runs")
        print(report(doc["uavs"], doc["obstacles"]))
        return
    repeats = 1 if args.quick else args.repeats
    load = "{:.2f} {:.2f} {:.2f}".format(*os.getloadavg())
    print(f"load average {load}; {os.cpu_count()} cores; median of {repeats} runs")

    uav_rows = []
    for uavs, side in ((3, 100.0), (10, 100.0), (50, 400.0), (200, 400.0)):
        row = {"uavs": uavs, "obstacles": 20, "side_m": side}
        row.update(run_plan(scenario_text(uavs=uavs, obstacles=20, side_m=side), repeats))
        uav_rows.append(row)
        print(f"  {uavs} UAVs: {row['seconds']:.2f} s", flush=True)
    growth(uav_rows, "uavs")
    obstacle_rows = []
    counts = (0, 20, 80) if args.quick else (0, 20, 80, 320)
    for obstacles in counts:
        row = {"uavs": 50, "obstacles": obstacles, "side_m": 400.0}
        row.update(run_plan(scenario_text(uavs=50, obstacles=obstacles, side_m=400.0),
                            repeats))
        obstacle_rows.append(row)
        print(f"  {obstacles} obstacles: {row['seconds']:.2f} s", flush=True)
    growth([r for r in obstacle_rows if r["obstacles"]], "obstacles")

    print(report(uav_rows, obstacle_rows))
    Path(args.json).write_text(json.dumps({"load": load, "repeats": repeats, "uavs": uav_rows,
                                           "obstacles": obstacle_rows}, indent=1))


if __name__ == "__main__":
    main()
