"""A real orchard: the whole ``ftlbo-mav plan`` process on a survey of thousands of trees.

Plain ``python benchmarks/orchard.py`` (``--quick``: the 5,000- and 20,000-tree orchards
once each; ``--trees N``: one orchard of about N trees). The orchard is written here
(``orchard_files``) as a tree-detection tool exports one: a GeoJSON of Points, one per
tree, each with its canopy ``radius`` (1 m), in north-south rows 7 m apart, trees 3 m
apart along a row, 12 m headlands at both ends. Three UAVs fly in a column (4 m apart,
north-south, one behind the other) through every aisle: ``[survey] spacing = 7``, the
lanes on the aisles' centre lines (one west of the first row and one east of the last),
``waypoints = "auto"``, the default planner and outputs. The 4,800-tree orchard (60 rows
of 80, 427 m x 264 m, 11 ha) has 61 lanes; the 20,000-tree one (125 rows of 160) 126.

Printed per orchard: trees, lanes, legs, wall seconds from process start to exit, the
peak resident memory of the ``plan`` process, whether the plan is feasible and its
predicted clearance, and the load average at the start (the machine is shared).

The goals (issue 30): about 5,000 trees <= 30 s, 20,000 trees <= 120 s, memory < 2 GiB.

Issue 51 (``--issue51``, :func:`issue51_rows`): its orchard (``issue51_files``: 60 rows of
80 trees 7 m x 4 m apart, canopy 1.2 m, 18 m headlands, rtk-fixed) flown by a column
and by a line (three UAVs 7 m apart, one an aisle) within 30 s, and refused within 5 s
(exit code 2) with 10 m headlands (the 8 m column cannot turn) and for a line 4 m apart
(8 m wide, it cannot be between rows 7 m apart).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from planner import table  # the benchmarks' one table printer (run as a script, beside it)
from scale import compile_package

from ftlbo_mav.geo import LocalFrame

ROOT = Path(__file__).resolve().parents[1]
LAT0, LON0 = 12.2331044, 109.1144313  # the example's south-west corner

ROW_SPACING_M = 7.0
TREE_SPACING_M = 3.0
HEADLAND_M = 12.0
CANOPY_RADIUS_M = 1.0
GOALS = {5_000: 30.0, 20_000: 120.0}
MEMORY_GOAL_MIB = 2048.0


def layout(trees: int) -> tuple[int, int]:
    """Rows and trees per row for about ``trees`` trees, the rows 5/3 as long as the
    orchard is wide at 5,000 trees (60 x 80) and keeping that shape."""
    if trees == 5_000:
        return 60, 80
    if trees == 20_000:
        return 125, 160
    rows = max(1, round((trees * 0.75) ** 0.5))
    return rows, max(1, round(trees / rows))


SHAPES = {  # the formation's offsets (east, north, up) metres
    "column": "[[0.0, 4.0, 0.0], [0.0, 0.0, 0.0], [0.0, -4.0, 0.0]]",  # through the aisles
    "line": "[[-4.0, 0.0, 0.0], [0.0, 0.0, 0.0], [4.0, 0.0, 0.0]]",  # across them
    "line7": "[[-7.0, 0.0, 0.0], [0.0, 0.0, 0.0], [7.0, 0.0, 0.0]]",  # one UAV an aisle
}


def orchard_files(folder: Path, *, rows: int, per_row: int,
                  tree_spacing_m: float = TREE_SPACING_M,
                  canopy_radius_m: float = CANOPY_RADIUS_M, headland_m: float = HEADLAND_M,
                  shape: str = "column", navigation: str = "rtk-fixed") -> Path:
    """Write ``orchard.geojson`` and ``orchard.toml`` into ``folder``; the scenario's path.

    ``rows`` north-south rows :data:`ROW_SPACING_M` apart of ``per_row`` trees
    ``tree_spacing_m`` apart (canopy ``canopy_radius_m``), ``headland_m`` from the last
    trees to the area's north and south edges; three UAVs 4 m apart in ``shape``
    (:data:`SHAPES`: a north-south column or an east-west line), ``[navigation] class``
    ``navigation``. Issue 51's orchard: ``rows=60, per_row=80, tree_spacing_m=4,
    canopy_radius_m=1.2, headland_m=18`` (:func:`issue51_files`)."""
    width = (rows + 1) * ROW_SPACING_M
    length = 2 * headland_m + (per_row - 1) * tree_spacing_m

    frame = LocalFrame(LAT0, LON0)  # the scenario's own: its origin the south-west corner

    def ll(e: float, n: float) -> tuple[float, float]:
        lat, lon, _ = frame.to_lla([e, n, 0.0])
        return float(lat), float(lon)

    e, n = np.meshgrid((np.arange(rows) + 1) * ROW_SPACING_M,
                       headland_m + np.arange(per_row) * tree_spacing_m, indexing="ij")
    lat, lon, _ = frame.to_lla(np.stack([e, n, np.zeros_like(e)], axis=-1))
    features = []
    for r in range(rows):
        for t in range(per_row):
            features.append(
                f'{{"type": "Feature", "properties": {{"name": "row {r + 1} tree {t + 1}", '
                f'"radius": {canopy_radius_m}}}, "geometry": {{"type": "Point", '
                f'"coordinates": [{lon[r, t]:.8f}, {lat[r, t]:.8f}]}}}}')
    (folder / "orchard.geojson").write_text(
        '{"type": "FeatureCollection", "name": "orchard", "features": [\n'
        + ",\n".join(features) + "\n]}\n")
    offsets = np.array(json.loads(SHAPES[shape]))
    # the outermost UAVs in the outer aisles: the lanes on the aisles' centre lines
    margin = ROW_SPACING_M / 2 + float(np.abs(offsets[:, 0]).max())
    start, goal = ll(margin, 5.0), ll(width - margin, length - 5.0 if rows % 2 == 0 else 5.0)
    text = "\n".join([
        f'name = "Orchard of {rows * per_row} trees, {rows} rows"',
        'obstacles_file = "orchard.geojson"',
        "[area]", f"corner_a = [{LAT0}, {LON0}]",
        "corner_b = [{:.8f}, {:.8f}]".format(*ll(width, length)),
        "min_altitude = 2.0", "max_altitude = 7.0",
        "[start]", "lat = {:.7f}\nlon = {:.7f}\nalt = 4.0".format(*start),
        "[goal]", "lat = {:.7f}\nlon = {:.7f}\nalt = 4.0".format(*goal),
        "[formation]", f"offsets = {SHAPES[shape]}",
        "clearance = 1.0", "[navigation]", f'class = "{navigation}"',  # aisles need RTK
        "[survey]", f"spacing = {ROW_SPACING_M}", "heading = 0.0", f"margin = {margin}",
        "[planner]", 'waypoints = "auto"', "seed = 0",
        "[mission]", "speed = 3.0", 'end_action = "land"', ""])
    path = folder / "orchard.toml"
    path.write_text(text)
    return path


ISSUE51 = {"rows": 60, "per_row": 80, "tree_spacing_m": 4.0, "canopy_radius_m": 1.2,
           "headland_m": 18.0, "navigation": "rtk-fixed"}
"""Issue 51's orchard: 4,800 trees, 60 rows of 80, 7 m x 4 m, canopy 1.2 m, 18 m headlands."""


