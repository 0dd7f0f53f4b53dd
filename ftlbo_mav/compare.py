"""Many seeds of several algorithms on one scenario: the paper's Table 2 with spread.

``compare(scenario, algorithms=..., runs=30)`` plans the scenario with every algorithm for
seeds ``0..runs-1`` (spread over processes), and returns a :class:`Comparison`: every
run's numbers and, per algorithm, the statistics of the converged cost. Rendering is
pure (:func:`table_markdown`, :func:`table_csv`, :func:`compare_document`,
:func:`convergence_figure`); :func:`write_comparison` is the only function that writes
files.

Definitions (docs/planning.md):

- *converged cost*: the paper's total cost (eq. 5) of the run's best plan. Statistics
  are over the feasible runs (an infeasible plan's cost is infinite).
- *iteration*: one FTLBO iteration's worth of evaluations (``2 * students + 1``); every
  algorithm's best cost is recorded on that clock (:class:`.optimizers.base.BudgetTracker`).
- *iterations to converge*: the first iteration whose best cost is within 0.1% of the
  run's final cost; *first feasible iteration*: the first whose best plan is feasible
  (the paper's table starts every algorithm from one cost, 248.28; random classes on our
  map often start with no feasible student at all).
- *seconds*: ``Plan.seconds``, the optimizer's wall time (for ``ftlbo-seeded`` with its
  routes and seeds), measured while the other processes run.
"""

from __future__ import annotations

import csv
import io
import json
import math
import multiprocessing
import os
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

from .mission.files import OutputFolder
from .planning.optimizers import OPTIMIZERS, evaluation_budget
from .planning.planner import check_size, plan
from .scenario import Scenario

CONVERGED_WITHIN = 1e-3
"""Relative distance to the final cost at which a run counts as converged."""


@dataclass(frozen=True)
class Run:
    """One algorithm on one seed. Costs are ``inf`` when the plan is infeasible."""

    algorithm: str
    seed: int
    cost: float
    length: float
    safety: float
    task: float
    feasible: bool
    first_feasible_iteration: int | None
    converged_iteration: int | None
    seconds: float
    evaluations: int
    length_ratio: float | None
    history: tuple[float, ...]


@dataclass(frozen=True)
class Summary:
    """Per algorithm: statistics of the converged cost over the feasible runs."""

    algorithm: str
    runs: int
    feasible: int
    min: float
    median: float
    mean: float
    max: float
    std: float
    first_feasible_median: float
    iterations_median: float
    seconds_median: float
    evaluations_median: float
    ratio_median: float | None

    @property
    def feasible_rate(self) -> float:
        return self.feasible / self.runs if self.runs else 0.0


@dataclass(frozen=True)
class Comparison:
    """Every run, in the order of ``algorithms`` then seed, and the settings used."""

    scenario: str
    algorithms: tuple[str, ...]
    students: int
    waypoints: int | str
    iterations: int
    lower_bound_length: float | None
    runs: tuple[Run, ...]

    @property
    def budget(self) -> int:
        return evaluation_budget(self.students, self.iterations)

    def of(self, algorithm: str) -> list[Run]:
        return [r for r in self.runs if r.algorithm == algorithm]

    def summaries(self) -> list[Summary]:
        return [summarize(algorithm, self.of(algorithm)) for algorithm in self.algorithms]


def converged_iteration(
    history: Sequence[float], *, within: float = CONVERGED_WITHIN
) -> int | None:
    """First iteration (1-based) within ``within`` (relative) of the final best cost."""
    h = np.asarray(history, float)
    if not len(h) or not np.isfinite(h[-1]):
        return None
    hit = np.nonzero(h <= h[-1] + within * abs(h[-1]))[0]
    return int(hit[0]) + 1


def first_feasible_iteration(history: Sequence[float]) -> int | None:
    """First iteration (1-based) whose best student is feasible (finite cost)."""
    hit = np.nonzero(np.isfinite(np.asarray(history, float)))[0]
    return int(hit[0]) + 1 if len(hit) else None


