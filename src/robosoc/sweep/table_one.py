"""The seed's Table I, measured: response time, execution time and energy per job of the estimator
(EKF) and PID tasks in the four builds, beside the seed's figures (docs/results.md).

    runs = measure_table(TableSpec(iterations=100, releases=("event", "periodic")))
    for line in format_table(runs): print(line)

Each build is the flight firmware (the shipped quadrotor project) on the seed's 2×2 chip, fed
either the built-in sensor stream (:func:`robosoc.cosim.replay.built_in_rows`, replayed: every build
gets the same samples) or flown closed-loop (:func:`robosoc.cosim.lockstep.fly_chip`).  The stream
starts with the flight plan's calibration on the ground; the measured window is the ``iterations``
samples from take-off on, so the jobs measured are those of the flying filter (the seed's "100
iterations of each task").  Per task: the jobs released in the window (the first ``iterations`` of
them), their response time (release to completion, the kernel's job log), execution time (cycles the
job ran) and energy split into the task's own, the kernel's (interrupts, scheduling, messaging), the
NoC's traffic and the idle task's (sleep) share (:mod:`robosoc.cosim.replay`).  Per build also the
end-to-end latency from a sample leaving the I/O tile to the PWM command carrying its number
arriving there, and the accuracy of the estimates and commands (:mod:`robosoc.analysis.accuracy`).

The builds run in parallel worker processes (``workers``), each reporting its samples as it goes.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import multiprocessing
import os
import queue
import threading
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from robosoc.analysis.accuracy import (
    TRUTH_QUATERNION,
    GoldenRun,
    PwmAgreement,
    QuaternionError,
    golden_replay,
    quaternion_error,
)
from robosoc.config.firmware import RELEASE_CHOICES, FirmwareConfig
from robosoc.config.project import BUILD_LABELS, FirmwareProject
from robosoc.config.scenario import PositionSensorConfig, ScenarioConfig
from robosoc.config.vehicle import VehicleConfig
from robosoc.control.flight import ROW_FIELDS
from robosoc.host.telemetry import ESTIMATE_QUATERNION

OWN_RELEASE = (
    "the tasks of a project whose main() robosoc generates have the release of its robosoc.toml; "
    "a project with its own main reads the scenario's as ROBOSOC_RELEASE_PERIODIC"
)
BUILDS = (("float", True), ("float", False), ("fixed", True), ("fixed", False))
"""(arith, multiplier) of the four builds, in the seed's column order."""


@dataclass(frozen=True)
class SeedFigure:
    response_ms: float
    energy_nj: float


@functools.cache
def _project(folder: str) -> FirmwareProject:
    return FirmwareConfig(project=folder).load_project()


def reference_figures(folder: str = "") -> dict[tuple[str, str], SeedFigure]:
    """The published figures of the project in ``folder`` ("": the shipped quadrotor project, whose
    are the seed paper's Table I; /work/shared/reference/platform.md §7), by (task, build), in the
    order of its robosoc.toml (``[[reference]]``)."""
    return {(f.task, f.build): SeedFigure(f.response_ms, f.energy_nj) for f in _project(folder).reference}


def task_label(folder: str, task: str) -> str:
    """How Table I prints ``task`` of the project in ``folder`` (its ``label``: EKF, PID...)."""
    return _project(folder).label(task)


SEED_MEAN_ERROR_FIXED_FLOAT = 0.0019
"""The seed's mean error per quaternion component, fixed against floating point."""
SEED_MEAN_ERROR_TRUTH = 0.0044
"""The seed's mean error of the EKF against the simulator's true pose (0.44 %)."""

ORDERINGS: tuple[tuple[str, str, str], ...] = (
    ("fixed < float (with multiplier)", "fixed+mul", "float+mul"),
    ("fixed < float (no multiplier)", "fixed-no-mul", "float-no-mul"),
    ("multiplier < none (float)", "float+mul", "float-no-mul"),
    ("multiplier < none (fixed)", "fixed+mul", "fixed-no-mul"),
    ("float+mul < fixed-no-mul (the seed's text)", "float+mul", "fixed-no-mul"),
)
"""(name, the build that should be lower, the build it is compared with): the seed's orderings, and
its remark that soft-float with the multiplier beats fixed point without it in both time and energy."""
METRICS = (("response", "response_us_mean", "response_ms"), ("energy", "energy_nj", "energy_nj"))
"""(metric, TaskRow field, SeedFigure field) the orderings are checked on."""
ENERGY_PARTS = ("task", "kernel", "noc", "idle")


