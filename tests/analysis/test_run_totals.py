"""The totals of a firmware run add up: the replay's per-tile, NoC and per-task energy, each job's
task, kernel, idle and NoC shares, the ``energy`` and ``cycles`` of ``summary.json`` and the
profile's totals, each against the chip's state arrays read directly and the energy written out
here, with the NoC's idle terms derived by hand (cycles x routers x ports).

The run: a short flight's samples replayed into the seed's firmware on its 2x2 chip (estimator on
(0, 1), PID on (1, 0), (1, 1) powered off), profiled, under both router models.  Its packets cross
every router: the samples go from the I/O tile (0, 0) to (0, 1), the estimate from (0, 1) to
(1, 0) over (1, 1) (XY routing: x first), the PWM command from (1, 0) back to (0, 0).
"""

from __future__ import annotations

import bisect
import dataclasses
import math
from collections import Counter

import numpy as np
import pytest

from robosoc.chip.energy import INSTRUCTION_CLASSES, STALL_KINDS, EnergyModel
from robosoc.chip.function_profile import NOC_ROW, profile_totals, summary_mismatches
from robosoc.config.chip import NocConfig
from robosoc.config.firmware import FirmwareConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import vehicle_preset
from robosoc.cosim.firmware_run import FirmwareRun, ReplayResult, noc_traffic_pj
from robosoc.cosim.replay import samples_from_rows
from robosoc.host import images
from robosoc.host.scenario_image import firmware_image
from robosoc.kernels import chip as kc
from robosoc.kernels import noc as nk
from robosoc.kernels.core_layout import S_CYCLE
from robosoc.outputs.run_summary import cycle_figures, energy_figures, task_figures, vehicle_summary
from robosoc.records import ENERGY_PARTS
from run_folders import host_rows

MODEL = EnergyModel.load()
SECONDS = 0.1  # ten samples
ROUTERS = 4  # the 2x2 mesh: the routers of the I/O tile and of the powered-off tile included
ARBITERS = ("hermes", "per-output")


def core_pj(counts: dict[str, int]) -> float:
    """Σ instructions × class pJ + stall cycles × kind pJ."""
    return math.fsum(counts.get(k, 0) * MODEL.instruction[k].pj for k in INSTRUCTION_CLASSES) + math.fsum(
        counts.get(k, 0) * MODEL.stall[k].pj for k in STALL_KINDS
    )


def noc_parts_pj(run: FirmwareRun, cycles: int) -> tuple[float, float]:
    """The routers' energy from their own counts in the NoC's arrays: (beyond idling, idling)."""
    c = {k: v.pj for k, v in MODEL.noc.items()}
    buffer, control = c["buffer_active"] - c["buffer_idle"], c["control_active"] - c["control_idle"]
    port, tile = run.chip.noc.port, run.chip.noc.tile
    traffic = idle = 0.0
    for t in range(ROUTERS):
        traffic += int(port[t, :, nk.P_BUSY].sum()) * buffer + int(tile[t, nk.T_BUSY]) * control
        idle += cycles * (nk.NPORTS * c["buffer_idle"] + c["control_idle"] + c["leakage"])
    return traffic, idle


def tile_counts(run: FirmwareRun, xy: tuple[int, int]) -> dict[str, int]:
    """The tile's counters as the chip keeps them (pinned to its arrays by tests/chip/test_chip_totals.py)."""
    return run.chip.counters(xy)


def replay(fw: FirmwareConfig, arbiter: str = "hermes", profile: bool = False) -> tuple[FirmwareRun, ReplayResult]:
    """Ten samples into the firmware, as :func:`robosoc.cosim.replay.replay` feeds them."""
    chip = dataclasses.replace(fw.seed_chip(), noc=NocConfig(arbiter=arbiter))
    run = FirmwareRun(fw, firmware_image(fw), chip=chip, profile=profile)
    samples = samples_from_rows(host_rows(SECONDS, seed=6), run.clock_ns)
    period = samples[1].cycle - samples[0].cycle
    for k, sample in enumerate(samples):
        run.inject(sample)
        run.run_to(samples[k + 1].cycle if k + 1 < len(samples) else sample.cycle + period)
        run.close_period()
    return run, run.result()


@pytest.fixture(scope="module", params=ARBITERS)
def replayed(request) -> tuple[FirmwareRun, ReplayResult]:
    return replay(FirmwareConfig(), request.param, profile=True)


def test_the_run_crosses_every_router(replayed) -> None:
    run, result = replayed
    assert run.tiles == [(0, 1), (1, 0)] and not run.chip.powered[3]
    assert (run.chip.noc.tile[:ROUTERS, nk.T_BUSY] > 0).all()
    assert len(result.samples) == len(result.commands) == 10


