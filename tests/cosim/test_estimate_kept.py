"""The chip controller keeps its estimate between telemetry reads: at every sample it is the
estimate of the newest values read (computed afresh), and a new read gives a new one."""

import dataclasses

import numpy as np

from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import vehicle_preset
from robosoc.cosim.lockstep import ChipController, fly_lockstep
from robosoc.host.telemetry import estimate_of


def test_the_kept_estimate_is_that_of_the_newest_telemetry_at_every_sample():
    scenario = dataclasses.replace(ScenarioConfig(), duration_s=0.3)
    vehicle = vehicle_preset(scenario.vehicle)
    controller = ChipController(scenario, vehicle)
    seen = []  # each estimate handed out, held (so no two share an id)

    def check(_world, _k):
        run = controller.run
        kept = controller.estimate
        if run is None or not run.latest:
            return
        fresh = estimate_of(run.latest)
        for a, b in zip(dataclasses.astuple(kept), dataclasses.astuple(fresh), strict=True):
            np.testing.assert_array_equal(a, b)
        if not seen or seen[-1] is not kept:
            seen.append(kept)

    fly_lockstep(scenario, vehicle, controller, on_sample=check)
    assert len(seen) > 10  # a new estimate after each read, not one kept for the flight