def build_config(arith: str, multiplier: bool, release: str, project: str = "") -> FirmwareConfig:
    """One of the four builds, with the default mapping, tick (262,144 cycles, 1.05 ms at 4 ns:
    ORCA's HellfireOS tick) and period (10 ticks); of the firmware project in ``project`` if given."""
    return FirmwareConfig(arith=arith, multiplier=multiplier, release=release, project=project)


@dataclass(frozen=True)
class TableSpec:
    """What to measure.

    Attributes:
        iterations: samples measured per build, from take-off on (1..10,000).
        releases: release modes, each with all four builds.
        closed_loop: fly each build closed-loop instead of replaying the built-in stream.
        seed: the flight's seed.
        workers: processes running builds at once (1: in this process).
        project: a firmware project's folder (docs/firmware-projects.md): its tasks, in the builds
            it supports ("": the shipped quadrotor project, whose reference figures are the seed's).
        base: the scenario Table I runs under (sensors and their noise, wind, plan, vehicle, chip,
            the firmware section's mapping, kernel settings and Q16.16 multiply routine); each build
            replaces its arithmetic, multiplier and release, the duration is the calibration plus the
            window. None: the built-in default, as before.
        scenario_file: where ``base`` was read from (printed with the table), "" if built in.
    """

    iterations: int = 100
    releases: tuple[str, ...] = ("event",)
    closed_loop: bool = False
    seed: int = 1
    workers: int = 2
    project: str = ""
    base: ScenarioConfig | None = None
    scenario_file: str = ""

    def __post_init__(self) -> None:
        if self.project and self.releases != ("event",):
            from robosoc.config.project import load_project

            if not load_project(self.project).project.main:
                raise ValueError(f"releases: {OWN_RELEASE}")
        if not 1 <= self.iterations <= 10_000:
            raise ValueError(f"iterations: must be between 1 and 10000, got {self.iterations}")
        if not self.releases or any(r not in RELEASE_CHOICES for r in self.releases):
            raise ValueError(f"releases: each must be one of {', '.join(RELEASE_CHOICES)}, got {self.releases}")
        if len(set(self.releases)) != len(self.releases):
            raise ValueError(f"releases: each at most once, got {self.releases}")
        if not 1 <= self.workers <= 64:
            raise ValueError(f"workers: must be between 1 and 64, got {self.workers}")

    def scenario(self) -> ScenarioConfig:
        """The scenario (``base`` or the default), long enough for the calibration and the measured
        window, with the spec's seed."""
        if self.base is None:
            base = ScenarioConfig()
            period = 1.0 / base.sensors.rate_hz
            return ScenarioConfig(duration_s=round(base.flight.takeoff_s + self.iterations * period, 9), seed=self.seed)
        seconds = self.base.flight.takeoff_s + self.iterations / self.base.sensors.rate_hz
        whole_ms = math.ceil(round(seconds * 1000.0, 6)) / 1000.0  # whole physics steps
        return dataclasses.replace(self.base, duration_s=whole_ms, seed=self.seed)

    def firmware(self, arith: str, multiplier: bool, release: str) -> FirmwareConfig:
        """One build: ``base``'s firmware section (or the default) with this arithmetic, multiplier
        and release."""
        if self.base is None:
            return build_config(arith, multiplier, release, self.project)
        return dataclasses.replace(
            self.base.firmware, arith=arith, multiplier=multiplier, release=release, project=self.project
        )

    def build_scenario(self, fw: FirmwareConfig) -> ScenarioConfig:
        """The scenario one build flies: :meth:`scenario` with ``fw`` (on ``base``'s chip, or the
        chip the build's mapping defaults to).

        Raises:
            ValueError: the build does not fit the chip (``firmware.multiplier: ...`` on tiles without
                the multiplier, a task on a tile without a powered core).
        """
        chip = self.base.chip if self.base is not None else fw.default_chip()
        return dataclasses.replace(self.scenario(), firmware=fw, chip=chip)

    @property
    def fixed_mul64(self) -> str:
        """The Q16.16 multiply routine of the builds without the multiplier."""
        return (self.base.firmware if self.base is not None else FirmwareConfig()).fixed_mul64

    def conditions(self) -> dict[str, Any]:
        """What Table I ran under, as printed and in ``table.json``."""
        sc = self.base if self.base is not None else ScenarioConfig()
        fw = dataclasses.replace(sc.firmware, project=self.project) if self.project else sc.firmware
        project, mapping = fw.load_project(), fw.mapping
        return {
            "scenario": self.scenario_file or "built-in",
            "sensor_noise": sc.sensors.noise,
            "mesh": f"{sc.chip.width}x{sc.chip.height}",
            "tiles": {t.name: list(mapping.get(t.name, (int(t.tile[0]), int(t.tile[1])))) for t in project.tasks},
            "fixed_mul64": fw.fixed_mul64,
        }