def test_replay_totals_are_each_tiles_and_the_nocs_energy(replayed) -> None:
    run, result = replayed
    chip = run.chip
    assert set(result.energy_pj) == {f"tile {xy}" for xy in run.tiles} | {"noc"}
    assert set(result.counters) == set(run.tiles)
    for xy in run.tiles:
        assert result.counters[xy] == tile_counts(run, xy)
        assert result.counters[xy]["cycles"] == int(chip.cores.st[chip.config.tile_index(xy), S_CYCLE])
        assert result.energy_pj[f"tile {xy}"] == pytest.approx(core_pj(tile_counts(run, xy)), rel=1e-12)
    assert result.cycles == chip.cycle == int(chip.noc.glob[nk.G_CYCLE]) - int(chip.noc.glob[nk.G_CYCLE0])
    traffic, idle = noc_parts_pj(run, result.cycles)
    assert result.energy_pj["noc"] == pytest.approx(traffic + idle, rel=1e-12)
    # the idle terms by hand: 4 routers x (5 buffers idle + switch control idle + leakage) every cycle
    c = {k: v.pj for k, v in MODEL.noc.items()}
    by_hand = result.cycles * ROUTERS * (5 * c["buffer_idle"] + c["control_idle"] + c["leakage"])
    assert idle == pytest.approx(by_hand, rel=1e-12)
    assert noc_traffic_pj(MODEL, chip.noc_counters()) == pytest.approx(traffic, rel=1e-9)


def test_task_energies_are_every_task_of_every_tile(replayed) -> None:
    run, result = replayed
    chip = run.chip
    want = set()
    for xy in run.tiles:
        t = chip.config.tile_index(xy)
        tasks = set(np.flatnonzero(chip.acc[t].any(axis=1)).tolist())
        # the kernel, the idle task and the tile's application task
        assert tasks == {images.KERNEL_TASK_ID, images.IDLE_TASK_ID, *run.image.tasks[xy].values()}
        want |= {(xy, task) for task in tasks}
        mine = [pj for (where, _), pj in result.task_energy_pj.items() if where == xy]
        assert math.fsum(mine) == pytest.approx(result.energy_pj[f"tile {xy}"], rel=1e-12)
    assert set(result.task_energy_pj) == want
    for (xy, task), pj in result.task_energy_pj.items():
        assert pj == pytest.approx(core_pj(chip.task_counters(xy)[task]), rel=1e-12)


def test_job_shares_add_up_to_each_tiles_energy_and_the_nocs_traffic(replayed) -> None:
    run, result = replayed
    # one estimator job and one PID job per sample, each in the period of its sample: every period's
    # counters are shared out, and the jobs' shares add up to the whole run
    assert [(j.task, j.tile) for j in result.jobs].count(("estimator", (0, 1))) == len(result.samples)
    assert [(j.task, j.tile) for j in result.jobs].count(("pid", (1, 0))) == len(result.samples)
    assert not any(j.spans_periods for j in result.jobs)
    for xy in run.tiles:
        jobs = [j for j in result.jobs if j.tile == xy]
        for part, task in (("kernel", images.KERNEL_TASK_ID), ("idle", images.IDLE_TASK_ID)):
            got = math.fsum(j.energy_pj[part] for j in jobs)
            assert got == pytest.approx(result.task_energy_pj[(xy, task)], rel=1e-9), (xy, part)
        (app_task,) = run.image.tasks[xy].values()
        got = math.fsum(j.energy_pj["task"] for j in jobs)
        assert got == pytest.approx(result.task_energy_pj[(xy, app_task)], rel=1e-9)
        # task + kernel + idle of the tile's jobs: the tile's energy
        got = math.fsum(j.energy_pj[p] for j in jobs for p in ("task", "kernel", "idle"))
        assert got == pytest.approx(core_pj(tile_counts(run, xy)), rel=1e-9), xy
    traffic, idle = noc_parts_pj(run, result.cycles)
    assert math.fsum(j.energy_pj["noc"] for j in result.jobs) == pytest.approx(traffic, rel=1e-9)
    # and the chip's energy: every job's four parts, plus the routers idling
    chip_pj = math.fsum(result.energy_pj.values())
    assert math.fsum(j.energy_total_pj for j in result.jobs) + idle == pytest.approx(chip_pj, rel=1e-9)
    assert chip_pj == pytest.approx(
        math.fsum(core_pj(tile_counts(run, xy)) for xy in run.tiles) + traffic + idle, rel=1e-12
    )


def test_jobs_of_one_task_in_one_period_share_its_counters() -> None:
    """Periodic release every 5 ticks (1,310,720 cycles) puts two jobs of each task in most sample
    periods (2,500,000 cycles): they share the task's counters of the period, as the jobs of a tile
    share the kernel's, so that their task parts and instructions still add up to the task's (each
    job was charged the whole period's before)."""
    run, result = replay(FirmwareConfig(release="periodic", period_ticks=5))
    starts = [s.cycle for s in result.samples]
    per_period = Counter((j.task, bisect.bisect_right(starts, j.release_cycle)) for j in result.jobs)
    assert max(per_period.values()) >= 2
    for xy in run.tiles:
        ((name, task),) = run.image.tasks[xy].items()
        jobs = [j for j in result.jobs if j.tile == xy]
        assert {j.task for j in jobs} == {name}
        got = math.fsum(j.energy_pj["task"] for j in jobs)
        assert got == pytest.approx(result.task_energy_pj[(xy, task)], rel=1e-9)
        assert sum(j.instructions for j in jobs) == run.chip.task_counters(xy)[task]["instructions"]
        got = math.fsum(j.energy_pj[p] for j in jobs for p in ("task", "kernel", "idle"))
        assert got == pytest.approx(result.energy_pj[f"tile {xy}"], rel=1e-9)


