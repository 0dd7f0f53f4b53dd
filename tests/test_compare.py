"""`compare`: many seeds per algorithm, the table, the JSON, the convergence figure."""

from __future__ import annotations

import csv
import io
import json
import math

from click.testing import CliRunner

from ftlbo_mav.cli import main
from ftlbo_mav.compare import (
    compare,
    compare_document,
    converged_iteration,
    first_feasible_iteration,
    table_csv,
    table_markdown,
)
from ftlbo_mav.scenario import parse_scenario

from .conftest import SMALL

FAST = dict(runs=2, students=10, iterations=6)
ALGORITHMS = ("ftlbo", "tlbo", "ga", "theta-pso", "ftlbo-seeded")


def test_iteration_helpers():
    history = [math.inf, math.inf, 120.0, 101.0, 100.05, 100.0]
    assert first_feasible_iteration(history) == 3
    assert converged_iteration(history) == 5  # 100.05 is within 0.1% of 100
    assert converged_iteration([math.inf, math.inf]) is None
    assert first_feasible_iteration([math.inf]) is None


def test_runs_are_the_same_in_one_process_or_many():
    scenario = parse_scenario(SMALL)
    one = compare(scenario, algorithms=ALGORITHMS, processes=1, **FAST)
    many = compare(scenario, algorithms=ALGORITHMS, processes=2, **FAST)
    assert [(r.algorithm, r.seed) for r in one.runs] == [
        (a, s) for a in ALGORITHMS for s in range(2)]
    for a, b in zip(one.runs, many.runs):
        assert (a.cost, a.history, a.evaluations) == (b.cost, b.history, b.evaluations)
    budget = 10 + 6 * 21
    assert all(r.evaluations == budget for r in one.runs if r.algorithm != "ftlbo-seeded")
    assert all(len(r.history) == 6 for r in one.runs)


def test_table_csv_and_json_have_one_row_per_algorithm():
    scenario = parse_scenario(SMALL)
    seen = []
    result = compare(scenario, algorithms=("ftlbo", "ga"), processes=1,
                     progress=seen.append, **FAST)
    assert len(seen) == 4
    table = table_markdown(result)
    rows = [line for line in table.splitlines() if line.startswith("|")]
    assert len(rows) == 4 and rows[2].startswith("| ftlbo |") and rows[3].startswith("| ga |")
    parsed = list(csv.DictReader(io.StringIO(table_csv(result))))
    assert [r["algorithm"] for r in parsed] == ["ftlbo", "ga"]
    for row, summary in zip(parsed, result.summaries()):
        if summary.feasible:
            assert float(row["median"]) == summary.median
            assert summary.min <= summary.median <= summary.max
    doc = compare_document(result)
    json.dumps(doc, allow_nan=False)  # no NaN or infinity in the file
    assert len(doc["runs"]) == 4 and doc["budget"] == 10 + 6 * 21
    assert doc["lower_bound_length"] > 0


def test_compare_command_writes_the_four_files(small_path, tmp_path):
    out = tmp_path / "cmp"
    result = CliRunner().invoke(main, [
        "compare", str(small_path), "-o", str(out), "--runs", "2", "--iterations", "4",
        "--students", "8", "--algorithms", "ftlbo,theta-pso", "--processes", "1"])
    assert result.exit_code == 0, result.output
    assert "| ftlbo |" in result.stdout and "| theta-pso |" in result.stdout
    assert "comparing" in result.stderr
    assert sorted(p.name for p in out.iterdir()) == [
        "compare.json", "convergence.png", "table.csv", "table.md"]
    assert (out / "convergence.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (out / "table.md").read_text() in result.stdout


def test_compare_command_refuses_an_unknown_algorithm(small_path, tmp_path):
    result = CliRunner().invoke(main, [
        "compare", str(small_path), "-o", str(tmp_path), "--algorithms", "ftlbo,pso"])
    assert result.exit_code == 2
    assert "unknown algorithm 'pso'" in result.output
    assert "Traceback" not in result.output