@dataclass(frozen=True)
class TaskRow:
    """One task of one build: the means over its measured jobs (times in us, energy in nJ per job).

    ``energy_nj`` is defined as the sum of the four parts, so the columns add up as printed."""

    task: str
    build: str
    release: str
    jobs: int
    response_us_mean: float
    response_us_max: float
    exec_us_mean: float
    exec_cycles_mean: float
    exec_cycles_max: int
    energy_nj_task: float
    energy_nj_kernel: float
    energy_nj_noc: float
    energy_nj_idle: float
    energy_nj: float
    deadline_misses: int


@dataclass(frozen=True)
class BuildRun:
    """One build measured: its task rows, latency and accuracy."""

    build: str
    release: str
    source: str  # "replay" or "closed-loop"
    samples: int  # samples in the measured window
    first_sample: int  # index of the window's first sample (take-off)
    tasks: dict[str, TaskRow]
    latency_us_mean: float  # sample leaves the I/O tile -> its PWM command arrives there
    latency_us_max: float
    samples_without_command: int  # in the window (periodic release drops stale samples)
    estimator_vs_golden: QuaternionError
    estimator_vs_truth: QuaternionError
    golden_vs_truth: QuaternionError
    pwm: PwmAgreement
    host_seconds: float
    #: sample index -> the chip's quaternion at the close of that sample's period (window only)
    estimates: dict[int, tuple[float, float, float, float]] = field(repr=False, default_factory=dict)


@dataclass(frozen=True)
class OrderingCheck:
    task: str
    metric: str  # "response" or "energy"
    name: str
    lower: str
    higher: str
    release: str
    seed_holds: bool
    holds: bool | None  # None: one of the builds was not measured


@dataclass
class TableResult:
    spec: TableSpec
    runs: list[BuildRun]
    orderings: list[OrderingCheck]
    #: (release, multiplier) -> fixed build's estimates against the float build's (replay only)
    fixed_vs_float: dict[tuple[str, bool], QuaternionError]

    def run(self, build: str, release: str) -> BuildRun | None:
        return next((r for r in self.runs if r.build == build and r.release == release), None)


# --- one build ----------------------------------------------------------------------------------


def task_row(jobs: Sequence, task: str, build: str, release: str, clock_ns: float) -> TaskRow:
    """The means of ``jobs`` (:class:`robosoc.records.JobRecord`, all of ``task``)."""
    n = len(jobs)
    if n == 0:
        nan = math.nan
        return TaskRow(task, build, release, 0, nan, nan, nan, nan, 0, nan, nan, nan, nan, nan, 0)
    parts = {p: math.fsum(j.energy_pj[p] for j in jobs) / n / 1000.0 for p in ENERGY_PARTS}
    exec_c = [j.exec_cycles for j in jobs]
    resp = [j.response_cycles for j in jobs]
    us = clock_ns / 1000.0
    return TaskRow(
        task=task, build=build, release=release, jobs=n,
        response_us_mean=sum(resp) / n * us, response_us_max=max(resp) * us,
        exec_us_mean=sum(exec_c) / n * us, exec_cycles_mean=sum(exec_c) / n, exec_cycles_max=max(exec_c),
        energy_nj_task=parts["task"], energy_nj_kernel=parts["kernel"], energy_nj_noc=parts["noc"],
        energy_nj_idle=parts["idle"], energy_nj=sum(parts[p] for p in ENERGY_PARTS),
        deadline_misses=sum(not j.deadline_met for j in jobs),
    )  # fmt: skip


