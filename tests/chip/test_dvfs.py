"""DVFS (``chip.dvfs``): the energy coefficients at an operating point by the scaling rules (switching
energy with V², leakage per cycle with V and the period), the points checked, and a flight's energy
against its counters times the scaled coefficients (docs/power.md, "DVFS")."""

from __future__ import annotations

import dataclasses

import pytest
from typer.testing import CliRunner

from robosoc.chip.energy import LEAKAGE_TERMS, EnergyModel
from robosoc.cli import app
from robosoc.config.chip import ChipConfig, DvfsConfig, TileConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.outputs.flight_session import fly_scenario

MODEL = EnergyModel.load()
POINTS = ((62.5, 0.7), (125.0, 0.8), (250.0, 1.0))


def test_switching_energy_scales_with_v_squared_and_leakage_with_v_and_the_period() -> None:
    at = MODEL.at_operating_point(0.8, 1.0, 8.0)  # 125 MHz at 0.8 V, from 1.0 V at 4 ns
    assert at.instruction["add"].pj == pytest.approx(23.58 * 0.64, rel=1e-12)
    assert at.instruction["memory"].pj == pytest.approx(43.15 * 0.64, rel=1e-12)
    assert at.stall["dma_cycle"].pj == pytest.approx(14.4 * 0.64, rel=1e-12)
    assert at.noc["buffer_idle"].pj == pytest.approx(1.459 * 0.64, rel=1e-12)
    assert at.noc["control_active"].pj == pytest.approx(10.621 * 0.64, rel=1e-12)
    # leakage: power x 0.8 (V), energy per cycle x 2 (the period doubled)
    assert at.stall["sleep_cycle"].pj == pytest.approx(0.9 * 1.6, rel=1e-12)
    assert at.noc["leakage"].pj == pytest.approx(0.892 * 1.6, rel=1e-12)
    assert at.clock_ns == 8.0 and "scaled for 0.8 V at 8 ns" in at.noc["leakage"].source
    assert set(LEAKAGE_TERMS) == {"sleep_cycle", "leakage"}


def test_the_reference_point_changes_nothing() -> None:
    chip = ChipConfig(dvfs=DvfsConfig(points=POINTS))
    at = MODEL.for_chip(chip)
    for table in ("instruction", "stall", "noc"):
        assert {k: c.pj for k, c in getattr(at, table).items()} == {k: c.pj for k, c in getattr(MODEL, table).items()}
    assert MODEL.for_chip(ChipConfig()) is MODEL  # no points: no scaling at all


def test_the_voltage_is_that_of_the_slowest_point_at_least_as_fast_as_the_clock() -> None:
    dvfs = DvfsConfig(points=POINTS)
    assert dvfs.voltage_at(4.0) == 1.0
    assert dvfs.voltage_at(8.0) == 0.8
    assert dvfs.voltage_at(10.0) == 0.8  # 100 MHz runs at the 125 MHz point's voltage
    assert dvfs.voltage_at(16.0) == 0.7
    assert dvfs.voltage_at(100.0) == 0.7
    assert dvfs.voltage_at(2.0) is None  # 500 MHz: above every point


def test_a_clock_above_the_highest_point_is_refused() -> None:
    with pytest.raises(ValueError, match=r"tile\.clock_period_ns: 4 ns \(250 MHz\) is faster than the highest DVFS"):
        ChipConfig(dvfs=DvfsConfig(points=((200.0, 0.9),)))
    with pytest.raises(ValueError, match="points"):
        DvfsConfig(points=((100.0, 1.0), (200.0, 0.9)))  # faster on less voltage
    with pytest.raises(ValueError, match="listed twice"):
        DvfsConfig(points=((100.0, 1.0), (100.0, 1.1)))


def test_a_dvfs_point_above_the_highest_frequency_is_refused_on_the_command_line(tmp_path) -> None:
    scenario = tmp_path / "fast.toml"
    scenario.write_text("[chip.dvfs]\npoints = [[200.0, 0.9]]\n")
    result = CliRunner().invoke(app, ["fly", str(scenario), "--no-out"])
    assert result.exit_code == 2, result.output
    assert "chip.tile.clock_period_ns" in result.output and "faster than the highest DVFS point" in result.output


def test_a_flights_energy_is_its_counters_times_the_scaled_coefficients() -> None:
    base = ScenarioConfig(duration_s=0.3)
    chip = dataclasses.replace(base.chip, tile=TileConfig(clock_period_ns=8.0), dvfs=DvfsConfig(points=POINTS))
    flight = fly_scenario(dataclasses.replace(base, chip=chip), None, plot=False)
    result = flight.results[0]
    assert result is not None and result.clock_ns == 8.0
    assert flight.summary["chip"]["dvfs_v"] == 0.8
    for xy, counts in result.counters.items():
        by_hand = 0.0
        for key, c in (*MODEL.instruction.items(), *MODEL.stall.items()):
            factor = 0.8 * 2.0 if key in LEAKAGE_TERMS else 0.64
            by_hand += counts.get(key, 0) * c.pj * factor
        assert result.energy_pj[f"tile {xy}"] == pytest.approx(by_hand, rel=1e-12), xy
        assert counts.get("sleep_cycle", 0) > 0  # both kinds of coefficient are exercised
    # response times count the 8 ns clock
    jobs = result.jobs_of("estimator")
    mean_us = sum(j.response_cycles for j in jobs) / len(jobs) * 8.0 / 1000
    assert flight.summary["tasks"]["estimator"]["response_us_mean"] == pytest.approx(mean_us)
