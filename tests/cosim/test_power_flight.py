"""A flight on the battery (``power.supply = "battery"``): the run folder's power columns and
``power`` summary, the budget against the chip's own energy, an empty pack mid-flight, refusals
before flying, determinism; and the constant supply leaving every output as it was (docs/power.md)."""

from __future__ import annotations

import csv
import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from robosoc.cli import app
from robosoc.config.power import BatteryConfig, PowerConfig
from robosoc.config.scenario import FlightPlan, ScenarioConfig
from robosoc.control.flight import ROW_FIELDS, column
from robosoc.control.flight_log import read_flight_log
from robosoc.outputs.flight_session import fly_scenario
from robosoc.outputs.report import render_report
from robosoc.outputs.run_folder import read_run_folder
from robosoc.outputs.run_summary import HOST_TIMING_KEYS, load_summary
from robosoc.physics.battery import Battery
from robosoc.records import POWER_FIELDS

runner = CliRunner()
SHORT = ScenarioConfig(
    duration_s=2.5,
    flight=FlightPlan(takeoff_s=0.5, climb_s=1.0),
    wind=dataclasses.replace(ScenarioConfig().wind, gusts=()),
)
BATTERY = PowerConfig(supply="battery")


def _power_columns(path: Path) -> tuple[list[str], np.ndarray]:
    with path.open() as handle:
        lines = list(csv.reader(handle))
    return lines[0], np.array(lines[1:], dtype=float)


def test_a_chip_flight_on_the_battery_keeps_a_budget_that_adds_up_to_the_chips_energy(tmp_path: Path) -> None:
    out = tmp_path / "run"
    flight = fly_scenario(dataclasses.replace(SHORT, power=BATTERY), out, plot=False, logs=False)
    header, table = _power_columns(out / "flight.csv")
    assert tuple(header) == (*ROW_FIELDS, *POWER_FIELDS)
    rows = read_flight_log(out / "flight.csv")  # the reader reads past the power columns
    assert rows.shape == (250, len(ROW_FIELDS))
    power = dict(zip(POWER_FIELDS, table[:, len(ROW_FIELDS) :].T, strict=True))
    summary = load_summary((out / "summary.json").read_text(), "summary.json")
    p = summary["power"]
    # the chip's part of the budget is the chip's own energy (tiles + NoC, summary's "energy")
    assert p["energy_j"]["chip"] == pytest.approx(summary["energy"]["total_uj"] * 1e-6, rel=1e-9)
    assert p["energy_j"]["avionics"] == pytest.approx(3.0 * 2.5, rel=1e-9)
    assert p["energy_j"]["total"] == pytest.approx(sum(p["energy_j"][k] for k in ("motors", "chip", "avionics")))
    assert p["chip_share"] == pytest.approx(p["energy_j"]["chip"] / p["energy_j"]["total"])
    # chip power per sample period, from the rows, adds up to the chip's energy too
    assert power["chip_w"].sum() * 0.01 == pytest.approx(p["energy_j"]["chip"], rel=1e-9)
    # the pack: voltage sags under load, state of charge falls by the charge the rows drew
    pack = Battery(BatteryConfig())
    assert power["pack_v"][0] == pytest.approx(pack.open_circuit_v())  # no current before the first step
    assert power["pack_v"].min() < pack.open_circuit_v() - 0.3
    assert np.all(np.diff(power["soc"]) <= 0)
    drawn_ah = 1.0 - p["pack"]["final_soc"]
    assert drawn_ah * 5.0 == pytest.approx(p["energy_j"]["total"] / np.mean(power["pack_v"]) / 3600, rel=0.02)
    # endurance: at the flight's mean power from take-off, from full to the 20 % reserve
    e = p["endurance"]
    assert e["to_soc"] == 0.2 and "reserve" in e["ended_by"] and "Tremblay" in e["assumptions"]
    assert 600 < e["hover_s"] < 4 * 3600
    assert e["hover_s"] == pytest.approx(0.8 * 5.0 * 3600 * 15.0 / e["at_power_w"], rel=0.15)  # ~15 V mean
    assert p["empty_at_s"] is None and p["after_empty"] is None
    assert flight.summary["power"]["mean_power_w"] == p["mean_power_w"]
    page = (out / "report.html").read_text() if (out / "report.html").exists() else render_report(read_run_folder(out))
    assert 'data-plot="power"' in page and "Endurance estimate" in page and "Tremblay" in page
    assert f"{p['energy_j']['chip']:,.3f}" in page  # the chip's part of the budget, in joules


