"""The flight end's counters and job energies, computed for all periods' accounting rows at once,
are each row's named counters and the energy model's ``total_pj`` of them (the per-row
computation), to the bit."""

import dataclasses
import itertools

import numpy as np
import pytest

from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import vehicle_preset
from robosoc.cosim.firmware_run import FirmwareRun, _period_values, _rows_pj
from robosoc.cosim.lockstep import ChipController, fly_lockstep
from robosoc.kernels.chip import NTASKS


@pytest.fixture(scope="module")
def run() -> FirmwareRun:
    """The firmware run of a 0.3 s lockstep flight of the default scenario, with the accounting rows
    jobs are charged to as they were after each period's close (``run.rows_after``: the test's own
    gather of ``chip.acc``, beside the run's)."""
    scenario = dataclasses.replace(ScenarioConfig(), duration_s=0.3)
    vehicle = vehicle_preset(scenario.vehicle)
    controller = ChipController(scenario, vehicle)
    rows_after: list[np.ndarray] = []
    close = FirmwareRun.close_period

    def close_and_keep(self: FirmwareRun) -> None:
        close(self)
        rows_after.append(self.chip.acc[self._acc_tiles, self._acc_tasks].copy())

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(FirmwareRun, "close_period", close_and_keep)
        fly_lockstep(scenario, vehicle, controller)
    assert controller.run is not None
    controller.run.rows_after = rows_after  # type: ignore[attr-defined]
    return controller.run


def test_all_periods_energies_at_once_equal_total_pj_row_by_row(run: FirmwareRun):
    periods = run._periods
    models = [run.tile_models[run.tiles[i]] for i in run._keys // NTASKS]
    energy = _rows_pj(_period_values(periods, len(run._keys)), models)
    assert energy.shape == (len(periods), len(run._keys))
    nonzero = 0
    for p, period in enumerate(periods):
        for r, key in enumerate(run._keys.tolist()):
            expected = models[r].total_pj(period.counters(key // NTASKS, key % NTASKS))
            assert energy[p, r] == expected  # exactly: the same products summed in the same order
            nonzero += expected > 0
    assert nonzero > len(periods)  # the tasks, kernel and idle did spend energy


def test_each_periods_counters_are_the_named_counters_of_its_rows_difference(run: FirmwareRun):
    # each period's close takes the counters of the accounting rows' differences in one call (a
    # sparse integer product): each equals account_counters of the difference of the rows as they
    # were after the two closes (the first period's from the rows at the run's start, before boot)
    from robosoc.chip.mpsoc import account_counter_map, account_counters

    names = account_counter_map()[0]
    values = _period_values(run._periods, len(run._keys))
    after = run.rows_after  # type: ignore[attr-defined]
    assert values.shape == (len(run._periods), len(run._keys), len(names)) and len(after) == len(run._periods)
    for p in range(1, len(run._periods)):
        for r in range(len(run._keys)):
            expected = account_counters(after[p][r] - after[p - 1][r])
            assert dict(zip(names, values[p, r].tolist(), strict=True)) == expected
    assert values[:, :, names.index("instructions")].sum() > 0
    assert values[1:, :, names.index("cycles")].min() > 0  # every row's task, kernel or idle ran each period


def test_each_periods_noc_energy_is_the_difference_of_the_traffic_energy_at_its_two_closes(run: FirmwareRun):
    # all periods' NoC traffic energies are taken at once from the routers' counters kept at each
    # close: each is, to the bit, the scalar traffic energy at its close less that at the one before
    from robosoc.cosim.firmware_run import noc_traffic_pj

    at_closes = [run._routers_at_start, *(p.routers for p in run._periods)]
    scalar = [noc_traffic_pj(run.model, run.chip.noc_counters_of(r)) for r in at_closes]
    assert all(type(v) is float for v in scalar)
    assert run._periods_noc_pj() == [after - before for before, after in itertools.pairwise(scalar)]
    assert sum(run._periods_noc_pj()) > 0  # the sensor packets and the tasks' messages crossed the mesh
    # the counters kept at the last close are the chip's own (nothing ran after it)
    assert run.chip.noc_counters_of(at_closes[-1]) == run.chip.noc_counters()