def first_armed(rows: np.ndarray) -> int:
    """Index of the first armed sample (take-off), len(rows) if none."""
    armed = np.flatnonzero(rows[:, ROW_FIELDS.index("armed")] > 0.5)
    return int(armed[0]) if len(armed) else len(rows)


def summarise(
    result, rows: np.ndarray, golden: GoldenRun, iterations: int, source: str
) -> BuildRun:  # fmt: skip
    """A replay's or flight's :class:`robosoc.cosim.firmware_run.ReplayResult` as a :class:`BuildRun`."""
    fw: FirmwareConfig = result.firmware
    k0 = first_armed(rows)
    window = range(k0, min(len(rows), k0 + iterations))
    start = result.samples[k0].cycle if k0 < len(result.samples) else result.cycles
    tasks = {}
    for name in dict.fromkeys(j.task for j in result.jobs):  # the tasks that ran, in order of their first job
        mine = sorted((j for j in result.jobs if j.task == name and j.release_cycle >= start),
                      key=lambda j: j.release_cycle)[:iterations]  # fmt: skip
        tasks[name] = task_row(mine, name, fw.label, fw.release, result.clock_ns)
    commands = {c.seq: c for c in result.commands}
    latency = [
        (commands[k].cycle - result.samples[k].cycle) * result.clock_ns / 1000.0 for k in window if k in commands
    ]
    estimates = {
        r.sample: tuple(r.values[n] for n in ESTIMATE_QUATERNION)
        for r in result.telemetry
        if r.sample in window and all(n in r.values for n in ESTIMATE_QUATERNION)
    }
    have = sorted(estimates)
    chip_q = np.array([estimates[k] for k in have]).reshape(-1, 4)
    ks = np.array(have, dtype=np.int64)
    truth = rows[:, TRUTH_QUATERNION]
    win = np.array(list(window), dtype=np.int64)
    return BuildRun(
        build=fw.label, release=fw.release, source=source, samples=len(window), first_sample=k0, tasks=tasks,
        latency_us_mean=sum(latency) / len(latency) if latency else math.nan,
        latency_us_max=max(latency) if latency else math.nan,
        samples_without_command=len(window) - len(latency),
        estimator_vs_golden=quaternion_error(chip_q, golden.quaternion[ks]),
        estimator_vs_truth=quaternion_error(chip_q, truth[ks]),
        golden_vs_truth=quaternion_error(golden.quaternion[win], truth[win]),
        pwm=PwmAgreement.of({c.seq: c.pwm for c in result.commands}, golden.pwm, list(window)),
        host_seconds=result.host_seconds, estimates=estimates,
    )  # fmt: skip


_progress: multiprocessing.queues.Queue | None = None


def _init_worker(progress: multiprocessing.queues.Queue) -> None:
    global _progress
    _progress = progress


def measure_build(
    fw: FirmwareConfig,
    spec: TableSpec,
    rows: np.ndarray | None,
    golden: GoldenRun | None,
    on_sample: Callable[[str, int, int], None] | None = None,
) -> BuildRun:
    """Replay ``rows`` into ``fw`` (or fly it closed-loop when ``rows`` is None) and summarise.

    ``on_sample(build key, done, total)`` reports progress (default: the worker's queue, if any).
    """
    from robosoc.cosim.lockstep import fly_chip
    from robosoc.cosim.replay import replay

    key = f"{fw.label} {fw.release}"

    def report(done: int, total: int) -> None:
        if on_sample is not None:
            on_sample(key, done, total)
        elif _progress is not None and (done == total or done % 10 == 0):
            _progress.put((key, done, total))

    if rows is None:
        scenario = spec.build_scenario(fw)
        if fw.project:  # the position fix for a project that takes it (its own stream: nothing else changes)
            sensors = dataclasses.replace(scenario.sensors, position=PositionSensorConfig(enabled=True))
            scenario = dataclasses.replace(scenario, sensors=sensors)
        total = scenario.samples
        flight = fly_chip(scenario, _vehicle(scenario), on_sample=lambda _w, k: report(k + 1, total))
        rows, result = flight.rows, flight.run
        golden = golden_replay(rows, scenario)
        return summarise(result, rows, golden, spec.iterations, "closed-loop")
    assert golden is not None
    if spec.base is None:
        result = replay(rows, fw, on_sample=report)
    else:
        scenario = spec.build_scenario(fw)
        result = replay(rows, fw, vehicle=_vehicle(scenario), scenario=scenario, chip=scenario.chip, on_sample=report)
    return summarise(result, rows, golden, spec.iterations, "replay")


