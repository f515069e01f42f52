"""Replaying a recorded sensor stream into the control firmware on the chip.

The harness behind ``robosoc firmware replay``, and the half of a co-simulation that does not need
the physics: every sensor sample of a flight log becomes a message from the I/O tile, injected at
the cycle of its timestamp; the chip runs the firmware (the estimator and PID tasks of
:mod:`robosoc.firmware.flight_app`); what comes back is the PWM command of each sample with the
cycle it reached the I/O tile, and one record per job of each task.

Time: sample k (timestamp t_k seconds) is injected in cycle ``first_cycle + round(t_k / clock)``;
``first_cycle`` leaves the firmware time to boot (the kernel's start-up takes a few ten thousand
cycles).  The chip is stepped from one injection to the next, and at each step the per-task
counters of every tile and the router counters are read, so each job's instructions and energy are
those of its task in the sample period in which it was released:

* ``task``: the job's own task (its TASK_ID on its tile) in that period;
* ``kernel``: the kernel's TASK_ID on the job's tile in that period (interrupt entry and exit,
  scheduling, messaging), shared equally by the jobs of that tile in the period;
* ``idle``: the idle task's on that tile (it sleeps: clock-gated cycles), shared likewise;
* ``noc``: what the routers spent in that period beyond idling (the flits' share: active buffers
  and switch control), shared equally by every job of the period; the routers' idle and leakage
  energy is the chip's whether or not a job runs, and is in the run's totals only.

With event release every job starts and ends within its sample period at 100 Hz (the issue's
budget), so the split is exact; a job that runs past the next sample is still charged only its
release period's counters, and the record says so (``spans_periods``).
"""

from __future__ import annotations

import bisect
import dataclasses
import time
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from robosoc.analysis.energy import EnergyModel
from robosoc.chip.elf import load_elf
from robosoc.chip.mpsoc import MPSoC
from robosoc.config.chip import ChipConfig
from robosoc.config.firmware import FirmwareConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import VehicleConfig, vehicle_preset
from robosoc.control.flight import ROW_FIELDS, fly
from robosoc.control.host import HostController
from robosoc.firmware import flight_app, images, packets

#: Cycle of the first sample's injection: the firmware has booted by then.
DEFAULT_FIRST_CYCLE = flight_app.FIRST_SAMPLE_CYCLE

TASK_NAMES = ("estimator", "pid")


@dataclass(frozen=True)
class SampleInput:
    """One sensor sample as the firmware receives it, and the cycle it is injected in."""

    seq: int
    time_s: float
    cycle: int
    payload: bytes


@dataclass(frozen=True)
class JobRecord:
    """One job of a firmware task: timing from the kernel's job log, cost from the simulator's counters."""

    task: str
    tile: tuple[int, int]
    job: int
    release_cycle: int
    start_cycle: int
    completion_cycle: int
    exec_cycles: int
    deadline_met: bool
    instructions: int
    energy_pj: dict[str, float]
    spans_periods: bool

    @property
    def response_cycles(self) -> int:
        return self.completion_cycle - self.release_cycle

    @property
    def energy_total_pj(self) -> float:
        return sum(self.energy_pj.values())


@dataclass(frozen=True)
class PwmCommand:
    seq: int
    pwm: tuple[int, int, int, int]
    cycle: int  # the PWM message's last packet reached the I/O tile


@dataclass
class ReplayResult:
    firmware: FirmwareConfig
    clock_ns: float
    samples: list[SampleInput]
    commands: list[PwmCommand]
    jobs: list[JobRecord]
    kernel_stats: dict[tuple[int, int], images.KernelStats]
    counters: dict[tuple[int, int], dict[str, int]]
    #: energy of each (tile, TASK_ID) over the whole replay (the jobs' ``task`` parts add up to these)
    task_energy_pj: dict[tuple[tuple[int, int], int], float]
    energy_pj: dict[str, float]
    cycles: int
    host_seconds: float
    dropped: list[str] = field(default_factory=list)

    def jobs_of(self, task: str) -> list[JobRecord]:
        return [j for j in self.jobs if j.task == task]

    @property
    def deadline_misses(self) -> int:
        return sum(not j.deadline_met for j in self.jobs)


# --- the sensor stream --------------------------------------------------------------------------


