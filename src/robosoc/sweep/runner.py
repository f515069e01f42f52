"""Running a sweep's points on a local process pool or a Dask cluster, resumably.

The points not yet finished in the output folder (:class:`~robosoc.sweep.store.SweepStore`) are
handed to workers; each result is stored as it arrives, so Ctrl-C, a crash of this process or a
lost worker costs at most the points in flight.  Both back ends run the same function,
:func:`robosoc.sweep.point.run_point`, on the same arguments, so they give the same rows.

* ``local`` (the default): a :class:`concurrent.futures.ProcessPoolExecutor` of ``workers``
  processes started with ``spawn`` (MuJoCo and numba state must not be forked).  A worker that
  dies (a segfault, the OOM killer) breaks the pool: the points it had in flight are tried once
  more in a new pool, and recorded as failed if they break it again.
* ``dask``: a :class:`dask.distributed.Client` of an existing scheduler (``tcp://host:8786``), or
  a :class:`dask.distributed.LocalCluster` of ``workers`` single-threaded processes when the
  address is ``local``.  Dask retries a task whose worker died; a task that kills workers
  repeatedly comes back as ``KilledWorker`` and is recorded as failed.

Each worker process imports robosoc once and keeps it: numba's compiled kernels and the
firmware images come from their on-disk caches once per worker, not once per point; the
firmware builds a sweep needs are made here before any worker starts (:func:`prepare`).
"""

from __future__ import annotations

import functools
import multiprocessing
import os
import signal
import threading
import time
from collections.abc import Callable, Iterator
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from robosoc.config.sweep import SweepConfig
from robosoc.sweep.plan import Point, plan
from robosoc.sweep.point import FAILED, PointResult, run_point
from robosoc.sweep.store import SweepStore

LOCAL = "local"
"""``--dask local``: start a LocalCluster instead of connecting to a scheduler."""

CRASHES_ALLOWED = 1
"""A point whose worker died is tried this many more times before it is recorded as failed."""


@dataclass
class SweepOutcome:
    """What a sweep did: its points, every finished record and where the table is."""

    points: list[Point]
    records: dict[str, dict[str, Any]]
    ran: int
    skipped: int
    table: Path

    @property
    def failures(self) -> list[dict[str, Any]]:
        """The failed points' records, in plan order."""
        order = {p.key: p.index for p in self.points}
        failed = [r for k, r in self.records.items() if k in order and r["status"] == FAILED]
        return sorted(failed, key=lambda r: order[r["key"]])

    @property
    def missing(self) -> int:
        """Points not finished (an interrupted sweep)."""
        return sum(1 for p in self.points if p.key not in self.records)


Progress = Callable[[Point, dict[str, Any]], None]


PR_SET_PDEATHSIG = 1
"""prctl(2) option: the signal a process gets when its parent dies (Linux)."""


def die_with_parent(parent: int) -> None:
    """Make this process end when ``parent`` does, even by SIGKILL: SIGKILL on the parent's death
    (Linux's PR_SET_PDEATHSIG), and, where that is not to be had, a thread watching the parent."""
    if os.getppid() != parent:  # the parent died before we got here
        os._exit(1)
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        if libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0) == 0:
            if os.getppid() != parent:  # died between the check and the prctl
                os._exit(1)
            return
    except (OSError, AttributeError):
        pass
    watch_parent(parent)


def watch_parent(parent: int, every_s: float = 1.0) -> threading.Thread:
    """A daemon thread that ends this process (``os._exit``) once ``parent`` is gone."""

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(every_s)
        os._exit(1)

    thread = threading.Thread(target=watch, name="robosoc-parent-watch", daemon=True)
    thread.start()
    return thread


def warm_worker(parent: int | None = None) -> None:
    """Import what a point needs once per worker process; Ctrl-C belongs to the driving process,
    and the worker ends with it (``parent``: its pid, also when it is killed)."""
    if threading.current_thread() is threading.main_thread():  # a Dask worker may run this in a thread
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    if parent is not None:
        die_with_parent(parent)
    import robosoc.outputs.flight_session  # noqa: F401  (physics, chip and firmware: once per process)