def test_an_empty_pack_mid_flight_keeps_the_logs_and_says_the_vehicle_fell(tmp_path: Path) -> None:
    tiny = PowerConfig(supply="battery", battery=BatteryConfig(capacity_ah=0.005))  # 18 A·s: empties at ~2.7 s
    scenario = dataclasses.replace(SHORT, controller="host", power=tiny, duration_s=4.0)
    out = tmp_path / "run"
    fly_scenario(scenario, out, plot=False, logs=False)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["complete"] is True
    p = summary["power"]
    assert p["empty_at_s"] is not None and 0.5 < p["empty_at_s"] < 4.0
    assert p["after_empty"].startswith("fell: touched down")
    rows = read_flight_log(out / "flight.csv")
    assert len(rows) == 400  # every row kept
    _, table = _power_columns(out / "flight.csv")
    t = column(rows, "t")
    after = t > p["empty_at_s"] + 0.01
    assert np.all(table[after, len(ROW_FIELDS)] == 0.0)  # no voltage once cut off
    z = column(rows, "z")
    assert z[-1] < 0.25  # back on the ground (rests at 0.18 m)


def test_a_battery_flight_is_repeatable_bit_for_bit(tmp_path: Path) -> None:
    scenario = dataclasses.replace(SHORT, controller="host", power=BATTERY)
    for name in ("a", "b"):
        fly_scenario(scenario, tmp_path / name, plot=False, logs=False)
    assert (tmp_path / "a/flight.csv").read_bytes() == (tmp_path / "b/flight.csv").read_bytes()
    a, b = (json.loads((tmp_path / n / "summary.json").read_text()) for n in ("a", "b"))
    for key in HOST_TIMING_KEYS:
        a.pop(key), b.pop(key)
    assert a == b


def test_the_constant_supply_writes_no_power_and_flies_as_before(tmp_path: Path) -> None:
    fly_scenario(dataclasses.replace(SHORT, controller="host"), tmp_path / "c", plot=False, logs=False)
    header, _ = _power_columns(tmp_path / "c/flight.csv")
    assert tuple(header) == ROW_FIELDS
    assert "power" not in json.loads((tmp_path / "c/summary.json").read_text())
    # a pack with no resistance and a voltage that stays at 14.8 V is not what "constant" means: the
    # constant supply ignores the pack entirely, so changing it changes nothing
    other = PowerConfig(battery=BatteryConfig(cells=2, capacity_ah=0.1))
    fly_scenario(dataclasses.replace(SHORT, controller="host", power=other), tmp_path / "d", plot=False, logs=False)
    assert (tmp_path / "c/flight.csv").read_bytes() == (tmp_path / "d/flight.csv").read_bytes()


def test_a_pack_that_cannot_lift_the_vehicle_is_refused_before_flying(tmp_path: Path) -> None:
    scenario = tmp_path / "weak.toml"
    scenario.write_text('[power]\nsupply = "battery"\n[power.battery]\ncells = 1\n')
    out = tmp_path / "run"
    result = runner.invoke(app, ["fly", str(scenario), "--controller", "host", "--out", str(out)])
    assert result.exit_code == 2, result.output
    assert f"{scenario}: power.battery.cells: the pack cannot lift the vehicle" in result.output
    assert not out.exists()
    with pytest.raises(ValueError, match=r"power\.battery\.cells"):
        fly_scenario(ScenarioConfig(power=PowerConfig(supply="battery", battery=BatteryConfig(cells=1))), None)


@pytest.mark.parametrize("soc", ["1.2", "-0.5"])
def test_a_state_of_charge_outside_0_1_is_refused_naming_the_field(tmp_path: Path, soc: str) -> None:
    scenario = tmp_path / "soc.toml"
    scenario.write_text(f'[power]\nsupply = "battery"\n[power.battery]\ninitial_soc = {soc}\n')
    result = runner.invoke(app, ["fly", str(scenario), "--no-out"])
    assert result.exit_code == 2, result.output
    assert "power.battery.initial_soc: must be in [0, 1]" in result.output


def test_supply_option_sets_the_field() -> None:
    result = runner.invoke(app, ["fly", "--supply", "solar", "--no-out"])
    assert result.exit_code == 2 and "--supply" in result.output