def _vehicle(scenario: ScenarioConfig) -> VehicleConfig:
    from robosoc.config.vehicle import vehicle_preset

    return vehicle_preset(scenario.vehicle)


# --- the table ----------------------------------------------------------------------------------


def check_orderings(runs: Sequence[BuildRun], folder: str = "") -> list[OrderingCheck]:
    """Each of :data:`ORDERINGS` for each task, metric and release mode measured, for the tasks the
    project in ``folder`` has reference figures of in every build (:func:`reference_figures`)."""
    figures = reference_figures(folder)
    tasks = [t for t in _project(folder).task_names if all((t, b) in figures for b in BUILD_LABELS)]
    out = []
    for release in dict.fromkeys(r.release for r in runs):
        by_build = {r.build: r for r in runs if r.release == release}
        measured = {task for r in by_build.values() for task in r.tasks}
        for task in [t for t in tasks if t in measured]:
            for metric, ours, theirs in METRICS:
                for name, lower, higher in ORDERINGS:
                    seed = getattr(figures[(task, lower)], theirs) < getattr(figures[(task, higher)], theirs)
                    holds = None
                    if lower in by_build and higher in by_build:
                        a = getattr(by_build[lower].tasks[task], ours)
                        b = getattr(by_build[higher].tasks[task], ours)
                        holds = bool(a < b) if not (math.isnan(a) or math.isnan(b)) else None
                    out.append(OrderingCheck(task, metric, name, lower, higher, release, seed, holds))
    return out


def fixed_against_float(runs: Sequence[BuildRun]) -> dict[tuple[str, bool], QuaternionError]:
    """The fixed-point builds' estimates against the soft-float builds' on the same samples (replay)."""
    out = {}
    for run in runs:
        if run.source != "replay" or not run.build.startswith("fixed"):
            continue
        mul = run.build.endswith("+mul")
        twin = "float+mul" if mul else "float-no-mul"
        other = next((r for r in runs if r.release == run.release and r.build == twin), None)
        if other is None:
            continue
        common = sorted(set(run.estimates) & set(other.estimates))
        a = np.array([run.estimates[k] for k in common]).reshape(-1, 4)
        b = np.array([other.estimates[k] for k in common]).reshape(-1, 4)
        out[(run.release, mul)] = quaternion_error(a, b)
    return out


def measure_table(spec: TableSpec, on_progress: Callable[[str, int, int], None] | None = None) -> TableResult:
    """Measure the four builds in every release mode of ``spec``.

    Args:
        spec: what to measure.
        on_progress: called with (build key, samples done, samples in all) as builds run.

    Raises:
        ValueError: a build does not fit the scenario's chip (the field named).
        robosoc.chip.mpsoc.ChipError / CoreError: a build's firmware faulted.
        CompileError: a build failed to compile.
    """
    from robosoc.host.scenario_image import firmware_image

    configs = [spec.firmware(arith, mul, release) for release in spec.releases for arith, mul in BUILDS]
    if spec.project:  # the builds the project supports
        from robosoc.config.project import load_project

        info = load_project(spec.project).project
        configs = [fw for fw in configs if fw.arith in info.arith and fw.multiplier in info.multiplier]
    for fw in configs:  # compile (or hit the cache) before the workers start
        if spec.base is None:
            firmware_image(fw)
        else:
            scenario = spec.build_scenario(fw)
            firmware_image(fw, _vehicle(scenario), scenario, scenario.chip)
    rows = golden = None
    if not spec.closed_loop:
        from robosoc.cosim import replay

        scenario = spec.scenario()
        if spec.base is None:
            rows = replay.built_in_rows(scenario.duration_s, spec.seed)
        else:
            rows = replay.scenario_rows(scenario)
        golden = golden_replay(rows, scenario)
    if spec.workers == 1:  # (four builds per release mode at least: workers always have work)
        runs = [measure_build(fw, spec, rows, golden, on_progress) for fw in configs]
    else:
        runs = _in_workers(configs, spec, rows, golden, on_progress)
    if spec.project:  # a project's tasks have no seed figures, nor an estimate the host reads
        return TableResult(spec, runs, check_orderings(runs, spec.project), {})
    return TableResult(spec, runs, check_orderings(runs), fixed_against_float(runs))