def issue51_files(folder: Path, *, shape: str = "column", headland_m: float = 18.0) -> Path:
    """Issue 51's orchard (:data:`ISSUE51`) in ``folder``, flown by a column or a line,
    with ``headland_m`` headlands (10: too narrow for the 8 m column to turn)."""
    return orchard_files(folder, **{**ISSUE51, "headland_m": headland_m}, shape=shape)


def _peak_rss_mib() -> float:
    """The largest resident set of any child waited for so far (Linux: KiB)."""
    return resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0


def plan_process(scenario: Path, out: Path, *, timeout_s: float
                 ) -> tuple[float, subprocess.CompletedProcess] | None:
    """``python -m ftlbo_mav plan scenario -o out`` in a fresh process: wall seconds from
    its start to its exit and the finished process (stderr ends with its own peak
    resident memory, ``peak_rss_kib N``); ``None`` when killed after ``timeout_s``."""
    t0 = time.perf_counter()
    try:
        # the peak memory of this child alone: a fresh interpreter that runs it and
        # reports its own children's maximum
        proc = subprocess.run(
            [sys.executable, "-c",
             "import resource, subprocess, sys; "
             "p = subprocess.run(sys.argv[1:]); "
             "print('peak_rss_kib', resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss,"
             " file=sys.stderr); sys.exit(p.returncode)",
             sys.executable, "-m", "ftlbo_mav", "plan", str(scenario), "-o", str(out)],
            capture_output=True, text=True, cwd=ROOT, timeout=timeout_s)
    except subprocess.TimeoutExpired:
        return None
    return time.perf_counter() - t0, proc


