"""The control firmware on the chip, driven one sensor sample at a time (:class:`FirmwareRun`).

The half of a co-simulation that does not need the physics, shared by the replay of a log
(:mod:`robosoc.cosim.replay`), the lockstep flight and the decoupled chip side: every sensor sample
becomes a message from the I/O tile, injected at the cycle of its timestamp; the chip runs the
firmware (a project's tasks, :mod:`robosoc.host.firmware_image`); what comes back is the PWM
command of each sample with the cycle it reached the I/O tile, and one record per job of each task.

Time: sample k (timestamp t_k seconds) is injected in cycle ``first_cycle + round(t_k / clock)``;
``first_cycle`` leaves the firmware time to boot (the kernel's start-up takes a few ten thousand
cycles).  The chip is stepped from one injection to the next, and at each step the per-task
counters of every tile and the router counters are read, so each job's instructions and energy are
those of its task in the sample period in which it was released:

* ``task``: the job's own task (its TASK_ID on its tile) in that period, shared equally by the
  task's jobs released in it (periodic release can put two in one period), instructions too;
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

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from robosoc.chip.energy import EnergyModel
from robosoc.chip.function_profile import FunctionProfile, chip_profile
from robosoc.chip.mpsoc import ChipError, MPSoC, account_counter_map
from robosoc.chip.single import CoreError
from robosoc.chip.step_calls import StepCalls
from robosoc.config.chip import ChipConfig
from robosoc.config.firmware import FirmwareConfig
from robosoc.host import images, packets
from robosoc.host.firmware_image import FIRST_SAMPLE_CYCLE, FirmwareImage
from robosoc.host.telemetry import TelemetryReader
from robosoc.kernels.chip import K_EXITED, K_STATE, K_TASK, NTASKS
from robosoc.kernels.noc import ROUTER_COUNTS
from robosoc.program.elf import Program, load_elf_once
from robosoc.records import JobRecord, PwmCommand, SampleInput

#: Cycle of the first sample's injection: the firmware has booted by then.
DEFAULT_FIRST_CYCLE = FIRST_SAMPLE_CYCLE


class TelemetryRead(NamedTuple):
    """The telemetry values read at the close of sample period ``sample`` (those of sleeping tiles:
    :class:`robosoc.host.telemetry.TelemetryReader`; a named tuple: a flight makes one per sample)."""

    sample: int
    values: dict[str, float]


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
    #: the firmware's telemetry, read at the close of each sample period (where a tile slept)
    telemetry: list[TelemetryRead] = field(default_factory=list)
    #: the exact per-function profile (a run made with ``profile=True``)
    profile: FunctionProfile | None = None

    def jobs_of(self, task: str) -> list[JobRecord]:
        return [j for j in self.jobs if j.task == task]

    @property
    def deadline_misses(self) -> int:
        return sum(not j.deadline_met for j in self.jobs)


class FirmwareRun:
    """The firmware on the chip, driven one sensor sample at a time: the part of :func:`replay`
    that the lockstep co-simulation (:mod:`robosoc.cosim.lockstep`) shares.

    Use: for each sample, :meth:`inject` it, :meth:`run_to` the chip (in one go or in pieces) up
    to the next sample's cycle, then :meth:`close_period`; :meth:`result` at the end.  Job records
    are charged to the sample period they were released in, from counter snapshots taken at
    :meth:`close_period`.

    Args:
        fw: the firmware build and task mapping.
        image: the firmware (:func:`robosoc.host.scenario_image.firmware_image`), built once by the caller.
        chip: the chip (default: :meth:`FirmwareConfig.default_chip`).
        energy: the energy model (default: the packaged coefficients).
        first_cycle: cycle of the first sample's injection.
        profile: count every instruction per function, tile and task (:meth:`function_profile`).
        timeline: record the chip's timeline for its trace (:mod:`robosoc.cosim.chip_timeline`); a
            run whose trace nobody writes leaves it off (about 2 % of a flight's host time).

    Raises:
        ValueError: the mapping does not fit the chip.
    """

    def __init__(
        self,
        fw: FirmwareConfig,
        image: FirmwareImage,
        *,
        chip: ChipConfig | None = None,
        energy: EnergyModel | None = None,
        first_cycle: int = DEFAULT_FIRST_CYCLE,
        profile: bool = False,
        timeline: bool = True,
    ) -> None:
        self.fw = fw
        self.image = image
        self.chip_config = chip or self.fw.default_chip()
        self.fw.check_chip(self.chip_config)
        base = energy or EnergyModel.load()
        self.model = base.for_chip(self.chip_config)  # DVFS: at its operating point
        self.first_cycle = first_cycle
        self.chip = MPSoC(self.chip_config)
        if timeline:
            self.chip.record_timeline()  # for the chip trace (cosim/chip_timeline.py)
        self.tiles = image.tiles
        #: each tile's core coefficients (a tile on its own clock has its own operating point)
        self.tile_models = {xy: base.for_tile(self.chip_config, xy) for xy in self.tiles}
        programs: dict[Path, Program] = {}
        for xy in self.tiles:
            elf = image.elf_for(xy)  # a tile on a divided clock: its kernel's tick in its own cycles
            if elf not in programs:
                programs[elf] = load_elf_once(elf, self.chip.regions())
            self.chip.load(xy, programs[elf])
        if profile:
            self.chip.enable_profile()  # exact counts per function: function_profile() reads them
        self.names = {(xy, tid): name for xy, ids in image.tasks.items() for name, tid in ids.items()}
        self.samples: list[SampleInput] = []
        self._sample_cycles: list[int] = []  # of the samples, for finding a job's period
        self.commands: list[PwmCommand] = []
        # the accounting rows jobs are charged to: every named task's, the kernel's and idle's per tile
        charged = sorted(
            {(i, task) for i, xy in enumerate(self.tiles) for (where, task) in self.names if where == xy}
            | {(i, task) for i in range(len(self.tiles)) for task in (images.KERNEL_TASK_ID, images.IDLE_TASK_ID)}
        )
        self._keys = np.array([i * NTASKS + task for i, task in charged], dtype=np.int64)
        self._tile_rows = np.array([self.chip.config.tile_index(xy) for xy in self.tiles], dtype=np.intp)
        self._acc_tiles = np.array([self.chip.config.tile_index(self.tiles[i]) for i, _ in charged], dtype=np.int64)
        self._acc_tasks = np.array([task for _, task in charged], dtype=np.int64)
        self._periods: list[_Period] = []  # per sample period: counters per (tile, task), routers' counters
        # the accounting rows at the last close (close_accounts keeps them), and the routers' counters
        # at the run's start (each period's NoC energy is taken from those at its two closes)
        self._previous = np.zeros((len(self._keys), self.chip.acc.shape[-1]), dtype=np.int64)
        # where each close's call writes (the same arrays at every call: chip/kernel_entry.py)
        self._close_out = np.empty((len(self._keys), len(account_counter_map()[0])), np.int64)
        self._close_routers = np.empty(len(ROUTER_COUNTS), np.int64)
        self._routers_at_start = self._accounts()[1]
        self._seen = dict.fromkeys(self.tiles, 0)
        self._job_logs: dict[tuple[int, int], images.JobLogReader] = {}  # made at the first close
        # (tile's position, bytes of its new records, chip cycle when read, samples injected then) at
        # each close, not parsed yet: a close only copies them (a flight closes a period per sample)
        self._unparsed: list[tuple[int, bytes, int, int]] = []
        #: the records parsed so far, in the order collected, a list per column (:meth:`_jobs`)
        self._job_columns: dict[str, list[int]] = {name: [] for name in _JOB_COLUMNS}
        self._dividers = np.array([self.chip.divider(xy) for xy in self.tiles], dtype=np.int64)
        self.telemetry: list[TelemetryRead] = []
        self._telemetry = TelemetryReader(self.chip, image.telemetry) if image.telemetry else None
        #: the newest value of each telemetry name read so far
        self.latest: dict[str, float] = {}
        self._start = time.perf_counter()

    @property
    def clock_ns(self) -> float:
        return self.chip.clock_ns

    @property
    def cycle(self) -> int:
        return self.chip.cycle

    @property
    def period_open(self) -> bool:
        """Whether the last injected sample's period has not been closed yet."""
        return len(self._periods) < len(self.samples)

    def inject(self, sample: SampleInput) -> None:
        """Send ``sample`` from the I/O tile to the firmware's sensor input at ``sample.cycle``."""
        tile, port = self.image.sensor
        for payload in images.io_packets(sample.payload, port, self.chip_config.io_tile, sample.seq):
            self.chip.inject(tile, payload, sample.cycle)
        if self.image.io_inputs:
            self._inject_extra(sample)
        self.samples.append(sample)
        self._sample_cycles.append(sample.cycle)

    def _inject_extra(self, sample: SampleInput) -> None:
        """The further packets the project takes (``image.io_inputs``), after the sensor packet.

        Raises:
            ValueError: the sample lacks one (the flight or log has no such reading).
        """
        extra = dict(sample.extra)
        for name, tile, port in self.image.io_inputs:
            if name not in extra:
                raise ValueError(f"sample {sample.seq}: the firmware takes {name} packets, the sample has none")
            for payload in images.io_packets(extra[name], port, self.chip_config.io_tile, sample.seq):
                self.chip.inject(tile, payload, sample.cycle)

    def run_to(self, cycle: int) -> list[PwmCommand]:
        """Run the chip to ``cycle``; the PWM commands that reached the I/O tile meanwhile.

        Raises:
            robosoc.chip.mpsoc.ChipError / CoreError: the firmware faulted (names tile, pc, symbol).
        """
        return self._arrived(self.chip.step(cycle))

    def run_to_calls(self, cycle: int) -> StepCalls[list[PwmCommand]]:
        """:meth:`run_to` as the chip loop calls it makes (:meth:`robosoc.chip.mpsoc.MPSoC.step_calls`)."""
        status = yield from self.chip.step_calls(cycle)
        return self._arrived(status)

    def _arrived(self, status: int) -> list[PwmCommand]:
        """After a step that returned ``status``: the PWM commands that reached the I/O tile in it."""
        try:
            self.chip.raise_failure(status)
        except (ChipError, CoreError) as exc:
            exc.args = (f"{exc.args[0]}{self._running_task(exc)}", *exc.args[1:])  # the task, by its name
            raise
        if K_EXITED in self.chip.cst[self._tile_rows, K_STATE].tolist():
            for xy in self.tiles:
                if self.chip.state(xy) == "exited":  # main returned, or refused a task: no task runs there
                    raise ChipError(f"tile {xy}: {self.image.exit_reason(self.chip.exit_code(xy))}", xy)
        received = self.chip.received()
        if not received:
            return []
        fresh = []
        # a PWM message fits one NoC packet, so no message straddles two calls
        for message in images.reassemble(received):
            if message.port != self.image.actuator_port:
                continue
            values = self._pwm_values(message.data)
            m0, m1, m2, m3 = packets.array(values, "pwm")
            fresh.append(
                PwmCommand(int(packets.scalar(values, "seq")), (int(m0), int(m1), int(m2), int(m3)), message.cycle)
            )
        self.commands += fresh
        return fresh

    def _pwm_values(self, data: bytes) -> dict[str, packets.Value]:
        """The fields of a PWM message that reached the I/O tile.

        Raises:
            ChipError: not a PWM packet (its size or kind), naming the message.
        """
        try:
            return packets.PWM.unpack(data)
        except ValueError as exc:
            name = self.image.actuator_message
            raise ChipError(
                f"the I/O tile received a malformed message {name!r} on its port {self.image.actuator_port}: "
                f"{exc} (send a robosoc_msg_{name}_t of ROBOSOC_MSG_{name.upper()}_BYTES)",
                None,
            ) from None

    def _running_task(self, exc: Exception) -> str:
        """`` (task 'name')`` of the task that ran on the failed tile, or nothing."""
        message = str(exc)
        for xy in self.tiles:
            if message.startswith(f"tile {xy}"):
                task = int(self.chip.cst[self.chip.config.tile_index(xy), K_TASK])
                name = self.names.get((xy, task))
                return f" (task {name!r})" if name else ""
        return ""

    def close_period(self) -> None:
        """End the period of the last injected sample (the chip is at the next sample's cycle):
        snapshot the counters, collect the jobs the kernels logged, and read the telemetry of every
        sleeping tile (:class:`robosoc.host.telemetry.TelemetryReader`, a host read: no cycle).

        Raises:
            RuntimeError: a tile's job log overflowed since the last call.
            ChipError: after the first period, a task the kernel does not hold (refused by the
                kernel, or never created by a project's own ``main``).
        """
        if not self._periods and self.image.task_table is not None:  # booted: main has created its tasks
            tables = {xy: self.image.task_table_of(xy) for xy in self.tiles}
            problem = self.image.missing_tasks({xy: t.created(self.chip, xy) for xy, t in tables.items() if t})
            if problem:
                raise ChipError(problem, None)
        counters, routers = self._accounts()
        if self._telemetry is not None:
            values = self._telemetry.read()
            if values:
                self.telemetry.append(TelemetryRead(len(self.samples) - 1, values))
                self.latest.update(values)
        self._periods.append(_Period(self._keys, counters, routers))
        now = self.chip.cycle
        for i, xy in enumerate(self.tiles):
            try:
                log = self._job_logs.get(xy)
                if log is None:
                    log = self._job_logs[xy] = images.JobLogReader(self.chip, xy)
                raw, count = log.new_records(self._seen[xy])
            except ValueError as exc:
                raise RuntimeError(f"{exc} (between two samples)") from exc
            if raw:
                self._unparsed.append((i, raw, now, len(self._sample_cycles)))
            self._seen[xy] = count

    def _jobs(self) -> dict[str, list[int]]:
        """Every job record collected so far, in the order collected, a list per column
        (:data:`_JOB_COLUMNS`): the tile's position in :attr:`tiles`, the task, the job's number, the
        flags, the release, start and completion as chip cycles (:func:`_full_cycle` of the 32-bit
        stamps, the record read at the close's cycle), the execution cycles in chip cycles, and the
        sample period of the release among the samples injected before the record was read.  The
        closes since the last call are parsed now, all at once."""
        if not self._unparsed:
            return self._job_columns
        chunks = self._unparsed
        records = images.job_record_columns(b"".join(raw for _, raw, _, _ in chunks))
        counts = [len(raw) // images.JOB_RECORD_DTYPE.itemsize for _, raw, _, _ in chunks]
        tile = np.repeat(np.array([i for i, _, _, _ in chunks], dtype=np.int64), counts)
        now = np.repeat(np.array([now for _, _, now, _ in chunks], dtype=np.int64), counts)
        known = np.repeat(np.array([samples for _, _, _, samples in chunks], dtype=np.int64), counts)
        d = self._dividers[tile]
        mine = now // d  # the read's cycle in the tile's core cycles

        def chip_cycles(stamps: np.ndarray) -> np.ndarray:  # for every record at once
            return _full_cycle(stamps.astype(np.int64), mine) * d

        release = chip_cycles(records["release"])
        # _period_of: the last sample injected at or before the release, of those known then
        after = np.minimum(np.searchsorted(np.array(self._sample_cycles, dtype=np.int64), release, "right"), known)
        columns = {
            "tile": tile, "task": records["task"], "job": records["job"], "flags": records["flags"],
            "release": release, "start": chip_cycles(records["start"]),
            "completion": chip_cycles(records["completion"]),
            "exec_cycles": records["exec_cycles"].astype(np.int64) * d, "period": np.maximum(after - 1, 0),
        }  # fmt: skip
        for name, values in columns.items():
            self._job_columns[name] += values.tolist()
        self._unparsed = []
        return self._job_columns

    def energy_pj(self) -> dict[str, float]:
        """The chip's energy so far, per application tile (``"tile (x, y)"``) and for the NoC
        (``"noc"``): what :meth:`result` reports as the run's totals, at the present cycle."""
        chip_, model = self.chip, self.model
        chip_.finish_accounting()
        total = {f"tile {xy}": _pj(self.tile_models[xy], chip_.counters(xy)) for xy in self.tiles}
        total["noc"] = sum(model.noc_pj(chip_.noc_counters()).values())
        return total

    def jobs_logged(self, since: int = 0) -> list[tuple[str, int, int]]:
        """(task, release cycle, completion cycle) of the jobs collected so far by
        :meth:`close_period`, from the ``since``-th on, in the order the kernels logged them (a
        live view; :meth:`result` gives the full records with their energy)."""
        jobs = self._jobs()
        out = []
        for i, task, release, completion in zip(
            jobs["tile"][since:], jobs["task"][since:], jobs["release"][since:], jobs["completion"][since:], strict=True
        ):
            out.append((self.names.get((self.tiles[i], task), f"task {task}"), release, completion))
        return out

    def _accounts(self) -> tuple[np.ndarray, np.ndarray]:
        """The counters of the accounting rows jobs are charged to (one row per key) since the last
        call; the routers' counters now (:meth:`robosoc.chip.mpsoc.MPSoC.noc_counters_of`)."""
        out, routers = self._close_out, self._close_routers
        self.chip.close_accounts(self._acc_tiles, self._acc_tasks, self._previous, out, routers)
        return out.copy(), routers.copy()

    def _periods_noc_pj(self) -> list[float]:
        """Each period's NoC traffic energy: the traffic energy at its close less that at the
        previous close (or the run's start), for all periods at once (numpy's products and sums,
        element by element those of :func:`noc_traffic_pj` of each close's counters)."""
        routers = np.stack([self._routers_at_start, *(p.routers for p in self._periods)])
        traffic = noc_traffic_pj(self.model, self.chip.noc_counters_of(routers))
        return np.diff(traffic).tolist()

    def function_profile(self) -> FunctionProfile:
        """The exact profile so far: cycles, instructions and energy per function, tile and task.

        Raises:
            RuntimeError: the run was made without ``profile=True``.
        """
        names = dict(self.names)
        for xy in self.tiles:
            names.setdefault((xy, images.KERNEL_TASK_ID), "kernel")
            names.setdefault((xy, images.IDLE_TASK_ID), "idle")
        return chip_profile(self.chip, self.tiles, self.model, names, self.tile_models)

    def result(self) -> ReplayResult:
        """Job records with their energy, the PWM commands, and the run's totals."""
        seconds = time.perf_counter() - self._start
        chip_, samples = self.chip, self.samples
        logged = {name: np.array(values, dtype=np.int64) for name, values in self._jobs().items()}
        tile, task, period = logged["tile"], logged["task"], logged["period"]
        values = _period_values(self._periods, len(self._keys))
        energy = _rows_pj(values, [self.tile_models[self.tiles[i]] for i in self._keys // NTASKS])
        instructions = values[:, :, account_counter_map()[0].index("instructions")]
        noc_pj = np.array(self._periods_noc_pj())
        # every record's accounting rows: its task's, its tile's kernel's and idle's
        row_of = np.full(len(self.tiles) * NTASKS, -1, dtype=np.int64)
        row_of[self._keys] = np.arange(len(self._keys))
        own = row_of[tile * NTASKS + task]
        kernel = row_of[tile * NTASKS + images.KERNEL_TASK_ID]
        idle = row_of[tile * NTASKS + images.IDLE_TASK_ID]
        # how many records each period, each tile in each period and each task in each period has, and
        # each record's place among its task's in its period (jobs of one task released in one period,
        # by periodic release, share its counters: the first ones get the remainder's instructions)
        periods = len(self._periods)
        per_period = _group_sizes(period)
        shared = _group_sizes(tile * periods + period)
        group = (tile * NTASKS + task) * periods + period
        alike = _group_sizes(group)
        order = np.argsort(group, kind="stable")
        first = np.searchsorted(group[order], group[order])  # where each record's group starts, in order
        place = np.empty_like(group)
        place[order] = np.arange(len(group)) - first
        quotient, remainder = np.divmod(instructions[period, own], alike)
        charged = (quotient + (place < remainder)).tolist()
        task_pj = (energy[period, own] / alike).tolist()
        kernel_pj = (energy[period, kernel] / shared).tolist()
        idle_pj = (energy[period, idle] / shared).tolist()
        noc_share = (noc_pj[period] / per_period).tolist()
        sample_cycles = self._sample_cycles
        jobs = []
        for i, t, job, flags, release, start, completion, exec_cycles, p, n, e_task, e_kernel, e_idle, e_noc in zip(
            *(logged[name].tolist() for name in _JOB_COLUMNS), charged, task_pj, kernel_pj, idle_pj, noc_share,
            strict=True,
        ):  # fmt: skip
            xy = self.tiles[i]
            name = self.names.get((xy, t))
            if name is None:
                continue
            jobs.append(
                JobRecord(
                    task=name, tile=xy, job=job, release_cycle=release, start_cycle=start,
                    completion_cycle=completion, exec_cycles=exec_cycles, deadline_met=bool(flags & images.JOB_MET),
                    instructions=n, energy_pj={"task": e_task, "kernel": e_kernel, "idle": e_idle, "noc": e_noc},
                    spans_periods=p + 1 < len(sample_cycles) and completion > sample_cycles[p + 1],
                )
            )  # fmt: skip
        total = self.energy_pj()
        counters = {xy: chip_.counters(xy) for xy in self.tiles}
        task_energy = {
            (xy, task): _pj(self.tile_models[xy], c) for xy in self.tiles for task, c in chip_.task_counters(xy).items()
        }
        return ReplayResult(
            firmware=self.fw, clock_ns=chip_.clock_ns, samples=list(samples), commands=list(self.commands),
            jobs=jobs, kernel_stats={xy: images.read_stats(chip_, xy) for xy in self.tiles}, counters=counters,
            task_energy_pj=task_energy, energy_pj=total, cycles=chip_.cycle, host_seconds=seconds,
            telemetry=list(self.telemetry), profile=self.function_profile() if chip_.cores.profiling else None,
        )  # fmt: skip


def _group_sizes(keys: np.ndarray) -> np.ndarray:
    """For each element of ``keys``, how many elements have its value."""
    _, inverse, counts = np.unique(keys, return_inverse=True, return_counts=True)
    return counts[inverse]


#: the columns of the job records collected (FirmwareRun._jobs), in the order result() takes them
_JOB_COLUMNS = ("tile", "task", "job", "flags", "release", "start", "completion", "exec_cycles", "period")


def _full_cycle(stamp: Any, now: Any) -> Any:
    """A 32-bit TIMER0 stamp of a job record placed on the chip's 64-bit timeline (it is at most
    2**32 cycles, 17 s at 4 ns, before ``now``, the chip's cycle when the record was read); ints,
    or int64 arrays element by element."""
    return now - ((now - stamp) & 0xFFFFFFFF)


def _pj(model: EnergyModel, counters: dict[str, int]) -> float:
    return model.total_pj(counters) if counters else 0.0


def _period_values(periods: Sequence[_Period], rows: int) -> np.ndarray:
    """The periods' counters as one array: [period, accounting row, counter]."""
    if not periods:
        return np.zeros((0, rows, len(account_counter_map()[0])), dtype=np.int64)
    return np.stack([p.values for p in periods])


def _rows_pj(values: np.ndarray, models: Sequence[EnergyModel]) -> np.ndarray:
    """:meth:`EnergyModel.total_pj` of every period's every accounting row at once ([period, row];
    row r with ``models[r]``): each row's sum takes the same products in the same order as
    ``total_pj`` of its counters' dict, so every value is the same to the bit (a counter the
    accounting rows do not have adds ``0 * pj``, which leaves a sum unchanged)."""
    names = {name: c for c, name in enumerate(account_counter_map()[0])}
    out = np.zeros(values.shape[:2])
    for r, model in enumerate(models):
        total = np.zeros(values.shape[0])
        for key, coeff in (*model.instruction.items(), *model.stall.items()):
            c = names.get(key)
            if c is not None:
                total += values[:, r, c] * coeff.pj
        out[:, r] = total
    return out


def noc_traffic_pj(model: EnergyModel, noc: dict[str, Any]) -> Any:
    """Router energy of ``noc`` counters beyond what the same routers spend idle for as long (an
    array of them for counters that are arrays)."""
    idle = dict(noc)
    idle["port_idle_cycles"] = noc["port_idle_cycles"] + noc["port_busy_cycles"]
    idle["port_busy_cycles"] = 0
    idle["router_busy_cycles"] = 0
    return sum(model.noc_pj(noc).values()) - sum(model.noc_pj(idle).values())


class _Period(NamedTuple):
    """What one sample period spent: per (tile, task) that jobs are charged to (the named tasks, the
    kernel, idle), its named counters (:func:`robosoc.chip.mpsoc.account_counters`) over the period,
    taken with the period's close in one call (:meth:`robosoc.chip.mpsoc.MPSoC.close_accounts`);
    the routers' counters at its close, whose traffic energies the flight's end takes (a float
    sum and difference per period, as they were taken at each close before)."""

    keys: np.ndarray  # tile position * NTASKS + task, sorted
    values: np.ndarray  # their counters over the period, one row each (account_counter_map()'s order)
    routers: np.ndarray  # the routers' counters at the period's close (robosoc.kernels.noc.ROUTER_COUNTS)

    def counters(self, tile: int, task: int) -> dict[str, int]:
        """Named counters of ``task`` on the tile at position ``tile`` over the period ({}: not a task
        jobs are charged to).  A task that has not run has zeros, which charge what nothing would."""
        k = int(self.keys.searchsorted(tile * NTASKS + task))
        if k == len(self.keys) or self.keys[k] != tile * NTASKS + task:
            return {}
        return dict(zip(account_counter_map()[0], self.values[k].tolist(), strict=True))