def _in_workers(
    configs: list[FirmwareConfig],
    spec: TableSpec,
    rows: np.ndarray | None,
    golden: GoldenRun | None,
    on_progress: Callable[[str, int, int], None] | None,
) -> list[BuildRun]:
    method = "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"
    ctx = multiprocessing.get_context(method)
    progress = ctx.Queue()
    done = threading.Event()

    def pump() -> None:
        while not done.is_set():
            try:
                key, k, total = progress.get(timeout=0.1)
            except queue.Empty:
                continue
            if on_progress is not None:
                on_progress(key, k, total)

    reader = threading.Thread(target=pump, daemon=True)
    reader.start()
    try:
        with ProcessPoolExecutor(
            max_workers=min(spec.workers, len(configs)), mp_context=ctx, initializer=_init_worker,
            initargs=(progress,),
        ) as pool:  # fmt: skip
            futures = [pool.submit(measure_build, fw, spec, rows, golden) for fw in configs]
            runs = [f.result() for f in futures]
    finally:
        done.set()
        reader.join()
    if on_progress is not None:
        for run in runs:
            on_progress(f"{run.build} {run.release}", 1, 1)
    return runs


def default_workers() -> int:
    """Processes to run builds in: the machine's cores (at most the four builds)."""
    return max(1, min(4, os.cpu_count() or 1))


# --- output -------------------------------------------------------------------------------------


def to_json(result: TableResult) -> dict:
    """The table as plain data (NaN as None), for ``table.json``."""

    def clean(value: Any) -> Any:  # JSON-like data, of the shape of its input
        if isinstance(value, float):
            return None if math.isnan(value) else value
        if isinstance(value, dict):
            return {str(k): clean(v) for k, v in value.items()}
        if isinstance(value, list | tuple):
            return [clean(v) for v in value]
        return value

    runs = []
    for run in result.runs:
        d = asdict(run)
        d.pop("estimates")
        d["estimator_vs_golden"]["mean_percent"] = run.estimator_vs_golden.mean_percent
        d["estimator_vs_truth"]["mean_percent"] = run.estimator_vs_truth.mean_percent
        for task in run.tasks:
            seed = _seed(result, task, run.build)
            d["tasks"][task]["seed_response_ms"] = seed.response_ms if seed else None
            d["tasks"][task]["seed_energy_nj"] = seed.energy_nj if seed else None
        runs.append(d)
    return clean(
        {
            "schema": 1,
            "spec": {
                k: v
                for k, v in asdict(result.spec).items()
                if (k != "project" or v) and k not in ("base", "scenario_file")  # the built-in: no project key
            },
            "conditions": result.spec.conditions(),
            "clock_ns": 4.0,
            "runs": runs,
            "orderings": [asdict(o) for o in result.orderings],
            "fixed_vs_float": [
                {"release": rel, "multiplier": mul, **asdict(err), "mean_percent": err.mean_percent}
                for (rel, mul), err in result.fixed_vs_float.items()
            ],
            "seed": {
                "table_i": [
                    {"task": t, "build": b, **asdict(f)} for (t, b), f in reference_figures(result.spec.project).items()
                ],
                "mean_error_fixed_float": SEED_MEAN_ERROR_FIXED_FLOAT,
                "mean_error_truth": SEED_MEAN_ERROR_TRUTH,
            },
        }
    )


CSV_FIELDS = (
    "release", "source", "build", "task", "jobs", "response_us_mean", "response_us_max", "exec_us_mean",
    "exec_cycles_mean", "exec_cycles_max", "energy_nj", "energy_nj_task", "energy_nj_kernel", "energy_nj_noc",
    "energy_nj_idle", "deadline_misses", "seed_response_ms", "seed_energy_nj", "latency_us_mean",
    "estimator_vs_golden_percent", "estimator_vs_truth_percent", "estimator_vs_truth_mean_deg", "pwm_within_one",
)  # fmt: skip
"""Columns of ``table.csv``: one row per (release, build, task)."""


