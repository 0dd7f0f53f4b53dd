"""The risk flights as Dask tasks: each flight one task, on a local cluster of this
machine's cores (the default) or on a running Dask cluster (``--scheduler ADDRESS``).

A task carries the plan folder's files (a few tens of kilobytes), so a worker on another
machine needs nothing but ftlbo-mav installed; it writes them to a temporary folder, flies
(:func:`.flight.fly_one`: its own emulated copters on ports the system chooses, so several
flights share a worker) and removes everything. A worker that dies loses only the flights
it was running, which Dask runs again elsewhere (its ``allowed-failures``); a flight that
raises is tried again twice (``retries``), then recorded as failed with its error; one
the scheduler cancels (a key lost with a dying worker) is sent again, twice at most.
"""

from __future__ import annotations

import logging
import os
import tempfile
import time
from collections.abc import Callable, Sequence
from concurrent.futures import CancelledError
from dataclasses import dataclass
from pathlib import Path

from ..errors import BadInput
from ..flight.planned import load_planned_flight
from .conditions import Ranges, draw
from .flight import fly_one

MAX_PLAN_BYTES = 50 * 1024 * 1024
CANCELLED_AGAIN = 2
"""How often a flight the scheduler cancelled (not one that failed: Dask's ``retries``
runs those again) is sent again before it is recorded as failed."""
NO_PROFILER = {"distributed.worker.profile.enabled": False}
"""Dask's worker samples every thread's stack (``sys._current_frames``) every 10 ms; a
flight starts and ends a dozen threads, and CPython before 3.12 can deadlock there (the
interpreter's thread-list lock against the GIL, python/cpython#106883: two runs of 100
flights hung, the worker's event loop in ``Worker.trigger_profile``). The workers fly
without it."""


@dataclass(frozen=True)
class Tally:
    """Where a run stands: flights ``done`` of ``total``, ``running`` now, and the
    running figures (the smallest true clearance so far, flights that left the plan)."""

    done: int
    total: int
    running: int
    least_clearance_m: float | None
    left_plan: int
    elapsed_s: float


def pack_plan(plan_dir: Path) -> dict[str, bytes]:
    """The plan folder's files (not its flight logs) by relative path."""
    files = {}
    for path in sorted(plan_dir.rglob("*")):
        rel = path.relative_to(plan_dir)
        if path.is_file() and rel.parts[0] not in ("flight", "risk"):
            files[str(rel)] = path.read_bytes()
    if sum(len(b) for b in files.values()) > MAX_PLAN_BYTES:
        raise BadInput(f"{plan_dir}: more than {MAX_PLAN_BYTES >> 20} MiB of files to send "
                       "with every flight")
    return files


def fly_packed(files: dict[str, bytes], ranges: Ranges, seed: int, copters: int,
               time_scale: float | None) -> dict:
    """One task: the plan written to a temporary folder, flown in flight ``seed``'s
    conditions, the folder removed."""
    _stop_profiler()  # a worker of a cluster started elsewhere, or started again
    with tempfile.TemporaryDirectory(prefix="ftlbo-risk-plan-") as tmp:
        for rel, data in files.items():
            path = Path(tmp) / rel
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(data)
        record = fly_one(tmp, draw(ranges, seed, copters), time_scale=time_scale)
    record["worker_pid"] = os.getpid()
    return record


def _failed(seed: int, why: str) -> dict:
    return {"seed": seed, "outcome": f"failed: {why}", "exit_code": None, "departures": []}


def _stop_profiler(dask_worker=None) -> None:
    """This worker's stack sampling stopped (:data:`NO_PROFILER`): from its event loop
    (``client.run``) or from a task (scheduled on that loop)."""
    worker = dask_worker
    if worker is None:
        try:
            from distributed import get_worker

            worker = get_worker()
        except (ImportError, ValueError):  # not in a Dask worker
            return
    callbacks = [pc for name, pc in worker.periodic_callbacks.items()
                 if name in ("profile", "profile-cycle") and pc.is_running()]
    for pc in callbacks:
        if dask_worker is not None:
            pc.stop()
        else:
            worker.loop.add_callback(pc.stop)


def run_flights(plan_dir: Path, ranges: Ranges, seeds: Sequence[int], *,
                scheduler: str | None = None, workers: int | None = None,
                time_scale: float | None = None,
                on_progress: Callable[[Tally], None] | None = None,
                task: Callable[..., dict] = fly_packed) -> list[dict]:
    """Fly ``plan_dir`` once per seed on Dask; the records in seed order. ``task``: one
    flight, called as :func:`fly_packed` is (the tests give one that kills its worker)."""
    from dask.distributed import Client, LocalCluster, as_completed

    planned = load_planned_flight(plan_dir)
    files = pack_plan(plan_dir)
    started = time.monotonic()
    cluster = None
    if scheduler is None:
        n = workers or os.cpu_count() or 1
        import dask

        with dask.config.set(NO_PROFILER):  # the workers (their nannies) take it along
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                   dashboard_address=None, silence_logs=logging.ERROR)
        client = Client(cluster)
    else:
        try:
            client = Client(scheduler, timeout="10s")
        except OSError as exc:
            raise BadInput(f"--scheduler {scheduler}: no Dask scheduler answered ({exc})") \
                from None
    try:
        client.run(_stop_profiler)
        slots = max(1, sum(client.nthreads().values()))
        packed = client.scatter(files, broadcast=True)

        def submit(seed: int, attempt: int, plan) -> object:
            return client.submit(task, plan, ranges, seed, planned.count, time_scale,
                                 key=f"risk-flight-{seed}-{os.getpid()}-{started}-{attempt}",
                                 pure=False, retries=2)

        futures = {submit(s, 0, packed): (s, 0) for s in seeds}
        records: dict[int, dict] = {}
        least, left = None, 0
        flights = as_completed(futures)
        for future in flights:
            seed, attempt = futures.pop(future)
            try:
                record = future.result()
            except CancelledError:
                # the scheduler let go of it (a worker's death can take a task's key,
                # or the plan's scattered copy, with it): the flight is not flown,
                # so it is sent again, the plan along with it
                if attempt < CANCELLED_AGAIN:
                    again = submit(seed, attempt + 1, files)
                    futures[again] = (seed, attempt + 1)
                    flights.add(again)
                    continue
                record = _failed(seed, "cancelled by the scheduler "
                                       f"{attempt + 1} time{'s' if attempt else ''}")
            except Exception as exc:  # noqa: BLE001 - a flight that kept failing is recorded
                record = _failed(seed, f"{type(exc).__name__}: {exc}")
            records[seed] = record
            c = record.get("true_min_clearance_m")
            if c is not None:
                least = c if least is None else min(least, c)
            left += record.get("outcome") == "left the plan"
            if on_progress is not None:
                done = len(records)
                on_progress(Tally(done, len(seeds), min(slots, len(seeds) - done), least,
                                  left, time.monotonic() - started))
        return [records[s] for s in seeds]
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
