"""``robosoc bench fly --breakdown``: the parts of a flight's host time add up to the flight's time,
count what happened, and change nothing of the flight."""

from __future__ import annotations

import dataclasses

import numpy as np
from typer.testing import CliRunner

from robosoc.benchmarks import fly_breakdown as fb
from robosoc.chip.mpsoc import MPSoC
from robosoc.cli import app
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import vehicle_preset
from robosoc.cosim.lockstep import fly_chip
from robosoc.kernels import chip as kc
from robosoc.physics import World

SCENARIO = ScenarioConfig(duration_s=0.3, seed=3)


def test_the_parts_add_up_to_the_measured_flight_and_count_its_events() -> None:
    fb.fly_breakdown(dataclasses.replace(SCENARIO, duration_s=0.01))  # compile outside
    b = fb.fly_breakdown(SCENARIO)
    # every part measured on its own (sections and the chip loop's ticks), the total around the flight
    assert abs(b.parts_s - b.total_s) <= 0.02 * b.total_s + 0.002, (b.parts_s, b.total_s)
    assert all(p.seconds >= 0 for p in b.parts if p.name != fb.CHIP_CALLS)
    assert b.part(fb.CHIP_CALLS).seconds > -0.01 * b.total_s  # two clocks: what is left of the call
    # what the flight is made of: 1 ms physics steps, 10 ms samples, one chip loop call per sample
    assert b.physics_steps == 300 and b.part("commands out").count == 300
    assert b.part("sample in").count == 30 and b.part("period close").count == 30  # 29 at samples, 1 at the end
    assert b.chip_loop_calls >= b.part("chip step (Python)").count >= 30  # auto's looks cut steps
    assert b.part("chip loop: interpreter").count > 0 and b.part("chip loop: NI accesses").count > 0
    # every sleep ends in a wake-up but for the tiles asleep at the end (the flight's two tiles)
    wakes = b.part("chip loop: wake-ups").count
    assert wakes is not None and 0 <= b.sleeps - wakes <= 2 and b.sleeps >= 2 * 30
    assert b.interrupt_entries >= 30 and b.quanta >= b.chip_loop_calls
    # the same flight as without the breakdown, and everything put back
    plain = fly_chip(SCENARIO, vehicle_preset(SCENARIO.vehicle))
    assert np.array_equal(b.rows, plain.rows, equal_nan=True)
    assert World.step.__name__ == "step" and MPSoC.step.__name__ == "step" and kc.run_chip.__name__ == "run_chip"


def test_bench_fly_breakdown_prints_the_parts_and_their_sum() -> None:
    result = CliRunner().invoke(app, ["bench", "fly", "--breakdown", "--duration", "0.1", "--arith", "fixed", "--mul"])
    assert result.exit_code == 0, result.output
    assert "chip fixed+mul: 0.1 s simulated" in result.output
    assert "sum of the parts" in result.output and "measured flight" in result.output
    assert "chip loop: interpreter" in result.output and "physics" in result.output


def test_bench_fly_breakdown_on_the_engine_asked_for_shows_its_translated_code() -> None:
    """``--engine jit``: the EKF tile's code runs translated, so the breakdown has a translated part
    and the interpreter keeps only what regions leave to it; ``interp`` has no translated part."""
    parts = {}
    for engine in ("jit", "interp"):
        result = CliRunner().invoke(
            app, ["bench", "fly", "--breakdown", "--duration", "0.1", "--arith", "fixed", "--mul", "--engine", engine]
        )
        assert result.exit_code == 0, result.output
        assert f"chip engine {engine}" in result.output
        parts[engine] = {
            line.split("│")[0].strip(): float(line.split("│")[1]) for line in result.output.splitlines() if "│" in line
        }
    assert parts["jit"]["chip loop: translated"] > 0 and parts["interp"]["chip loop: translated"] == 0
    assert parts["jit"]["chip loop: interpreter"] < parts["interp"]["chip loop: interpreter"]