def csv_rows(result: TableResult) -> list[list[object]]:
    out = []
    for run in result.runs:
        for task, row in run.tasks.items():
            seed = _seed(result, task, run.build) or SeedFigure(math.nan, math.nan)
            out.append(
                [
                    run.release, run.source, run.build, task, row.jobs, row.response_us_mean, row.response_us_max,
                    row.exec_us_mean, row.exec_cycles_mean, row.exec_cycles_max, row.energy_nj, row.energy_nj_task,
                    row.energy_nj_kernel, row.energy_nj_noc, row.energy_nj_idle, row.deadline_misses,
                    seed.response_ms, seed.energy_nj, run.latency_us_mean, run.estimator_vs_golden.mean_percent,
                    run.estimator_vs_truth.mean_percent, run.estimator_vs_truth.mean_deg, run.pwm.within_one,
                ]
            )  # fmt: skip
    return out


def _seed(result: TableResult, task: str, build: str) -> SeedFigure | None:
    """The reference figure for a task and build (the seed's, for the shipped quadrotor project), or None."""
    return reference_figures(result.spec.project).get((task, build))


def _num(value: float, digits: int = 1) -> str:
    return "-" if value is None or (isinstance(value, float) and math.isnan(value)) else f"{value:,.{digits}f}"


_CELL = 24
_LABEL = 30
_TASK_LINES: tuple[tuple[str, Callable[[TaskRow], float], Callable[[SeedFigure], float] | None, int], ...] = (
    ("jobs", lambda r: r.jobs, None, 0),
    ("response mean (us)", lambda r: r.response_us_mean, lambda s: s.response_ms * 1000.0, 1),
    ("response max (us)", lambda r: r.response_us_max, None, 1),
    ("execution mean (us)", lambda r: r.exec_us_mean, None, 1),
    ("energy per job (nJ)", lambda r: r.energy_nj, lambda s: s.energy_nj, 1),
    ("  task (nJ)", lambda r: r.energy_nj_task, None, 1),
    ("  kernel (nJ)", lambda r: r.energy_nj_kernel, None, 1),
    ("  NoC (nJ)", lambda r: r.energy_nj_noc, None, 1),
    ("  idle (nJ)", lambda r: r.energy_nj_idle, None, 1),
    ("deadline misses", lambda r: r.deadline_misses, None, 0),
)
"""Table I's lines per task: label, our figure, the seed's (if it has one), decimals."""


def _task_lines(result: TableResult, task: str, runs: dict[str, BuildRun], labels: Sequence[str]) -> list[str]:
    out = []
    name = task_label(result.spec.project, task)
    for label, ours, seed_of, digits in _TASK_LINES:
        cells = []
        for b in labels:
            run = runs.get(b)
            row = run.tasks.get(task) if run is not None else None
            text = _num(ours(row) if row is not None else math.nan, digits)
            seed = _seed(result, task, b)
            if seed_of is not None and seed is not None:
                text += f" [{_num(seed_of(seed), digits)}]"
            cells.append(f"{text:>{_CELL}}")
        out.append(f"{name + ' ' + label:<{_LABEL}}" + "".join(cells))
    return out


MUL64_TEXT = {
    "shift-add": "shift-and-add (fix16_mul64_soft, robosoc's)",
    "muldi3": "64-bit product through compiler-rt __muldi3 (as HellfireOS)",
}
"""How Table I names the Q16.16 multiply routine of the builds without the multiplier."""


def _conditions_line(spec: TableSpec) -> str:
    c = spec.conditions()
    noise = "on" if c["sensor_noise"] else "off"
    tiles = ", ".join(f"{task} on {tuple(xy)}" for task, xy in c["tiles"].items())
    return (
        f"conditions: scenario {c['scenario']} (sensor noise {noise}), {c['mesh']} mesh, {tiles}; "
        f"Q16.16 multiply without the multiplier: {MUL64_TEXT[c['fixed_mul64']]}"
    )