def run_one(scenario: Scenario, algorithm: str, seed: int, *, students: int | None = None,
            iterations: int | None = None, waypoints: int | str | None = None) -> Run:
    """Plan ``scenario`` once and keep the numbers a comparison needs."""
    p = plan(scenario, algorithm=algorithm, seed=seed, students=students,
             iterations=iterations, waypoints=waypoints)
    history = tuple(float(h) for h in p.history)
    return Run(
        algorithm=algorithm,
        seed=seed,
        cost=float(p.cost.total) if p.feasible else math.inf,
        length=float(p.cost.length),
        safety=float(p.cost.safety),
        task=float(p.cost.task),
        feasible=p.feasible,
        first_feasible_iteration=first_feasible_iteration(history),
        converged_iteration=converged_iteration(history),
        seconds=float(p.seconds),
        evaluations=int(p.evaluations),
        length_ratio=p.length_ratio if p.feasible else None,
        history=history,
    )


def summarize(algorithm: str, runs: Sequence[Run]) -> Summary:
    """Statistics of ``runs`` of one algorithm (cost statistics over feasible runs)."""
    costs = np.array([r.cost for r in runs if r.feasible], float)
    nan = math.nan

    def stat(fn, values):
        return float(fn(values)) if len(values) else nan

    iterations = [r.converged_iteration for r in runs if r.converged_iteration is not None]
    ratios = [r.length_ratio for r in runs if r.length_ratio is not None]
    first = [r.first_feasible_iteration for r in runs if r.first_feasible_iteration is not None]
    return Summary(
        algorithm=algorithm,
        runs=len(runs),
        feasible=len(costs),
        min=stat(np.min, costs),
        median=stat(np.median, costs),
        mean=stat(np.mean, costs),
        max=stat(np.max, costs),
        std=stat(np.std, costs),
        first_feasible_median=stat(np.median, first),
        iterations_median=stat(np.median, iterations),
        seconds_median=stat(np.median, [r.seconds for r in runs]),
        evaluations_median=stat(np.median, [r.evaluations for r in runs]),
        ratio_median=float(np.median(ratios)) if ratios else None,
    )


# --------------------------------------------------------------------------- running

_WORKER_SCENARIO: Scenario | None = None


def _init_worker(scenario: Scenario) -> None:
    global _WORKER_SCENARIO
    _WORKER_SCENARIO = scenario


def _work(job: tuple[str, int, dict]) -> Run:
    algorithm, seed, overrides = job
    return run_one(_WORKER_SCENARIO, algorithm, seed, **overrides)


def compare(
    scenario: Scenario,
    *,
    algorithms: Sequence[str],
    runs: int = 30,
    students: int | None = None,
    iterations: int | None = None,
    waypoints: int | str | None = None,
    processes: int | None = None,
    progress: Callable[[Run], None] | None = None,
) -> Comparison:
    """Run every algorithm on seeds ``0..runs-1``; ``processes`` (default: the cores) > 1
    spreads the runs over worker processes. ``progress(run)`` after every finished run."""
    unknown = [a for a in algorithms if a not in OPTIMIZERS]
    if unknown:
        raise ValueError(f"unknown algorithm {unknown[0]!r}; known: {', '.join(OPTIMIZERS)}")
    overrides = {"students": students, "iterations": iterations, "waypoints": waypoints}
    check_size(scenario, replace(scenario.planner, **{
        k: v for k, v in overrides.items() if v is not None}), repeats=runs * len(algorithms))
    jobs = [(a, seed, overrides) for a in algorithms for seed in range(runs)]
    processes = processes or os.cpu_count() or 1
    results: dict[tuple[str, int], Run] = {}
    # A fresh copy drops cached, unpicklable state (the pyproj frame) before pickling.
    portable = replace(scenario)
    if processes > 1 and len(jobs) > 1:
        context = multiprocessing.get_context("fork" if os.name == "posix" else "spawn")
        with ProcessPoolExecutor(max_workers=min(processes, len(jobs)), mp_context=context,
                                 initializer=_init_worker, initargs=(portable,)) as pool:
            for future in as_completed([pool.submit(_work, job) for job in jobs]):
                run = future.result()
                results[run.algorithm, run.seed] = run
                if progress is not None:
                    progress(run)
    else:
        _init_worker(portable)
        for job in jobs:
            run = _work(job)
            results[run.algorithm, run.seed] = run
            if progress is not None:
                progress(run)
    settings = scenario.planner
    first = next(iter(results.values()))
    bound = plan_bound(scenario, waypoints=waypoints)
    return Comparison(
        scenario=scenario.name or scenario.source,
        algorithms=tuple(algorithms),
        students=students or settings.students,
        waypoints=waypoints or settings.waypoints,
        iterations=len(first.history),
        lower_bound_length=bound,
        runs=tuple(results[a, s] for a in algorithms for s in range(runs)),
    )


