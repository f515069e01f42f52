"""The flight end's counters and job energies, computed for all periods' accounting rows at once,
are each row's named counters and the energy model's ``total_pj`` of them (the per-row
computation), to the bit."""

import dataclasses

import pytest

from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import vehicle_preset
from robosoc.cosim.firmware_run import FirmwareRun, _period_values, _rows_pj
from robosoc.cosim.lockstep import ChipController, fly_lockstep
from robosoc.kernels.chip import NTASKS


@pytest.fixture(scope="module")
def run() -> FirmwareRun:
    """The firmware run of a 0.3 s lockstep flight of the default scenario."""
    scenario = dataclasses.replace(ScenarioConfig(), duration_s=0.3)
    vehicle = vehicle_preset(scenario.vehicle)
    controller = ChipController(scenario, vehicle)
    fly_lockstep(scenario, vehicle, controller)
    assert controller.run is not None
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


def test_all_periods_counters_at_once_are_each_rows_named_counters(run: FirmwareRun):
    # the flight keeps each period's accounting-row differences and takes the counters of all
    # periods in one product at its end: each equals account_counters of that row difference
    from robosoc.chip.mpsoc import account_counter_map, account_counters

    names = account_counter_map()[0]
    values = _period_values(run._periods, len(run._keys))
    assert values.shape == (len(run._periods), len(run._keys), len(names))
    for p, period in enumerate(run._periods):
        for r in range(len(run._keys)):
            assert dict(zip(names, values[p, r].tolist(), strict=True)) == account_counters(period.deltas[r])
    assert values[:, :, names.index("instructions")].sum() > 0