def format_table(result: TableResult) -> list[str]:
    """Table I as text lines: per release mode the four builds' figures with the seed's beside them."""
    lines: list[str] = []
    labels = [FirmwareConfig(arith=a, multiplier=m).label for a, m in BUILDS]
    width = _CELL
    for release in result.spec.releases:
        runs = {r.build: r for r in result.runs if r.release == release}
        if not runs:
            continue
        any_run = next(iter(runs.values()))
        whose = f"project {result.spec.project}, " if result.spec.project else ""
        brackets = " (seed's figure in brackets)" if reference_figures(result.spec.project) else ""
        lines.append(
            f"Table I — {whose}{release} release, {any_run.source}, {any_run.samples} samples from take-off per "
            f"build{brackets}"
        )
        lines.append(_conditions_line(result.spec))
        lines.append(f"{'':<{_LABEL}}" + "".join(f"{b:>{width}}" for b in labels))
        for task in dict.fromkeys(t for r in runs.values() for t in r.tasks):
            lines += _task_lines(result, task, runs, labels)
        cells = "".join(f"{_num(runs[b].latency_us_mean) if b in runs else '-':>{width}}" for b in labels)
        lines.append(f"{'sample -> PWM mean (us)':<30}" + cells)
        cells = "".join(f"{runs[b].samples_without_command if b in runs else '-':>{width}}" for b in labels)
        lines.append(f"{'samples without a command':<30}" + cells)
        if any(o.release == release for o in result.orderings):
            lines.append("orderings (lower is better; seed: holds in the seed's Table I; ours: holds here):")
        for o in result.orderings:
            if o.release != release:
                continue
            ours = "-" if o.holds is None else ("yes" if o.holds else "NO")
            seed = "yes" if o.seed_holds else "NO"
            label = task_label(result.spec.project, o.task)
            lines.append(f"  {label} {o.metric:<8} {o.name:<44} seed {seed:<4} ours {ours}")
        if result.spec.project:
            lines.append("PWM commands against the float64 golden model (the built-in estimator and PID):")
            for b in labels:
                if b in runs:
                    pwm = runs[b].pwm
                    lines.append(
                        f"  {b:<13} within 1 count {_num(100 * pwm.within_one, 1)} % (max diff {pwm.max_diff})"
                    )
            lines.append("")
            continue
        lines.append("accuracy (mean error per quaternion component in %, the seed's terms; mean / max angle):")
        for b in labels:
            run = runs.get(b)
            if run is None:
                continue
            g, t = run.estimator_vs_golden, run.estimator_vs_truth
            lines.append(
                f"  {b:<13} EKF vs float64 golden {_num(g.mean_percent, 4)} % ({_num(g.mean_deg, 4)}° / "
                f"{_num(g.max_deg, 4)}°); vs truth {_num(t.mean_percent, 3)} % ({_num(t.mean_deg, 3)}° / "
                f"{_num(t.max_deg, 3)}°); PWM within 1 count of golden {_num(100 * run.pwm.within_one, 1)} % "
                f"(max diff {run.pwm.max_diff})"
            )
        gold = any_run.golden_vs_truth
        lines.append(
            f"  {'golden':<13} float64 EKF vs truth {_num(gold.mean_percent, 3)} % ({_num(gold.mean_deg, 3)}° / "
            f"{_num(gold.max_deg, 3)}°); seed: EKF vs truth {100 * SEED_MEAN_ERROR_TRUTH:.2f} %"
        )
        for (rel, mul), err in result.fixed_vs_float.items():
            if rel == release:
                lines.append(
                    f"  fixed vs float ({'with' if mul else 'no'} multiplier): {_num(err.mean_percent, 4)} % "
                    f"({_num(err.mean_deg, 4)}° / {_num(err.max_deg, 4)}°); seed: "
                    f"{100 * SEED_MEAN_ERROR_FIXED_FLOAT:.2f} %"
                )
        lines.append("")
    return lines


__all__ = [
    "BUILDS",
    "CSV_FIELDS",
    "ORDERINGS",
    "BuildRun",
    "OrderingCheck",
    "TableResult",
    "TableSpec",
    "TaskRow",
    "build_config",
    "check_orderings",
    "csv_rows",
    "default_workers",
    "first_armed",
    "format_table",
    "measure_build",
    "measure_table",
    "reference_figures",
    "summarise",
    "task_row",
    "to_json",
]