def plan_bound(scenario: Scenario, *, waypoints: int | str | None = None) -> float | None:
    """The scenario's lower bound on the centroid length (metres; the sum of its legs'),
    ``None``: no route. ``waypoints`` is not used (the bound does not depend on it)."""
    from .planning.planner import route_lower_bound

    return route_lower_bound(scenario)


# --------------------------------------------------------------------------- rendering

COLUMNS = (
    ("algorithm", "algorithm"),
    ("runs", "runs"),
    ("feasible", "feasible"),
    ("min", "min cost"),
    ("median", "median cost"),
    ("mean", "mean cost"),
    ("max", "max cost"),
    ("std", "std"),
    ("first_feasible_median", "first feasible iteration (median)"),
    ("iterations_median", "iterations to converge (median)"),
    ("seconds_median", "seconds (median)"),
    ("evaluations_median", "evaluations (median)"),
    ("ratio_median", "length / bound (median)"),
)


def _cells(s: Summary) -> list[str]:
    def num(v, fmt="{:.2f}"):
        return "-" if v is None or (isinstance(v, float) and math.isnan(v)) else fmt.format(v)

    return [
        s.algorithm, str(s.runs), f"{s.feasible_rate:.0%}", num(s.min), num(s.median),
        num(s.mean), num(s.max), num(s.std), num(s.first_feasible_median, "{:.0f}"),
        num(s.iterations_median, "{:.0f}"), num(s.seconds_median, "{:.3f}"),
        num(s.evaluations_median, "{:.0f}"), num(s.ratio_median, "{:.4f}"),
    ]


def table_markdown(comparison: Comparison) -> str:
    """The Table-2 style table in Markdown, with a line on what was run."""
    c = comparison
    bound = "none (no route)" if c.lower_bound_length is None else f"{c.lower_bound_length:.2f} m"
    lines = [
        f"{c.scenario}: {len(c.runs) // max(len(c.algorithms), 1)} seeds per algorithm, "
        f"{c.students} students, {c.waypoints} waypoints, {c.iterations} iterations "
        f"(budget {c.budget} evaluations); lower bound on the centroid length {bound}. "
        "Costs are the paper's eq. 5 over the feasible runs.",
        "",
        "| " + " | ".join(title for _, title in COLUMNS) + " |",
        "|" + "|".join(" --- " if i == 0 else " ---: " for i in range(len(COLUMNS))) + "|",
    ]
    for s in c.summaries():
        lines.append("| " + " | ".join(_cells(s)) + " |")
    return "\n".join(lines) + "\n"


