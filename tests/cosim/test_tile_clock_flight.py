"""The flight firmware with the estimator's tile on its own clock (docs/power.md, "Per-tile clock").

The estimator's tile (0, 1) runs at the chip's clock divided by 2 at its DVFS point's 0.8 V, the
rest at 4 ns and 1.0 V: its kernel ticks as often as the others (the tick in its own cycles), its
jobs take twice the chip cycles, its energy is its counters times the coefficients scaled for its
own point, and a tick that does not divide into its cycles is refused before flying.
"""

from __future__ import annotations

import dataclasses

import pytest
from typer.testing import CliRunner

from robosoc.chip.energy import LEAKAGE_TERMS, EnergyModel
from robosoc.cli import app
from robosoc.config.chip import DvfsConfig, TileOverride
from robosoc.config.scenario import ScenarioConfig
from robosoc.host.scenario_image import scenario_image
from robosoc.outputs.flight_session import fly_scenario
from robosoc.program.elf import load_elf

MODEL = EnergyModel.load()
POINTS = ((62.5, 0.7), (125.0, 0.8), (250.0, 1.0))
ESTIMATOR = (0, 1)


def fly(estimator_ns: float):
    base = ScenarioConfig(duration_s=0.5)
    chip = dataclasses.replace(
        base.chip,
        dvfs=DvfsConfig(points=POINTS),
        tiles=(TileOverride(x=ESTIMATOR[0], y=ESTIMATOR[1], clock_period_ns=estimator_ns),),
    )
    flight = fly_scenario(dataclasses.replace(base, chip=chip), None, plot=False)
    result = flight.results[0]
    assert result is not None
    return flight, result


def test_the_estimators_tile_at_half_the_clock() -> None:
    full_flight, full = fly(4.0)
    half_flight, half = fly(8.0)
    assert half_flight.summary["chip"]["tile_clocks"] == {"0,1": {"clock_ns": 8.0, "divider": 2, "dvfs_v": 0.8}}
    assert "tile_clocks" not in full_flight.summary["chip"]  # a divider of 1 is the chip's clock
    # the tick lasts 1 ms on every tile: as many ticks on the slow tile as on the others
    assert half.kernel_stats[ESTIMATOR].ticks == half.kernel_stats[(1, 0)].ticks == full.kernel_stats[ESTIMATOR].ticks
    assert half.kernel_stats[ESTIMATOR].tick_cycles == 262144 // 2  # in its own cycles
    # each estimator job: the same work (a few polls more or fewer), each core cycle two chip cycles
    a, b = full.jobs_of("estimator"), half.jobs_of("estimator")
    assert len(a) == len(b) == 50
    assert sum(j.instructions for j in b) == pytest.approx(sum(j.instructions for j in a), rel=0.01)
    ratio = sum(j.response_cycles for j in b) / sum(j.response_cycles for j in a)
    assert 1.95 < ratio < 2.05
    assert all(j.exec_cycles % 2 == 0 for j in b)  # counted in chip cycles
    # the PID's tile, at the chip's clock, answers as fast as before once its message is there
    assert half.jobs_of("pid")[5].exec_cycles == pytest.approx(full.jobs_of("pid")[5].exec_cycles, rel=0.05)
    # energy: the slow tile's counters times the coefficients at 0.8 V and 8 ns, the other's unscaled
    for xy, counts in half.counters.items():
        by_hand = 0.0
        for key, c in (*MODEL.instruction.items(), *MODEL.stall.items()):
            factor = (0.8 * 2.0 if key in LEAKAGE_TERMS else 0.64) if xy == ESTIMATOR else 1.0
            by_hand += counts.get(key, 0) * c.pj * factor
        assert half.energy_pj[f"tile {xy}"] == pytest.approx(by_hand, rel=1e-12), xy
    assert half.counters[ESTIMATOR]["sleep_cycle"] > 0


def test_a_tick_that_does_not_divide_into_the_tiles_cycles_is_refused(tmp_path) -> None:
    scenario = tmp_path / "third.toml"
    scenario.write_text("[[chip.tiles]]\nx = 0\ny = 1\nclock_period_ns = 12.0\n")
    result = CliRunner().invoke(app, ["fly", str(scenario), "--no-out"])
    assert result.exit_code == 2, result.output
    assert "firmware.tick_cycles" in result.output and "divided by 3" in result.output
    scenario.write_text("[[chip.tiles]]\nx = 0\ny = 1\nclock_period_ns = 6.0\n")
    result = CliRunner().invoke(app, ["fly", str(scenario), "--no-out"])
    assert result.exit_code == 2, result.output
    assert "chip.tiles[0].clock_period_ns: 6 ns is not a whole multiple of the chip's clock" in result.output


def test_a_tile_whose_image_lays_out_differently_is_read_by_its_own_symbols() -> None:
    """At a divider of 8 the estimator's kernel tick (32768 cycles) fits a shorter instruction
    sequence, so its image's symbols lie elsewhere than the other tile's: the host reads the job log,
    the task table and the estimate telemetry of that tile from its own image."""
    _, result = fly(32.0)
    base = ScenarioConfig(duration_s=0.5)
    chip = dataclasses.replace(
        base.chip, dvfs=DvfsConfig(points=POINTS), tiles=(TileOverride(x=0, y=1, clock_period_ns=32.0),)
    )
    scenario = dataclasses.replace(base, chip=chip)
    built = scenario_image(scenario, scenario.vehicle_config())
    own = built.elf_for(ESTIMATOR)
    assert own != built.elf
    assert load_elf(own).address_of("os_job_log") != load_elf(built.elf).address_of("os_job_log")
    assert len(result.jobs_of("estimator")) == 50 and len(result.jobs_of("pid")) == 50
    assert result.kernel_stats[ESTIMATOR].ticks == result.kernel_stats[(1, 0)].ticks
    # the estimate columns come from the estimator tile's telemetry: on the ground, the resting height
    heights = [read.values["est_height"] for read in result.telemetry[10:]]
    rest = scenario.vehicle_config().rest_height
    assert heights and all(abs(h - rest) < 0.05 for h in heights)