def prepare(config: SweepConfig, points: list[Point], on_status: Callable[[str], None]) -> None:
    """Build, once and before the workers start, every firmware image the points will load, and
    compile the chip kernels into numba's cache if they are not there (workers then only load)."""
    from robosoc.config.validate import ConfigError
    from robosoc.config.vehicle import vehicle_preset
    from robosoc.cosim.chip_warmup import prepare_chip
    from robosoc.host.scenario_image import scenario_image

    seen: set[str] = set()
    for point in points:
        try:
            scenario = config.scenario(point.assignment)
        except ConfigError:
            continue  # recorded as failed when it runs
        if scenario.controller != "chip":
            continue
        vehicle = vehicle_preset(scenario.vehicle)
        token = repr((scenario.firmware, scenario.chip, vehicle, scenario.flight, scenario.sensors, scenario.power))
        if token in seen:
            continue
        seen.add(token)
        try:
            prepare_chip(scenario.chip, functools.partial(scenario_image, scenario, vehicle), on_status)
        except Exception:
            continue


class SchedulerError(Exception):
    """The Dask scheduler (or a LocalCluster) could not be reached or started."""

    def __init__(self, address: str, cause: BaseException) -> None:
        super().__init__(f"cannot reach the scheduler at {address}: {cause}" if address != LOCAL else
                         f"cannot start a Dask LocalCluster: {cause}")  # fmt: skip
        self.address = address


class _LocalPool:
    """Points on a process pool; rebuilt when a worker dies."""

    def __init__(self, workers: int) -> None:
        self.workers = workers
        self.pool = self._new()

    def _new(self) -> ProcessPoolExecutor:
        return ProcessPoolExecutor(
            self.workers,
            mp_context=multiprocessing.get_context("spawn"),
            initializer=warm_worker,
            initargs=(os.getpid(),),
        )

    def run(self, config: SweepConfig, todo: list[Point]) -> Iterator[tuple[Point, PointResult]]:
        queue = list(todo)
        crashes: dict[str, int] = {}
        running: dict[Future, Point] = {}
        while queue or running:
            while queue and len(running) < 2 * self.workers:
                point = queue.pop(0)
                running[self.pool.submit(run_point, config.base, point, config.source, config.base_fields)] = point
            done, _ = wait(running, return_when=FIRST_COMPLETED)
            broken = False
            for future in done:
                point = running.pop(future)
                try:
                    yield point, future.result()
                except BrokenProcessPool:
                    broken = True
                    crashes[point.key] = crashes.get(point.key, 0) + 1
                    if crashes[point.key] > CRASHES_ALLOWED:
                        yield point, PointResult(point.key, FAILED, "the worker process died while running it")
                    else:
                        queue.insert(0, point)
            if broken:
                for future, point in running.items():  # every point in flight went down with the pool
                    future.cancel()
                    queue.insert(0, point)
                running.clear()
                self.pool.shutdown(wait=False, cancel_futures=True)
                self.pool = self._new()

    def close(self, abort: bool) -> None:
        self.pool.shutdown(wait=not abort, cancel_futures=True)
        if abort:
            for child in multiprocessing.active_children():
                child.terminate()


