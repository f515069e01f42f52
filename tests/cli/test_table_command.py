"""`robosoc table` end to end: its files read back with the csv and json modules."""

import csv
import json
from pathlib import Path

from typer.testing import CliRunner

from robosoc.cli import app
from robosoc.sweep.table_one import CSV_FIELDS, ENERGY_PARTS


def test_table_writes_csv_and_json(tmp_path: Path) -> None:
    result = CliRunner().invoke(app, ["table", "--iterations", "2", "--workers", "2", "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert "Table I" in result.output and "orderings" in result.output and "accuracy" in result.output
    with (tmp_path / "table.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert tuple(rows[0]) == CSV_FIELDS and len(rows) == 8
    for row in rows:
        assert int(row["jobs"]) == 2
        parts = sum(float(row[f"energy_nj_{p}"]) for p in ENERGY_PARTS)
        assert abs(float(row["energy_nj"]) - parts) <= 1e-9 * parts
    data = json.loads((tmp_path / "table.json").read_text())
    assert {r["build"] for r in data["runs"]} == {"float+mul", "float-no-mul", "fixed+mul", "fixed-no-mul"}
    assert not list(tmp_path.glob("*.partial"))


def _table(tmp_path: Path, *args: str) -> tuple[str, dict, list[dict]]:
    out = tmp_path / "out"
    result = CliRunner().invoke(app, ["table", *args, "--iterations", "2", "--workers", "2", "--out", str(out)])
    assert result.exit_code == 0, result.output
    with (out / "table.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    return result.output, json.loads((out / "table.json").read_text()), rows


def test_table_under_a_scenario_file_with_another_mesh_and_mapping(tmp_path: Path) -> None:
    """A 3x2 chip, the estimator on (2, 1) and the PID on (1, 0), sensor noise off: every build runs
    there (its conditions printed and in table.json), and the event release is the scenario's."""
    scenario = tmp_path / "far.toml"
    scenario.write_text(
        'name = "far"\n[sensors]\nnoise = false\n[[firmware.placement]]\ntask = "estimator"\ntile = [2, 1]\n'
        "[chip]\nwidth = 3\nheight = 2\n"
    )
    text, data, rows = _table(tmp_path, str(scenario))
    assert f"conditions: scenario {scenario} (sensor noise off), 3x2 mesh, estimator on (2, 1), pid on (1, 0)" in text
    assert data["conditions"] == {
        "scenario": str(scenario), "sensor_noise": False, "mesh": "3x2",
        "tiles": {"estimator": [2, 1], "pid": [1, 0]}, "fixed_mul64": "shift-add",
    }  # fmt: skip
    assert len(rows) == 8 and all(int(r["jobs"]) == 2 and r["release"] == "event" for r in rows)


def test_fixed_mul_changes_only_the_fixed_point_build_without_the_multiplier(tmp_path: Path) -> None:
    """--fixed-mul muldi3: the same replay, and only fixed-no-mul forms its products through __muldi3
    (about 470 cycles against about 190): its estimator runs longer, every other row is the same."""
    default_text, _, default_rows = _table(tmp_path / "a")
    text, data, rows = _table(tmp_path / "b", "--fixed-mul", "muldi3")
    assert "Q16.16 multiply without the multiplier: shift-and-add" in default_text
    assert "Q16.16 multiply without the multiplier: 64-bit product through compiler-rt __muldi3" in text
    assert data["conditions"]["fixed_mul64"] == "muldi3"
    for before, after in zip(default_rows, rows, strict=True):
        assert (before["build"], before["task"]) == (after["build"], after["task"])
        if before["build"] != "fixed-no-mul":
            assert before == after
        elif before["task"] == "estimator":
            assert float(after["exec_cycles_mean"]) > 1.2 * float(before["exec_cycles_mean"])


def test_a_scenario_whose_chip_cannot_run_a_build_is_refused(tmp_path: Path) -> None:
    scenario = tmp_path / "nomul.toml"
    scenario.write_text("[chip.tile]\nmultiplier = false\n[firmware]\nmultiplier = false\n")
    result = CliRunner().invoke(app, ["table", str(scenario), "--iterations", "1"])
    assert result.exit_code == 2
    assert (
        f"{scenario}: firmware.multiplier: the build uses the multiplier but task 'estimator' runs on [0, 1], which "
        "has none" in " ".join(result.output.split())
    )
    assert "(the float+mul build)" in result.output
