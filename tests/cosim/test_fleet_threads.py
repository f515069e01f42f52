"""The vehicles' chips run on several host threads at once exactly as one after the other: each
vehicle's flight.csv and jobs.csv are the same bytes whatever the number of threads, with the
interpreter and with every word translated (``jit``: regions are written and entered between the
loop calls while the other chips run)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from robosoc.config.scenario import ScenarioConfig
from robosoc.outputs.flight_session import fly_scenario, vehicle_folder
from robosoc.outputs.run_folder import FLIGHT_CSV, JOBS_CSV


def _files(scenario: ScenarioConfig, out: Path, threads: int) -> list[tuple[bytes, bytes]]:
    flight = fly_scenario(scenario, out, plot=False, logs=False, threads=threads)
    assert flight.summary["complete"]
    folders = [vehicle_folder(out, i, scenario.vehicles) for i in range(scenario.vehicles)]
    return [((f / FLIGHT_CSV).read_bytes(), (f / JOBS_CSV).read_bytes()) for f in folders]


@pytest.mark.parametrize(("vehicles", "engine"), [(2, "interp"), (4, "interp"), (3, "jit")])
def test_a_fleet_flies_the_same_on_one_thread_and_on_several(tmp_path: Path, vehicles: int, engine: str) -> None:
    base = ScenarioConfig(duration_s=0.15, seed=4, vehicles=vehicles)
    scenario = dataclasses.replace(base, chip=dataclasses.replace(base.chip, engine=engine))
    alone = _files(scenario, tmp_path / "one", threads=1)
    assert len(alone) == vehicles
    assert alone[0][0] != alone[1][0]  # each vehicle its own sensors: a mix-up would show
    assert all(jobs.count(b"\n") > 10 for _, jobs in alone)  # the chips ran jobs
    for threads in (2, vehicles):
        assert _files(scenario, tmp_path / f"t{threads}", threads=threads) == alone, threads
