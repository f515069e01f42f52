"""``chip.noc.power_off_unused_routers``: the routers of powered-off tiles that no XY route between
powered tiles crosses are switched off: they cost nothing, and nothing else changes (docs/power.md)."""

from __future__ import annotations

import dataclasses

import pytest

from robosoc.chip.energy import EnergyModel
from robosoc.config.chip import ChipConfig, NocConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.outputs.flight_session import fly_scenario

MODEL = EnergyModel.load()
OFF = ((1, 1), (2, 0), (2, 1), (2, 2), (0, 2), (1, 2))  # a 3x3 with only (0, 0), (0, 1), (1, 0) on


def test_only_routers_on_no_route_between_powered_tiles_are_switched_off() -> None:
    chip = ChipConfig(width=3, height=3, powered_off=OFF, noc=NocConfig(power_off_unused_routers=True))
    # (0, 1) -> (1, 0) goes east first, through (1, 1): that router stays on
    assert sorted(chip.routers_off()) == sorted(set(OFF) - {(1, 1)})
    assert ChipConfig(width=3, height=3, powered_off=OFF).routers_off() == ()  # off by default
    # the seed's 2x2: (1, 1) is on the estimator -> PID route, so nothing is switched off
    seed = ScenarioConfig().chip
    assert dataclasses.replace(seed, noc=NocConfig(power_off_unused_routers=True)).routers_off() == ()


def test_switched_off_routers_cost_nothing_and_change_nothing_else() -> None:
    base = ScenarioConfig(duration_s=0.3)
    runs = []
    for off in (False, True):
        chip = ChipConfig(width=3, height=3, powered_off=OFF, noc=NocConfig(power_off_unused_routers=off))
        flight = fly_scenario(dataclasses.replace(base, chip=chip), None, plot=False)
        runs.append(flight.results[0])
    on, cut = runs
    assert on is not None and cut is not None
    assert [j.completion_cycle for j in on.jobs] == [j.completion_cycle for j in cut.jobs]
    assert {k: v for k, v in on.energy_pj.items() if k != "noc"} == {
        k: v for k, v in cut.energy_pj.items() if k != "noc"
    }
    # five routers x every cycle x an idle router's energy: 5 buffers idle + control idle + leakage
    c = {k: v.pj for k, v in MODEL.noc.items()}
    idle_router = 5 * c["buffer_idle"] + c["control_idle"] + c["leakage"]
    assert on.energy_pj["noc"] - cut.energy_pj["noc"] == pytest.approx(5 * on.cycles * idle_router, rel=1e-9)
