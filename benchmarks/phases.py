"""Where one ``plan`` process spends its time: the imports, the first plan (numba's
start-up inside it), the same plan again in the same process with nothing kept from the
first (the planning work alone), and the files written.

Plain ``python benchmarks/phases.py`` plans ``benchmarks/scale.py``'s 400 m field with 10
UAVs among 320 trees (issue 30's goal: the whole process in 1 s); ``--uavs``,
``--trees``, ``--side`` choose another of its fields, ``--scenario FILE`` any scenario.
Each figure is measured in a fresh process (this script runs itself once per
``--repeats``, default 3) and printed per run, so the spread shows. The process's start
(the interpreter, before the first import) is measured apart, as ``python -c pass``.

``start-up in the first plan`` is the first plan's time less the same plan's again:
numba's import, its CPU target and the cached machine code of each compiled loop the
plan runs, and whatever else the first plan pays once.
"""

from __future__ import annotations

import time

STARTED = time.perf_counter()  # before any import of this script's but time's

import argparse  # noqa: E402
import json  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
from pathlib import Path  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def measure(scenario: Path, out: Path) -> dict:
    """The phases of one plan in this process (run it in a fresh one)."""
    t0 = STARTED
    import ftlbo_mav.cli  # noqa: F401  (what `ftlbo-mav plan` imports first)
    from ftlbo_mav.ardupilot import flight_path
    from ftlbo_mav.mission.export import write_plan
    from ftlbo_mav.planning import tangents
    from ftlbo_mav.planning.planner import plan
    from ftlbo_mav.scenario import load_scenario

    imports = time.perf_counter() - t0
    t = time.perf_counter()
    loaded = load_scenario(scenario)
    read = time.perf_counter() - t
    t = time.perf_counter()
    planned = plan(loaded)
    first = time.perf_counter() - t
    t = time.perf_counter()
    write_plan(planned, out)
    files = time.perf_counter() - t
    # the same plan again, nothing kept: no flights to take up, no graph's bitangents
    flight_path._FLOWN = flight_path._Flown()
    tangents._LAST_BITANGENTS.clear()
    t = time.perf_counter()
    plan(loaded)
    again = time.perf_counter() - t
    return {"imports_s": imports, "scenario_s": read, "first_plan_s": first,
            "files_s": files, "plan_again_s": again, "startup_in_first_s": first - again,
            "feasible": bool(planned.feasible)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", type=Path, help="a scenario file (default: a field "
                        "of benchmarks/scale.py)")
    parser.add_argument("--uavs", type=int, default=10)
    parser.add_argument("--trees", type=int, default=320)
    parser.add_argument("--side", type=float, default=400.0, help="field side, m")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--child", nargs=2, metavar=("SCENARIO", "OUT"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        print(json.dumps(measure(Path(args.child[0]), Path(args.child[1]))))
        return
    if args.repeats < 1:
        parser.error("--repeats: at least 1")
    from scale import compile_package, scenario_text  # (numpy: not before a child's imports)

    compile_package()
    with tempfile.TemporaryDirectory() as tmp:
        scenario = args.scenario
        what = str(scenario)
        if scenario is None:
            scenario = Path(tmp) / "field.toml"
            scenario.write_text(scenario_text(uavs=args.uavs, obstacles=args.trees,
                                              side_m=args.side))
            what = f"{args.uavs} UAVs, {args.trees} trees, {args.side:g} m field"
        elif not scenario.is_file():
            parser.error(f"--scenario {scenario}: no such file")
        print(f"{what}; {sys.executable}", flush=True)
        names = ["interpreter", "imports", "scenario", "first plan", "files", "plan again",
                 "start-up in the first plan", "feasible"]
        print("  ".join(f"{n:>12s}" for n in names))
        for r in range(args.repeats):
            t = time.perf_counter()
            subprocess.run([sys.executable, "-c", "pass"], check=True)
            interpreter = time.perf_counter() - t
            proc = subprocess.run([sys.executable, __file__, "--child", str(scenario),
                                   str(Path(tmp) / f"out{r}")], cwd=ROOT, capture_output=True,
                                  text=True)
            if proc.returncode != 0:
                raise SystemExit(f"plan failed: {proc.stderr.strip().splitlines()[-1:]}")
            f = json.loads(proc.stdout.strip().splitlines()[-1])
            row = [interpreter, f["imports_s"], f["scenario_s"], f["first_plan_s"],
                   f["files_s"], f["plan_again_s"], f["startup_in_first_s"]]
            print("  ".join(f"{v:>11.3f}s" for v in row)
                  + f"  {'yes' if f['feasible'] else 'no':>12s}", flush=True)


if __name__ == "__main__":
    main()
