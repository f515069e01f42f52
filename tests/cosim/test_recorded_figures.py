"""The default flight and Table I against figures recorded before the built-in application moved.

``recorded/builtin_figures.json`` holds what ``robosoc fly --out DIR`` and ``robosoc table --out DIR``
wrote at commit fb6a385, before the flight firmware became an ordinary project (issue 32): the
summary's figures (less the host's timing and the ``firmware`` object, whose keys were renamed),
Table I's JSON, and the digests of ``jobs.csv``, ``flight.csv`` and ``table.csv``; and the digest of
``table.csv`` for both releases (``--release both --iterations 20``, recorded at 14bda7e, whose
built-in application was still fb6a385's).  Every figure must come out the same today, bit for bit.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from robosoc.cli import app

RECORDED = json.loads((Path(__file__).parent / "recorded" / "builtin_figures.json").read_text())
HOST_TIMING = ("host_s", "real_time_factor", "host_seconds")


def _figures(value: object) -> object:
    if isinstance(value, dict):
        return {k: _figures(v) for k, v in value.items() if k not in HOST_TIMING}
    if isinstance(value, list):
        return [_figures(v) for v in value]
    return value


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.mark.parametrize("key", ["fly", "table", "table_both_20"])
def test_default_figures_are_those_recorded_before_the_move(tmp_path: Path, key: str) -> None:
    recorded = RECORDED[key]
    command = key.split("_")[0]
    result = CliRunner().invoke(app, [command, *recorded.get("args", []), "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    if command == "fly":
        summary = _figures(json.loads((tmp_path / "summary.json").read_text()))
        assert isinstance(summary, dict)
        summary.pop("firmware")
        assert summary == recorded["summary"]
    elif "json" in recorded:  # every recorded figure (keys added since, as "conditions", aside)
        table = _figures(json.loads((tmp_path / "table.json").read_text()))
        assert isinstance(table, dict)
        assert {k: table.get(k) for k in recorded["json"]} == recorded["json"]
    for name, digest in recorded["sha256"].items():
        assert _sha256(tmp_path / name) == digest, name