def test_summary_energy_and_cycles_are_the_runs(replayed) -> None:
    run, result = replayed
    chip = run.chip
    energy = energy_figures(result)
    tiles = {f"{x},{y}": core_pj(tile_counts(run, (x, y))) / 1e6 for x, y in run.tiles}
    assert energy["tiles_uj"].keys() == tiles.keys()
    for key, uj in tiles.items():
        assert energy["tiles_uj"][key] == pytest.approx(uj, rel=1e-12), key
    noc_uj = sum(noc_parts_pj(run, result.cycles)) / 1e6
    assert energy["noc_uj"] == pytest.approx(noc_uj, rel=1e-12)
    assert energy["total_uj"] == pytest.approx(math.fsum(tiles.values()) + noc_uj, rel=1e-12)
    cycles = cycle_figures(result)
    assert cycles == {
        "chip": chip.cycle,
        "tiles": {f"{x},{y}": int(chip.cores.st[chip.config.tile_index((x, y)), S_CYCLE]) for x, y in run.tiles},
    }
    tasks = task_figures(result)
    assert set(tasks) == {"estimator", "pid"}
    for name, figures in tasks.items():
        jobs = result.jobs_of(name)
        assert figures["jobs"] == len(jobs) == len(result.samples)
        mean = math.fsum(j.energy_pj[p] for j in jobs for p in ENERGY_PARTS) / len(jobs) / 1000
        assert figures["energy_nj_mean"] == pytest.approx(mean, rel=1e-12)
        parts = math.fsum(figures[f"energy_nj_{p}_mean"] for p in ENERGY_PARTS)
        assert parts == pytest.approx(figures["energy_nj_mean"], rel=1e-12)
    # the summary the product writes holds the same objects, and the profile agrees with it
    scenario = ScenarioConfig(duration_s=SECONDS)
    rest = vehicle_preset(scenario.vehicle).rest_height
    summary = vehicle_summary(scenario, host_rows(SECONDS, seed=6), rest, result, SECONDS, 1.0)
    assert summary["energy"] == energy and summary["cycles"] == cycles
    assert summary_mismatches(result.profile, summary) == []


def test_profile_totals_are_the_runs_per_tile_and_task(replayed) -> None:
    run, result = replayed
    chip = run.chip
    totals = profile_totals(result.profile)
    assert set(totals) == {*run.tiles, None}
    for xy in run.tiles:
        t = chip.config.tile_index(xy)
        counts = tile_counts(run, xy)
        assert totals[xy]["cycles"] == int(chip.cores.st[t, S_CYCLE]) == counts["cycles"]
        # the exact profile's per-word executions, every task bank: the tile's instructions
        assert totals[xy]["instructions"] == int(chip.cores.executions(t).sum()) == counts["instructions"]
        assert totals[xy]["energy_pj"] == pytest.approx(core_pj(counts), rel=1e-12)
        for task, tc in chip.task_counters(xy).items():
            rows = [r for r in result.profile.rows if r.tile == xy and r.task == task]
            assert sum(r.cycles for r in rows) == tc["cycles"], (xy, task)
            assert sum(r.instructions for r in rows) == tc["instructions"], (xy, task)
            assert math.fsum(r.energy_pj for r in rows) == pytest.approx(core_pj(tc), rel=1e-12), (xy, task)
    (noc,) = [r for r in result.profile.rows if r.function == NOC_ROW]
    noc_pj = sum(noc_parts_pj(run, result.cycles))
    assert noc.energy_pj == totals[None]["energy_pj"] == pytest.approx(noc_pj, rel=1e-12)
    data = result.profile.to_json()["totals"]
    tiles_uj = {f"{x},{y}": core_pj(tile_counts(run, (x, y))) / 1e6 for x, y in run.tiles}
    assert data["tiles_uj"] == pytest.approx(tiles_uj, rel=1e-12)
    assert data["cycles"] == {f"{x},{y}": tile_counts(run, (x, y))["cycles"] for x, y in run.tiles}
    assert data["noc_uj"] == pytest.approx(noc_pj / 1e6, rel=1e-12)
    assert data["total_uj"] == pytest.approx(math.fsum(tiles_uj.values()) + noc_pj / 1e6, rel=1e-12)


def test_the_accounting_covers_the_whole_run(replayed) -> None:
    """Every cycle of every tile is in exactly one task's row (nothing left unattributed at the end)."""
    run, _ = replayed
    chip = run.chip
    for xy in run.tiles:
        t = chip.config.tile_index(xy)
        assert chip.acc[t, :, kc.A_CYCLES].sum() == chip.cores.st[t, S_CYCLE]
        assert chip.acc[t, :, kc.A_SLEEP].sum() == chip.cst[t, kc.K_SLEEP_CYCLES] > 0