def _peak_mib(proc: subprocess.CompletedProcess) -> float | None:
    peak = re.search(r"peak_rss_kib (\d+)", proc.stderr)
    return round(int(peak.group(1)) / 1024.0, 1) if peak else None


def run_orchard(trees: int, *, timeout_s: float = 600.0) -> dict:
    """Plan the orchard of about ``trees`` trees once, in a fresh process."""
    rows, per_row = layout(trees)
    compile_package()  # as installed: the bytecode written
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        scenario = orchard_files(folder, rows=rows, per_row=per_row)
        done = plan_process(scenario, folder / "out", timeout_s=timeout_s)
        if done is None:
            return {"what": f"orchard {trees} trees", "trees": rows * per_row,
                    "seconds": None, "timeout_s": timeout_s}
        seconds, proc = done
        out = proc.stdout + proc.stderr
        clearance = re.search(r"flown path \(predicted\): clearance ([\d.]+) m", out)
        legs = re.search(r"(\d+) legs?,", out)
        plan = folder / "out" / "plan.json"
        lanes = len(json.loads(plan.read_text()).get("survey", {}).get("lanes", [])) \
            if plan.is_file() else None
        return {"what": f"orchard {trees} trees", "trees": rows * per_row, "rows": rows,
                "lanes": lanes, "legs": int(legs.group(1)) if legs else None,
                "seconds": round(seconds, 2),
                "peak_rss_mib": _peak_mib(proc),
                "exit": proc.returncode, "feasible": proc.returncode == 0 and "feasible;" in out,
                "clearance_m": float(clearance.group(1)) if clearance else None,
                "last": out.strip().splitlines()[-3:]}


ISSUE51_GOALS = [  # (what, shape, headland m, limit s, refused)
    ("issue 51 orchard, a column through the aisles", "column", 18.0, 30.0, False),
    ("issue 51 orchard, a line across the aisles (7 m apart)", "line7", 18.0, 30.0, False),
    ("issue 51 orchard, 10 m headlands: refused", "column", 10.0, 5.0, True),
    ("issue 51 orchard, a line 4 m apart across 7 m aisles: refused", "line", 18.0, 5.0, True),
]
REFUSED_EXIT = 2
"""The exit code of a refused scenario (``cli_errors.user_errors``: a ScenarioError)."""


