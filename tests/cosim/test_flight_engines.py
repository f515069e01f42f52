"""Every engine flies the four firmware builds, one vehicle or several, exactly as the interpreter:
flight rows, PWM commands, job records (cycles, instructions, energy), per-tile counters and chip
cycles identical (docs/translation.md).  ``jit`` translates every word at its first arrival, so the
firmware's hot code and its interrupt path run translated; ``auto`` decides by itself (the flight
is short: mostly interpreted, which is what it chooses on a short flight)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from robosoc.config.chip import TileOverride
from robosoc.config.firmware import FirmwareConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import vehicle_preset
from robosoc.cosim.lockstep import ChipController, fly_lockstep_fleet
from robosoc.host.scenario_image import scenario_image
from robosoc.outputs.flight_session import fleet_vehicles

BUILDS = [FirmwareConfig(arith=a, multiplier=m) for a in ("float", "fixed") for m in (False, True)]


def flight(scenario: ScenarioConfig, engine: str) -> tuple:
    scenario = dataclasses.replace(scenario, chip=dataclasses.replace(scenario.chip, engine=engine))
    vehicle = vehicle_preset(scenario.vehicle)
    image = scenario_image(scenario, vehicle)
    controllers = [ChipController(scenario, vehicle, image=image) for _ in range(scenario.vehicles)]
    rows = fly_lockstep_fleet(scenario, fleet_vehicles(scenario), controllers)
    results = [c.result for c in controllers]
    assert all(r is not None for r in results)
    if engine == "jit":  # the firmware ran translated (its tests' counterpart: the interpreter's)
        stats = [c.run.chip._jit.stats for c in controllers if c.run is not None]
        assert stats and all(st is not None and st.regions + st.reused > 0 for st in stats)
    return rows, [
        (r.commands, r.jobs, r.counters, r.task_energy_pj, r.energy_pj, r.cycles, r.telemetry)
        for r in results
        if r is not None
    ]


@pytest.mark.parametrize("fw", BUILDS, ids=lambda fw: fw.label)
def test_every_build_flies_the_same_with_every_engine(fw: FirmwareConfig) -> None:
    scenario = ScenarioConfig(duration_s=0.25, seed=6, firmware=fw)
    rows, runs = flight(scenario, "interp")
    assert runs[0][1], "the flight ran jobs"
    for engine in ("jit", "auto"):
        other_rows, other_runs = flight(scenario, engine)
        assert all(np.array_equal(a, b, equal_nan=True) for a, b in zip(rows, other_rows, strict=True)), engine
        assert other_runs == runs, engine


def test_several_vehicles_fly_the_same_with_every_engine() -> None:
    scenario = ScenarioConfig(duration_s=0.15, seed=2, vehicles=3)
    rows, runs = flight(scenario, "interp")
    assert len(runs) == 3 and not np.array_equal(rows[0], rows[1], equal_nan=True)  # their own sensors
    other_rows, other_runs = flight(scenario, "jit")
    assert all(np.array_equal(a, b, equal_nan=True) for a, b in zip(rows, other_rows, strict=True))
    assert other_runs == runs


def test_a_flight_with_the_estimators_tile_on_its_own_clock_is_the_same_with_every_engine() -> None:
    # the estimator's tile at the chip's clock divided by 4 (docs/power.md, "Per-tile clock")
    base = ScenarioConfig(duration_s=0.25, seed=3)
    chip = dataclasses.replace(base.chip, tiles=(TileOverride(x=0, y=1, clock_period_ns=16.0),))
    scenario = dataclasses.replace(base, chip=chip)
    rows, runs = flight(scenario, "interp")
    estimator = [j for j in runs[0][1] if j.task == "estimator"]
    assert estimator and all(j.release_cycle % 4 == j.completion_cycle % 4 == 0 for j in estimator)  # its cycles
    for engine in ("jit", "auto"):
        other_rows, other_runs = flight(scenario, engine)
        assert all(np.array_equal(a, b, equal_nan=True) for a, b in zip(rows, other_rows, strict=True)), engine
        assert other_runs == runs, engine