def samples_from_rows(rows: np.ndarray, clock_ns: float, first_cycle: int = DEFAULT_FIRST_CYCLE) -> list[SampleInput]:
    """Sensor messages of a flight (rows with the columns of :data:`ROW_FIELDS`, e.g. a flight log).

    Raises:
        ValueError: a column is missing (an old log without the sensor columns) or times go back.
    """
    if rows.ndim != 2 or rows.shape[1] != len(ROW_FIELDS):
        raise ValueError(f"a flight has {len(ROW_FIELDS)} columns (robosoc.control.flight.ROW_FIELDS)")
    col = {name: rows[:, k] for k, name in enumerate(ROW_FIELDS)}
    times = col["t"]
    if len(times) and (np.diff(times) <= 0).any():
        raise ValueError("sample times must increase")
    out = []
    for k in range(len(rows)):
        t = float(times[k])
        dt = float(times[k] - times[k - 1]) if k else float(times[1] - times[0]) if len(times) > 1 else 0.01
        values = {
            "kind": packets.SENSOR.kind,
            "flags": packets.FLAG_ARMED if col["armed"][k] > 0.5 else 0,
            "seq": k,
            "time_us": round(t * 1e6),
            "dt_us": round(dt * 1e6),
            "gyro": tuple(float(col[f"gyro_{a}"][k]) for a in "xyz"),
            "accel": tuple(float(col[f"accel_{a}"][k]) for a in "xyz"),
            "mag": tuple(float(col[f"mag_{a}"][k]) for a in "xyz"),
            "baro_altitude": float(col["baro_altitude"][k]),
            "setpoint": tuple(float(col[f"sp_{n}"][k]) for n in ("roll", "pitch", "yaw", "height")),
            "height_feedforward": (float(col["sp_height_rate"][k]), float(col["sp_height_accel"][k])),
        }
        cycle = first_cycle + round(t * 1e9 / clock_ns)
        out.append(SampleInput(k, t, cycle, packets.SENSOR.pack(values)))
    return out


def built_in_rows(seconds: float = 10.0, seed: int = 1) -> np.ndarray:
    """The built-in sensor stream: the default scenario flown by the host controller."""
    scenario = ScenarioConfig(duration_s=seconds)
    vehicle = vehicle_preset(scenario.vehicle)
    return fly(scenario, vehicle, HostController.for_scenario(scenario, vehicle), seed)


# --- the replay ---------------------------------------------------------------------------------


def replay(
    rows: np.ndarray,
    fw: FirmwareConfig | None = None,
    *,
    vehicle: VehicleConfig | None = None,
    scenario: ScenarioConfig | None = None,
    chip: ChipConfig | None = None,
    energy: EnergyModel | None = None,
    first_cycle: int = DEFAULT_FIRST_CYCLE,
    on_sample: Callable[[int, int], None] | None = None,
) -> ReplayResult:
    """Run the firmware on the chip against the sensor samples of ``rows`` (a flight's rows).

    Args:
        rows: a flight (:func:`robosoc.control.flight.fly` or a flight log read back).
        fw: the firmware build and task mapping (default: fixed point with the multiplier).
        vehicle, scenario: the configuration the firmware's control parameters come from.
        chip: the chip (default: the seed's 2×2 for the mapping, :meth:`FirmwareConfig.seed_chip`).
        energy: the energy model (default: the packaged coefficients).
        first_cycle: cycle of the first sample's injection.
        on_sample: called with (samples done, samples in all) as the replay goes (progress bars).

    Raises:
        ValueError: the mapping does not fit the chip, or the rows are not a flight.
        robosoc.chip.mpsoc.ChipError / CoreError: the firmware faulted (names tile, pc, symbol).
    """
    fw = fw or FirmwareConfig()
    chip_config = chip or fw.seed_chip()
    fw.check_chip(chip_config)
    model = energy or EnergyModel.load()
    elf = flight_app.build(fw, vehicle=vehicle, scenario=scenario)
    chip_ = MPSoC(chip_config)
    program = load_elf(elf, chip_.regions())
    tiles = flight_app.app_tiles(fw)
    for xy in tiles:
        chip_.load(xy, program)
    samples = samples_from_rows(rows, chip_.clock_ns, first_cycle)
    names = {(xy, tid): name for xy in tiles for name, tid in flight_app.task_ids(fw, xy).items()}

    start = time.perf_counter()
    periods: list[dict] = []  # per sample period: counter deltas per (tile, task) and NoC energy
    previous = _snapshot(chip_, tiles, model)
    seen = dict.fromkeys(tiles, 0)
    logged: list[tuple[tuple[int, int], images.JobRecord, int]] = []  # (tile, record, period)
    received: list[tuple[int, list[int]]] = []
    period = samples[1].cycle - samples[0].cycle if len(samples) > 1 else round(10e6 / chip_.clock_ns)
    for k, sample in enumerate(samples):
        for payload in flight_app.sensor_payloads(sample.payload, fw, chip_config, seq=k):
            chip_.inject(tuple(fw.ekf_tile), payload, sample.cycle)  # type: ignore[arg-type]
        chip_.step(samples[k + 1].cycle if k + 1 < len(samples) else sample.cycle + period)
        received += chip_.received()
        current = _snapshot(chip_, tiles, model)
        periods.append(_delta(previous, current))
        previous = current
        for xy in tiles:
            log = images.read_job_log(chip_, xy)
            count = log.lost + len(log.records)
            fresh = count - seen[xy]
            if fresh > len(log.records):
                raise RuntimeError(f"tile {xy}: the job log overflowed between two samples")
            for r in log.records[len(log.records) - fresh :] if fresh else []:
                r = _unwrapped(r, chip_.cycle)
                logged.append((xy, r, _period_of(samples, r.release)))
            seen[xy] = count
        if on_sample is not None:
            on_sample(k + 1, len(samples))
    seconds = time.perf_counter() - start

    per_period = Counter(p for _, _, p in logged)
    per_tile_period = Counter((xy, p) for xy, _, p in logged)
    jobs = []
    for xy, r, p in logged:
        name = names.get((xy, r.task))
        if name is None:
            continue
        delta = periods[p]
        counters = delta["tasks"].get((xy, r.task), {})
        shared = per_tile_period[(xy, p)]
        energy_pj = {
            "task": _pj(model, counters),
            "kernel": _pj(model, delta["tasks"].get((xy, images.KERNEL_TASK_ID), {})) / shared,
            "idle": _pj(model, delta["tasks"].get((xy, images.IDLE_TASK_ID), {})) / shared,
            "noc": delta["noc_pj"] / per_period[p],
        }
        jobs.append(
            JobRecord(
                task=name, tile=xy, job=r.job, release_cycle=r.release, start_cycle=r.start,
                completion_cycle=r.completion, exec_cycles=r.exec_cycles, deadline_met=r.met,
                instructions=int(counters.get("instructions", 0)), energy_pj=energy_pj,
                spans_periods=p + 1 < len(samples) and r.completion > samples[p + 1].cycle,
            )
        )  # fmt: skip

    commands = []
    for message in images.reassemble(received):
        if message.port != packets.PWM_PORT:
            continue
        values = packets.PWM.unpack(message.data)
        commands.append(PwmCommand(int(values["seq"]), tuple(int(v) for v in values["pwm"]), message.cycle))  # type: ignore[arg-type]
    chip_.finish_accounting()
    counters = {xy: chip_.counters(xy) for xy in tiles}
    task_energy = {(xy, task): _pj(model, c) for xy in tiles for task, c in chip_.task_counters(xy).items()}
    total = {f"tile {xy}": _pj(model, c) for xy, c in counters.items()}
    total["noc"] = sum(model.noc_pj(chip_.noc_counters()).values())
    return ReplayResult(
        firmware=fw, clock_ns=chip_.clock_ns, samples=samples, commands=commands, jobs=jobs,
        kernel_stats={xy: images.read_stats(chip_, xy) for xy in tiles}, counters=counters,
        task_energy_pj=task_energy, energy_pj=total,
        cycles=chip_.cycle, host_seconds=seconds,
    )  # fmt: skip


