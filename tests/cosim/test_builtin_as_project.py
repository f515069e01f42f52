"""The shipped quadrotor project is the built-in application: the same flight, job for job, bit for bit.

The project (``firmware/templates/quadrotor``) is built by the project path (its robosoc.toml, the
generated header, its own ``main``), the built-in by ``robosoc.host.flight_app``; flying both in
lockstep must give identical flight rows (the estimate columns through the project's declared
telemetry) and identical job records, energy included, in every build and both releases.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from robosoc.config.firmware import FirmwareConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import vehicle_preset
from robosoc.cosim.lockstep import fly_chip
from robosoc.firmware import TEMPLATES_DIR

QUADROTOR = str(TEMPLATES_DIR / "quadrotor")


def _fly(fw: FirmwareConfig, duration_s: float):
    scenario = ScenarioConfig(duration_s=duration_s, firmware=fw)
    return fly_chip(scenario, vehicle_preset(scenario.vehicle))


def _jobs(flight) -> list[tuple]:
    return [dataclasses.astuple(j) for j in flight.run.jobs]


@pytest.mark.parametrize(
    ("arith", "multiplier", "release"),
    [("fixed", True, "event"), ("fixed", False, "event"), ("float", True, "event"), ("float", False, "periodic")],
)
def test_the_quadrotor_project_flies_exactly_as_the_built_in(arith: str, multiplier: bool, release: str) -> None:
    fw = FirmwareConfig(arith=arith, multiplier=multiplier, release=release)
    built_in = _fly(fw, 0.4)
    project = _fly(dataclasses.replace(fw, project=QUADROTOR), 0.4)
    assert len(built_in.run.jobs) >= 2 * 39  # both tasks, every sample but the last period's
    np.testing.assert_array_equal(built_in.rows, project.rows)  # estimate columns included (NaN == NaN)
    assert _jobs(built_in) == _jobs(project)
    assert built_in.run.energy_pj == project.run.energy_pj and built_in.run.cycles == project.run.cycles
