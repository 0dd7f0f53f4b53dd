"""The Dask side of ``risk``: a worker that dies loses only the flights it was running,
which run again elsewhere; the records come back in seed order. On a real two-worker
local cluster, with a stand-in for the flight (the flights themselves:
tests/integration/test_risk.py)."""

from __future__ import annotations

import functools
import os
import time
from pathlib import Path

from ftlbo_mav.risk.conditions import Ranges
from ftlbo_mav.risk.engine import run_flights

from ..conftest import EXAMPLE


def _dies_on_its_first_try(marks: str, files, ranges, seed, copters, time_scale) -> dict:
    """Seed 1's first try takes its worker process down with it (as a worker killed by
    the machine's out-of-memory killer); seed 2's first try is cancelled by the scheduler
    (as a key lost with a dying worker); every other try is a completed flight."""
    first = Path(marks) / f"seed{seed}"
    if seed == 1 and not first.exists():
        first.write_text(str(os.getpid()))
        os._exit(1)
    if seed == 2 and not first.exists():
        from distributed import Future, get_client, get_worker

        first.write_text(str(os.getpid()))
        client = get_client()
        client.cancel([Future(get_worker().get_current_task(), client)], force=True)
        time.sleep(1.0)  # (its result, if any, is never asked for)
    return {"seed": seed, "outcome": "completed", "exit_code": 0, "departures": [],
            "true_min_clearance_m": 1.0 + seed, "worker_pid": os.getpid(),
            "files": len(files), "copters": copters}


def test_a_worker_that_dies_loses_only_its_flight_which_runs_again(tmp_path):
    task = functools.partial(_dies_on_its_first_try, str(tmp_path))
    seen = []
    records = run_flights(EXAMPLE.with_suffix(""), Ranges(), [0, 1, 2, 3], workers=2,
                          task=task, on_progress=seen.append)
    assert [r["seed"] for r in records] == [0, 1, 2, 3]
    assert all(r["outcome"] == "completed" for r in records), records
    died = int((tmp_path / "seed1").read_text())
    assert records[1]["worker_pid"] != died  # flown again, by another worker process
    assert (tmp_path / "seed2").exists()  # cancelled once, sent again
    assert records[0]["files"] > 0 and records[0]["copters"] == 3  # the plan went along
    assert [t.done for t in seen] == [1, 2, 3, 4] and seen[-1].least_clearance_m == 1.0