def test_below_the_reserve_the_failsafe_returns_to_its_hover_height_holds_it_and_lands(tmp_path: Path) -> None:
    """A 0.02 Ah pack (72 A·s) with a 60 % reserve: the reserve comes at about 4.8 s, hovering at
    1 m; the firmware's failsafe (built for a battery flight) climbs at 0.5 m/s to its 1.5 m hover
    height, holds it 0.5 s, descends at 0.5 m/s and stops the motors on the ground, before the
    cut-off.  Checked on the rows' heights and motor commands."""
    pack = PowerConfig(
        supply="battery",
        reserve_soc=0.6,
        failsafe_height_m=1.5,
        failsafe_hold_s=0.5,
        battery=BatteryConfig(capacity_ah=0.02),
    )
    scenario = dataclasses.replace(SHORT, power=pack, duration_s=11.0)
    out = tmp_path / "run"
    fly_scenario(scenario, out, plot=False, logs=False)
    summary = json.loads((out / "summary.json").read_text())
    p = summary["power"]
    failsafe = p["failsafe"]
    assert failsafe is not None and failsafe["reserve_soc"] == 0.6
    assert failsafe["height_m"] == 1.5 and failsafe["hold_s"] == 0.5
    rows = read_flight_log(out / "flight.csv")
    _, table = _power_columns(out / "flight.csv")
    soc = table[:, len(ROW_FIELDS) + POWER_FIELDS.index("soc")]
    t, z = column(rows, "t"), column(rows, "z")
    # the cue is the first step below the reserve, seen in the rows' state of charge
    at = failsafe["at_s"]
    first_low = t[np.flatnonzero(soc < 0.6)[0]]
    assert first_low - 0.01 <= at <= first_low
    assert abs(z[t < at][-1] - 1.0) < 0.1  # hovering at 1 m when it came, half a metre below 1.5 m
    # it climbs to the failsafe height: there within 0.1 m about 1 s later (0.5 m at 0.5 m/s)
    reached = failsafe["reached_s"]
    assert reached is not None and at + 0.6 < reached < at + 1.6
    assert np.all(np.abs(z[(t >= at) & (t < reached)] - 1.0) < 0.6)  # on its way up, no detour
    assert z[(t >= at) & (t < reached)].min() > 0.9  # it does not descend first
    # then holds it: the hold and the settling take it no lower than 1.35 m for the next 0.5 s
    holding = (t >= reached) & (t < reached + 0.5)
    assert np.all(z[holding] > 1.35) and np.all(z[holding] < 1.65)
    # and lands: touchdown at a landing's speed, after the hold, the motors off from then on
    assert failsafe["outcome"].startswith("landed: touched down")
    speed = float(failsafe["outcome"].split(" at ")[-1].split(" m/s")[0])
    down = float(failsafe["outcome"].split("touched down at ")[1].split(" s")[0])
    assert speed <= 0.65  # the 0.5 m/s descent, not a fall
    assert reached + 0.5 + 1.5 / 0.5 * 0.7 < down  # 1.3 m down at 0.5 m/s takes 2.6 s
    pwm = rows[:, [ROW_FIELDS.index(f"pwm{i}") for i in range(4)]]
    after = t > down + 0.5
    assert after.sum() > 100 and np.all(pwm[after] == 0)  # disarmed on the ground and staying so
    assert np.all(z[after] < 0.2)
    assert p["empty_at_s"] is None  # it landed on the reserve, before the cut-off
    assert p["pack"]["final_soc"] > 0.1


@pytest.mark.parametrize(
    "line,expect",
    [
        ("failsafe_height_m = 0.2", "power.failsafe_height_m: 0.2 m is not above the height at which"),
        ("failsafe_height_m = -1.0", "power.failsafe_height_m: must be in (0, 100]"),
        ("failsafe_hold_s = 120.0", "power.failsafe_hold_s: must be in [0, 60]"),
    ],
)
def test_a_bad_failsafe_height_or_hold_is_refused_naming_the_field(tmp_path: Path, line: str, expect: str) -> None:
    scenario = tmp_path / "failsafe.toml"
    scenario.write_text(f'[power]\nsupply = "battery"\n{line}\n')
    result = runner.invoke(app, ["fly", str(scenario), "--no-out"])
    assert result.exit_code == 2, result.output
    assert expect in result.output, result.output