def table_csv(comparison: Comparison) -> str:
    """The same statistics, one row per algorithm, full precision."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow([key for key, _ in COLUMNS] + ["feasible_rate"])
    for s in comparison.summaries():
        row = asdict(s)
        writer.writerow(["" if row[k] is None else row[k] for k, _ in COLUMNS]
                        + [s.feasible_rate])
    return buf.getvalue()


def _json_number(v):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return None
    return v


def compare_document(comparison: Comparison) -> dict:
    """``compare.json``: settings, summaries and every run (infinite costs as null)."""
    c = comparison
    return {
        "scenario": c.scenario,
        "algorithms": list(c.algorithms),
        "students": c.students,
        "waypoints": c.waypoints,
        "iterations": c.iterations,
        "budget": c.budget,
        "lower_bound_length": c.lower_bound_length,
        "summary": [
            {k: _json_number(v) for k, v in asdict(s).items()} | {"feasible_rate": s.feasible_rate}
            for s in c.summaries()
        ],
        "runs": [
            {k: ([_json_number(round(h, 6)) for h in v] if k == "history"
                 else _json_number(v))
             for k, v in asdict(r).items()}
            for r in c.runs
        ],
    }


def convergence_figure(comparison: Comparison):
    """Median best cost per iteration with the inter-quartile band, one line per
    algorithm (the paper's convergence figure, over seeds). Returns a Figure (Agg)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    c = comparison
    fig = Figure(figsize=(7.0, 4.5), dpi=120)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    finite_low, finite_high = [], []
    for algorithm in c.algorithms:
        runs = c.of(algorithm)
        h = np.array([r.history for r in runs], float)  # inf: no feasible student yet
        # Nearest-rank quantiles: an infeasible run counts as the worst, so a quantile is
        # known (finite) once that share of the runs is feasible, and not drawn before.
        q25, q50, q75 = np.percentile(h, [25, 50, 75], axis=0, method="inverted_cdf")
        q25, q50, q75 = (np.where(np.isfinite(q), q, np.nan) for q in (q25, q50, q75))
        x = np.arange(1, h.shape[1] + 1)
        feasible = sum(r.feasible for r in runs)
        (line,) = ax.plot(x, q50, linewidth=1.8, zorder=3,
                          label=f"{algorithm} ({feasible}/{len(runs)} runs feasible)")
        ax.fill_between(x, q25, q75, color=line.get_color(), alpha=0.15, linewidth=0, zorder=1)
        if np.isfinite(q50).any():  # y range: from the lowest quartile to the medians
            finite_low.append(np.nanmin(q25))  # after the first few iterations' plunge
            later = q50[h.shape[1] // 15 :]
            finite_high.append(np.nanmax(later) if np.isfinite(later).any() else np.nanmax(q50))
    if c.lower_bound_length is not None:
        ax.axhline(c.lower_bound_length, color="black", linestyle=":", linewidth=1.0, zorder=2,
                   label=f"lower bound on the length ({c.lower_bound_length:.2f} m)")
        finite_low.append(c.lower_bound_length)
    if finite_low and finite_high:
        lo, hi = min(finite_low), max(finite_high)
        ax.set_ylim(lo - 0.05 * (hi - lo), hi + 0.05 * (hi - lo))
    ax.set_xlabel(f"iteration (FTLBO's {2 * c.students + 1} evaluations each)")
    ax.set_ylabel("best cost (eq. 5)")
    ax.set_title(f"Convergence on {c.scenario}: median and inter-quartile band", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    return fig


def comparison_files(comparison: Comparison) -> dict[str, str | bytes]:
    """``table.md``, ``table.csv``, ``compare.json`` and ``convergence.png`` by name (pure)."""
    from .plots import render_png

    return {
        "table.md": table_markdown(comparison),
        "table.csv": table_csv(comparison),
        "compare.json": json.dumps(compare_document(comparison), indent=1) + "\n",
        "convergence.png": render_png(convergence_figure(comparison)),
    }


def write_comparison(comparison: Comparison, out_dir: str | Path) -> list[Path]:
    """Write :func:`comparison_files` into ``out_dir``, all or none."""
    files = comparison_files(comparison)
    with OutputFolder(out_dir) as out:
        return out.write_all(files)