class _DaskPool:
    """Points on a Dask cluster (an existing scheduler, or a LocalCluster)."""

    def __init__(self, address: str, workers: int, on_status: Callable[[str], None] = lambda _text: None) -> None:
        from dask.distributed import Client, LocalCluster

        self.cluster = None
        try:
            if address == LOCAL:
                self.cluster = LocalCluster(
                    n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0"
                )
                self.client = Client(self.cluster)
            else:
                self.client = Client(address, timeout="20s")
        except (OSError, TimeoutError) as exc:
            raise SchedulerError(address, exc) from exc
        if address != LOCAL:
            count = self.workers()
            on_status(f"the Dask scheduler at {address} has {count} worker{'s' if count != 1 else ''}")
        self.client.run(warm_worker)

    def workers(self) -> int:
        """The cluster's workers now (a scheduler's, not this machine's cores)."""
        try:
            return len(self.client.scheduler_info().get("workers", {}))
        except Exception:  # a count for a message only
            return 0

    @property
    def dashboard(self) -> str | None:
        return getattr(self.client, "dashboard_link", None)

    def run(self, config: SweepConfig, todo: list[Point]) -> Iterator[tuple[Point, PointResult]]:
        from dask.distributed import as_completed

        base = self.client.scatter(config.base, broadcast=True)
        fields = self.client.scatter(config.base_fields, broadcast=True)
        futures = {}
        for point in todo:
            key = f"robosoc-point-{point.key}"
            futures[self.client.submit(run_point, base, point, config.source, fields, key=key, pure=False)] = point
        for future in as_completed(futures):
            point = futures[future]
            try:
                result = future.result()
            except Exception as exc:
                result = PointResult(point.key, FAILED, f"{type(exc).__name__}: {exc}")
            future.release()
            yield point, result

    def close(self, abort: bool) -> None:
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()


def run_sweep(
    config: SweepConfig,
    out: Path,
    *,
    workers: int = 1,
    dask: str | None = None,
    retry_failed: bool = False,
    on_start: Callable[[int, int], None] | None = None,
    on_point: Progress | None = None,
    on_status: Callable[[str], None] | None = None,
) -> SweepOutcome:
    """Run every point of ``config`` not yet finished in ``out``; results stored as they come.

    Args:
        workers: local processes (or LocalCluster workers with ``dask="local"``).
        dask: a scheduler address, ``"local"``, or None for the local pool.
        retry_failed: run again the points recorded as failed.
        on_start: called with (points to run, points already finished).
        on_point: called with each finished point and its record.
        on_status: told what is prepared before the workers start (firmware builds, compiling).

    Raises:
        KeyboardInterrupt: after stopping the workers; every point finished so far is kept.
        robosoc.sweep.store.FolderInUse: another sweep runs in ``out`` (its pid is said).
        robosoc.sweep.store.RecordError: a record in ``out/results`` is not one (names the file).
        SchedulerError: ``dask`` could not be reached or started.
    """
    points = plan(config)
    store = SweepStore(out)
    with store.lock():
        return _run(config, store, points, workers, dask, retry_failed, on_start, on_point, on_status)


def _run(
    config: SweepConfig,
    store: SweepStore,
    points: list[Point],
    workers: int,
    dask: str | None,
    retry_failed: bool,
    on_start: Callable[[int, int], None] | None,
    on_point: Progress | None,
    on_status: Callable[[str], None] | None,
) -> SweepOutcome:
    records = store.records()
    if retry_failed:
        for key in [k for k, r in records.items() if r["status"] == FAILED]:
            store.forget(key)
            del records[key]
    todo = [p for p in points if p.key not in records]
    if on_start is not None:
        on_start(len(todo), len(points) - len(todo))
    varied = config.varied()
    ran = 0
    if todo:
        prepare(config, todo, on_status or (lambda _text: None))
        pool: _LocalPool | _DaskPool = (
            _DaskPool(dask, workers, on_status or (lambda _text: None)) if dask else _LocalPool(workers)
        )
        aborted = True
        try:
            for point, result in pool.run(config, todo):
                records[point.key] = store.save(point, result)
                store.write_table(points, varied, config.metrics)
                ran += 1
                if on_point is not None:
                    on_point(point, records[point.key])
            aborted = False
        finally:
            pool.close(abort=aborted)
            store.write_table(points, varied, config.metrics)
    table = store.write_table(points, varied, config.metrics)
    return SweepOutcome(points, records, ran, len(points) - len(todo), table)


__all__ = ["LOCAL", "SchedulerError", "SweepOutcome", "die_with_parent", "prepare", "run_sweep", "warm_worker"]
