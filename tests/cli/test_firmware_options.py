"""``robosoc firmware``'s configuration: defaults, then the ``--config`` file, then the options the
user typed (an option not typed does not override the file); errors name ``--config``."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from robosoc.cli.errors import CliError
from robosoc.cli.firmware import _firmware
from robosoc.cli.scenario_flags import ScenarioFlags
from robosoc.config.firmware import FirmwareConfig


def _flags(**values: Any) -> ScenarioFlags:
    return ScenarioFlags.of(None, None, values)


@pytest.fixture
def config(tmp_path: Path) -> Path:
    path = tmp_path / "fw.toml"
    path.write_text('arith = "float"\nmultiplier = false\nperiod_ticks = 5\n')
    return path


def test_defaults_without_file_or_options() -> None:
    assert _firmware(_flags(), None) == FirmwareConfig()


def test_the_file_then_the_typed_options(config: Path) -> None:
    from_file = _firmware(_flags(), config)
    assert (from_file.arith, from_file.multiplier, from_file.period_ticks) == ("float", False, 5)
    assert _firmware(_flags(mul=None), config).multiplier is False  # not typed: the file's
    typed = _firmware(_flags(arith="fixed", mul=True), config)
    assert (typed.arith, typed.multiplier, typed.period_ticks) == ("fixed", True, 5)


def test_a_bad_file_is_named_by_its_option(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text("period_ticks = 0\n")
    with pytest.raises(CliError) as caught:
        _firmware(_flags(), bad)
    assert caught.value.message.startswith(f"--config: {bad}: period_ticks: ")