def _unwrapped(record: images.JobRecord, now: int) -> images.JobRecord:
    """The record with its 32-bit TIMER0 stamps placed on the chip's 64-bit timeline (they are at
    most 2**32 cycles, 17 s at 4 ns, before ``now``)."""

    def full(value: int) -> int:
        return now - ((now - value) & 0xFFFFFFFF)

    return dataclasses.replace(
        record, release=full(record.release), start=full(record.start), completion=full(record.completion),
        deadline=full(record.deadline),
    )  # fmt: skip


def _period_of(samples: Sequence[SampleInput], cycle: int) -> int:
    """Index of the sample period [cycle_k, cycle_k+1) holding ``cycle`` (0 before the first)."""
    return max(0, bisect.bisect_right([s.cycle for s in samples], cycle) - 1)


def _pj(model: EnergyModel, counters: dict[str, int]) -> float:
    return sum(model.breakdown_pj(counters).values()) if counters else 0.0


def noc_traffic_pj(model: EnergyModel, noc: dict[str, int]) -> float:
    """Router energy of ``noc`` counters beyond what the same routers spend idle for as long."""
    idle = dict(noc)
    idle["port_idle_cycles"] = noc["port_idle_cycles"] + noc["port_busy_cycles"]
    idle["port_busy_cycles"] = 0
    idle["router_busy_cycles"] = 0
    return sum(model.noc_pj(noc).values()) - sum(model.noc_pj(idle).values())


def _snapshot(chip: MPSoC, tiles: Sequence[tuple[int, int]], model: EnergyModel) -> dict:
    chip.finish_accounting()
    tasks = {(xy, task): c for xy in tiles for task, c in chip.task_counters(xy).items()}
    return {"tasks": tasks, "noc_pj": noc_traffic_pj(model, chip.noc_counters())}


def _delta(before: dict, after: dict) -> dict:
    tasks = {}
    for key, c in after["tasks"].items():
        old = before["tasks"].get(key, {})
        tasks[key] = {name: value - old.get(name, 0) for name, value in c.items()}
    return {"tasks": tasks, "noc_pj": after["noc_pj"] - before["noc_pj"]}