def issue51_rows(*, timeout_s: float = 120.0) -> list[dict]:
    """Issue 51's goals measured now, as rows of ``benchmarks/goals.py`` (its ``row``):
    the 4,800-tree orchard (:data:`ISSUE51`) planned by a whole ``ftlbo-mav plan``
    process within 30 s flown by a column through the aisles and by a line across them
    (three UAVs 7 m apart, one an aisle: a line 4 m apart cannot be between the rows),
    each feasible; the same orchard with 10 m headlands, where the 8 m column cannot
    turn, and the 4 m line refused within 5 s with exit code :data:`REFUSED_EXIT`; and
    every process's peak resident memory under 2 GiB (a row of its own). Each process is
    killed after ``timeout_s`` seconds. The load average is in each row's note."""
    from goals import row  # the benchmarks' one row format (run as a script, beside it)

    compile_package()
    rows, peaks = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for k, (what, shape, headland, limit, refused) in enumerate(ISSUE51_GOALS):
            folder = Path(tmp) / str(k)
            folder.mkdir()
            scenario = issue51_files(folder, shape=shape, headland_m=headland)
            load = " ".join(f"{x:.2f}" for x in os.getloadavg())
            done = plan_process(scenario, folder / "out", timeout_s=timeout_s)
            if done is None:
                rows.append(row(what, "issue 51", f"<= {limit:g} s", f"timeout > {timeout_s:g} s",
                                False, value=None, limit_value=limit,
                                note=f"load {load} at the start"))
                continue
            seconds, proc = done
            peak = _peak_mib(proc)
            peaks.append(peak or 0.0)
            text = proc.stdout + proc.stderr
            if refused:
                ok = proc.returncode == REFUSED_EXIT and "cannot be flown" in text
                said = f"{seconds:.2f} s, exit {proc.returncode}" + ("" if ok else ", not refused")
            else:
                ok = proc.returncode == 0 and "feasible;" in text
                said = f"{seconds:.2f} s" + ("" if ok else f", exit {proc.returncode}, infeasible")
            rows.append(row(what, "issue 51", f"<= {limit:g} s" + (", exit 2" if refused else ""),
                            said, ok and seconds <= limit, value=round(seconds, 2),
                            limit_value=limit, peak_rss_mib=peak,
                            note=f"load {load} at the start; benchmarks/orchard.py issue51_rows"))
    top = max(peaks) if peaks else None
    rows.append(row("issue 51 orchard, peak memory of every plan process", "issue 51",
                    f"< {MEMORY_GOAL_MIB:g} MiB", f"{top} MiB" if top else "not measured",
                    top is not None and top < MEMORY_GOAL_MIB, value=top,
                    limit_value=MEMORY_GOAL_MIB, peak_rss_mib=top))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="5,000 and 20,000 trees once")
    parser.add_argument("--trees", type=int, action="append", default=[],
                        help="an orchard of about this many trees (repeatable)")
    parser.add_argument("--json", default="orchard-benchmark.json", help="output JSON path")
    parser.add_argument("--timeout", type=float, default=600.0, help="seconds per plan")
    parser.add_argument("--issue51", action="store_true",
                        help="issue 51's goals only (issue51_rows), as goals.py's rows")
    args = parser.parse_args()
    sizes = args.trees or [5_000, 20_000]
    load = os.getloadavg()
    print(f"load average at start: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}", flush=True)
    if args.issue51:
        rows = issue51_rows(timeout_s=args.timeout)
        print(table(["goal", "limit", "measured", "peak MiB", "status", "note"],
                    [[r["goal"], r["limit"], r["measured"], r["peak_rss_mib"], r["status"],
                      r["note"]] for r in rows]))
        Path(args.json).write_text(json.dumps({"load": load, "rows": rows}, indent=1) + "\n")
        return
    rows = []
    for trees in sizes:
        row = run_orchard(trees, timeout_s=args.timeout)
        rows.append(row)
        print(json.dumps({k: v for k, v in row.items() if k != "last"}), flush=True)
        if not row.get("feasible"):
            print("  " + "\n  ".join(row.get("last", [])), flush=True)
    print(table(["trees", "lanes", "legs", "plan s", "goal s", "peak MiB", "feasible",
                 "clearance m"],
                [[r["trees"], r.get("lanes"), r.get("legs"),
                  f"{r['seconds']:.1f}" if r["seconds"] is not None
                  else f"timeout > {r['timeout_s']:g}",
                  f"<= {GOALS[s]:g}" if s in GOALS else "", r.get("peak_rss_mib"),
                  "yes" if r.get("feasible") else "no", r.get("clearance_m")]
                 for s, r in zip(sizes, rows)]))
    Path(args.json).write_text(json.dumps({"load": load, "rows": rows}, indent=1) + "\n")


if __name__ == "__main__":
    main()
