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
